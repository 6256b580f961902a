"""Root isolation for event finding on analytic trajectories.

The transport model never looks for events on a time grid. It splits a window
into pieces on which a function is monotone (known from the zeros of its
derivative, themselves isolated the same way from the next derivative, down to
a level where the zeros are analytic) and solves on each piece with brentq.
A monotone piece holds at most one root, so none is stepped over; the only
loss is a root of even multiplicity (a tangency without sign change), which
changes no contact state.
"""

from __future__ import annotations

from typing import Callable, Iterable

import numpy as np
from scipy.optimize import brentq


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
            r = brentq(f, a, b, xtol=xtol, rtol=4 * np.finfo(float).eps)
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
                return brentq(f, a, b, xtol=xtol, rtol=4 * np.finfo(float).eps)
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
