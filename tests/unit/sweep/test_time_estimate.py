"""A sweep's estimate of its wall time, from each run's steps (vibrofeed.sweep.execute.time_estimate)."""

from types import SimpleNamespace

from vibrofeed.parameters import STEPS_PER_SECOND
from vibrofeed.sweep.execute import time_estimate
from vibrofeed.values import duration


def job(t_end, dt):
    return SimpleNamespace(values={"t_end": str(t_end), "dt": str(dt)})


def test_runs_shared_between_workers():
    # 4 runs of 1e6 steps each: 4e6 steps, two at a time
    jobs = [job(1.0, 1e-6)] * 4
    said = time_estimate(jobs, 2)
    assert said.startswith(f"about {duration(2e6 / STEPS_PER_SECOND)} to run")


def test_the_longest_run_bounds_it():
    # one long run and a short one on 8 workers: the long one's time, not the sum / 8
    said = time_estimate([job(1.0, 1e-7), job(1.0, 1e-5)], 8)
    assert said.startswith(f"about {duration(1e7 / STEPS_PER_SECOND)} to run")


def test_runs_without_an_estimate():
    jobs = [job(1.0, 1e-6), SimpleNamespace(values={"dt": "1e-6"})]  # no t_end: not estimated
    assert "(1 not estimated)" in time_estimate(jobs, 1)
    assert time_estimate([SimpleNamespace(values={})], 1) == ""
