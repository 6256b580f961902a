"""Event-driven single-part model: events against closed forms, invariants, sub-hopping."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from vibrofeed.models.constants import G
from vibrofeed.models.part_on_surface import PartOnSurface, PartParams, mean_velocity, simulate
from vibrofeed.models.subhopping import FIGURE8, normalised_speed, square_wave_speed
from vibrofeed.models.surface import SineWaveform, SquareWaveAccel

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
