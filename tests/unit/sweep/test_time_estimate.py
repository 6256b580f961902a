"""A sweep's estimate of its wall time, from each run's steps and the spheres of the parts it
holds (vibrofeed.sweep.execute.time_estimate, vibrofeed.parameters.step_seconds)."""

import warnings
from types import SimpleNamespace

import pytest

from helpers import REPO
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import estimated_seconds
from vibrofeed.parameters import resolve
from vibrofeed.sweep.execute import time_estimate
from vibrofeed.values import duration

# a feeder's step without parts, a bowl's, and one sphere's share (vibrofeed.parameters.STEP_SECONDS)
FEEDER, BOWL, SPHERE = 30e-6, 150e-6, 0.3e-6


def job(t_end, dt, **more):
    values = {"t_end": t_end, "dt": dt, **more}
    return SimpleNamespace(values={k: str(v) for k, v in values.items()})


def test_runs_shared_between_workers():
    # 4 runs of 1e6 steps each (no parts named: one sphere held): 4e6 steps, two at a time
    jobs = [job(1.0, 1e-6)] * 4
    said = time_estimate(jobs, 2)
    assert said.startswith(f"about {duration(2e6 * (FEEDER + SPHERE))} to run")


def test_the_longest_run_bounds_it():
    # one long run and a short one on 8 workers: the long one's time, not the sum / 8
    said = time_estimate([job(1.0, 1e-7), job(1.0, 1e-5)], 8)
    assert said.startswith(f"about {duration(1e7 * (FEEDER + SPHERE))} to run")


def test_runs_without_an_estimate():
    jobs = [job(1.0, 1e-6), SimpleNamespace(values={"dt": "1e-6"})]  # no t_end: not estimated
    assert "(1 not estimated)" in time_estimate(jobs, 1)
    assert time_estimate([SimpleNamespace(values={})], 1) == ""


def test_the_parts_held_set_the_cost_of_a_step():
    """A sweep of a line of boxes was estimated at 4 minutes and took 15: the estimate ran every
    deck at the demo's speed. By hand: the pile, the track's and half of those fed are held,
    each a sphere, or a box's 36 (1.0 x 0.5 x 0.35 mm at clump_spacing 1)."""
    spheres = job(1.0, 1e-6, n_parts=40, n_track=10, inlet_rate=20, part_size=3e-4)
    (seconds, steps, _dt) = estimated_seconds(spheres.values)
    assert steps == pytest.approx(1e6, rel=1e-12)
    assert seconds == pytest.approx(1e6 * (FEEDER + SPHERE * (40 + 10 + 20 * 1.0 / 2)), rel=1e-12)
    boxes = job(1.0, 1e-6, n_parts=40, n_track=10, inlet_rate=20, part_size=1e-3, part_width=5e-4,
                part_thickness=3.5e-4, shape=3, clump_spacing=1.0)
    assert estimated_seconds(boxes.values)[0] == pytest.approx(1e6 * (FEEDER + SPHERE * 60 * 36), rel=1e-12)
    # the orientation demo's line as it runs (12 pre-filled, 9 parts/s over 2 s): 21 boxes of 36
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        values = resolve(Deck.find(REPO / "feeders" / "orient_line.toml"), {})
    seconds, steps, _dt = estimated_seconds(values)
    assert seconds == pytest.approx(steps * (FEEDER + SPHERE * 21 * 36), rel=1e-12)


def test_a_line_holds_no_more_fed_parts_than_cover_its_floors():
    """The orientation demo's line draws 110 boxes a second from its store over 2 s, and was
    estimated at 1 h 34 min holding 122 boxes (it held 17-20 and ran 10-13 minutes): what it
    delivers or rejects leaves it. By hand: 12 pre-filled and no more fed ones than lie side
    by side on its floors, (5 x 1.4 + 8 x 1.5) mm^2 over a box's 1.0 x 0.5 mm footprint."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        values = resolve(Deck.find(REPO / "feeders" / "orient_ledge.toml"), {})
    held = 12 + (5 * 1.4 + 8 * 1.5) / (1.0 * 0.5)
    seconds, steps, _dt = estimated_seconds(values)
    assert seconds == pytest.approx(steps * (FEEDER + SPHERE * held * 36), rel=1e-12)
    # a line fed less than its floors hold keeps its half of the fed ones (above: 21 boxes)
    assert held < 12 + 110 * 2 / 2


def test_a_bowls_mesh_costs_its_step():
    """The bowl sweep was estimated at 5.5 minutes and took about 15: a bowl's 602 triangles,
    turned and lifted at every step, cost five times a track's. By hand: the bowl-line demo
    (10 dies in the pile, 40 on the track, 9 spheres each) at 150 us + 450 x 0.3 us a step."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        values = resolve(Deck.find(REPO / "feeders" / "bowl_line.toml"), {})
    seconds, steps, _dt = estimated_seconds(values)
    assert seconds == pytest.approx(steps * (BOWL + SPHERE * 50 * 9), rel=1e-12)
