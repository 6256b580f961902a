"""The one-line summary `vibrofeed run` prints: a result it cannot analyse fully says so and
is still summarised (the run did what it said; its summary must not fail it)."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

import vibrofeed.run_summary as RS
from helpers import parts, write_result
from vibrofeed.engine.runner import RunResult
from vibrofeed.run_summary import run_summary

FREQ = 50.0  # [Hz]


def one_part(path, frames_per_period: float, periods: int = 6):
    """A part resting on a plate that moves normal to itself, A = 10 um, sampled at the given
    number of frames per period."""
    dt = 1 / (FREQ * frames_per_period)
    times = np.arange(0, periods / FREQ + 1e-12, dt)
    w, amp = 2 * math.pi * FREQ, 1e-5
    frames, surface = [], []
    for k, t in enumerate(times):
        z = amp * math.sin(w * t)
        frames.append((k, float(t), parts([1], [[0.0, 0.0, z + 5e-4]])))
        surface.append((np.array([0, 0, z]), np.array([0, 0, amp * w * math.cos(w * t)])))
    write_result(path, frames, surface=surface)
    return RunResult(output=path, log=path.with_suffix(".log"), deck="single_part", ranks=1,
                     n_steps=len(times), dt=1e-6, frames=len(times), sim_time=float(times[-1]), wall=1.0)


def test_frames_too_sparse_for_the_hops_are_said_not_to_count_them(tmp_path):
    line = run_summary(one_part(tmp_path / "sparse.h5", frames_per_period=1))
    assert "hops not counted" in line and "output_dt <= 0.0025 s" in line  # T/8 at 50 Hz


def test_frames_that_follow_the_surface_count_the_hops(tmp_path):
    line = run_summary(one_part(tmp_path / "dense.h5", frames_per_period=20))
    assert "0 hops" in line and "hops not counted" not in line


def test_a_part_that_flies_off_and_never_lands_is_said_to_be_in_the_air(tmp_path):
    # Issue 36: "0 hops, airborne 0 % of the time, highest 35.8 mm" for a part flying 36 mm above
    # the plate. Here a part rests on a still plate (pressed: a contact force m g) until 20 ms,
    # then leaves it at 1 m/s and is still rising at 0.1 s (it would land 2 v / g = 204 ms later).
    g, v0, t_l, mass, dt = 9.81, 1.0, 0.02, 1e-6, 1e-3
    times = np.arange(0, 0.1 + dt / 2, dt)
    frames = []
    for k, t in enumerate(times):
        s = max(t - t_l, 0.0)
        z, v = 5e-4 + v0 * s - g / 2 * s * s, (v0 - g * s) if t > t_l else 0.0
        force = -mass * g if t > t_l else 0.0  # total force: gravity alone once in flight
        frames.append((k, float(t), parts([1], [[0.0, 0.0, z]], velocity=[[0, 0, v]],
                                          force=[[0, 0, force]], mass=mass)))
    path = write_result(tmp_path / "off.h5", frames,
                        variables={"freq": ("50", "Hz", "f", "50"), "incline": ("0", "deg", "i", "0")})
    run = RunResult(output=path, log=path.with_suffix(".log"), deck="single_part", ranks=1,
                    n_steps=len(times), dt=1e-6, frames=len(times), sim_time=0.1, wall=1.0)
    highest = v0 * 0.08 - g / 2 * 0.08 ** 2  # 48.6 mm above the plate at the last frame
    assert f"{highest * 1e3:.3g}" == "48.6"
    assert run_summary(run).endswith(
        "0 hops, in flight from t = 0.02 s to the end, airborne 80% of the time, highest 48.6 mm")


# ---------------------------------------------------------------- the line from a faked result
class FakeResult:
    """What run_summary reads of a result, set by hand."""

    def __init__(self, n=1, n_frames=3, balance=None, parameters=None):
        self.part_ids = list(range(n))
        self.n_frames = n_frames
        self.mass_balance = balance
        self.parameters = {"freq": "50"} if parameters is None else parameters

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def fake_run(**kw):
    run = dict(reused=False, deck="d", sim_time=1.0, target_error=None, stop_reason="",
               stopped_early=False, wall=2.0, steps_per_second=5000.0, ranks=1, frames=3,
               output="o.h5", run_id="0" * 40)
    run.update(kw)
    return SimpleNamespace(**run)


def analyses(monkeypatch, velocity=0.0, durations=()):
    transport = SimpleNamespace(mean_velocity=velocity)
    flights = SimpleNamespace(durations=np.asarray(durations, float), n_hops=len(durations),
                              airborne_fraction=0.5, max_gap=2e-3, in_flight_at_end=None)
    def analysis(results):
        return lambda r: SimpleNamespace(run=lambda: SimpleNamespace(results=results))

    monkeypatch.setattr(RS, "Transport", analysis(transport))
    monkeypatch.setattr(RS, "Flights", analysis(flights))


@pytest.mark.parametrize("x, text", [(1.5, "1.5 m/s"), (1.0, "1 m/s"), (0.0025, "2.5 mm/s"),
                                     (2.5e-6, "2.5 um/s"), (2.5e-8, "0.025 um/s")])
def test_speeds_take_the_largest_prefix_they_reach(x, text):
    assert RS._si(x, "m/s") == text


def test_the_reason_a_run_stopped_is_said_only_with_a_target_error():
    assert RS._stopped(fake_run(target_error=None, stop_reason="time limit")) == ""
    assert RS._stopped(fake_run(target_error=0.1, stop_reason="")) == ""
    assert RS._stopped(fake_run(target_error=0.1, stop_reason="error reached",
                                stopped_early=True)) == " (stopped early: error reached)"


def test_a_feeder_line_says_where_its_parts_went(monkeypatch):
    balance = {k: np.array([0, v]) for k, v in
               dict(inserted=10, on_track=3, exited=5, lost=1, rejected=1).items()}
    monkeypatch.setattr(RS, "Result", lambda path: FakeResult(n=4, balance=balance))
    line = run_summary(fake_run())
    assert line.endswith(" | 10 parts fed: 5 exited, 1 rejected, 3 on the track, 1 lost")
    balance["returned"] = np.array([0, 2])
    del balance["rejected"]
    line = run_summary(fake_run())
    assert line.endswith(" | 8 parts fed + 2 returned: 5 exited, 3 on the track, 1 lost")


def test_without_a_frequency_a_hop_is_one_lasting_a_twentieth_of_a_second(monkeypatch):
    # no "freq": a period of 1 s; hops last >= 0.05 s, shorter ones are rebounds
    monkeypatch.setattr(RS, "Result", lambda path: FakeResult(parameters={}))
    analyses(monkeypatch, velocity=0.01, durations=[0.03, 0.06])
    line = run_summary(fake_run())
    assert line.endswith(" | 1 part, mean speed 10 mm/s along x, 1 hops (+1 short rebounds), "
                         "airborne 50% of the time, highest 2 mm")


def test_two_frames_are_too_few_for_a_speed_or_hops(monkeypatch):
    monkeypatch.setattr(RS, "Result", lambda path: FakeResult(n_frames=2))
    analyses(monkeypatch, velocity=0.01, durations=[0.03])
    assert run_summary(fake_run()).endswith(" | 1 part")
