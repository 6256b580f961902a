"""Flights of one part: every answer of a bouncing part whose impacts are known exactly.

A ball dropped onto a still floor with restitution e bounces at
t_1 = sqrt(2 h / g), t_k+1 = t_k + 2 e^k g t_1 / g; every impact falls between
frames, so each shows up only as a velocity jump between two airborne frames.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from helpers import parts, write_result
from vibrofeed.postproc import Flights, Results
from vibrofeed.postproc.flights import normal_contact_force
from vibrofeed.results.reader import Result

G = 9.81
R = 5e-4
M = 1e-6
E = 0.5
H0 = 2e-3


def bounces(n=5):
    t1 = math.sqrt(2 * H0 / G)
    out, t, v = [], t1, G * t1
    for _ in range(n):
        out.append((t, -v, E * v))  # impact time, velocity before, after
        v *= E
        t += 2 * v / G
    return out


def state(t, hits):
    """Height of the ball's bottom above the floor and its velocity at time t."""
    t0, z0, v0 = 0.0, H0, 0.0
    for th, _, v_out in hits:
        if th <= t:
            t0, z0, v0 = th, 0.0, v_out
    return z0 + v0 * (t - t0) - G / 2 * (t - t0) ** 2, v0 - G * (t - t0)


def bouncing_file(tmp_path, dt=1.7e-4, press=0.0, n=5):
    hits = bounces(n)
    times = np.arange(0.0, hits[-1][0] - dt / 3, dt)
    frames = []
    for k, t in enumerate(times):
        z, v = state(t, hits)
        frames.append((k, float(t), parts([7], [[0.0, 0.0, z + R]], radius=R, mass=M,
                                          velocity=[[0, 0, v]], force=[[0, 0, -M * G - press]])))
    variables = {"freq": ("50", "Hz", "f", "50"), "incline": ("0", "deg", "i", "0"),
                 "normal_force": (repr(press), "N", "p", "0")}
    return Result(write_result(tmp_path / "b.h5", frames, variables=variables)), times, hits


@pytest.mark.parametrize("press", [0.0, 3e-6])
def test_every_answer_of_a_bouncing_ball(tmp_path, press):
    r, times, hits = bouncing_file(tmp_path, press=press)
    with r:
        res = Flights(r).run().results
    t_hit = np.array([h[0] for h in hits if h[0] < times[-1]])
    assert res.part_id == 7
    assert res.landings == pytest.approx(t_hit, abs=1e-9)
    assert res.takeoffs == pytest.approx(t_hit, abs=1e-9)       # each impact launches again
    assert res.takeoff_kinds == ["rebound"] * len(t_hit)
    assert res.flights == pytest.approx(np.column_stack([t_hit[:-1], t_hit[1:]]), abs=1e-9)
    assert res.kinds == ["rebound"] * (len(t_hit) - 1) and res.n_hops == len(t_hit) - 1
    assert res.durations == pytest.approx(np.diff(t_hit), abs=1e-9)
    assert res.airborne_fraction == pytest.approx(np.diff(t_hit).sum() / times[-1], rel=1e-6)
    assert res.max_gap == pytest.approx(H0, abs=1e-15)  # m: the first frame's
    assert res.impacts[:, 0] == pytest.approx(t_hit, abs=1e-9)
    assert res.impacts[:, 1] == pytest.approx([h[1] for h in hits[:len(t_hit)]], rel=1e-6)
    assert res.impacts[:, 2] == pytest.approx(E, rel=1e-6)
    assert res.realised_restitution == pytest.approx(E, rel=1e-6)
    assert res.contact_force == pytest.approx(np.zeros(len(times)), abs=1e-18)  # all in flight


def test_a_later_start_counts_the_airborne_time_from_there(tmp_path):
    r, times, hits = bouncing_file(tmp_path)
    first = int(np.searchsorted(times, hits[0][0]))  # the first frame after the first impact
    with r:
        res = Flights(r).run(start=first).results
    t_hit = np.array([h[0] for h in hits[1:] if h[0] < times[-1]])
    assert res.time[0] == pytest.approx(times[first], abs=1e-15)  # s
    assert res.landings == pytest.approx(t_hit, abs=1e-9)
    # the record starts in flight: the flight under way has no launch in it
    assert res.n_hops == len(t_hit) - 1
    span = times[-1] - times[first]
    assert res.airborne_fraction == pytest.approx(np.diff(t_hit).sum() / span, rel=1e-6)


def test_normal_contact_force_removes_gravity_and_the_pressing_force(tmp_path):
    press = 2e-6
    frames = [(k, 1e-4 * k, parts([1], [[0, 0, R]], radius=R, mass=M, force=[[0, 0, 0.0]]))
              for k in range(3)]
    variables = {"normal_force": (repr(press), "N", "p", "0"), "incline": ("30", "deg", "i", "0")}
    with Result(write_result(tmp_path / "p.h5", frames, variables=variables)) as r:
        fc = normal_contact_force(r, 1)
        # resting: the floor carries the weight's normal part and the pressing force
        assert fc == pytest.approx(np.full(3, M * G * math.cos(math.radians(30)) + press), rel=1e-12)
        assert normal_contact_force(r, 1, frames=[1, 2]).shape == (2,)


def test_a_part_seen_in_one_frame_has_no_flights(tmp_path):
    frames = [(0, 0.0, parts([1], [[0, 0, R + 1e-3]], radius=R, mass=M, force=[[0, 0, -M * G]])),
              (1, 1e-4, parts([2], [[0, 0, R]], radius=R, mass=M))]
    with Result(write_result(tmp_path / "o.h5", frames)) as r:
        res = Flights(r, part_id=1).run().results
        assert res.n_hops == 0 and len(res.landings) == 0 and res.airborne_fraction == 0.0
        assert res.max_gap == pytest.approx(1e-3, abs=1e-15)  # m
        with pytest.raises(KeyError, match="particle id 3"):
            Flights(r, part_id=3).run()


def test_results_name_missing_answers_as_attributes():
    res = Results(a=1)
    assert not hasattr(res, "b") and getattr(res, "b", None) is None
    with pytest.raises(AttributeError, match="no result 'b'; results are: a"):
        _ = res.b
    del res.a
    assert "a" not in res
    with pytest.raises(AttributeError):
        del res.a
