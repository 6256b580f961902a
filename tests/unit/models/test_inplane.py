"""In-plane waveforms: stick-slip closed form, optimal stick-slip bound, sliding (median) limit."""

import math

import numpy as np
import pytest

from vibrofeed.models.constants import G
from vibrofeed.models.inplane import (
    coulomb_pump_speed_curve,
    optimal_stick_slip_speed,
    optimal_stick_slip_waveform,
    sliding_limit_speed,
    stick_slip_closed_form,
    stick_slip_speed_curve,
)
from vibrofeed.models.part_on_surface import PartParams, mean_velocity
from vibrofeed.models.surface import (
    CoulombPumpWaveform,
    PiecewiseConstantAccel,
    SampledWaveform,
    StickSlipWaveform,
)

MU_S, MU_K = 0.6, 0.4
PART = PartParams(MU_S, MU_K)
FAST = dict(n_transient=8, n_block=4, max_blocks=4, rtol=1e-9)


def test_stick_slip_waveform_matches_closed_form():
    wf = StickSlipWaveform(20.0, 0.5 * G, 1.5 * G)
    ss = mean_velocity(wf, PART)
    assert ss.converged
    assert ss.velocity == pytest.approx(stick_slip_closed_form(wf, MU_S, MU_K), rel=1e-9)


def test_stick_slip_curve_zero_until_backward_acceleration_exceeds_static_friction():
    f, frac = 20.0, 0.75
    v_peak = np.array([0.2, 0.9, 1.3, 3.0]) * MU_S * G * (1 - frac) / (2 * f)   # a_b / (mu_s g)
    v = stick_slip_speed_curve(f, v_peak, frac, PART, **FAST)
    assert abs(v[0]) < 1e-15 * v_peak[0] and abs(v[1]) < 1e-15 * v_peak[1]   # rigid sticking
    assert 0 < v[2] < v[3] < v_peak[3]


def test_optimal_waveform_reaches_the_bound():
    a_max, f = 2 * G, 20.0
    wf = optimal_stick_slip_waveform(a_max, MU_S, MU_K, f)
    assert max(wf.max_abs_acceleration()) <= a_max
    v = mean_velocity(wf, PART, **FAST).velocity
    assert v == pytest.approx(optimal_stick_slip_speed(a_max, MU_S, MU_K, f), rel=1e-9)


def test_three_phase_family_brute_force_never_beats_the_bound():
    """Grid over (stick acceleration a1, stick duration) of +a1, -a_max, +a_max waveforms."""
    a_max, f = 2 * G, 20.0
    T = 1 / f
    v_star = optimal_stick_slip_speed(a_max, MU_S, MU_K, f)
    best, arg = -1.0, None
    for a1 in MU_S * G * np.array([0.5, 0.8, 0.95, 1.0, 1.2, 2.0, a_max / (MU_S * G)]):
        for x1 in np.linspace(0.05, 0.95, 19):
            t1 = x1 * T
            if T - t1 < a1 * t1 / a_max:
                continue
            t2 = (T - t1 + a1 * t1 / a_max) / 2
            wf = PiecewiseConstantAccel([t1, t2, T - t1 - t2], [a1, -a_max, a_max])
            v = mean_velocity(wf, PART, **FAST).velocity
            if v > best:
                best, arg = v, (a1, x1)
    assert best <= v_star * (1 + 1e-9)
    assert best == pytest.approx(v_star, rel=1e-6)        # the grid contains the optimum
    # the optimum is a grid point: equal up to linspace's rounding
    assert arg[0] == pytest.approx(MU_S * G, rel=1e-12)
    assert arg[1] == pytest.approx(MU_K / (MU_S + MU_K), rel=1e-12)


def test_random_waveforms_never_beat_the_bound():
    """General 4-piece waveforms with |a| <= a_max, including always-sliding ones."""
    a_max, f = 2 * G, 20.0
    T = 1 / f
    v_star = optimal_stick_slip_speed(a_max, MU_S, MU_K, f)
    rng = np.random.default_rng(0)
    n, worst = 0, 0.0
    while n < 60:
        a = rng.uniform(-1, 1, 3) * a_max
        d = rng.uniform(0.05, 1, 4)
        d *= T / d.sum()
        a4 = -(a @ d[:3]) / d[3]
        if abs(a4) > a_max:
            continue
        n += 1
        v = mean_velocity(PiecewiseConstantAccel(d, np.append(a, a4)), PART, **FAST).velocity
        worst = max(worst, abs(v))
    assert worst < v_star


def test_coulomb_pump_high_frequency_limit_is_median_of_surface_velocity():
    """Same velocity profile at higher frequency: the part speed tends to the median (here the
    forward speed, held for more than half the period), the error falling like 1/f."""
    v_f = 0.05
    errs = []
    for f in (80.0, 320.0):
        wf = CoulombPumpWaveform(f, v_f, 3 * G * f / 20)        # fixed shape, accelerations ~ f
        assert wf.forward_fraction > 0.5
        assert sliding_limit_speed(wf) == pytest.approx(v_f, rel=1e-9)
        errs.append(v_f - mean_velocity(wf, PART).velocity)
    assert 0 < errs[1] < errs[0] / 3.0
    assert errs[1] < 0.05 * v_f


def test_smooth_asymmetric_waveform_sliding_limit():
    """Two-harmonic in-plane motion: the high-frequency part speed tends to np.median(v_s)."""
    V = 0.05
    th = (np.arange(200000) + 0.5) / 200000 * 2 * math.pi
    median = np.median(V * (np.cos(th) + 0.5 * np.cos(2 * th + 1.0)))
    assert abs(median) > 0.2 * V                           # a genuinely non-zero median

    def wave(f, n=48):
        w, t = 2 * math.pi * f, np.arange(n) / n * 2 * math.pi
        return SampledWaveform(1 / f, V / w * (np.sin(t) + 0.25 * np.sin(2 * t + 1.0)))

    errs = []
    for f in (200.0, 800.0):
        wf = wave(f)
        lim = sliding_limit_speed(wf)
        assert lim == pytest.approx(median, abs=2e-3 * V)   # spline of 48 samples vs analytic
        v = mean_velocity(wf, PART, n_transient=10, n_block=12, max_blocks=2, initial=dict(vx=lim)).velocity
        errs.append(abs(v - lim))
    assert errs[1] < errs[0] / 2.5 and errs[1] < 0.03 * V


def test_sliding_limit_balance_on_incline():
    wf = CoulombPumpWaveform(50.0, 0.05, 40.0)
    plain = sliding_limit_speed(wf)
    beta = 2.0
    V = sliding_limit_speed(wf, mu_k=MU_K, incline=beta)
    ts = (np.arange(200000) + 0.5) * wf.period / 200000
    vs = wf.velocity(ts)[0]
    # mu_k g cos(beta) (T_above - T_below) = g sin(beta) T, up to one sample
    lhs = MU_K * math.cos(math.radians(beta)) * np.mean(np.sign(vs - V))
    assert lhs == pytest.approx(math.sin(math.radians(beta)), abs=2 * MU_K / 200000)
    assert V < plain


def test_coulomb_pump_curve_shape():
    f, acc = 20.0, 3 * G
    vmax = acc / (4 * f)
    v = coulomb_pump_speed_curve(f, vmax * np.array([0.1, 0.4, 1.0]), acc, PART,
                                 n_transient=100, n_block=4, rtol=1e-12)
    assert v[0] > 0 and v[1] > 0
    assert abs(v[2]) < 1e-9 * vmax        # symmetric triangle velocity at the limit: no transport


def test_frictionless_slip_re_sticks_exactly_at_the_end_of_the_forward_phase():
    # mu_k = 0: the part slides back at its top speed while the surface falls away and comes back, and
    # meets it again at the end of the next forward phase (t* = a_b t_b / a_f = t_f): it moves at the
    # surface's peak speed for good. Numbers exact in binary: T = 1 s, t_f = 0.75 s, t_b = 0.25 s.
    wf = StickSlipWaveform(1.0, 1.0, 3.0)
    assert list(wf.durations) == [0.75, 0.25]
    assert stick_slip_closed_form(wf, 0.2, 0.0, g=10.0) == wf.peak_speed == 0.375
