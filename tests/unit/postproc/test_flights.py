"""Flights of one part: every answer of a bouncing part whose impacts are known exactly.

A ball dropped onto a still floor with restitution e bounces at
t_1 = sqrt(2 h / g), t_k+1 = t_k + 2 e^k g t_1 / g; every impact falls between
frames, so each shows up only as a velocity jump between two airborne frames.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from bulk_synthetic import enclosing_radius
from helpers import parts, write_bulk_result, write_result
from vibrofeed.errors import InputError
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
    # dropped from H0 at the first frame and in flight after the last impact: never at rest
    assert res.airborne_at_start and res.in_flight_at_end == pytest.approx(t_hit[-1], abs=1e-9)
    assert res.airborne_fraction == pytest.approx(1.0, abs=1e-9)
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
    assert res.airborne_at_start and res.time[-1] - res.time[0] == pytest.approx(span, abs=1e-15)
    assert res.airborne_fraction == pytest.approx(1.0, abs=1e-9)  # in flight throughout, as before


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


# -- chips: a body's lowest point is its lowest sphere's ------------------------------------
R_S, PITCH = 7.5e-5, 1e-4
# three spheres in an L (a corner and its two neighbours): their mean, the body's centre, is
# not the middle sphere, nor the middle of any two
CHIP_L = np.array([[0.0, 0.0, 0.0, R_S], [PITCH, 0.0, 0.0, R_S], [0.0, PITCH, 0.0, R_S]])


@pytest.mark.parametrize("tilt_deg, depth", [
    # turned by a about x, a sphere at y (from the centre, mean y = PITCH / 3) is y sin(a) up: at
    # +30 degrees the two at y = -PITCH / 3 are lowest, at -30 the one at y = 2 PITCH / 3
    (30.0, R_S + PITCH / 3 * 0.5),
    (-30.0, R_S + 2 * PITCH / 3 * 0.5),
])
def test_an_l_shaped_chip_falls_onto_the_plate_from_its_lowest_sphere(tmp_path, tilt_deg, depth):
    # Dropped from rest with its lowest point h0 = 10 um above a still plate, the chip lands at
    # sqrt(2 h0 / g) and rests; its force is not recorded (a body), so contact is the gap.
    h0 = 1e-5
    t_land = math.sqrt(2 * h0 / G)
    a = math.radians(tilt_deg) / 2
    q = [math.cos(a), math.sin(a), 0.0, 0.0]
    times = np.arange(20) * 1e-4
    gaps = np.where(times < t_land, h0 - G / 2 * times ** 2, 0.0)
    frames = []
    for k, t in enumerate(times):
        p = parts([1], [[0.0, 0.0, depth + gaps[k]]], radius=enclosing_radius(CHIP_L), mass=M,
                  velocity=[[0, 0, -G * t if t < t_land else 0.0]])
        p["force"] = np.full((1, 3), np.nan)
        p["orientation"] = np.array([q])
        frames.append((k, float(t), p))
    variables = {"freq": ("100", "Hz", "f", "100"), "incline": ("0", "deg", "i", "0")}
    with Result(write_bulk_result(tmp_path / "l.h5", frames, variables=variables, body_template=CHIP_L)) as r:
        res = Flights(r).run().results
    assert res.gap == pytest.approx(gaps, abs=1e-12)               # m
    assert res.landings == pytest.approx([t_land], abs=1e-9)       # s
    assert len(res.takeoffs) == 0


# -- frames too far apart for the surface's motion -----------------------------------------
def plate_file(path, times, zs, vs, freq, part_z=1e-3):
    """A part hanging still part_z above the plane over a surface recorded at the given frames."""
    frames = [(k, float(t), parts([1], [[0.0, 0.0, part_z + R]], radius=R, mass=M, force=[[0, 0, -M * G]]))
              for k, t in enumerate(times)]
    surface = [([0.0, 0.0, z], [0.0, 0.0, v]) for z, v in zip(zs, vs)]
    variables = {"freq": (repr(float(freq)), "Hz", "f", "50"), "incline": ("0", "deg", "i", "0")}
    return Result(write_result(path, frames, surface=surface, variables=variables))


def test_a_still_floor_is_followed_at_any_frame_spacing(tmp_path):
    # the bouncing ball, its floor still, frames 5 ms apart at a 50 Hz deck (a quarter period,
    # twice the limit for a moving surface): the impacts between frames are found all the same
    r, times, hits = bouncing_file(tmp_path, dt=5e-3, n=3)
    with r:
        res = Flights(r).run().results
    t_hit = np.array([h[0] for h in hits if h[0] < times[-1]])
    assert len(t_hit) == 2 and res.landings == pytest.approx(t_hit, abs=1e-9)   # s


def test_frames_at_the_plates_turning_points_are_refused(tmp_path):
    # frames half a period apart catch the plate at its top and bottom, standing still there
    # (velocity 0 at every frame): it moves between them all the same
    amp, freq = 5e-5, 100.0
    times = np.arange(6) * 0.5 / freq
    with plate_file(tmp_path / "t.h5", times, amp * (-1.0) ** np.arange(6), np.zeros(6), freq) as r, \
            pytest.raises(InputError, match=r"output_dt <= 0\.00125 s"):
        Flights(r).run()


def test_frames_too_far_apart_for_a_slow_plate_are_refused(tmp_path):
    # a 0.5 Hz shaker (period 2 s) recorded every 0.5 s: a quarter period, twice the limit
    freq, amp = 0.5, 1e-3
    times = np.arange(6) * 0.5
    w = 2 * math.pi * freq
    zs, vs = amp * np.sin(w * times), amp * w * np.cos(w * times)
    with plate_file(tmp_path / "s.h5", times, zs, vs, freq) as r, \
            pytest.raises(InputError, match=r"output_dt <= 0\.25 s"):
        Flights(r).run()


def test_a_part_seen_in_one_frame_over_a_moving_plate_has_no_flights(tmp_path):
    # one frame has no spacing to refuse
    with plate_file(tmp_path / "o.h5", [0.0], [0.0], [0.03], 100.0) as r:
        res = Flights(r).run().results
    assert res.n_hops == 0 and len(res.landings) == 0 and res.airborne_fraction == 0.0
    assert res.max_gap == pytest.approx(1e-3, abs=1e-15)   # m


@pytest.mark.parametrize("freq, times, msg", [
    # 120 Hz (period 1000 / 120 = 8.33 ms) recorded every 2 ms: eight frames a period need
    # output_dt <= 0.125 / 120 = 0.00104 s
    (120.0, np.arange(6) * 2e-3,
     "flights: frames 2 ms apart cannot follow a surface vibrating at 120 Hz (period 8.33 ms): "
     "the events between frames need at least 8 frames per period (output_dt <= 0.00104 s)"),
    # two frames 8 ms apart over a 50 Hz plate (period 20 ms; output_dt <= 0.125 / 50 =
    # 0.0025 s): one interval is a spacing to refuse, given to three digits (8 ms, not 7.99)
    (50.0, np.array([0.0, 8e-3]),
     "flights: frames 8 ms apart cannot follow a surface vibrating at 50 Hz (period 20 ms): "
     "the events between frames need at least 8 frames per period (output_dt <= 0.0025 s)"),
])
def test_the_refusal_says_the_spacing_the_period_and_the_frames_needed(tmp_path, freq, times, msg):
    amp, w = 2e-5, 2 * math.pi * freq
    zs, vs = amp * np.sin(w * times), amp * w * np.cos(w * times)
    with plate_file(tmp_path / "m.h5", times, zs, vs, freq) as r, \
            pytest.raises(InputError, match=re.escape(msg)):
        Flights(r).run()


def test_a_part_that_drifts_off_a_vertical_track_is_airborne(tmp_path):
    # Issue 36 (-p incline=-90): gravity along the track, none into it. The recorded force (0
    # here) plus the part's weight into the surface, m g cos(-90 deg) = m g 6e-17, leaves a
    # push of rounding size: no contact. The part leaves the plate at t = 0 at 0.1 m/s and
    # drifts 5 mm off it in 0.05 s: in flight from 0 to the end, never landing.
    dt, v = 1e-3, 0.1
    times = np.arange(0, 0.05 + dt / 2, dt)
    frames = [(k, float(t), parts([3], [[0.0, 0.0, R + v * t]], radius=R, mass=M, velocity=[[0, 0, v]]))
              for k, t in enumerate(times)]
    variables = {"freq": ("50", "Hz", "f", "50"), "incline": ("-90", "deg", "i", "0")}
    with Result(write_result(tmp_path / "v.h5", frames, variables=variables)) as r:
        assert normal_contact_force(r, 3)[1:] == pytest.approx(M * G * math.cos(math.radians(-90)),
                                                               rel=1e-3)   # N: > 0, by rounding
        res = Flights(r).run().results
    assert res.takeoffs == pytest.approx([0.0], abs=1e-12) and len(res.landings) == 0
    assert res.n_hops == 0 and not res.airborne_at_start
    assert res.in_flight_at_end == pytest.approx(0.0, abs=1e-12)
    assert res.airborne_fraction == pytest.approx(1.0, abs=1e-9)
    assert res.max_gap == pytest.approx(v * times[-1], rel=1e-9)  # m: 5 mm
