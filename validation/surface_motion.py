"""Prescribed motion z_s(t) of a vibrating surface, cut into monotone pieces.

The stick/slip model (``vertical.py``) needs the surface position, velocity
and acceleration, and it locates its events exactly: where the acceleration
leaves the stick band, and where the relative velocity returns to zero. Both
searches become bracketed root finds once time is cut into *pieces* on which
the acceleration is continuous and monotone:

* a level crossing of the acceleration lies in a piece whose end values
  straddle the level (one root at most per piece);
* the relative velocity w = v_s - v_p (part accelerating at a constant a_p)
  has w' = a_s - a_p, so w is unimodal on a piece and its extremum is a level
  crossing of a_s at a_p.

A surface object therefore offers ``position``, ``velocity``,
``acceleration`` (vectorised, right-continuous at jumps) and
``pieces(t0, t1)``. Three kinds are provided:

* ``PolynomialSurface``: a piecewise polynomial position (scipy ``PPoly``,
  optionally repeated with a period). Velocity and acceleration are its exact
  derivatives; the pieces are the polynomial intervals split at the roots of
  the jerk, so the monotone cut is exact. Used for the two-level waveform and
  for the spline through a measured platform position.
* ``CallableSurface``: any three callables, with optional ``breakpoints``
  (acceleration jumps) and ``turning_points`` (acceleration extrema). With
  turning points the cut is exact; without, the acceleration is assumed
  monotone between samples ``max_step`` apart (an excursion out of the stick
  band shorter than ``max_step`` could be missed; make it smaller if the
  drive has such features).
* ``sine_drive`` and ``two_level_drive`` build the two standard drives.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.interpolate import PPoly

__all__ = [
    "Pieces",
    "PolynomialSurface",
    "CallableSurface",
    "sine_drive",
    "two_level_drive",
    "two_level_down_time",
]


@dataclass(frozen=True)
class Pieces:
    """Surface motion over a window, cut where the acceleration may turn or jump.

    ``edges`` (n+1) increase; on the closed piece i = [edges[i], edges[i+1]]
    the acceleration (continued from inside) is continuous and monotone.
    ``v`` is the velocity at the edges (continuous everywhere);
    ``a_start``/``a_end`` the one-sided accelerations just inside each piece.
    ``local(i, t, nu)`` evaluates derivative nu (0, 1, 2) of the position with
    piece i's own formula, so at an edge it gives that piece's one-sided value.
    """

    edges: np.ndarray
    v: np.ndarray
    a_start: np.ndarray
    a_end: np.ndarray
    local: Callable[[int, float, int], float]

    @property
    def n(self) -> int:
        return len(self.edges) - 1


def _unique_sorted(times: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """Sorted edges in [t0, t1] with t0 and t1, near-duplicates merged."""
    times = np.asarray(times, dtype=float)
    times = times[np.isfinite(times) & (times > t0) & (times < t1)]
    edges = np.unique(np.concatenate(([t0], times, [t1])))
    # Pieces shorter than a few ulps carry no information and make brackets
    # degenerate; merge them into their neighbour.
    tol = 8.0 * np.finfo(float).eps * max(1.0, abs(t0), abs(t1))
    keep = np.concatenate(([True], np.diff(edges) > tol))
    keep[-1] = True
    edges = edges[keep]
    if len(edges) >= 3 and edges[-1] - edges[-2] <= tol:
        edges = np.delete(edges, -2)
    return edges


class PolynomialSurface:
    """Surface whose position is a piecewise polynomial (exact derivatives).

    ``pp`` is a scipy ``PPoly`` (or anything ``PPoly.from_spline`` accepts,
    e.g. a ``BSpline``). With ``period`` the polynomial must span exactly one
    period, [pp.x[0], pp.x[0] + period], and is repeated for all t; without,
    evaluation outside [pp.x[0], pp.x[-1]] raises ``ValueError``.
    """

    def __init__(self, pp, period: float | None = None):
        if not isinstance(pp, PPoly):
            pp = PPoly.from_spline(pp)
        x = np.asarray(pp.x, dtype=float)
        # Drop zero-length intervals (repeated knots of a B-spline).
        keep = np.concatenate((np.diff(x) > 0, [True]))
        if not keep.all():
            cidx = np.nonzero(keep[:-1])[0]
            pp = PPoly(pp.c[:, cidx], x[keep], extrapolate=False)
            x = pp.x
        if period is not None:
            if not math.isclose(x[-1] - x[0], period, rel_tol=1e-12, abs_tol=0.0):
                raise ValueError(
                    f"a periodic polynomial must span one period: spans "
                    f"{x[-1] - x[0]!r}, period {period!r}")
        self.period = None if period is None else float(period)
        self._x = x
        self._derivs = [pp, pp.derivative(1), pp.derivative(2)]
        # Coefficient columns as Python tuples: a Horner loop on floats is
        # several times faster than numpy for one scalar, and the event
        # search calls it often.
        self._coef = [[tuple(float(c) for c in d.c[:, k]) for k in range(d.c.shape[1])]
                      for d in self._derivs]
        self._jerk = pp.derivative(3)
        self._cache: dict[tuple[float, float], Pieces] = {}

    @property
    def domain(self) -> tuple[float, float]:
        """Interval where the position is defined (one period if periodic)."""
        return float(self._x[0]), float(self._x[-1])

    def _reduce(self, t):
        """Map times into the polynomial's own interval."""
        t = np.asarray(t, dtype=float)
        x0, x1 = self._x[0], self._x[-1]
        if self.period is not None:
            return x0 + np.mod(t - x0, self.period)
        span = 1e-12 * max(1.0, abs(x0), abs(x1))
        if np.any((t < x0 - span) | (t > x1 + span)):
            raise ValueError(
                f"time outside the surface motion's domain [{x0:g}, {x1:g}] s")
        return np.clip(t, x0, x1)

    def _eval(self, t, nu):
        return self._derivs[nu](self._reduce(t))

    def position(self, t):
        return self._eval(t, 0)

    def velocity(self, t):
        return self._eval(t, 1)

    def acceleration(self, t):
        return self._eval(t, 2)

    def pieces(self, t0: float, t1: float) -> Pieces:
        key = (float(t0), float(t1))
        if key not in self._cache:
            self._cache.clear()  # keep one window: replays reuse it many times
            self._cache[key] = self._make_pieces(*key)
        return self._cache[key]

    def _base_edges(self) -> np.ndarray:
        """Interval ends and acceleration turning points over one span."""
        roots = self._jerk.roots(discontinuity=False, extrapolate=False)
        return np.unique(np.concatenate((self._x, roots[np.isfinite(roots)])))

    def _make_pieces(self, t0: float, t1: float) -> Pieces:
        if not t1 > t0:
            raise ValueError(f"empty time window [{t0}, {t1}]")
        base = self._base_edges()
        x0 = self._x[0]
        if self.period is None:
            self._reduce(np.array([t0, t1]))  # raises when outside the domain
            shift = np.zeros(1)
        else:
            k0 = math.floor((t0 - x0) / self.period)
            k1 = math.floor((t1 - x0) / self.period)
            shift = self.period * np.arange(k0, k1 + 1)
        edges = _unique_sorted((base[None, :] + shift[:, None]).ravel(), t0, t1)
        # Polynomial interval (and period shift) of each piece, from its midpoint.
        mid = 0.5 * (edges[:-1] + edges[1:])
        if self.period is None:
            origin = np.zeros_like(mid)
        else:
            origin = np.floor((mid - x0) / self.period) * self.period
        interval = np.clip(np.searchsorted(self._x, mid - origin, side="right") - 1,
                           0, len(self._x) - 2)
        start = self._x[interval] + origin  # time where that polynomial's x = 0

        def horner_vec(nu, tt):
            c = self._derivs[nu].c[:, interval]
            dx = tt - start
            out = np.zeros_like(dx)
            for row in c:
                out = out * dx + row
            return out

        coef = self._coef
        start_list = start.tolist()
        interval_list = interval.tolist()

        def local(i: int, t: float, nu: int) -> float:
            dx = t - start_list[i]
            out = 0.0
            for c in coef[nu][interval_list[i]]:
                out = out * dx + c
            return out

        # The velocity is continuous: piece starts, plus the end of the last piece.
        v = np.append(horner_vec(1, edges[:-1]), horner_vec(1, edges[1:])[-1])
        return Pieces(edges=edges, v=v, a_start=horner_vec(2, edges[:-1]),
                      a_end=horner_vec(2, edges[1:]), local=local)


class CallableSurface:
    """Surface motion given as three callables of time.

    ``acceleration`` should return the right-hand value at a jump; the times
    of jumps go in ``breakpoints``. ``turning_points`` (times of acceleration
    extrema), if known, make the monotone cut exact; otherwise the
    acceleration is sampled every ``max_step`` (default: period/256, or the
    window/4096) and assumed monotone in between. With ``period``, the
    breakpoints and turning points are those of one period, starting at 0,
    and are repeated.
    """

    def __init__(self, position: Callable, velocity: Callable, acceleration: Callable,
                 breakpoints=(), turning_points=None, period: float | None = None,
                 max_step: float | None = None):
        self._z, self._v, self._a = position, velocity, acceleration
        self.period = None if period is None else float(period)
        self._breaks = np.asarray(breakpoints, dtype=float).ravel()
        self._turns = None if turning_points is None else np.asarray(
            turning_points, dtype=float).ravel()
        self.max_step = max_step

    def position(self, t):
        return np.asarray(self._z(np.asarray(t, dtype=float)), dtype=float)

    def velocity(self, t):
        return np.asarray(self._v(np.asarray(t, dtype=float)), dtype=float)

    def acceleration(self, t):
        return np.asarray(self._a(np.asarray(t, dtype=float)), dtype=float)

    def _repeat(self, times: np.ndarray, t0: float, t1: float) -> np.ndarray:
        if self.period is None or times.size == 0:
            return times
        k = np.arange(math.floor(t0 / self.period) - 1, math.floor(t1 / self.period) + 2)
        return (times[None, :] + self.period * k[:, None]).ravel()

    def pieces(self, t0: float, t1: float) -> Pieces:
        if not t1 > t0:
            raise ValueError(f"empty time window [{t0}, {t1}]")
        breaks = self._repeat(self._breaks, t0, t1)
        breaks = breaks[(breaks >= t0) & (breaks <= t1)]
        extra = [breaks]
        if self._turns is not None:
            extra.append(self._repeat(self._turns, t0, t1))
        else:
            step = self.max_step or ((self.period / 256) if self.period else (t1 - t0) / 4096)
            n = max(1, math.ceil((t1 - t0) / step))
            extra.append(np.linspace(t0, t1, n + 1))
        edges = _unique_sorted(np.concatenate(extra), t0, t1)
        # Which edges are jumps: one-sided accelerations are taken a hair
        # inside the piece there (the callable's value at the jump is one side).
        near = np.zeros(len(edges), dtype=bool)
        if breaks.size:
            idx = np.searchsorted(edges, breaks).clip(0, len(edges) - 1)
            near[idx[np.isclose(edges[idx], breaks, rtol=0, atol=1e-12 * max(1.0, t1))]] = True
        length = np.diff(edges)
        eps = np.maximum(1e-9 * length, 4 * np.spacing(np.maximum(abs(edges[1:]), 1.0)))
        ts = np.where(near[:-1], edges[:-1] + eps, edges[:-1])
        te = np.where(near[1:], edges[1:] - eps, edges[1:])
        lo_list, hi_list = ts.tolist(), te.tolist()
        z, v, a = self._z, self._v, self._a

        def local(i: int, t: float, nu: int) -> float:
            if nu == 2:
                t = min(max(t, lo_list[i]), hi_list[i])
                return float(a(t))
            return float((z, v)[nu](t))

        return Pieces(edges=edges, v=self.velocity(edges), a_start=self.acceleration(ts),
                      a_end=self.acceleration(te), local=local)


def sine_drive(amplitude: float, frequency: float, phase: float = 0.0) -> CallableSurface:
    """z_s = A sin(2 pi f t + phase): the usual harmonic drive [m, Hz, rad]."""
    if not (amplitude >= 0 and frequency > 0):
        raise ValueError("sine drive needs amplitude >= 0 and frequency > 0")
    w = 2.0 * math.pi * frequency
    period = 1.0 / frequency
    # Acceleration -A w^2 sin(w t + phase) turns where w t + phase = pi/2 + k pi.
    turns = np.mod((np.array([0.5, 1.5]) * math.pi - phase) / w, period)
    return CallableSurface(
        position=lambda t: amplitude * np.sin(w * t + phase),
        velocity=lambda t: amplitude * w * np.cos(w * t + phase),
        acceleration=lambda t: -amplitude * w * w * np.sin(w * t + phase),
        turning_points=turns, period=period)


def two_level_down_time(a_up: float, t_up: float, a_down: float) -> float:
    """Drop duration making the mean acceleration zero: a_up t_up = a_down t_down."""
    return a_up * t_up / a_down


def two_level_drive(a_up: float, t_up: float, a_down: float) -> PolynomialSurface:
    """Two-level acceleration waveform, periodic, zero mean velocity.

    Over one period T = t_up + t_down, starting at t = 0: acceleration +a_up
    for t_up, then -a_down for t_down = a_up t_up / a_down (zero mean
    acceleration, so the velocity is periodic). The velocity is a triangle
    from -a_up t_up/2 to +a_up t_up/2 (zero mean, so the position is periodic
    too) and the position is piecewise quadratic with z_s(0) = 0.
    """
    if not (a_up > 0 and t_up > 0 and a_down > 0):
        raise ValueError("two-level drive needs a_up > 0, t_up > 0, a_down > 0")
    t_down = two_level_down_time(a_up, t_up, a_down)
    dv = a_up * t_up
    v0 = -0.5 * dv
    z_top = v0 * t_up + 0.5 * a_up * t_up ** 2  # position at the end of the rise
    # PPoly coefficients, highest power first, local variable x = t - x_left.
    c = np.array([[0.5 * a_up, -0.5 * a_down],
                  [v0, v0 + dv],
                  [0.0, z_top]])
    return PolynomialSurface(PPoly(c, [0.0, t_up, t_up + t_down], extrapolate=False),
                             period=t_up + t_down)
