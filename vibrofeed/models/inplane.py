"""In-plane (horizontal-only) vibratory transport (Khan & Sarma, §2.1).

Speed curves of the asymmetric stick-slip and Coulomb-pump waveforms computed
with the event-driven model, and two limits as closed or semi-closed forms:

* `optimal_stick_slip_speed`: the largest steady mean part speed any
  horizontal periodic surface motion of period T can give under the bound
  |a_s| <= a_max (Umbanhowar & Lynch, "Optimal vibratory stick-slip transport",
  IEEE T-ASE 2008). The optimal surface acceleration has three phases:
  +mu_s g (the part sticks and is carried forward with the largest acceleration
  static friction allows), -a_max (the part slips forward, decelerating at
  mu_k g), +a_max (the surface catches up with the part; the part re-sticks
  exactly when the phase ends). Derivation (rederived here): with
  Dv = velocity swing, stick time t1 = Dv/(mu_s g), slip time
  tau = t2 + t3 = Dv/(mu_k g), t1 + tau = T, the surface's zero mean velocity
  gives a part mean speed equal to the mean relative velocity, a triangle of
  area (a_max^2 - mu_k^2 g^2) tau^2 / (4 a_max). Hence
      v* = g T mu_s^2 (alpha^2 - mu_k^2) / (4 alpha (mu_s + mu_k)^2),
      alpha = a_max / g  (requires alpha >= mu_s, else the part never slips).
* `sliding_limit_speed`: when the part slides all the time (high frequency:
  the velocity it gains or loses by friction in a period, ~ mu_k g T, is
  small against the surface velocity swing) its velocity V is nearly constant
  and changes per period by mu_k g (T_above(V) - T_below(V)), T_above/below
  the times the surface is faster/slower than V. The steady state balances
  the two: V is the median of the surface velocity over a period (friction
  the same both ways, flat horizontal track). With normal motion or an
  incline the balance is weighted: mu_k int n(t) sign(v_s - V) dt = g sin(beta) T.
"""

from __future__ import annotations

import math

import numpy as np

from .constants import G
from .part_on_surface import PartParams, mean_velocity
from .surface import CoulombPumpWaveform, PiecewiseConstantAccel, StickSlipWaveform, SurfaceMotion


def optimal_stick_slip_speed(a_max: float, mu_s: float, mu_k: float, freq: float,
                             g: float = G) -> float:
    """Best steady mean part speed [m/s] of horizontal vibration with |a| <= a_max.

    a_max [m/s^2], mu_s, mu_k [-], freq [Hz], g [m/s^2]. Umbanhowar & Lynch's
    optimal three-phase stick-slip waveform (see module docstring); 0 if
    a_max <= mu_s g (the part can never be made to slip from rest).
    """
    alpha = a_max / g
    if alpha <= mu_s:
        return 0.0
    return g / freq * mu_s ** 2 * (alpha ** 2 - mu_k ** 2) / (4 * alpha * (mu_s + mu_k) ** 2)


def optimal_stick_slip_waveform(a_max: float, mu_s: float, mu_k: float, freq: float,
                                g: float = G) -> PiecewiseConstantAccel:
    """The optimal three-phase surface acceleration (+mu_s g, -a_max, +a_max).

    Durations: t1 = T mu_k/(mu_s + mu_k), tau = T mu_s/(mu_s + mu_k),
    t2 = tau (a_max + mu_k g)/(2 a_max), t3 = tau (a_max - mu_k g)/(2 a_max).
    Returns a PiecewiseConstantAccel (no normal motion) starting with the
    stick phase.
    """
    if a_max <= mu_s * g:
        raise ValueError("need a_max > mu_s g")
    T = 1.0 / freq
    t1 = T * mu_k / (mu_s + mu_k)
    tau = T - t1
    t2 = tau * (a_max + mu_k * g) / (2 * a_max)
    return PiecewiseConstantAccel([t1, t2, tau - t2], [mu_s * g, -a_max, a_max])


def sliding_limit_speed(waveform: SurfaceMotion, mu_k: float | None = None, incline: float = 0.0,
                        g: float = G, n: int = 200_000) -> float:
    """High-frequency (always sliding) limit of the part speed [m/s].

    Solves mu_k int_0^T n(t) sign(v_s(t) - V) dt = g sin(beta) T for V, with
    n = g cos(beta) + a_n(t) (see module docstring); for a flat track without
    normal motion this is the median of the surface velocity v_s over a
    period, and mu_k is not needed. The integral uses n midpoint samples per
    period (accuracy ~ (max |a_s|) T / n); V by bisection (the left side is
    non-increasing in V).
    """
    T = waveform.period
    ts = (np.arange(n) + 0.5) * T / n
    vs = waveform.velocity(ts)[0]
    beta = math.radians(incline)
    wts = g * math.cos(beta) + waveform.acceleration(ts)[1]
    if np.any(wts <= 0):
        raise ValueError("the part would lose contact: no sliding limit")
    rhs = 0.0                    # g sin(beta) T / (mu_k dt): right side in sample units
    if incline != 0.0:
        if mu_k is None or mu_k <= 0:
            raise ValueError("mu_k > 0 needed on an incline")
        rhs = g * math.sin(beta) * n / mu_k

    def excess(V):               # non-increasing in V
        return np.sum(wts * np.sign(vs - V)) - rhs

    lo, hi = float(vs.min()), float(vs.max())
    if excess(lo) < 0 or excess(hi) > 0:
        raise ValueError("friction cannot hold the part against the incline")
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if excess(mid) > 0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-15 * max(abs(lo), abs(hi), 1e-300):
            break
    return 0.5 * (lo + hi)


def stick_slip_closed_form(waveform: StickSlipWaveform, mu_s: float, mu_k: float,
                           g: float = G) -> float:
    """Steady mean part speed [m/s] for the two-phase stick-slip waveform, flat track.

    Valid when a_forward <= mu_s g < a_backward (stick forward, slip back) and
    the part re-sticks within the forward phase: during the backward phase
    (t_b) the relative velocity grows at a_b - mu_k g, during the next forward
    phase it decays at a_f + mu_k g over t* = (a_b - mu_k g) t_b / (a_f + mu_k g);
    the mean relative velocity (= mean part speed, the surface's mean being
    zero) is the triangle area (a_b - mu_k g) t_b (t_b + t*) / (2 T).
    Raises ValueError outside that regime.
    """
    af, ab, T = waveform.a_forward, waveform.a_backward, waveform.period
    tf, tb = waveform.durations
    if not (af <= mu_s * g < ab):
        raise ValueError("not in the stick-forward / slip-back regime")
    ts = (ab - mu_k * g) * tb / (af + mu_k * g)
    if ts > tf:
        raise ValueError("the part does not re-stick within the forward phase")
    return (ab - mu_k * g) * tb * (tb + ts) / (2 * T)


def speed_curve(make_waveform, peak_speeds, part: PartParams, g: float = G, **kw):
    """Steady mean part speed [m/s] for each surface peak speed [m/s].

    make_waveform(peak_speed) -> SurfaceMotion; part : PartParams; extra keywords go
    to `part_on_surface.mean_velocity`. Returns an array.
    """
    return np.array([mean_velocity(make_waveform(v), part, g=g, **kw).velocity for v in peak_speeds])


def stick_slip_speed_curve(freq: float, peak_speeds, forward_fraction: float, part: PartParams,
                           g: float = G, **kw):
    """Part speed [m/s] vs peak surface speed [m/s] for the stick-slip waveform
    (report 2.1, Figure 1) at fixed frequency [Hz] and forward-time fraction."""
    return speed_curve(lambda v: StickSlipWaveform.from_peak_speed(freq, v, forward_fraction),
                       peak_speeds, part, g, **kw)


def coulomb_pump_speed_curve(freq: float, peak_speeds, accel: float, part: PartParams,
                             g: float = G, **kw):
    """Part speed [m/s] vs forward surface speed [m/s] for the Coulomb pump
    (report 2.1, Figure 2) at fixed frequency [Hz] and reversal acceleration
    [m/s^2] (peak speeds up to accel / (4 freq))."""
    return speed_curve(lambda v: CoulombPumpWaveform(freq, v, accel), peak_speeds, part, g, **kw)
