"""Hopping (Gamma > 1): period-one limits, period doubling, locking, phase optimisation."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from vibrofeed.models import hopping as H
from vibrofeed.models.part_on_surface import PartOnSurface, PartParams
from vibrofeed.models.subhopping import FIGURE8, normalised_speed
from vibrofeed.models.surface import SineWaveform


def _flight_duration(th0, gamma):
    """Independent closed-form flight: leaving the surface sin(theta) at th0 with its velocity
    (e = 0), gravity 1/Gamma; first s > 0 with sin th0 + s cos th0 - s^2 / (2 Gamma) = sin(th0 + s)."""
    def gap(s):
        return np.sin(th0) + s * np.cos(th0) - s * s / (2 * gamma) - np.sin(th0 + s)

    s = np.arange(1e-3, 8 * math.pi, 1e-3)
    k = np.nonzero(gap(s) < 0)[0][0]
    assert k > 0                                     # the part did leave (Gamma sin th0 > 1)
    return brentq(gap, s[k - 1], s[k], xtol=1e-15)


def _gain(th0, tau, phase_rad):
    """Relative tangential displacement of one flight (ideal_speed's idealisation)."""
    return np.cos(th0 - phase_rad) * tau - (np.sin(th0 + tau - phase_rad) - np.sin(th0 - phase_rad))


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


# ------------------------------------------------------ survivors of the models-contact target
def test_figure8_is_the_reports_subhopping_case():
    # report Fig. 8: A = 1.6 in its units (g = 2) for both amplitudes, delta = 0, mu = 0.75
    assert 2 * FIGURE8["gamma_t"] == pytest.approx(1.6, abs=1e-12)
    assert 2 * FIGURE8["gamma_n"] == pytest.approx(1.6, abs=1e-12)
    assert FIGURE8["phase"] == 0.0 and FIGURE8["mu"] == 0.75
    # sub-hopping: Gamma_n < 1, the part never leaves the surface
    wf = SineWaveform.from_gamma(50.0, FIGURE8["gamma_n"], FIGURE8["gamma_t"], FIGURE8["phase"])
    m = PartOnSurface(wf, PartParams(FIGURE8["mu"], FIGURE8["mu"]), record=False)
    m.start(0.0).run(5 * wf.period)
    kinds = {ev.kind for ev in m.events}
    assert "slip" in kinds and "launch" not in kinds and "impact" not in kinds


def test_period_one_limit_defaults_to_one_period():
    assert H.period_one_limit() == pytest.approx(math.sqrt(1 + math.pi ** 2), abs=1e-12)


@pytest.mark.parametrize("n", [2, 3])
def test_rebound_window_for_longer_flights(n):
    """Upper end: Gamma cos th_l = ((2n+1) pi - 2 th_l) / 2, inside (Gamma_n, Gamma_{n+1})."""
    lo, hi = H.rebound_window(n)
    assert lo == pytest.approx(math.sqrt(1 + (n * math.pi) ** 2), abs=1e-12)
    assert lo < hi < math.sqrt(1 + ((n + 1) * math.pi) ** 2)
    th = math.asin(1 / hi)
    assert hi * math.cos(th) == pytest.approx(((2 * n + 1) * math.pi - 2 * th) / 2, abs=1e-11)
    # the model's flight lands there with the surface's velocity (triple root: ~eps^(1/3))
    fl = H.first_flight(hi)
    assert fl.duration == pytest.approx((2 * n + 1) * math.pi - 2 * th, abs=1e-4)
    assert abs(fl.w_land) < 1e-6


@pytest.mark.parametrize("e", [0.0, 0.3])
def test_period_two_single_impact_orbit(e):
    """n = 2: flight of two periods; cos th* = 2 pi (1-e) / ((1+e) Gamma), w* = -2 pi / Gamma - cos th*."""
    g = 0.97 * H.period_doubling_closed_form(e, 2)
    th, w, J = H.period_one_orbit(g, e, 2)
    c = 2 * math.pi * (1 - e) / ((1 + e) * g)
    assert math.cos(th) == pytest.approx(c, abs=1e-9) and math.sin(th) > 0
    assert w == pytest.approx(-2 * math.pi / g - c, abs=1e-9)
    assert np.linalg.det(J) == pytest.approx(e * e, abs=1e-6)


def test_period_doubling_of_a_seven_period_orbit():
    # the orbit exists only above 7 pi (1-e)/(1+e) = 21.55: the scan must start there, not at 1
    e = 0.01
    assert H.period_doubling_onset(e, 7) == pytest.approx(H.period_doubling_closed_form(e, 7), abs=1e-6)


def test_period_one_orbit_refuses_a_false_convergence(monkeypatch):
    """The orbit is checked on the model's map, not taken on the solver's word."""
    real = H.fsolve

    def lying(F, x0, **kw):
        sol, info, _, _ = real(F, x0, **kw)
        return sol + np.array([1e-5, 0.0]), info, 1, "converged"   # 1e-5 rad off the fixed point

    monkeypatch.setattr(H, "fsolve", lying)
    with pytest.raises(RuntimeError, match="not found"):
        H.period_one_orbit(2.0, 0.3)


def test_locked_limit_when_the_first_probe_is_already_unlocked():
    # step = 1: the first probe, Gamma = 2, is unlocked at e = 0.3, so the bisection starts
    # from the bracket (1, 2]
    assert not H.is_locked(2.0, 0.3)
    assert H.locked_limit(0.3, step=1.0) == pytest.approx(H.locked_limit(0.3), abs=1e-8)


def test_stroboscopic_period_up_to_max_period():
    # locked orbit (Gamma < sqrt(1 + pi^2), e = 0): period one at once, whatever max_period
    for max_period in (1, 3):
        assert H.stroboscopic_period(2.5, 0.0, n_transient=5, max_period=max_period)[0] == 1
    # period-two attractor (sqrt(4 + pi^2) < 3.8): not period one, found with max_period >= 2
    assert H.stroboscopic_period(3.8, 0.0, n_transient=100, max_period=1)[0] == 0
    assert H.stroboscopic_period(3.8, 0.0, n_transient=100, max_period=2)[0] == 2


@pytest.mark.parametrize("gamma", [2.0, 3.2])
def test_ideal_speed_of_the_locked_hop_is_its_gain_per_period(gamma):
    """Locked orbit (e = 0): one flight per period from theta_l; mean speed = gain / 2 pi, at the
    default phase 0. At 3.2 each flight lands after the next theta = 0 mod 2 pi, i.e. the one
    under way at the end of the averaging window started inside it and counts."""
    th = math.asin(1 / gamma)
    tau = _flight_duration(th, gamma)
    assert (th + tau > 2 * math.pi) == (gamma > 3.0)
    assert H.ideal_speed(gamma) == pytest.approx(_gain(th, tau, 0.0) / (2 * math.pi), rel=1e-9)


def test_ideal_speed_of_the_period_two_hop_is_its_cycle_mean():
    """Gamma = 3.8, e = 0: long and short jumps, each relaunched at once (Gamma sin > 1), summing to
    two periods. The default window (whole cycles) averages to the cycle's mean gain / 4 pi."""
    g = 3.8

    def two_jumps(th):
        tau1 = _flight_duration(th, g)
        return tau1 + _flight_duration(th + tau1, g) - 4 * math.pi

    # the 2-cycle's launch phase lies between theta_l and the period-one fixed point acos(pi / g)
    tha = brentq(two_jumps, math.asin(1 / g) + 1e-3, math.acos(math.pi / g) - 1e-2, xtol=1e-15)
    ta = _flight_duration(tha, g)
    tb = _flight_duration(tha + ta, g)
    assert abs(ta - tb) > 0.5                        # a genuine long/short pair
    ph = np.radians([0.0, 30.0])
    expected = (_gain(tha, ta, ph) + _gain(tha + ta, tb, ph)) / (4 * math.pi)
    np.testing.assert_allclose(H.ideal_speed(g, 0.0, np.array([0.0, 30.0])), expected, rtol=1e-8)


def test_optimal_phase_wraps_into_minus_180_to_180(monkeypatch):
    """A single flight of one period from th0 gains in proportion to cos(th0 - phase): optimum th0.
    At th0 = 179.8 deg the grid's best point is -180 and the bounded search ends below it."""
    th0 = math.radians(179.8)

    def one_flight(gamma, e, n_periods):
        return [H.Flight(th0, 2 * math.pi, 0.0, "launch")], {}, (0.0, 2 * math.pi)

    monkeypatch.setattr(H, "run_flights", one_flight)
    assert H.optimal_phase(2.0) == pytest.approx(179.8, abs=1e-4)


class Strobed:
    """A stand-in for the model seen once per period: its relative state at the k-th sample
    is ``offset(k)`` (exactly periodic where offset is, drifting where it drifts)."""

    def __init__(self, offset):
        self.offset, self.t, self.z, self.vz = offset, 0.0, 0.0, 1.0

    def start(self, t, z=None, vz=None):
        self.t = t

    def run(self, t_end):
        self.t = t_end
        k = round(t_end / (2 * math.pi))
        self.z, self.vz = math.sin(t_end) + self.offset(k), math.cos(t_end)


def test_the_attractor_repeats_to_a_tenth_of_a_micro_unit_by_default(monkeypatch):
    """A state still drifting by 5e-7 a period has no period at the default tolerance 1e-7;
    at 1e-6 it would pass for period one."""
    monkeypatch.setattr(H, "_model", lambda gamma, e: Strobed(lambda k: 5e-7 * k))
    assert H.stroboscopic_period(2.5, 0.0, n_transient=0)[0] == 0
    assert H.stroboscopic_period(2.5, 0.0, n_transient=0, tol=1e-6)[0] == 1


def test_periods_up_to_eight_are_found_by_default(monkeypatch):
    monkeypatch.setattr(H, "_model", lambda gamma, e: Strobed(lambda k: 0.1 * (k % 8)))
    assert H.stroboscopic_period(2.5, 0.0, n_transient=0)[0] == 8
    assert H.stroboscopic_period(2.5, 0.0, n_transient=0, max_period=7)[0] == 0


def test_the_bifurcation_diagram_keeps_jumps_of_min_jump_and_sweeps_up_by_default(monkeypatch):
    """Flights of exactly min_jump periods are kept, shorter ones dropped; each Gamma starts
    from the state the previous one ended in (the amplitude raised through the lower values)."""
    given = []

    def flights(gamma, e, n_periods, n_transient, state):
        given.append(state)
        durations = (0.5 * 2 * math.pi, 0.25 * 2 * math.pi)  # 0.5 and 0.25 periods, exactly
        return [H.Flight(0.0, d, 0.0, "launch") for d in durations], {"after": gamma}, (0.0, 1.0)

    monkeypatch.setattr(H, "run_flights", flights)
    out = H.bifurcation_diagram([2.0, 3.0], 0.0, min_jump=0.5)
    assert [d.tolist() for d in out] == [[0.5], [0.5]]
    assert given == [None, {"after": 2.0}]
