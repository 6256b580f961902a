"""Post-processing on small hand-computed trajectories."""

import numpy as np
import pytest

from vibrofeed.postproc.flights import Flights
from vibrofeed.postproc.transport import Transport
from vibrofeed.results.reader import Result

from helpers import parts, write_result

G = 9.81
R = 5e-4


def one_part_run(tmp_path, times, z, x=None, surface_z=None, freq="50"):
    x = np.zeros_like(times) if x is None else x
    sz = np.zeros_like(times) if surface_z is None else surface_z
    frames = [(k, t, parts([1], [[x[k], 0.0, z[k]]], radius=R)) for k, t in enumerate(times)]
    surface = [([0, 0, sz[k]], [0, 0, 0]) for k in range(len(times))]
    variables = {"freq": (freq, "Hz", "f", freq)}
    return Result(write_result(tmp_path / "one.h5", frames, surface, variables))


def test_one_hop_from_a_still_surface(tmp_path):
    # Part resting, then launched at t0 with v0, landing at t0 + 2 v0 / g.
    t0, v0, dt = 0.02, 0.049, 1e-4  # launch on a frame: no kink between frames
    times = np.arange(0, 0.05, dt)
    s = times - t0
    # The flight parabola continues one frame below the surface, as a contact's
    # overlap does, then the part rests.
    z = R + np.where((s > 0) & (s < 2 * v0 / G + dt), v0 * s - G / 2 * s ** 2, 0.0)
    with one_part_run(tmp_path, times, z) as r:
        fl = Flights().compute(r)
    t_land = t0 + 2 * v0 / G
    # Linear interpolation of a parabola between frames: time error <= g dt^2 / (8 v).
    assert fl.n_hops == 1
    assert fl.landings[0] == pytest.approx(t_land, abs=G * dt ** 2 / (8 * v0))
    # The take-off is where the gap rises through the tolerance: s = tol / v0 to first order.
    assert fl.takeoffs[0] == pytest.approx(t0 + fl.tolerance / v0, abs=G * dt ** 2 / (8 * v0) + 1e-7)
    assert fl.durations[0] == pytest.approx(t_land - (t0 + fl.tolerance / v0),
                                            abs=2 * (G * dt ** 2 / (8 * v0) + 1e-7))
    assert fl.max_gap == pytest.approx(v0 ** 2 / (2 * G), rel=1e-3)
    assert fl.airborne_fraction == pytest.approx((2 * v0 / G) / 0.05, abs=2 * dt / 0.05)


def test_no_hops_when_resting_on_a_moving_surface(tmp_path):
    times = np.arange(0, 0.04, 1e-4)
    sz = 1e-4 * np.sin(2 * np.pi * 50 * times)
    with one_part_run(tmp_path, times, R + sz - 1e-8, surface_z=sz) as r:
        fl = Flights().compute(r)
    assert fl.n_hops == 0 and fl.airborne_fraction == 0.0 and fl.max_gap == pytest.approx(-1e-8)


def test_transport_over_whole_periods_removes_the_oscillation(tmp_path):
    v, a, w = 0.01, 1e-3, 2 * np.pi * 50
    times = np.arange(0, 0.1 + 1e-12, 1e-4)
    x = v * times + a * np.sin(w * times)
    with one_part_run(tmp_path, times, np.full_like(times, R), x=x) as r:
        tr = Transport(start=0.013).compute(r)
        # a window of whole periods: the sine term cancels exactly
        assert (tr.window[1] - tr.window[0]) * 50 == pytest.approx(round((tr.window[1] - tr.window[0]) * 50))
        assert tr.mean_velocity == pytest.approx(v, rel=1e-9)
        # a naive window of 0.013..0.2 s would be off by a sin term
        naive = (x[-1] - x[130]) / (times[-1] - times[130])
        assert abs(naive - v) > 1e-3


def test_transport_needs_a_window(tmp_path):
    times = np.arange(0, 0.01, 1e-4)
    with one_part_run(tmp_path, times, np.full_like(times, R)) as r:
        with pytest.raises(ValueError, match="no time window"):
            Transport(start=1.0).compute(r)
