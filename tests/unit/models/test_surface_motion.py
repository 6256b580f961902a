"""Surface motions: kinematic consistency, periodicity, breakpoints, exact level crossings, pieces."""

import math

import numpy as np
import pytest

from vibrofeed.models.constants import G
from vibrofeed.models.surface import (
    CoulombPumpWaveform,
    PiecewiseConstantAccel,
    SampledWaveform,
    SineWaveform,
    SquareWaveAccel,
    StickSlipWaveform,
    SurfaceMotion,
    sine_drive,
    two_level_drive,
)


def _brute_roots(wf, cx, cz, level, t0, t1, n=200001):
    ts = np.linspace(t0, t1, n)
    ax, az = wf.acceleration(ts)
    f = cx * ax + cz * az - level
    k = np.nonzero(np.sign(f[:-1]) != np.sign(f[1:]))[0]
    return ts[k] - f[k] * (ts[k + 1] - ts[k]) / (f[k + 1] - f[k])


def test_sine_conventions():
    wf = SineWaveform(50.0, 1e-4, 2e-4, phase=30.0)
    w = 2 * math.pi * 50
    t = np.linspace(0, 0.05, 7)
    x, z = wf.position(t)
    np.testing.assert_allclose(x, 1e-4 * np.sin(w * t), rtol=0, atol=1e-18)
    np.testing.assert_allclose(z, 2e-4 * np.sin(w * t + math.radians(30)), rtol=0, atol=1e-18)
    assert wf.gamma(G) == pytest.approx(2e-4 * w * w / G, rel=1e-14)
    # the normal motion leads: it peaks phase/360 of a period earlier than x
    t_peak_x, t_peak_z = 0.25 / 50, 0.25 / 50 - 30 / 360 / 50
    assert wf.position(t_peak_z)[1] == pytest.approx(2e-4, rel=1e-12)
    assert wf.position(t_peak_x)[0] == pytest.approx(1e-4, rel=1e-12)
    g2 = SineWaveform.from_gamma(30.0, 2.0, 0.5, 90.0)
    assert g2.gamma() == pytest.approx(2.0, rel=1e-14)
    assert g2.amp_t * g2.omega ** 2 / G == pytest.approx(0.5, rel=1e-14)


@pytest.mark.parametrize("wf", [
    SineWaveform(40.0, 3e-4, 1e-4, 70.0),
    SquareWaveAccel(40.0, 5.0, 3.0, 60.0),
    StickSlipWaveform(25.0, 3.0, 9.0),
    CoulombPumpWaveform(25.0, 0.03, 20.0),
])
def test_derivatives_consistent_and_periodic(wf):
    """Finite differences of displacement/velocity match velocity/acceleration; zero means."""
    T = wf.period
    t = np.linspace(0.013 * T, 2.9 * T, 50)
    h = 1e-7 * T
    (x1, z1), (x0, z0) = wf.position(t + h), wf.position(t - h)
    vx, vz = wf.velocity(t)
    scale_v = wf.max_speed()
    np.testing.assert_allclose((x1 - x0) / (2 * h), vx, rtol=0, atol=1e-6 * scale_v)
    np.testing.assert_allclose((z1 - z0) / (2 * h), vz, rtol=0, atol=1e-6 * scale_v)
    # periodicity and zero mean velocity / displacement over a period
    for k in (0, 1, 2):
        np.testing.assert_allclose(wf._call(t + T, k), wf._call(t, k),
                                   rtol=0, atol=1e-9 * (scale_v + 1e-30) * T ** (1 - k) * 10)
    ts = (np.arange(20000) + 0.5) * T / 20000
    assert abs(np.mean(wf.velocity(ts)[0])) < 1e-6 * scale_v
    assert abs(np.mean(wf.position(ts)[0])) < 1e-6 * scale_v * T


def test_piecewise_constant_continuity_and_validation():
    wf = PiecewiseConstantAccel([0.01, 0.02, 0.005], [3.0, -2.0, 2.0], [1.0, 0.0, -2.0])
    for tb in wf.breakpoints(0.0, 0.1):
        eps = 1e-11
        for k in (0, 1):   # displacement and velocity continuous at breakpoints
            np.testing.assert_allclose(wf._call(tb - eps, k), wf._call(tb + eps, k), rtol=0, atol=1e-9)
        # right-continuous acceleration at a breakpoint
        assert wf.acceleration(tb) == wf.acceleration(tb + 1e-6)
    with pytest.raises(ValueError):
        PiecewiseConstantAccel([0.01, 0.01], [1.0, -2.0])


def test_square_wave_matches_sign_of_sine():
    f, ph = 20.0, 50.0
    wf = SquareWaveAccel(f, 4.0, 2.0, ph)
    t = np.random.default_rng(0).uniform(0, 3 / f, 400)
    w = 2 * math.pi * f
    ax, az = wf.acceleration(t)
    np.testing.assert_array_equal(ax, -4.0 * np.sign(np.sin(w * t)))
    np.testing.assert_array_equal(az, -2.0 * np.sign(np.sin(w * t + math.radians(ph))))
    expected = np.sort(np.array([0, 0.5, (-ph / 360) % 1, (-ph / 360 + 0.5) % 1]) / f)
    np.testing.assert_allclose(wf.breakpoints(-1e-9, 1 / f - 1e-9), expected, rtol=0, atol=1e-15)


def test_stick_slip_and_coulomb_pump_parameters():
    f = 20.0
    ss = StickSlipWaveform.from_peak_speed(f, 0.04, 0.7)
    assert ss.durations[0] == pytest.approx(0.7 / f, rel=1e-12)
    v = ss.velocity(np.linspace(0, 1 / f, 4001))[0]
    assert v.max() == pytest.approx(0.04, rel=1e-9) and v.min() == pytest.approx(-0.04, rel=1e-9)
    assert ss.a_forward * ss.durations[0] == pytest.approx(ss.a_backward * ss.durations[1], rel=1e-12)
    cp = CoulombPumpWaveform(f, 0.05, 30.0)
    v = cp.velocity(np.linspace(0, 1 / f, 40001))[0]
    assert v.max() == pytest.approx(0.05, rel=1e-12)
    assert cp.velocity(cp.starts[2])[0] == pytest.approx(-cp.back_speed, rel=1e-12)
    assert v.min() >= -cp.back_speed * (1 + 1e-12)
    assert np.mean(np.isclose(v, 0.05, rtol=1e-12, atol=0)) == pytest.approx(cp.forward_fraction, abs=1e-3)
    with pytest.raises(ValueError):
        CoulombPumpWaveform(f, 30.0 / (4 * f) * 1.01, 30.0)


def test_sampled_spline_reproduces_sine_and_is_c2():
    f, A = 10.0, 1e-3
    n = 256
    th = np.arange(n) / n * 2 * math.pi
    wf = SampledWaveform(1 / f, A * np.sin(th), A * np.cos(th))
    ref = SineWaveform(f, A, A, 90.0)
    t = np.random.default_rng(1).uniform(0, 1 / f, 300)
    for k, tol in ((0, 1e-8), (1, 1e-6), (2, 1e-3)):    # spline errors O(h^4), O(h^3), O(h^2)
        np.testing.assert_allclose(wf._call(t, k), ref._call(t, k),
                                   atol=tol * A * (2 * math.pi * f) ** k, rtol=0)
    for tb in wf.breakpoints(0.0, 0.1)[:10]:
        np.testing.assert_allclose(wf.acceleration(tb - 1e-12), wf.acceleration(tb + 1e-12),
                                   rtol=0, atol=1e-6)


@pytest.mark.parametrize("wf", [
    SineWaveform(50.0, 1e-4, 2e-4, 30.0),
    SampledWaveform(0.1, 1e-3 * np.sin(np.linspace(0, 2 * np.pi, 12, endpoint=False)) ** 3,
                    1e-3 * np.cos(np.linspace(0, 2 * np.pi, 12, endpoint=False))),
])
def test_accel_roots_match_brute_force(wf):
    rng = np.random.default_rng(3)
    T = wf.period
    ax_m, az_m = wf.max_abs_acceleration()
    for _ in range(20):
        cx, cz = rng.normal(size=2)
        level = rng.uniform(-1, 1) * (abs(cx) * ax_m + abs(cz) * az_m)
        t0 = rng.uniform(0, T)
        pieces = np.concatenate([[t0], wf.breakpoints(t0, t0 + 2 * T), [t0 + 2 * T]])
        got = np.concatenate([wf.accel_roots(cx, cz, level, a, b) for a, b in zip(pieces[:-1], pieces[1:])])
        ref = _brute_roots(wf, cx, cz, level, t0, t0 + 2 * T)
        assert got.size == ref.size
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-8 * T)


def test_next_breakpoint():
    wf = StickSlipWaveform(10.0, 2.0, 6.0)          # edges at 0 and 0.075
    assert wf.next_breakpoint(0.0) == pytest.approx(0.075, rel=1e-12)  # s
    assert wf.next_breakpoint(0.075) == pytest.approx(0.1, rel=1e-12)
    assert wf.next_breakpoint(0.3 - 1e-16) == pytest.approx(0.375, rel=1e-12)  # rounding-level: passed
    assert math.isinf(SineWaveform(10.0, 1.0, 1.0).next_breakpoint(0.3))


@pytest.mark.parametrize("motion", [
    SineWaveform(40.0, 3e-4, 1e-4, 70.0),
    StickSlipWaveform(25.0, 3.0, 9.0),
    sine_drive(2e-4, 40.0, 0.3),
    two_level_drive(0.5 * G, 0.02, 15 * G),
])
def test_every_motion_answers_the_one_protocol(motion):
    """(x, z) from position/velocity/acceleration, and monotone along-track pieces."""
    assert isinstance(motion, SurfaceMotion)
    T = motion.period
    t = np.linspace(0.0, 2 * T, 9)
    for f in (motion.position, motion.velocity, motion.acceleration):
        x, z = f(t)
        assert x.shape == z.shape == t.shape
    P = motion.pieces(0.1 * T, 2.3 * T)
    assert P.edges[0] == 0.1 * T and P.edges[-1] == 2.3 * T and np.all(np.diff(P.edges) > 0)
    np.testing.assert_allclose(P.v, motion.velocity(P.edges)[0], rtol=1e-12, atol=1e-15)
    for b in motion.breakpoints(0.1 * T, 2.3 * T):      # a jump is always a piece edge
        assert np.min(np.abs(P.edges - b)) <= 1e-12 * T
