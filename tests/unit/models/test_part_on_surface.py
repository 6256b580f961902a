"""Event-driven single-part model: events against closed forms, invariants, sub-hopping."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from vibrofeed.models.constants import G
from vibrofeed.models.part_on_surface import PartOnSurface, PartParams, mean_velocity, simulate
from vibrofeed.models.subhopping import FIGURE8, normalised_speed, square_wave_speed
from vibrofeed.models.surface import SineWaveform, SquareWaveAccel, StickSlipWaveform

F = 50.0
W = 2 * math.pi * F


def _normal_phase(t, wf):
    return (W * t + math.radians(wf.phase)) % (2 * math.pi)


@pytest.mark.parametrize("gamma, gamma_t, phase, incline, mu", [
    (1.3, 0.0, 0.0, 0.0, 0.5),
    (2.0, 0.0, 0.0, 0.0, 0.5),
    (3.1, 1.5, 40.0, 0.0, 0.3),       # tangential motion and slip do not move the launch
    (2.5, 1.0, 120.0, 8.0, 0.6),      # incline: launch at asin(cos(beta) / Gamma)
])
def test_launch_phase_is_asin_inverse_gamma(gamma, gamma_t, phase, incline, mu):
    wf = SineWaveform.from_gamma(F, gamma, gamma_t, phase, G)
    tr = simulate(wf, PartParams(mu, mu), n_periods=6, incline=incline)
    launches = tr.events_of("launch")
    assert len(launches) >= 3
    expected = math.asin(math.cos(math.radians(incline)) / gamma)
    checked = 0
    for ev in launches:
        if ev.t < 1e-12:
            continue
        # launches from rest happen at theta_l; a relaunch after impact happens at the impact
        prev = [e for e in tr.events if e.t < ev.t and e.kind in ("stick", "slip", "impact")]
        if prev and prev[-1].kind != "impact":
            assert _normal_phase(ev.t, wf) == pytest.approx(expected, abs=1e-10)
            checked += 1
    assert checked >= 3


def _landing_closed_form(gamma, th_l):
    """First root of the (corrected) parabola minus sine, by a fine scan and brentq."""
    def h(th):
        d = th - th_l
        return math.sin(th_l) + d * math.cos(th_l) - d * d / (2 * gamma) - math.sin(th)
    grid = th_l + np.linspace(1e-3, 8 * math.pi, 200001)
    vals = np.array([h(x) for x in grid])
    k = np.nonzero(vals < 0)[0][0]
    return brentq(h, grid[k - 1], grid[k], xtol=1e-15)


@pytest.mark.parametrize("gamma", [1.5, 2.0, 2.7, 4.0, 7.0])
def test_flight_duration_and_landing_against_parabola_sine_intersection(gamma):
    wf = SineWaveform.from_gamma(F, gamma, 0.0, 0.0, G)
    m = PartOnSurface(wf, PartParams(0.5, 0.5)).start(0.0)
    m.run(10 / F, stop_on=("impact",))
    launch = [e for e in m.events if e.kind == "launch"][0]
    impact = [e for e in m.events if e.kind == "impact"][0]
    th_l = math.asin(1 / gamma)
    th_i = _landing_closed_form(gamma, th_l)
    assert W * launch.t == pytest.approx(th_l, abs=1e-11)
    assert W * impact.t == pytest.approx(th_i, abs=1e-9)
    # landing velocities: part = cos(th_l) - (th_i - th_l)/gamma, surface = cos(th_i) (units amp w)
    amp = wf.amp_n
    w_rel = (math.cos(th_l) - (th_i - th_l) / gamma - math.cos(th_i)) * amp * W
    assert impact.info["w"] == pytest.approx(w_rel, rel=1e-8)


def test_energy_and_momentum_conserved_in_flight():
    wf = SineWaveform.from_gamma(F, 3.0, 2.0, 30.0, G)
    beta = 5.0
    tr = simulate(wf, PartParams(0.4, 0.3, e=0.2), n_periods=4, incline=beta, samples_per_period=400)
    gt, gn = G * math.sin(math.radians(beta)), G * math.cos(math.radians(beta))
    fl = tr.phase == "flight"
    assert fl.sum() > 100
    # identify individual flights between events and check each one
    ev_t = np.array([e.t for e in tr.events])
    seg = np.searchsorted(ev_t, tr.t, side="right")
    for s in np.unique(seg[fl]):
        sel = fl & (seg == s)
        if sel.sum() < 5:
            continue
        energy = 0.5 * (tr.vx[sel] ** 2 + tr.vz[sel] ** 2) + gt * tr.x[sel] + gn * tr.z[sel]
        assert np.ptp(energy) <= 1e-12 * (np.max(tr.vx[sel] ** 2 + tr.vz[sel] ** 2) + 1e-300) + 1e-18
        # momentum along the slope changes only by gravity: vx + gt t constant
        assert np.ptp(tr.vx[sel] + gt * tr.t[sel]) < 1e-14
        assert np.all(tr.z[sel] >= tr.zs[sel] - 1e-15)   # never below the surface


def test_pure_sticking_inside_friction_cone():
    """|a_t| <= mu_s (g + a_n) at all times: the part moves rigidly with the surface."""
    gamma_t, gamma_n, mu = 0.2, 0.5, 0.75
    assert gamma_t < mu * (1 - gamma_n)
    wf = SineWaveform.from_gamma(F, gamma_n, gamma_t, 37.0, G)
    tr = simulate(wf, PartParams(mu, 0.5 * mu), n_periods=5)
    assert {e.kind for e in tr.events} == {"stick"}
    assert np.all(tr.phase == "stick")
    np.testing.assert_allclose(tr.x - tr.xs, 0.0, atol=1e-18)
    np.testing.assert_allclose(tr.vx - tr.vxs, 0.0, atol=1e-18)


def test_symmetric_inplane_sine_gives_zero_net_speed():
    wf = SineWaveform.from_gamma(F, 0.0, 1.0, 0.0, G)        # slips: 1.0 > mu
    part = PartParams(0.5, 0.4)
    tr = simulate(wf, part, n_periods=4)
    assert tr.events_of("slip")
    ss = mean_velocity(wf, part)
    assert ss.converged
    assert abs(ss.velocity) < 1e-9 * wf.amp_t * W


def test_stick_slip_transitions_respect_the_friction_cone():
    wf = SineWaveform.from_gamma(F, 0.6, 0.9, 60.0, G)
    part = PartParams(0.6, 0.35)
    tr = simulate(wf, part, n_periods=6, incline=3.0, samples_per_period=300)
    gt, gn = G * math.sin(math.radians(3.0)), G * math.cos(math.radians(3.0))
    assert tr.events_of("stick") and tr.events_of("slip")
    for ev in tr.events_of("stick"):
        ax, az = wf.acceleration(ev.t)
        assert abs(ax + gt) <= part.mu_s * (gn + az) * (1 + 1e-12)
        assert ev.vx == pytest.approx(wf.velocity(ev.t)[0], abs=1e-15)
    stick = tr.phase == "stick"
    np.testing.assert_allclose(tr.vx[stick], tr.vxs[stick], rtol=0, atol=1e-15)
    # slip samples: the relative velocity keeps the sign given by the slip event
    slips = tr.events_of("slip")
    for ev in slips:
        t_next = min([e.t for e in tr.events if e.t > ev.t] + [tr.t[-1]])
        sel = (tr.t > ev.t + 1e-6 / F) & (tr.t < t_next - 1e-6 / F)
        u = tr.vx[sel] - tr.vxs[sel]
        assert np.all(np.sign(u) == ev.info["direction"])


def test_impact_tangential_impulse_is_impulsive_coulomb():
    wf = SineWaveform(F, 0.0, 0.0)                 # still surface
    mu = 0.3
    for vx, expect in ((0.03, 0.0), (0.5, None)):      # mu |w| = 0.042 m/s
        m = PartOnSurface(wf, PartParams(mu, mu, e=0.0)).start(0.0, z=1e-3, vx=vx, vz=0.0)
        m.run(0.1, stop_on=("impact",))
        imp = [e for e in m.events if e.kind == "impact"][0]
        w = imp.info["w"]
        assert w == pytest.approx(-math.sqrt(2 * G * 1e-3), rel=1e-12)
        if expect is not None:                     # |u| <= mu |w|: relative motion stopped
            assert imp.vx == 0.0
        else:                                      # reduced by mu * normal impulse
            assert imp.vx == pytest.approx(vx + mu * w, rel=1e-12)


def test_chattering_ends_at_geometric_series_sum():
    """Drop on a still surface: rest time = t1 + 2 e v1 / (g (1 - e)), finitely many impacts."""
    wf = SineWaveform(10.0, 0.0, 0.0)
    h0 = 0.01
    for e in (0.3, 0.5, 0.8):
        m = PartOnSurface(wf, PartParams(0.5, 0.5, e=e), chatter_tol=1e-6).start(0.0, z=h0)
        m.run(3.0)
        t1 = math.sqrt(2 * h0 / G)
        t_rest = t1 + 2 * e * (G * t1) / (G * (1 - e))
        rest = [ev for ev in m.events if ev.kind == "rest"]
        assert len(rest) == 1
        assert rest[0].t == pytest.approx(t_rest, rel=1e-12)
        impacts = [ev for ev in m.events if ev.kind == "impact"]
        # explicit bounces until the remaining series is shorter than chatter_tol periods
        n_expected = math.ceil(math.log(1e-6 * 0.1 * G * (1 - e) / (2 * e * G * t1)) / math.log(e)) + 1
        assert abs(len(impacts) - n_expected) <= 1
        # rebound speeds form the geometric sequence e^k v1
        ws = np.array([-ev.info["w"] for ev in impacts])
        np.testing.assert_allclose(ws[1:] / ws[:-1], e, rtol=1e-6)
        assert m.mode == "stick" and m.z == 0.0


# ------------------------------------------------------------------ sub-hopping
def test_square_wave_subhopping_matches_closed_form():
    acc_t, acc_n, mu_s, mu_k = 0.8 * G, 0.5 * G, 0.75, 0.6
    wf = SquareWaveAccel(F, acc_t, acc_n, 0.0)
    ss = mean_velocity(wf, PartParams(mu_s, mu_k))
    assert ss.converged
    assert ss.velocity == pytest.approx(square_wave_speed(F, acc_t, acc_n, mu_s, mu_k), rel=1e-9)


def test_subhopping_figure8_phase_and_incline():
    gt, gn, mu = FIGURE8["gamma_t"], FIGURE8["gamma_n"], FIGURE8["mu"]
    v0 = normalised_speed(gt, gn, 0.0, mu)
    assert v0 > 0.1                                      # report Fig. 8: net forward motion
    # mirror symmetry x -> -x on a flat track: phase + 180 reverses the motion exactly
    for ph in (0.0, 45.0, 90.0):
        mirrored = normalised_speed(gt, gn, ph + 180.0, mu)
        assert mirrored == pytest.approx(-normalised_speed(gt, gn, ph, mu), abs=1e-9)
    # uphill conveying is slower, downhill faster, monotonically
    v_inc = [normalised_speed(gt, gn, 0.0, mu, incline=b) for b in (-6.0, -3.0, 0.0, 3.0, 6.0)]
    assert np.all(np.diff(v_inc) < 0)
    # without normal vibration the sine is symmetric: no transport; speed grows as Gamma_n -> 1
    v_gn = [normalised_speed(gt, g_n, 0.0, mu) for g_n in (0.0, 0.3, 0.6, 0.9, 0.99)]
    assert abs(v_gn[0]) < 1e-9 and np.all(np.diff(v_gn) > 0)


# ------------------------------------------------------- parameters and defaults
def test_part_params_accept_their_closed_bounds_and_refuse_beyond():
    # 0 <= mu_k <= mu_s, 0 <= e < 1, mass > 0: each limit itself is allowed
    assert PartParams(0.5, 0.0).mu_k == 0.0            # frictionless sliding, static friction kept
    assert PartParams(0.0, 0.0).mu_s == 0.0
    assert PartParams(0.5, 0.5, e=0.0).e == 0.0
    assert PartParams(0.5, 0.4).mass == 1.0            # default: 1 kg
    for kw in (dict(mu_s=0.5, mu_k=-1e-12), dict(mu_s=0.5, mu_k=0.5 + 1e-12),
               dict(mu_s=0.5, mu_k=0.4, e=1.0), dict(mu_s=0.5, mu_k=0.4, e=-1e-12),
               dict(mu_s=0.5, mu_k=0.4, mass=0.0)):
        with pytest.raises(ValueError):
            PartParams(**kw)


def test_simulate_defaults_to_ten_periods_of_a_hundred_samples():
    wf = SineWaveform(F, 0.0, 0.0)
    tr = simulate(wf, PartParams(0.5, 0.5))
    assert tr.t[0] == 0.0 and tr.t[-1] == pytest.approx(10 / F, rel=1e-15)
    assert len(tr.t) == 1001                            # the start's stick event is a grid time


def test_mean_velocity_stops_at_two_blocks_equal_within_a_zero_tolerance():
    """Convergence is change <= tol: on a still surface two blocks are exactly 0 m/s, so even
    tol = 0 (rtol = atol = 0) is met after the second block."""
    ss = mean_velocity(SineWaveform(F, 0.0, 0.0), PartParams(0.5, 0.5), rtol=0.0, atol=0.0)
    assert ss.block_velocities == [0.0, 0.0]
    assert ss.converged and ss.change == 0.0 and ss.velocity == 0.0
    assert ss.n_periods == 20 + 2 * 24                  # default transient and block length


def test_mean_velocity_gives_up_after_twenty_blocks_of_an_accelerating_part():
    """A part sliding down an incline steeper than its friction angle on a still surface never
    converges: x = -a t^2 / 2, a = g (sin b - mu_k cos b), so the mean over the block
    [t_a, t_b] is -a (t_a + t_b) / 2 and consecutive blocks differ by a * 24 T."""
    beta, mu = 20.0, 0.3                                 # tan(20 deg) = 0.36 > mu
    a = G * (math.sin(math.radians(beta)) - mu * math.cos(math.radians(beta)))
    T = 1 / F
    ss = mean_velocity(SineWaveform(F, 0.0, 0.0), PartParams(mu, mu), incline=beta)
    assert not ss.converged
    assert len(ss.block_velocities) == 20 and ss.n_periods == 20 + 20 * 24
    t_a = (20 + 24 * np.arange(20)) * T
    np.testing.assert_allclose(ss.block_velocities, -0.5 * a * (2 * t_a + 24 * T), rtol=1e-10)
    assert ss.change == pytest.approx(a * 24 * T, rel=1e-8)
    assert ss.velocity == pytest.approx(-0.5 * a * (t_a[-1] + t_a[-2] + 24 * T), rel=1e-10)


# ------------------------------------------------------------ stick -> slip
@pytest.mark.parametrize("incline, direction", [(11.5, -1), (-11.5, +1)])
def test_first_slip_on_an_incline_leaves_the_cone_on_the_side_gravity_shifts_it_to(incline, direction):
    """a_x = -A sin(w t) with A = 0.6 g, mu_s = 0.5, |beta| = 11.5 deg: mu_s g cos b - g |sin b|
    = 0.291 g < A < mu_s g cos b + g |sin b| = 0.689 g, so only one edge of the cone
    -mu_s n <= a_x + g sin b <= mu_s n is reached. Uphill the part lags once
    a_x = mu_s g cos b - g sin b (w t = pi + asin(...)); downhill it leads once
    a_x = -mu_s g cos b - g sin b (w t = asin(...))."""
    A, mu_s = 0.6, 0.5                                  # in g
    b = math.radians(incline)
    wf = SineWaveform.from_gamma(F, 0.0, A, 0.0, G)
    m = PartOnSurface(wf, PartParams(mu_s, 0.4), incline=incline).start(0.0)
    m.run(1 / F, stop_on=("slip",))
    slip = [ev for ev in m.events if ev.kind == "slip"][0]
    k = (mu_s * math.cos(b) - abs(math.sin(b))) / A
    wt = math.pi + math.asin(k) if direction < 0 else math.asin(k)
    assert slip.info["direction"] == direction
    assert W * slip.t == pytest.approx(wt, abs=1e-10)


# ------------------------------------------------------------------- impacts
def test_impact_reports_the_normal_impulse_times_the_mass():
    wf = SineWaveform(F, 0.0, 0.0)
    h0, e = 1e-3, 0.4
    v1 = math.sqrt(2 * G * h0)
    for part, mass in ((PartParams(0.3, 0.3, e=e), 1.0), (PartParams(0.3, 0.3, e=e, mass=2.5), 2.5)):
        m = PartOnSurface(wf, part).start(0.0, z=h0)
        m.run(1.0, stop_on=("impact",))
        imp = [ev for ev in m.events if ev.kind == "impact"][0]
        assert imp.info["impulse_n"] == pytest.approx((1 + e) * v1 * mass, rel=1e-12)


def test_unresolvable_last_bounce_is_a_plain_landing():
    """Without summation (chatter_tol = 0) the bounces go on until a flight is shorter than the
    merge gap (1e-10 T): that last 'impact' finds the part a rounding-level bit above and
    rising, and lands it without a rebound. No impact reports a separating normal velocity
    (w > 0) or a pulling impulse; the part rests where the geometric series ends."""
    wf = SineWaveform(10.0, 0.0, 0.0)
    h0, e = 0.01, 0.5
    m = PartOnSurface(wf, PartParams(0.5, 0.5, e=e), chatter_tol=0.0).start(0.0, z=h0)
    m.run(0.3)
    impacts = [ev for ev in m.events if ev.kind == "impact"]
    assert not any(ev.kind == "rest" for ev in m.events)
    assert len(impacts) > 20
    assert all(ev.info["w"] <= 0.0 and ev.info["impulse_n"] >= 0.0 for ev in impacts)
    assert not impacts[-1].info["rebound"]
    t1 = math.sqrt(2 * h0 / G)
    assert impacts[-1].t == pytest.approx(t1 + 2 * e * t1 / (1 - e), abs=1e-9 * wf.period)
    assert m.mode == "stick" and m.z == 0.0


@pytest.mark.parametrize("chatter_tol", [1.0, 1e-6])
def test_chattering_friction_takes_the_whole_geometric_series_of_impulses(chatter_tol):
    """Drop at vx0 on a still surface: the impacts' normal impulses per unit mass are
    (1 + e) v1 e^k, in all (1 + e) v1 / (1 - e); each takes mu_k times its impulse off the
    sliding speed. chatter_tol = 1 period sums the series from the first impact on
    (2 e v1 / (g (1 - e)) = 0.09 s < 0.1 s), 1e-6 after explicit bounces: the same result."""
    wf = SineWaveform(10.0, 0.0, 0.0)
    h0, e, mu, mass = 0.01, 0.5, 0.3, 2.0
    v1 = math.sqrt(2 * G * h0)
    loss = mu * (1 + e) * v1 / (1 - e)                  # 0.40 m/s
    for vx0 in (0.6, 0.3):                              # slides on / stopped by the summed tail
        m = PartOnSurface(wf, PartParams(mu, mu, e=e, mass=mass), chatter_tol=chatter_tol)
        m.start(0.0, z=h0, vx=vx0)
        m.run(0.5, stop_on=("rest",))
        rest = [ev for ev in m.events if ev.kind == "rest"][0]
        assert rest.vx == pytest.approx(max(vx0 - loss, 0.0), rel=1e-12, abs=1e-15)
        if chatter_tol == 1.0:                          # summed from the first impact
            assert sum(ev.kind == "impact" for ev in m.events) == 1
            w_in = e * v1
            assert rest.info["summed_impulse_n"] == pytest.approx(
                (1 + e) * w_in / (1 - e) * mass, rel=1e-12)
        if vx0 < loss:                                  # stopped: rests and sticks in place
            m.run(1.0)
            assert m.events[-1].kind == "stick" and m.events[-1].t == rest.t
            assert m.x == rest.x and m.vx == 0.0


@pytest.mark.parametrize("before", [1.5e-12, 0.027])
def test_chatter_summation_never_spans_a_breakpoint(before):
    """Drop on a stick-slip (in-plane) waveform of period 1 s whose stroke reverses at t_b,
    before the rest time t_r = t1 + 2 e t1 / (1 - e) of the bounce series. The series is only
    summed from an impact after t_b, also when t_b is 1.5e-12 periods before t_r (beyond the
    1e-12-period tolerance by which breakpoints are told apart from the end), or 0.027 s
    before it (between the 2nd and 3rd impacts, 0.045 and 0.023 s before t_r)."""
    h0, e = 0.01, 0.5
    t1 = math.sqrt(2 * h0 / G)
    t_r = t1 + 2 * e * t1 / (1 - e)
    t_b = t_r - before
    a_f = 1.0
    wf = StickSlipWaveform(1.0, a_f, a_f * t_b / (1.0 - t_b))   # forward stroke lasts t_b
    assert wf.breakpoints(0.0, 0.9) == pytest.approx([t_b], abs=1e-15)
    m = PartOnSurface(wf, PartParams(0.5, 0.3, e=e), chatter_tol=1.0).start(0.0, z=h0)
    m.run(0.9)
    for ev in m.events:
        if ev.kind == "rest":
            assert not ev.t - ev.info["summed_time"] < t_b < ev.t
    assert sum(ev.kind == "impact" for ev in m.events) >= 3
    assert m.events[-1].t == pytest.approx(t_r, abs=1e-9)
    assert m.mode in ("stick", "slip") and m.z == wf.position(m.t)[1]


def test_chatter_summation_ignores_tangential_accelerations():
    """Only a loss of contact (n = 0) or a breakpoint stops the summation. Without normal
    motion n = g throughout, so the series is summed exactly at the first impact it fits
    in chatter_tol, even while the tangential acceleration A sin(w t), A = 2 g, passes -g
    inside it (at t = 13 T / 12). Dropped to land at t1 = 0.9 T with e = 1/7: the series
    lasts 2 e t1 / (1 - e) = 0.3 T <= chatter_tol = 0.5 T."""
    T = 1 / F
    wf = SineWaveform.from_gamma(F, 0.0, 2.0, 0.0, G)
    t1, e = 0.9 * T, 1 / 7
    m = PartOnSurface(wf, PartParams(0.5, 0.5, e=e), chatter_tol=0.5).start(0.0, z=0.5 * G * t1 ** 2)
    m.run(2 * T, stop_on=("rest",))
    impacts = [ev for ev in m.events if ev.kind == "impact"]
    rest = [ev for ev in m.events if ev.kind == "rest"]
    assert len(impacts) == 1 and impacts[0].t == pytest.approx(t1, abs=1e-12 * T)
    assert len(rest) == 1 and rest[0].t == pytest.approx(1.2 * T, abs=1e-12 * T)


@pytest.mark.parametrize("before_jump", [0.0, 5e-13])
def test_slip_ending_where_the_surface_drops_away_launches_with_the_surface_speed(before_jump):
    """Square wave, normal acceleration -1.5 g on (0, T/2), +1.5 g on (T/2, T): the surface
    drops away at T. A part slipping forward (u > 0) from 0.6 T, decelerated relative to the
    surface at mu_k n + a_t = mu_k 2.5 g + 0.5 g, is given u0 such that u reaches 0 at the jump
    (or 5e-13 T before it, inside the 1e-12 T by which the motion counts as past its jump).
    It leaves with zero relative velocity: vx = the surface's tangential speed v_t(T)."""
    T = 1 / F
    acc_t, acc_n, mu = 0.5 * G, 1.5 * G, 0.4
    wf = SquareWaveAccel(F, acc_t, acc_n, 0.0)
    t0, t_stop = 0.6 * T, T * (1 - before_jump)
    vx0 = wf.velocity(t0)[0] + (mu * (G + acc_n) + acc_t) * (t_stop - t0)
    m = PartOnSurface(wf, PartParams(mu, mu)).start(t0, vx=vx0)
    m.run(1.5 * T, stop_on=("launch",))
    launch = m.events[-1]
    assert launch.kind == "launch" and launch.t == pytest.approx(T, abs=1e-12 * T)
    vt, vn = acc_t * T / 4, acc_n * T / 4            # triangle speeds peak at the period start
    assert launch.vx == pytest.approx(vt, rel=1e-9) and launch.vz == pytest.approx(vn, rel=1e-9)
