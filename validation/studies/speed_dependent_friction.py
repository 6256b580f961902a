"""Stick/slip with a speed-dependent kinetic friction (investigation variant).

Used by ``vertical_study`` to test whether a kinetic friction that changes
with the slip speed explains the measured trials better than Coulomb's
constant one. The law is the simplest with exact events: mu_k below a slip
speed v_c, mu_k_fast at or above it (mu_k_fast < mu_k: velocity weakening,
Stribeck-like; > mu_k: strengthening). The part's acceleration stays
piecewise constant, so the event roots of the vertical model
(``models.roots``) carry over: besides
w = v_s - v_p = 0 there are crossings of |w| = v_c, found as zeros of
w - s v_c with the same bracketed search. With strengthening, |w| can be
held at v_c (neither regime moves it away): the part then "rides" at a
constant slip speed while the surface acceleration stays between the two
slip accelerations, handled like sticking with an offset velocity.

Not part of the validated model: with mu_k_fast = mu_k it reproduces
``vertical.simulate`` exactly (tested), otherwise it is a hypothesis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import said
from ...models.roots import slip_end, stick_decision, stick_exit
from ...models.vertical import Contact

__all__ = ["simulate_speed_dependent"]


@dataclass(frozen=True)
class _Segment:
    t0: float
    t1: float
    kind: str  # "stick", "slip" or "ride"
    z0: float
    v0: float
    accel: float  # slip
    offset: float  # stick/ride: z_p - z_s at t0
    slip_speed: float  # ride: w held at this value


def _first_level(P, i, t0, v0, a_p, level, direction, from_level, tol):
    """First time w = v_s - v_p equals ``level``; w - level moves with sign ``direction``."""
    return slip_end(P, i, t0, v0 + level, direction, a_p, tol, from_zero=from_level)


def simulate_speed_dependent(surface, contact: Contact, mu_k_fast: float, v_c: float,
                             t_end: float, t_start: float = 0.0, z0: float | None = None,
                             t_eval=None):
    """Part z(t) at ``t_eval`` (and stuck fraction) with the two-level kinetic law.

    Starts with the part at the surface velocity, like ``vertical.simulate``.
    Returns (z at t_eval, stuck fraction, segments).
    """
    if not v_c > 0:
        raise ValueError("v_c must be > 0")
    P = surface.pieces(t_start, t_end)
    lo, hi = contact.stick_lower, contact.stick_upper
    tol = 1e-9 * (abs(lo) + abs(hi)) + 1e-12
    fn_m = contact.normal_force / contact.mass
    a_slow = {s: s * contact.mu_k * fn_m - contact.g for s in (1, -1)}
    a_fast = {s: s * mu_k_fast * fn_m - contact.g for s in (1, -1)}
    t = float(t_start)
    z = float(surface.position(t)[0]) if z0 is None else float(z0)
    v = P.local(0, t, 1)
    i = 0
    side = stick_decision(P, 0, t, lo, hi, tol)
    state = ("stick", 0) if side == 0 else ("slow", side)
    segments: list[_Segment] = []
    repeats = 0
    while t < t_end:
        kind, s = state
        if kind in ("stick", "ride"):
            w_hold = 0.0 if kind == "stick" else s * v_c
            band = (lo, hi) if kind == "stick" else tuple(sorted((a_slow[s], a_fast[s])))
            offset = z - P.local(i, t, 0)
            hit = stick_exit(P, i, t, *band, held=kind == "stick")
            t1, j, out = (t_end, P.n - 1, 0) if hit is None else hit
            segments.append(_Segment(t, t1, kind, z, v, 0.0, offset, w_hold))
            z = P.local(j, t1, 0) + offset - w_hold * (t1 - t)
            v = P.local(j, t1, 1) - w_hold
            if kind == "stick":
                state = ("slow", out)
            else:  # leaves the ride: above the band s*w grows (fast), else falls (slow)
                a_out = band[1] if out > 0 else band[0]
                state = ("fast", s) if s * (a_out - a_fast[s]) >= 0 else ("slow", s)
        else:
            a_p = (a_slow if kind == "slow" else a_fast)[s]
            w0 = P.local(i, t, 1) - v
            candidates = []
            if kind == "slow":
                # Starts at w = 0 (from sticking) or at |w| = v_c (coming down);
                # ends back at w = 0 or up at |w| = v_c.
                at_zero = abs(w0) <= 1e-12
                hz = _first_level(P, i, t, v, a_p, 0.0, s, at_zero, tol)
                if hz is not None:
                    candidates.append((hz[0], hz[1], "zero"))
                hv = _first_level(P, i, t, v, a_p, s * v_c, -s, not at_zero, tol)
                if hv is not None:
                    candidates.append((hv[0], hv[1], "vc"))
            else:  # fast: starts at |w| = v_c going up, ends back there
                hv = _first_level(P, i, t, v, a_p, s * v_c, s, True, tol)
                if hv is not None:
                    candidates.append((hv[0], hv[1], "vc"))
            if candidates:
                t1, j, what = min(candidates, key=lambda c: c[0])
            else:
                t1, j, what = t_end, P.n - 1, None
            tau = t1 - t
            segments.append(_Segment(t, t1, "slip", z, v, a_p, 0.0, 0.0))
            z = z + v * tau + 0.5 * a_p * tau * tau
            v = v + a_p * tau
            if what is not None and t1 >= P.edges[j + 1] and j + 1 < P.n:
                j += 1
            if what == "zero":
                v = P.local(j, t1, 1)
                side = stick_decision(P, j, t1, lo, hi, tol)
                state = ("stick", 0) if side == 0 else ("slow", side)
            elif what == "vc":
                a = P.local(j, t1, 2)
                v = P.local(j, t1, 1) - s * v_c
                grows_fast = s * (a - a_fast[s]) > 0
                falls_slow = s * (a - a_slow[s]) < 0
                if kind == "slow":
                    state = ("fast", s) if grows_fast else ("ride", s)
                else:
                    state = ("slow", s) if falls_slow else ("ride", s)
        repeats = repeats + 1 if t1 <= t else 0
        if repeats > 6:
            raise RuntimeError(f"speed-dependent friction: chattering at t = {said(t)} s")
        t, i = t1, j
    t_eval = np.asarray(t_eval if t_eval is not None else [t_end], dtype=float)
    starts = np.array([g.t0 for g in segments])
    k = np.clip(np.searchsorted(starts, t_eval, side="right") - 1, 0, len(segments) - 1)
    out = np.empty_like(t_eval)
    for n, (tt, kk) in enumerate(zip(t_eval, k)):
        g = segments[kk]
        if g.kind == "slip":
            tau = tt - g.t0
            out[n] = g.z0 + g.v0 * tau + 0.5 * g.accel * tau * tau
        else:
            out[n] = float(surface.position(tt)[0]) + g.offset - g.slip_speed * (tt - g.t0)
    stuck = sum(g.t1 - g.t0 for g in segments if g.kind == "stick") / (t_end - t_start)
    return out, stuck, segments
