"""Post-processing on small hand-computed trajectories."""

import numpy as np
import pytest
from scipy.optimize import brentq

from vibrofeed.postproc.flights import Flights
from vibrofeed.postproc.transport import Transport
from vibrofeed.results.reader import Result

from helpers import parts, write_result

G = 9.81
R = 5e-4
M = 1e-6


def run_file(tmp_path, times, z, vz, fz, x=None, surface_z=None, surface_vz=None, freq="50"):
    """A one-part result; force fz is the TOTAL force (gravity included), as LIGGGHTS records it."""
    n = len(times)
    x = np.zeros(n) if x is None else x
    sz = np.zeros(n) if surface_z is None else surface_z
    svz = np.zeros(n) if surface_vz is None else surface_vz
    frames = [(k, t, parts([1], [[x[k], 0.0, z[k]]], radius=R, mass=M,
                           velocity=[[0, 0, vz[k]]], force=[[0, 0, fz[k]]]))
              for k, t in enumerate(times)]
    surface = [([0, 0, sz[k]], [0, 0, svz[k]]) for k in range(n)]
    variables = {"freq": (freq, "Hz", "f", freq), "incline": ("0", "deg", "i", "0")}
    return Result(write_result(tmp_path / "one.h5", frames, surface, variables))


def test_lift_off_and_landing_on_a_sine_plate(tmp_path):
    # Rigid model, e = 0: on the plate until its downward acceleration reaches g,
    # free flight, then back on the plate (report 2.3, with the README's corrections).
    gamma, f, dt = 1.5, 50.0, 1e-4
    w = 2 * np.pi * f
    A = gamma * G / w ** 2
    t_l = np.arcsin(1 / gamma) / w
    zl, vl = A * np.sin(w * t_l), A * w * np.cos(w * t_l)
    fly = lambda t: zl + vl * (t - t_l) - G / 2 * (t - t_l) ** 2   # noqa: E731
    t_land = brentq(lambda t: fly(t) - A * np.sin(w * t), t_l + 1e-4, t_l + 0.02)
    times = np.arange(0, t_l + 1 / f, dt)  # up to the next lift-off
    zs, vs, acc = A * np.sin(w * times), A * w * np.cos(w * times), -A * w ** 2 * np.sin(w * times)
    air = (times > t_l) & (times < t_land)
    z = np.where(air, fly(times), zs) + R
    vz = np.where(air, vl - G * (times - t_l), vs)
    fz = np.where(air, -M * G, M * acc)  # in contact the part moves with the plate
    with run_file(tmp_path, times, z, vz, fz, surface_z=zs, surface_vz=vs) as r:
        fl = Flights().compute(r)
    assert fl.kinds == ["lift-off"] and fl.n_hops == 1
    # Linear extrapolation of the contact force m (g + a_s) over one frame:
    # error <= 2 w tan(theta_l) dt^2 (its curvature over its slope).
    theta = np.arcsin(1 / gamma)
    assert fl.takeoffs[0] == pytest.approx(t_l, abs=2 * w * np.tan(theta) * dt ** 2)
    # The landing is the root of the free flight: exact up to the surface's
    # Hermite interpolation (A w^4 dt^4 / 384 in height).
    assert fl.landings[0] == pytest.approx(t_land, abs=1e-9)
    assert fl.durations[0] == pytest.approx(t_land - t_l, abs=2 * w * np.tan(theta) * dt ** 2)
    assert fl.restitution(0) == 0.0          # e = 0: no rebound
    assert fl.max_gap == pytest.approx(np.max(z - R - zs))


def test_impacts_between_frames_are_found(tmp_path):
    # A ball bouncing on a still floor with e = 0.5; every impact falls between frames.
    e, v0, dt = 0.5, 0.2, 1e-4
    bounces, t, v = [], 0.00003, v0   # launched upwards at t = 3e-5 s
    while len(bounces) < 4:
        t += 2 * v / G
        bounces.append((t, v))
        v *= e
    times = np.arange(0, bounces[-1][0] - 1e-4, dt)
    z, vz = np.empty_like(times), np.empty_like(times)
    starts = [(0.00003, v0)] + [(tb, vb * e) for tb, vb in bounces]
    for k, s in enumerate(times):
        t0, v = max((st for st in starts if st[0] <= s), default=(0.00003, v0))
        z[k], vz[k] = v * (s - t0) - G / 2 * (s - t0) ** 2, v - G * (s - t0)
    z[times < 0.00003], vz[times < 0.00003] = 0.0, 0.0
    fz = np.where(times < 0.00003, 0.0, -M * G)
    with run_file(tmp_path, times, z + R, vz, fz) as r:
        fl = Flights().compute(r)
    expected = [tb for tb, _ in bounces if tb < times[-1]]
    assert len(fl.landings) == len(expected)
    assert np.allclose(fl.landings, expected, atol=1e-9)
    assert fl.kinds[1:] == ["rebound"] * (len(fl.kinds) - 1)
    for k in range(len(expected)):
        assert fl.restitution(k) == pytest.approx(e, rel=1e-6)


def test_no_hops_when_resting_on_a_moving_surface(tmp_path):
    times = np.arange(0, 0.04, 1e-4)
    w = 2 * np.pi * 50
    a = 0.8 * G / w ** 2  # Gamma = 0.8: the plate always pushes
    sz, sv = a * np.sin(w * times), a * w * np.cos(w * times)
    fz = M * (-a * w ** 2 * np.sin(w * times))
    with run_file(tmp_path, times, R + sz - 1e-8, sv, fz, surface_z=sz, surface_vz=sv) as r:
        fl = Flights().compute(r)
    assert fl.n_hops == 0 and fl.airborne_fraction == 0.0 and len(fl.landings) == 0
    assert fl.max_gap == pytest.approx(-1e-8)


def test_transport_over_whole_periods_removes_the_oscillation(tmp_path):
    v, a, w = 0.01, 1e-3, 2 * np.pi * 50
    times = np.arange(0, 0.1 + 1e-12, 1e-4)
    x = v * times + a * np.sin(w * times)
    n = len(times)
    with run_file(tmp_path, times, np.full(n, R), np.zeros(n), np.zeros(n), x=x) as r:
        tr = Transport(start=0.013).compute(r)
        # a window of whole periods: the sine term cancels exactly
        assert (tr.window[1] - tr.window[0]) * 50 == pytest.approx(round((tr.window[1] - tr.window[0]) * 50))
        assert tr.mean_velocity == pytest.approx(v, rel=1e-9)
        # a naive window of 0.013..0.1 s would be off by a sin term
        naive = (x[-1] - x[130]) / (times[-1] - times[130])
        assert abs(naive - v) > 1e-3


def test_transport_needs_a_window(tmp_path):
    times = np.arange(0, 0.01, 1e-4)
    n = len(times)
    with run_file(tmp_path, times, np.full(n, R), np.zeros(n), np.zeros(n)) as r:
        with pytest.raises(ValueError, match="no time window"):
            Transport(start=1.0).compute(r)
