"""Event roots: every bracketed root search of the models, in one place.

No model looks for events on a time grid. A window is split into pieces on
which a function is monotone, and each piece is solved with Brent's method: a
monotone piece holds at most one root, so none is stepped over; the only loss
is a root of even multiplicity (a tangency without sign change), which changes
no contact state.

* ``all_roots``, ``first_descent``, ``first_negative_interval``: the pieces come
  from the zeros of the derivative, themselves isolated the same way from the
  next derivative, down to a level where the zeros are analytic
  (``SurfaceMotion.accel_roots``). Used by the part-on-surface model.
* ``stick_exit``, ``slip_end``, ``stick_decision``: the pieces are the
  surface's own ``Pieces`` (acceleration continuous and monotone on each).
  Leaving the stick band is a level crossing of the acceleration (one per piece
  at most); while slipping at a constant part acceleration a_p the relative
  velocity w = v_s - v_p has w' = a_s - a_p, so it is unimodal on a piece and
  its extremum is a level crossing too. Used by the vertical-transport model
  and its speed-dependent friction variant.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np
from scipy.optimize import brentq

from .surface import Pieces

#: Absolute tolerance [s] of event times on Pieces, and Brent's relative one.
XTOL = 1e-14
RTOL = 4 * np.finfo(float).eps

# Splits closer than MERGE * xtol are merged: analytic roots of phase functions
# like sin(w t + psi) carry a rounding error of a few ulp of w t, which after
# many periods exceeds xtol; 1e4 * xtol (1e-10 periods in the model) is still
# far below any physical time scale.
MERGE = 1e4


def _points(t0: float, t1: float, splits: Iterable[float], xtol: float) -> list[float]:
    """t0, the splits strictly inside (t0, t1), t1; points closer than MERGE*xtol merged.

    Merging matters when a split coincides with t0 up to rounding (e.g. the
    relative velocity starts turning at the very instant slip begins): a
    sliver piece would otherwise be classified by rounding noise.
    """
    gap = MERGE * xtol
    pts = [t0]
    for s in sorted(splits):
        if s - pts[-1] > gap and t1 - s > gap:
            pts.append(float(s))
    pts.append(t1)
    return pts


def _pieces(t0: float, t1: float, splits: Iterable[float], xtol: float):
    pts = _points(t0, t1, splits, xtol)
    return list(zip(pts[:-1], pts[1:]))


def all_roots(f: Callable[[float], float], t0: float, t1: float,
              splits: Iterable[float], xtol: float) -> list[float]:
    """All sign changes of f in [t0, t1], f monotone between consecutive splits.

    Returns the sorted roots (a root shared by two pieces appears once).
    """
    roots: list[float] = []
    pieces = _pieces(t0, t1, splits, xtol)
    fa = f(t0)
    for a, b in pieces:
        fb = f(b)
        if fa == 0.0:
            r = a
        elif fb == 0.0:
            r = b
        elif (fa < 0.0) != (fb < 0.0):
            r = brentq(f, a, b, xtol=xtol, rtol=RTOL)
        else:
            r = None
        if r is not None and (not roots or r - roots[-1] > xtol):
            roots.append(r)
        fa = fb
    return roots


def first_descent(f: Callable[[float], float], t0: float, t1: float,
                  splits: Iterable[float], xtol: float) -> float | None:
    """First time in [t0, t1] where f reaches 0 while decreasing.

    f is conceptually >= 0 at t0 (the model is in a valid state) and monotone
    between consecutive splits. The direction of each piece is taken from its
    end values, not from the sign of a value that may be a rounding-level
    zero: a piece that starts at ~0 and rises holds no event (e.g. the gap
    just after a launch), one that starts at <= 0 and falls is an event at its
    start. Returns None if f stays positive.
    """
    fa = f(t0)
    for a, b in _pieces(t0, t1, splits, xtol):
        fb = f(b)
        if fb < fa:                      # decreasing piece
            if fa <= 0.0:
                return a
            if fb <= 0.0:
                return brentq(f, a, b, xtol=xtol, rtol=RTOL)
        fa = fb
    return None


def first_negative_interval(funcs: list[Callable[[float], float]],
                            t0: float, t1: float, roots: Iterable[float], xtol: float):
    """First interval start where any of several functions becomes negative.

    funcs are functions whose sign can only change at the given roots (all
    their zeros in (t0, t1]); roots within xtol of each other or of t0 are
    merged so that no interval is a rounding-level sliver. Each interval between consecutive roots is
    classified by the signs at its midpoint. Returns (t_start, index of the
    first negative function) or (None, None).
    """
    pts = _points(t0, t1, roots, xtol)
    for a, b in zip(pts[:-1], pts[1:]):
        mid = 0.5 * (a + b)
        for k, fun in enumerate(funcs):
            if fun(mid) < 0.0:
                return a, k
    return None, None


# ------------------------------------------------- events on a surface's Pieces
def stick_decision(P: Pieces, j: int, t: float, lo: float, hi: float, tol: float) -> int:
    """At zero relative velocity: 0 to stick, +1/-1 to slip upward/downward.

    Uses the right-hand acceleration (piece j contains t at its start side).
    Within ``tol`` of a band edge (event times are exact only to ~1e-14 s),
    the piece's trend decides, so an exit found at t is not undone at t.
    """
    a = P.local(j, t, 2)
    a_end = P.a_end[j]
    if a > hi + tol or (a >= hi - tol and a_end > hi):
        return 1
    if a < lo - tol or (a <= lo + tol and a_end < lo):
        return -1
    return 0


def _chunks(i: int, n: int):
    """Index ranges [j0, j1) from piece i onward, growing so short searches stay cheap."""
    size = 16
    while i < n:
        yield i, min(n, i + size)
        i += size
        size *= 2


def _accel_above(t: float, P: Pieces, j: int, level: float) -> float:
    """Piece j's acceleration at t minus ``level`` (a root is a level crossing)."""
    return P.local(j, t, 2) - level


def stick_exit(P: Pieces, i: int, t: float, lo: float, hi: float, held: bool = False):
    """First time >= t where the surface acceleration leaves [lo, hi].

    ``held``: the part is stuck at t as :func:`stick_decision` found, which allows a_s(t)
    a rounding error outside the band (a start on a band edge, a_s turning inward): the
    band is widened to a_s(t), or the exit would be found at t at once."""
    a_t = P.local(i, t, 2)
    if held:
        lo, hi = min(lo, a_t), max(hi, a_t)
    for j0, j1 in _chunks(i, P.n):
        a_s = P.a_start[j0:j1].copy()
        a_e = P.a_end[j0:j1]
        if j0 == i:
            a_s[0] = a_t
        bad = np.flatnonzero((a_s < lo) | (a_s > hi) | (a_e < lo) | (a_e > hi))
        if bad.size == 0:
            continue
        k = bad[0]
        j = j0 + k
        start = t if j == i else P.edges[j]
        if a_s[k] > hi:  # a jump out of the band at the piece start
            return start, j, 1
        if a_s[k] < lo:
            return start, j, -1
        level, side = (hi, 1) if a_e[k] > hi else (lo, -1)
        t_x = brentq(_accel_above, start, P.edges[j + 1], args=(P, j, level),
                     xtol=XTOL, rtol=RTOL)
        return t_x, j, side
    return None


def slip_end(P: Pieces, i: int, t0: float, v0: float, s: int, a_p: float,
              tol: float, from_zero: bool = True):
    """First time > t0 where the relative velocity w = v_s - v_p reaches zero.

    sgn(w) = s just after t0. ``from_zero``: the slip starts at w(t0) = 0
    (an event), rather than from an initial condition with w(t0) != 0.
    """
    def w(tau, j):
        return P.local(j, tau, 1) - v0 - a_p * (tau - t0)

    d_first = P.local(i, t0, 2) - a_p
    if from_zero:
        if abs(d_first) <= tol:
            d_first = 0.0  # leaving exactly at a_s = a_p (e.g. mu_k = mu_s): trend decides
        if s * d_first < 0 or (d_first == 0 and s * (P.a_end[i] - a_p) <= 0):
            return t0, i  # cannot move away in direction s: decide again at once
    for j0, j1 in _chunks(i, P.n):
        t_end = P.edges[j0 + 1:j1 + 1]
        sw_end = s * (P.v[j0 + 1:j1 + 1] - v0 - a_p * (t_end - t0))
        d_s = P.a_start[j0:j1] - a_p
        if j0 == i:
            d_s = d_s.copy()
            d_s[0] = d_first
        d_e = P.a_end[j0:j1] - a_p
        # s*w returns to 0 either by the piece end, or inside at a local minimum.
        cross = sw_end <= 0
        dip = (s * d_s < 0) & (s * d_e > 0)
        for k in np.flatnonzero(cross | dip):
            j = j0 + k
            p = t0 if j == i else P.edges[j]
            q = P.edges[j + 1]
            if d_s[k] * d_e[k] < 0:  # interior extremum of w where a_s = a_p
                t_m = brentq(_accel_above, p, q, args=(P, j, a_p), xtol=XTOL, rtol=RTOL)
                sw_m = s * w(t_m, j)
                if s * d_s[k] < 0:  # s*w falls to a minimum at t_m
                    if sw_m <= 0:
                        return brentq(w, p, t_m, args=(j,), xtol=XTOL, rtol=RTOL), j
                    continue  # rises again after t_m: no crossing in this piece
                if cross[k]:  # s*w rises to a maximum, then falls through zero
                    return brentq(w, t_m, q, args=(j,), xtol=XTOL, rtol=RTOL), j
                continue
            if j == i and from_zero:
                continue  # monotone away from w(t0) = 0: no return in the first piece
            if cross[k]:
                return brentq(w, p, q, args=(j,), xtol=XTOL, rtol=RTOL), j
    return None
