"""Hopping (Gamma > 1): period-one limits, period doubling, locking, phase optimisation."""

import math

import numpy as np
import pytest

from vibrofeed.models import hopping as H
from vibrofeed.models.subhopping import normalised_speed


def test_period_one_limits_closed_form_values():
    # corrected report formula sqrt(1 + n^2 pi^2); the report's numbers in its units (g = 2) are 2x these
    for n, ref in zip((1, 2, 3, 4), (3.2969, 6.3623, 9.4777, 12.6061)):
        assert H.period_one_limit(n) == pytest.approx(ref, abs=5e-5)
        report = (6.5938, 12.7245, 18.9554, 25.2122)[n - 1]
        assert 2 * H.period_one_limit(n) == pytest.approx(report, abs=1e-4)


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_period_one_limit_from_the_model(n):
    g = H.period_one_limit_numeric(n)
    assert g == pytest.approx(H.period_one_limit(n), abs=1e-6)
    # a model flight at the closed-form Gamma lasts exactly n periods and lands at the launch phase
    fl = H.first_flight(H.period_one_limit(n))
    assert fl.duration == pytest.approx(2 * math.pi * n, abs=1e-9)
    assert fl.theta0 == pytest.approx(H.launch_phase(H.period_one_limit(n)), abs=1e-12)


def test_zero_impulse_landing_at_upper_end_of_rebound_window():
    """At the upper end the part lands at pi - theta_l with the surface's velocity (no impact)."""
    lo, hi = H.rebound_window(1)
    assert lo == pytest.approx(H.period_one_limit(1), abs=1e-12)
    th = H.launch_phase(hi)
    assert hi * math.cos(th) == pytest.approx((3 * math.pi - 2 * th) / 2, abs=1e-12)
    fl = H.first_flight(hi)
    # the landing is a triple root of gap(theta): location accurate to ~eps^(1/3)
    assert fl.duration == pytest.approx(3 * math.pi - 2 * th, abs=1e-4)
    assert abs(fl.w_land) < 1e-6


@pytest.mark.parametrize("e", [0.0, 0.1, 0.3, 0.5])
def test_period_doubling_onset_from_return_map(e):
    g_pd = H.period_doubling_onset(e)
    assert g_pd == pytest.approx(H.period_doubling_closed_form(e), abs=1e-6)
    if e == 0.0:
        assert g_pd == pytest.approx(math.sqrt(4 + math.pi ** 2), abs=1e-6)
    # fixed point: flight 2 pi, lands at its take-off height; Jacobian det = e^2 (area contraction)
    th, _, J = H.period_one_orbit(0.97 * g_pd, e)
    assert np.linalg.det(J) == pytest.approx(e * e, abs=1e-6)
    assert math.cos(th) == pytest.approx(math.pi * (1 - e) / ((1 + e) * 0.97 * g_pd), abs=1e-9)


def test_e0_period_doubling_appears_just_above_sqrt_4_plus_pi2():
    g_pd = math.sqrt(4 + math.pi ** 2)
    p_below, _ = H.stroboscopic_period(0.99 * g_pd, 0.0, n_transient=400)
    p_above, _ = H.stroboscopic_period(1.01 * g_pd, 0.0, n_transient=400)
    assert p_below == 1 and p_above == 2
    # below: one jump length (one period); above: alternating long and short jumps summing to 2 periods
    below, above = H.bifurcation_diagram([0.99 * g_pd, 1.01 * g_pd], 0.0, n_periods=16,
                                         n_transient=400, sweep=False)
    assert below.size >= 10 and np.ptp(below) < 1e-9
    assert below[0] == pytest.approx(1.0, abs=1e-9)
    lengths = np.unique(np.round(above, 6))
    assert lengths.size == 2
    assert lengths.sum() == pytest.approx(2.0, abs=1e-6)


def test_locked_limit():
    assert H.locked_limit(0.0) == pytest.approx(H.period_one_limit(1), abs=1e-6)
    g1, g3 = H.locked_limit(0.1), H.locked_limit(0.3)
    # chattering takes time: the locked range shrinks markedly with e
    assert 1.0 < g3 < g1 < H.period_one_limit(1) - 0.5
    assert H.is_locked(g3 - 1e-4, 0.3) and not H.is_locked(g3 + 1e-4, 0.3)


@pytest.mark.parametrize("gamma", [1.05, 1.5, 2.5, 3.2])
def test_optimal_phase_matches_closed_form(gamma):
    """Locked period-one hop: gain(phi) = cos(phi)(tau - sin tau) + sin(phi)(1 - cos tau),
    phi = th_l - phase."""
    tau = H.first_flight(gamma).duration
    th_l = H.launch_phase(gamma)
    expected = math.degrees(th_l - math.atan2(1 - math.cos(tau), tau - math.sin(tau)))
    assert H.optimal_phase(gamma) == pytest.approx(expected, abs=1e-4)


def test_phase_optimisation_small_and_large_gamma():
    """Report 2.4 says ~90 deg at small Gamma and ~0 deg at large Gamma. The model agrees at large
    Gamma (launch at the peak tangential velocity, phase = theta_l) but at small Gamma hops are short
    and the gain is set by the surface's tangential deceleration at launch, so the optimum tends to
    theta_l - 90 deg + O(tau) -> small, not 90 deg."""
    assert abs(H.optimal_phase(3.2) - math.degrees(H.launch_phase(3.2))) < 0.1   # flight = ~1 period
    assert abs(H.optimal_phase(1.05)) < 15.0
    v = H.ideal_speed(1.05, 0.0, np.array([0.0, 90.0]))
    assert v[0] > v[1]


@pytest.mark.parametrize("gamma, gamma_t", [(1.2, 0.5), (2.0, 1.0)])
def test_full_model_tends_to_ideal_speed_at_large_friction(gamma, gamma_t):
    ideal = H.ideal_speed(gamma, 0.0, 15.0)
    v = normalised_speed(gamma_t, gamma, 15.0, 100.0, max_blocks=6)
    assert v == pytest.approx(ideal, rel=5e-3)
