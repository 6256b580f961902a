"""Hopping of a part on a sinusoidally vibrating surface, Gamma > 1 (Khan & Sarma, §2.3.2, §2.4).

The normal motion of the part does not depend on the tangential one (friction
and the tangential impulse do not act along z), so the hopping dynamics is
the bouncing-ball problem: a surface z_s = amp_n sin(theta), theta = w t the
normal phase, and gravity g cos(beta). Everything here is in the report's
dimensionless form, with one change of scale: lengths in units of amp_n and
time in 1/w, so that gravity is 1/Gamma (the report's units, where gravity is
2, have A = 2 Gamma). Gamma = amp_n w^2 / g; on an inclined track use
Gamma / cos(beta).

All quantities are computed with the event-driven model of
`part_on_surface` (SineWaveform with w = 1, amp_n = 1, g = 1/Gamma),
so the thresholds below are properties of the same model that is compared
with DEM, not separate approximations. Closed forms are given alongside where
they exist (and are used by the tests as independent checks).

Corrections of the report (Khan & Sarma, "Vibratory Assembly Update: Part
Transportation Mechanics Analysis", §2.3 and §2.3.2):
* launch at theta_l = asin(1/Gamma) (the report's asin(g/A) in its units);
* flight h_p = sin th_l + (th - th_l) cos th_l - (th - th_l)^2 / (2 Gamma)
  (gravity with a minus sign);
* period-one limit Gamma_n = sqrt(1 + n^2 pi^2), not 1 + n^2 pi^2 (the text's
  "A(1 - sin^2)" should read "A sqrt(1 - sin^2)");
* the "rebound"/"no rebound" boundary equation, printed garbled, is solved
  here in the form Gamma cos th_l = ((2n+1) pi - 2 th_l) / 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, fsolve, minimize_scalar

from .constants import TWO_PI
from .part_on_surface import PartOnSurface, PartParams
from .surface import SineWaveform

_UNIT_WAVE = SineWaveform(1.0 / TWO_PI, 0.0, 1.0, 0.0)   # w = 1 rad/s, amp_n = 1


def _model(gamma: float, e: float, chatter_tol: float = 1e-7, record: bool = False) -> PartOnSurface:
    """Dimensionless vertical model: surface sin(theta), gravity 1/gamma."""
    return PartOnSurface(_UNIT_WAVE, PartParams(1.0, 1.0, e), 0.0, 1.0 / gamma,
                         chatter_tol=chatter_tol, record=record)


# ----------------------------------------------------------------- closed forms
def launch_phase(gamma: float) -> float:
    """Launch phase theta_l = asin(1/Gamma) [rad] of a part resting on the surface.

    The part leaves when the surface accelerates downwards faster than gravity
    (report 2.3, corrected: theta_l = asin(g/A) in the report's units).
    """
    if gamma < 1.0:
        raise ValueError("no launch for Gamma < 1")
    return math.asin(1.0 / gamma)


def period_one_limit(n: int = 1) -> float:
    """Gamma at which a flight from the locked launch lasts exactly n periods [-].

    Closed form sqrt(1 + n^2 pi^2) (report 2.3.2, corrected from g(1 + n^2 pi^2)):
    3.2969, 6.3623, 9.4777, 12.6061 for n = 1..4. For e = 0, locked period-one
    orbits exist for Gamma < period_one_limit(1).
    """
    return math.sqrt(1.0 + (n * math.pi) ** 2)


def period_doubling_closed_form(e: float = 0.0, n: int = 1) -> float:
    """Period-doubling Gamma of the single-impact period-n orbit (bouncing ball).

    At the fixed point the flight lasts 2 pi n and lands at the launch height,
    cos(theta*) = n pi (1 - e) / ((1 + e) Gamma), and the impact map's Jacobian
    (det = e^2) has eigenvalue -1 when Gamma sin(theta*) = 2 (1 + e^2)/(1 + e)^2:
    Gamma^2 = (n pi (1-e)/(1+e))^2 + (2 (1+e^2)/(1+e)^2)^2.
    For e = 0: sqrt(4 + pi^2) = 3.7242. Used as an independent check of
    `period_doubling_onset`.
    """
    a = n * math.pi * (1 - e) / (1 + e)
    b = 2 * (1 + e * e) / (1 + e) ** 2
    return math.hypot(a, b)


def rebound_window(n: int = 1) -> tuple[float, float]:
    """Gamma range (e = 0) over which flights from the locked launch land while
    the surface accelerates down faster than g, i.e. the part is relaunched at
    once instead of resting (report 2.3.2, "rebounding" solutions).

    Lower end: period_one_limit(n) (flight = 2 pi n, lands at theta_l).
    Upper end: flight = (2n+1) pi - 2 theta_l, landing at pi - theta_l with
    zero relative velocity, i.e. Gamma cos th_l = ((2n+1) pi - 2 th_l) / 2 with
    th_l = asin(1/Gamma) (the report's garbled equation, solved numerically).
    """
    lo = period_one_limit(n)

    def f(g):
        th = math.asin(1.0 / g)
        return g * math.cos(th) - ((2 * n + 1) * math.pi - 2 * th) / 2

    hi = brentq(f, lo, period_one_limit(n + 1), xtol=1e-14)
    return lo, hi


# ------------------------------------------------------------ model functions
@dataclass
class Flight:
    """One flight: start phase theta0 [rad], duration [rad], landing relative
    normal velocity w (in amp_n w units, <= 0), and whether it started at a
    launch from contact ('launch') or a rebound ('rebound')."""

    theta0: float
    duration: float
    w_land: float
    start: str


def _flights(m: PartOnSurface, first_event: int = 0) -> list[Flight]:
    out, start, kind = [], None, None
    for ev in m.events[first_event:]:
        if ev.kind == "launch":
            start, kind = ev.t, "launch"
        elif ev.kind == "impact":
            if start is not None:
                out.append(Flight(start, ev.t - start, ev.info["w"], kind))
            start, kind = (ev.t, "rebound") if ev.info["rebound"] else (None, None)
        elif ev.kind in ("rest", "stick", "slip"):
            start = None                 # summed chatter or contact: no flight
    return out


def first_flight(gamma: float, e: float = 0.0) -> Flight:
    """Flight of a part launched from rest (at theta_l), simulated by the model."""
    m = _model(gamma, e)
    m.start(0.0)
    m.run(200.0 * TWO_PI, stop_on=("impact",))
    fl = _flights(m)
    if not fl:
        raise RuntimeError("no flight (Gamma <= 1?)")
    return fl[0]


def period_one_limit_numeric(n: int = 1) -> float:
    """Gamma at which the model's flight from the locked launch lasts n periods.

    Root of first_flight(Gamma).duration - 2 pi n, bracketed between the
    closed-form limits for n - 1/2 and n + 1/2; compare period_one_limit(n).
    """
    lo = math.sqrt(1 + ((n - 0.5) * math.pi) ** 2)
    hi = math.sqrt(1 + ((n + 0.5) * math.pi) ** 2)
    return brentq(lambda g: first_flight(g).duration - TWO_PI * n, lo, hi, xtol=1e-13)


def is_locked(gamma: float, e: float) -> bool:
    """True if a part launched from rest is back at rest on the surface (its
    chattering completed) before the next launch phase theta_l + 2 pi, i.e. a
    locked period-one orbit exists at this Gamma."""
    m = _model(gamma, e)
    m.start(0.0)
    m.run(4.0 * TWO_PI, stop_on=("launch",))      # first launch, at theta_l
    t_next = m.t + TWO_PI
    m.run(t_next - 1e-9)
    return m.mode == "stick"


def locked_limit(e: float, step: float = 0.01, xtol: float = 1e-9) -> float:
    """Largest Gamma of the locked period-one orbits for restitution e [-].

    Locked orbit: launch at theta_l, flight, impact(s), chattering completed
    (summed) and rest before theta_l + 2 pi. Computed from the model by a scan
    upward from Gamma = 1 and bisection on `is_locked`. For e = 0 this is
    period_one_limit(1) = sqrt(1 + pi^2); for e > 0 the chattering sequence
    takes time and the limit is lower.
    """
    g_lo, g = 1.0 + 1e-6, 1.0 + step
    while is_locked(g, e):
        g_lo, g = g, g + step
        if g > period_one_limit(1) + 0.5:
            raise RuntimeError("locked orbits beyond the e = 0 limit: unexpected")
    g_hi = g
    while g_hi - g_lo > xtol:
        mid = 0.5 * (g_lo + g_hi)
        if is_locked(mid, e):
            g_lo = mid
        else:
            g_hi = mid
    return 0.5 * (g_lo + g_hi)


def impact_map(theta: float, w: float, gamma: float, e: float):
    """Model's return map from one impact to the next.

    theta : impact phase [rad]; w : relative normal velocity before the impact
    [amp_n w units], w <= 0. Returns (theta_next, w_next, contact) where
    contact is True if the part rested or stuck on the surface in between.
    """
    m = _model(gamma, e)
    zs = math.sin(theta)
    vn = math.cos(theta)
    m.start(theta, z=zs, vz=vn - e * w)     # state just after the impact
    n0 = len(m.events)
    m.run(theta + 400.0 * TWO_PI, stop_on=("impact",))
    imp = [ev for ev in m.events[n0:] if ev.kind == "impact"]
    if not imp:
        raise RuntimeError("no further impact")
    contact = any(ev.kind in ("rest", "stick", "slip") for ev in m.events[n0:])
    return imp[-1].t, imp[-1].info["w"], contact


def period_one_orbit(gamma: float, e: float, n: int = 1):
    """Single-impact period-n orbit of the model's impact map.

    Returns (theta*, w*, J): impact phase [rad] in [0, 2 pi), relative impact
    velocity, and the 2x2 Jacobian of the map (central differences) at the
    fixed point. The Newton search starts from the analytic fixed point
    (see period_doubling_closed_form) and is refined on the model's map.
    Raises RuntimeError if no such orbit exists at this Gamma.
    """
    c = n * math.pi * (1 - e) / ((1 + e) * gamma)
    if c >= 1:
        raise RuntimeError("no single-impact period-n orbit")
    th0 = math.acos(c)                         # sin > 0 branch (the stable one)
    w0 = -n * math.pi / gamma - c              # part velocity - surface velocity

    def F(p):
        th, w = p
        th1, w1, _ = impact_map(th, w, gamma, e)
        return [th1 - th - TWO_PI * n, w1 - w]

    sol, _, ier, msg = fsolve(F, [th0, w0], full_output=True, xtol=1e-13)
    th, w = sol
    th1, w1, contact = impact_map(th, w, gamma, e)
    if ier != 1 or contact or abs(th1 - th - TWO_PI * n) > 1e-8:
        raise RuntimeError(f"period-one orbit not found at Gamma={gamma}: {msg}")
    h = 1e-6
    J = np.empty((2, 2))
    for j, d in enumerate(([h, 0.0], [0.0, h])):
        p1 = impact_map(th + d[0], w + d[1], gamma, e)
        p0 = impact_map(th - d[0], w - d[1], gamma, e)
        J[0, j] = (p1[0] - p0[0]) / (2 * h)
        J[1, j] = (p1[1] - p0[1]) / (2 * h)
    return th % TWO_PI, w, J


def period_doubling_onset(e: float = 0.0, n: int = 1, step: float = 0.02) -> float:
    """Gamma at which the single-impact period-n orbit of the model period-doubles.

    Computed from the model's return map: the Jacobian at the fixed point has
    an eigenvalue -1 when 1 + tr J + det J = 0; this is bracketed by a scan in
    Gamma (step) from just above the orbit's existence and solved by brentq.
    For e = 0 this is sqrt(4 + pi^2) = 3.7242 (above it the unlocked period-one
    orbit of report 2.3.2 bifurcates into the long/short jump pair).
    """
    def f(g):
        _, _, J = period_one_orbit(g, e, n)
        return 1.0 + np.trace(J) + np.linalg.det(J)

    g_exist = max(1.0, n * math.pi * (1 - e) / (1 + e))
    if e == 0.0:
        g_exist = period_one_limit(n)             # below: locked, multiplier 0
    g_prev, f_prev = None, None
    g = g_exist + step
    while g < g_exist + 20.0:
        try:
            fg = f(g)
        except RuntimeError:
            g_prev, f_prev = None, None
            g += step
            continue
        if f_prev is not None and f_prev > 0 >= fg:
            return brentq(f, g_prev, g, xtol=1e-10)
        g_prev, f_prev = g, fg
        g += step
    raise RuntimeError("no period doubling found")


# ----------------------------------------------------- long runs and diagrams
def run_flights(gamma: float, e: float = 0.0, n_periods: int = 200, n_transient: int = 100,
                state: dict | None = None):
    """Simulate the hopping part and return its flights after a transient.

    gamma : normal Gamma; e : restitution; n_periods recorded after
    n_transient periods; state : optional start state from a previous run
    (dict t, z, vz; for sweeps in Gamma, as the report discusses: the
    amplitude is raised through the lower values). Returns (flights, state,
    (t_start, t_end)) with the recorded window in dimensionless time: the
    flights that start in the window, the last one followed to its landing,
    so that a periodic motion over whole cycles yields each flight once.
    """
    m = _model(gamma, e)
    if state is None:
        m.start(0.0)
    else:
        m.start(state["t"], z=state["z"], vz=state["vz"])
    t_rec = m.t + n_transient * TWO_PI
    m.run(t_rec)
    n0 = len(m.events)
    t_end = t_rec + n_periods * TWO_PI
    m.run(t_end)
    if m.mode == "flight":      # started in the window (or before it: then skipped below)
        m.run(t_end + 400.0 * TWO_PI, stop_on=("impact",))
    fl = _flights(m, n0)        # a flight already under way at t_rec has no start event: skipped
    return fl, dict(t=m.t, z=m.z, vz=m.vz), (t_rec, t_end)


def stroboscopic_period(gamma: float, e: float = 0.0, n_transient: int = 400, max_period: int = 8,
                        tol: float = 1e-7, state: dict | None = None):
    """Period (in surface periods) of the attractor reached by the model.

    The relative state (gap, relative normal velocity) is sampled once per
    period at theta = 0 mod 2 pi after n_transient periods; the smallest p <=
    max_period with samples repeating to tol (over 3 p samples) is returned,
    0 if none (chaotic, quasi-periodic or still converging). Also returns the
    final state for sweeps. Used by `period_one_loss`.
    """
    m = _model(gamma, e)
    if state is None:
        m.start(0.0)
    else:
        m.start(state["t"], z=state["z"], vz=state["vz"])
    k0 = math.ceil(m.t / TWO_PI - 1e-12) + n_transient
    m.run(k0 * TWO_PI)
    samples = []
    for k in range(4 * max_period):
        m.run((k0 + k) * TWO_PI)
        samples.append((m.z - math.sin(m.t), m.vz - math.cos(m.t)))
    a = np.array(samples)
    period = 0
    for p in range(1, max_period + 1):
        if np.all(np.abs(a[p:3 * p + p] - a[:3 * p]) <= tol):
            period = p
            break
    return period, dict(t=m.t, z=m.z, vz=m.vz)


def period_one_loss(e: float, g_start: float = 1.01, step: float = 0.005, g_stop: float = 6.0,
                    n_transient: int = 400) -> float:
    """Gamma at which the attractor stops being period-one in an upward sweep.

    Scan of `stroboscopic_period` from g_start in steps of `step`, each Gamma
    started from the final state of the previous one (the amplitude is raised
    through the lower values, as the report discusses). Returns the first
    Gamma whose attractor is not period-one (resolution: step; close to a
    period doubling the convergence is slow, so the scan can trigger up to a
    few steps early). For e = 0 this is just above sqrt(4 + pi^2).
    """
    state, g = None, g_start
    while g < g_stop:
        p, state = stroboscopic_period(g, e, n_transient, state=state)
        if p != 1:
            return g
        g += step
    raise RuntimeError("period one up to g_stop")


def bifurcation_diagram(gammas, e: float = 0.0, n_periods: int = 64, n_transient: int = 200,
                        min_jump: float = 1e-2, sweep: bool = True):
    """Jump lengths vs Gamma (report Figure 9, left curve and ruled surface).

    Returns a list (one per Gamma) of arrays of flight durations in periods
    (theta_jump / 2 pi) in the recorded window; flights shorter than min_jump
    periods (chattering bounces) are left out. With sweep=True each Gamma
    starts from the final state of the previous one.
    """
    out, state = [], None
    for g in gammas:
        fl, st, _ = run_flights(g, e, n_periods, n_transient, state if sweep else None)
        state = st
        d = np.array([f.duration for f in fl]) / TWO_PI
        out.append(d[d >= min_jump])
    return out


def ideal_speed(gamma: float, e: float = 0.0, phase: float | np.ndarray = 0.0,
                n_periods: int = 96, n_transient: int = 100):
    """Mean tangential speed of the hopping part / (amp_t w) [-], idealised.

    Idealisation of report 2.3.2 (Figure 9, right curve) and 2.4: the part
    takes the surface's tangential velocity whenever it touches it (infinite
    friction, impulsive at impacts), so it only moves relative to the surface
    in flight. A flight starting at normal phase th0 with duration tau gains,
    relative to the surface x_s = amp_t sin(th - phase):
        cos(th0 - phase) tau - [sin(th0 + tau - phase) - sin(th0 - phase)].
    phase [deg] may be an array (the normal motion does not depend on it).
    Averaged over n_periods whole periods after n_transient.
    """
    fl, _, (ta, tb) = run_flights(gamma, e, n_periods, n_transient)
    ph = np.radians(np.atleast_1d(np.asarray(phase, dtype=float)))[:, None]
    th0 = np.array([f.theta0 for f in fl])[None, :]
    tau = np.array([f.duration for f in fl])[None, :]
    gain = np.cos(th0 - ph) * tau - (np.sin(th0 + tau - ph) - np.sin(th0 - ph))
    v = gain.sum(axis=1) / (tb - ta)
    return float(v[0]) if np.ndim(phase) == 0 else v


def optimal_phase(gamma: float, e: float = 0.0, n_periods: int = 96) -> float:
    """Phase [deg] in [-180, 180) maximising `ideal_speed` (report 2.4).

    The report: near 90 deg at small Gamma (launch near the top, theta_l -> pi/2),
    near 0 deg at large Gamma (theta_l -> 0).
    """
    grid = np.linspace(-180.0, 180.0, 361)[:-1]
    fl, _, (ta, tb) = run_flights(gamma, e, n_periods)
    th0 = np.array([f.theta0 for f in fl])
    tau = np.array([f.duration for f in fl])

    def speed(p):
        ph = math.radians(p)
        return np.sum(np.cos(th0 - ph) * tau - (np.sin(th0 + tau - ph) - np.sin(th0 - ph))) / (tb - ta)

    v = np.array([speed(p) for p in grid])
    k = int(np.argmax(v))
    res = minimize_scalar(lambda p: -speed(p), bounds=(grid[k] - 1.0, grid[k] + 1.0),
                          method="bounded", options={"xatol": 1e-6})
    return float((res.x + 180.0) % 360.0 - 180.0)
