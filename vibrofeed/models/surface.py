"""Surface motions: the one description of how a vibrating surface moves.

Frame (project convention): x along the track, z normal to the surface. All
quantities are SI: m, m/s, m/s^2. Every model of ``vibrofeed.models`` is driven
by a :class:`SurfaceMotion`, and so is the deck generator: one object answers

``position(t)``, ``velocity(t)``, ``acceleration(t)``
    (x, z) of the surface at time(s) t [s], vectorised over t; at a jump the
    acceleration takes its right-hand (later) value;
``period``
    [s], or None for a motion that does not repeat (a measured drive);
``breakpoints(t0, t1)``, ``next_breakpoint(t)``
    times between which the motion is smooth, so that event finding never
    steps over a jump of acceleration;
``accel_roots(cx, cz, level, t0, t1)``
    the times in (t0, t1] where cx a_x(t) + cz a_z(t) = level, inside one
    smooth piece. The part-on-surface model needs exactly these: loss of
    contact (a_z = -g cos beta), the friction-cone boundaries and the turning
    points of the relative velocity are all level crossings of a linear
    combination of the two accelerations;
``pieces(t0, t1)``
    the along-track motion over a window cut into :class:`Pieces` on which
    a_x is continuous and monotone. The vertical-transport model needs these:
    leaving the stick band is a level crossing of a_x (at most one per piece),
    and the relative velocity of a part slipping at constant acceleration is
    unimodal on a piece (see ``vertical``).

Periodic motions on both axes (Khan & Sarma, "Vibratory Assembly Update: Part
Transportation Mechanics Analysis", sections 2.1-2.4, cited below as the report)
------------------------------------------------------------------------------------
SineWaveform
    x_s = amp_t sin(2 pi f t), z_s = amp_n sin(2 pi f t + phase) (report 2.2-2.4;
    `phase` is the lead of the normal motion; the report calls its delta a "lag"
    but writes a_ys = B sin(theta + delta), which is a lead: same as ours).
SquareWaveAccel
    square-wave acceleration on both axes, the same phase convention as the sine
    (report 2.2.1, Figures 4-7).
StickSlipWaveform
    asymmetric two-phase in-plane waveform (report 2.1, Figure 1; Reznik & Canny,
    Quaid): forward acceleration the part can follow, short backward
    acceleration it cannot.
CoulombPumpWaveform
    in-plane waveform of report 2.1, Figure 2: long constant forward velocity,
    quick reversal (B) and quick re-acceleration (C).
PiecewiseConstantAccel
    any periodic piecewise-constant acceleration (the three above are built on it).
SampledWaveform
    any periodic motion given as displacement samples; periodic cubic spline
    (C2: acceleration continuous and piecewise linear).

Drives along the track only (z_s = 0)
-------------------------------------
PolynomialSurface
    a piecewise polynomial position (scipy ``PPoly``, optionally repeated with
    a period); velocity and acceleration are its exact derivatives and its
    pieces are exact (polynomial intervals split at the roots of the jerk).
    The measured platform motion (``replay.trials.fit_position``) and the
    two-level drive (``two_level_drive``) are such surfaces.
CallableSurface
    any three callables, with optional ``breakpoints`` (acceleration jumps)
    and ``turning_points`` (acceleration extrema). With turning points the
    monotone cut is exact; without, the acceleration is assumed monotone
    between samples ``max_step`` apart (an excursion out of the stick band
    shorter than ``max_step`` could be missed; make it smaller if the drive
    has such features). ``sine_drive`` builds the harmonic one.

Level crossings are analytic for the sine, trivial for constant pieces and
linear pieces (spline); the generic fallback brackets sign changes. Pieces are
exact for polynomials and drives with turning points, sampled (period/256)
otherwise.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline, PPoly
from scipy.optimize import brentq

from .constants import TWO_PI, G

__all__ = [
    "SurfaceMotion",
    "Pieces",
    "SineWaveform",
    "PiecewiseConstantAccel",
    "SquareWaveAccel",
    "StickSlipWaveform",
    "CoulombPumpWaveform",
    "SampledWaveform",
    "PolynomialSurface",
    "CallableSurface",
    "sine_drive",
    "two_level_drive",
    "two_level_down_time",
]


@dataclass(frozen=True)
class Pieces:
    """Along-track motion over a window, cut where the acceleration may turn or jump.

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


def _repeat(times: np.ndarray, period: float | None, t0: float, t1: float) -> np.ndarray:
    """Times of one period (from 0) repeated over every period touching [t0, t1]."""
    if period is None or times.size == 0:
        return times
    k = np.arange(math.floor(t0 / period) - 1, math.floor(t1 / period) + 2)
    return (times[None, :] + period * k[:, None]).ravel()


def sampled_pieces(position: Callable, velocity: Callable, acceleration: Callable,
                   t0: float, t1: float, breakpoints=(), turning_points=None,
                   period: float | None = None, max_step: float | None = None) -> Pieces:
    """Pieces of a one-axis motion given as callables (vectorised over t).

    ``breakpoints`` (acceleration jumps) and ``turning_points`` (acceleration
    extrema) are those of one period, from 0, if ``period`` is given. Without
    turning points the acceleration is sampled every ``max_step`` (default:
    period/256, or the window/4096) and assumed monotone in between.
    """
    if not t1 > t0:
        raise ValueError(f"empty time window [{t0}, {t1}]")
    breaks = _repeat(np.asarray(breakpoints, dtype=float).ravel(), period, t0, t1)
    breaks = breaks[(breaks >= t0) & (breaks <= t1)]
    extra = [breaks]
    if turning_points is not None:
        extra.append(_repeat(np.asarray(turning_points, dtype=float).ravel(), period, t0, t1))
    else:
        step = max_step or ((period / 256) if period else (t1 - t0) / 4096)
        n = max(1, math.ceil((t1 - t0) / step))
        extra.append(np.linspace(t0, t1, n + 1))
    edges = _unique_sorted(np.concatenate(extra), t0, t1)
    # Which edges are jumps: one-sided accelerations are taken a hair
    # inside the piece there (the callable's value at the jump is one side).
    near = np.zeros(len(edges), dtype=bool)
    if breaks.size:
        idx = np.searchsorted(edges, breaks).clip(0, len(edges) - 1)
        # The merge of near-duplicates may have kept an edge a few ulps before the break
        # (a sample) instead of the break: the jump is at whichever neighbour is nearer.
        prev = np.maximum(idx - 1, 0)
        idx = np.where(np.abs(edges[prev] - breaks) < np.abs(edges[idx] - breaks), prev, idx)
        near[idx[np.isclose(edges[idx], breaks, rtol=0, atol=1e-12 * max(1.0, t1))]] = True
    length = np.diff(edges)
    eps = np.maximum(1e-9 * length, 4 * np.spacing(np.maximum(abs(edges[1:]), 1.0)))
    ts = np.where(near[:-1], edges[:-1] + eps, edges[:-1])
    te = np.where(near[1:], edges[1:] - eps, edges[1:])
    lo_list, hi_list = ts.tolist(), te.tolist()

    def local(i: int, t: float, nu: int) -> float:
        if nu == 2:
            t = min(max(t, lo_list[i]), hi_list[i])
            return float(acceleration(t))
        return float((position, velocity)[nu](t))

    def vector(f, t):
        return np.asarray(f(np.asarray(t, dtype=float)), dtype=float)

    return Pieces(edges=edges, v=vector(velocity, edges), a_start=vector(acceleration, ts),
                  a_end=vector(acceleration, te), local=local)


class SurfaceMotion:
    """Base class of surface motions (the protocol of the module docstring).

    Periodic subclasses set ``period`` [s] and implement ``_eval(tau, order)``
    returning the (x, z) derivatives of order 0, 1 or 2 at phase times tau in
    [0, period); others override ``_call(t, order)``.
    """

    period: float | None = None

    # -- evaluation -------------------------------------------------------
    def _eval(self, tau: np.ndarray, order: int):
        raise NotImplementedError

    _eval_scalar = None   # optional fast path: (t: float, order) -> (x, z) floats

    def _call(self, t, order):
        if self._eval_scalar is not None and isinstance(t, (float, int, np.floating)):
            return self._eval_scalar(float(t), order)
        t = np.asarray(t, dtype=float)
        x, z = self._eval(self._phase_time(t), order)
        if t.ndim == 0:
            return float(x), float(z)
        return x, z

    def _phase_time(self, t):
        return np.mod(t, self.period)

    def position(self, t):
        """Surface position (x_s, z_s) [m] at time(s) t [s]."""
        return self._call(t, 0)

    def velocity(self, t):
        """Surface velocity (v_x, v_z) [m/s] at time(s) t [s]."""
        return self._call(t, 1)

    def acceleration(self, t):
        """Surface acceleration (a_x, a_z) [m/s^2] at time(s) t [s].

        At a breakpoint of a piecewise motion the right-hand (later) value is
        returned.
        """
        return self._call(t, 2)

    @property
    def freq(self) -> float:
        """Fundamental frequency [Hz]."""
        return 1.0 / self._period()

    def _period(self) -> float:
        if self.period is None:
            raise ValueError(f"{type(self).__name__} is not periodic")
        return self.period

    # -- structure --------------------------------------------------------
    def _edges(self) -> np.ndarray:
        """Breakpoints: within one period, in [0, period), or absolute times if
        not periodic. Smooth motions: none."""
        return np.empty(0)

    def breakpoints(self, t0: float, t1: float) -> np.ndarray:
        """Sorted times in (t0, t1) [s] between which the motion is smooth.

        For piecewise motions these are where the acceleration may jump
        (or, for splines, where its slope jumps); empty for smooth ones.
        """
        edges = self._edges()
        if edges.size == 0 or t1 <= t0:
            return np.empty(0)
        T = self.period
        if T is None:
            eps = 1e-12 * (t1 - t0)
            return np.sort(edges[(edges > t0 + eps) & (edges < t1 - eps)])
        k0 = math.floor(t0 / T) - 1
        k1 = math.floor(t1 / T) + 1
        ks = np.arange(k0, k1 + 1)
        out = (ks[:, None] * T + edges[None, :]).ravel()
        eps = 1e-12 * T
        return np.sort(out[(out > t0 + eps) & (out < t1 - eps)])

    def next_breakpoint(self, t: float) -> float:
        """First breakpoint after t [s] (by more than 1e-12 period), +inf if smooth."""
        edges = self._edges()
        if edges.size == 0:
            return math.inf
        T = self.period
        if T is None:
            later = edges[edges > t + 1e-12 * max(1.0, abs(t))]
            return float(later.min()) if later.size else math.inf
        lim = t + 1e-12 * T
        k = math.floor(t / T) - 1
        while True:                      # at most three passes (rounding of t / T)
            base = k * T
            i = int(np.searchsorted(edges, lim - base, side="right"))
            if i < edges.size and base + edges[i] > lim:
                return base + float(edges[i])
            k += 1

    def accel_roots(self, cx: float, cz: float, level: float, t0: float, t1: float) -> np.ndarray:
        """Times in (t0, t1] where cx*a_x(t) + cz*a_z(t) = level.

        Assumes [t0, t1] lies inside one smooth piece. This generic version
        brackets sign changes on 400 samples per period (or per window) and
        refines them with brentq (it can miss a pair of roots closer than the
        sampling step); the concrete motions below override it with exact
        solutions where they have them.
        """
        span = self.period or (t1 - t0)
        n = max(8, int(math.ceil(400 * (t1 - t0) / span)))
        ts = np.linspace(t0, t1, n + 1)

        def f(t):
            ax, az = self.acceleration(t)
            return cx * ax + cz * az - level

        fs = f(ts)
        roots = []
        for a, b, fa, fb in zip(ts[:-1], ts[1:], fs[:-1], fs[1:]):
            if fb == 0.0:
                roots.append(b)
            elif fa * fb < 0.0:
                roots.append(brentq(f, a, b, xtol=1e-15 * span))
        return np.asarray(roots)

    def pieces(self, t0: float, t1: float) -> Pieces:
        """The along-track motion over [t0, t1] cut into monotone pieces.

        Generic version: the breakpoints are piece edges and the acceleration
        is sampled every period/256 in between (see ``sampled_pieces``).
        """
        return sampled_pieces(lambda t: self.position(t)[0], lambda t: self.velocity(t)[0],
                              lambda t: self.acceleration(t)[0], t0, t1,
                              breakpoints=self._edges(), period=self.period)

    def max_speed(self) -> float:
        """Largest surface speed |v| over a period [m/s] (sampled, for scales)."""
        ts = np.linspace(0.0, self._period(), 1025)
        vx, vz = self.velocity(ts)
        return float(np.max(np.hypot(vx, vz)))

    def max_abs_acceleration(self):
        """(max |a_x|, max |a_z|) over a period [m/s^2] (sampled at 4097 points)."""
        ts = np.linspace(0.0, self._period(), 4097)
        ax, az = self.acceleration(ts)
        return float(np.max(np.abs(ax))), float(np.max(np.abs(az)))


# ---------------------------------------------------------------------------
class SineWaveform(SurfaceMotion):
    """Sinusoidal surface motion on both axes (report 2.3, 2.4).

    x_s(t) = amp_t sin(w t),  z_s(t) = amp_n sin(w t + phase),  w = 2 pi freq.

    Parameters
    ----------
    freq : float
        Frequency [Hz].
    amp_t, amp_n : float
        Tangential and normal displacement amplitudes [m].
    phase : float
        Lead of the normal motion over the tangential one [deg].
    """

    def __init__(self, freq: float, amp_t: float, amp_n: float, phase: float = 0.0):
        if freq <= 0:
            raise ValueError("freq must be positive")
        self.period = 1.0 / freq
        self.omega = TWO_PI * freq
        self.amp_t = float(amp_t)
        self.amp_n = float(amp_n)
        self.phase = float(phase)
        self._phi = math.radians(phase)

    @classmethod
    def from_gamma(cls, freq: float, gamma_n: float, gamma_t: float = 0.0,
                   phase: float = 0.0, g: float = G) -> SineWaveform:
        """Build from dimensionless peak accelerations Gamma = amp w^2 / g.

        gamma_n, gamma_t : normal and tangential Gamma [-]; g [m/s^2].
        """
        w2 = (TWO_PI * freq) ** 2
        return cls(freq, gamma_t * g / w2, gamma_n * g / w2, phase)

    def gamma(self, g: float = G) -> float:
        """Normal Gamma = amp_n w^2 / g [-]."""
        return self.amp_n * self.omega ** 2 / g

    def _phase_time(self, t):
        return t  # analytic in t: no reduction needed (keeps full precision)

    def _eval(self, t, order):
        w, p = self.omega, self._phi
        a = w * t
        if order == 0:
            return self.amp_t * np.sin(a), self.amp_n * np.sin(a + p)
        if order == 1:
            return self.amp_t * w * np.cos(a), self.amp_n * w * np.cos(a + p)
        return -self.amp_t * w * w * np.sin(a), -self.amp_n * w * w * np.sin(a + p)

    def _eval_scalar(self, t, order):
        w, a = self.omega, self.omega * t
        b = a + self._phi
        if order == 0:
            return self.amp_t * math.sin(a), self.amp_n * math.sin(b)
        if order == 1:
            return self.amp_t * w * math.cos(a), self.amp_n * w * math.cos(b)
        return -self.amp_t * w * w * math.sin(a), -self.amp_n * w * w * math.sin(b)

    def accel_roots(self, cx, cz, level, t0, t1):
        # cx a_x + cz a_z = -w^2 Im[(cx A_t + cz A_n e^{i p}) e^{i w t}] = -w^2 R sin(w t + psi)
        w = self.omega
        lead = complex(math.cos(self._phi), math.sin(self._phi))
        c = complex(cx * self.amp_t, 0.0) + cz * self.amp_n * lead
        R = abs(c)
        if R * w * w <= 1e-300:
            return np.empty(0)
        psi = math.atan2(c.imag, c.real)
        s = -level / (w * w * R)
        if abs(s) > 1.0:
            return np.empty(0)
        base = [math.asin(s)]
        if abs(s) < 1.0:
            base.append(math.pi - base[0])
        out = []
        for b in base:
            # w t + psi = b + 2 pi k
            k0 = math.floor((w * t0 + psi - b) / TWO_PI)
            for k in range(k0, k0 + int((t1 - t0) * w / TWO_PI) + 3):
                t = (b + TWO_PI * k - psi) / w
                if t0 < t <= t1:
                    out.append(t)
        return np.sort(np.asarray(out))

    def max_speed(self):
        return self.omega * math.hypot(self.amp_t, self.amp_n)

    def max_abs_acceleration(self):
        w2 = self.omega ** 2
        return self.amp_t * w2, self.amp_n * w2


# ---------------------------------------------------------------------------
class PiecewiseConstantAccel(SurfaceMotion):
    """Periodic surface motion with piecewise-constant acceleration.

    Parameters
    ----------
    durations : sequence of float
        Durations of the pieces [s]; their sum is the period.
    acc_x, acc_z : sequence of float
        Accelerations on each piece [m/s^2]. The velocity change over a period
        must vanish on both axes (sum a_i d_i = 0), else the motion is not
        periodic.

    The velocity and displacement integration constants are chosen so that
    both have zero mean over a period (the surface oscillates about a fixed
    mean position).
    """

    def __init__(self, durations, acc_x, acc_z=None):
        d = np.asarray(durations, dtype=float)
        ax = np.asarray(acc_x, dtype=float)
        az = np.zeros_like(ax) if acc_z is None else np.asarray(acc_z, dtype=float)
        if not (d.shape == ax.shape == az.shape) or d.ndim != 1:
            raise ValueError("durations, acc_x, acc_z must be 1-D of equal length")
        if np.any(d < 0) or d.sum() <= 0:
            raise ValueError("durations must be non-negative with a positive sum")
        keep = d > 0
        d, ax, az = d[keep], ax[keep], az[keep]
        self.period = float(d.sum())
        self.durations = d
        self.acc = np.vstack([ax, az])                 # (2, n)
        self.starts = np.concatenate([[0.0], np.cumsum(d)[:-1]])
        scale = np.abs(self.acc).max(initial=0.0) * self.period + 1e-300
        dv = self.acc @ d
        if np.any(np.abs(dv) > 1e-9 * scale):
            raise ValueError(f"net velocity change per period {dv} must be zero")
        # velocity at piece starts with v(0)=0, then shift to zero mean
        v0 = np.concatenate([np.zeros((2, 1)), np.cumsum(self.acc * d, axis=1)[:, :-1]], axis=1)
        mean_v = (v0 * d + 0.5 * self.acc * d ** 2).sum(axis=1) / self.period
        v0 = v0 - mean_v[:, None]
        x0 = np.concatenate([np.zeros((2, 1)),
                             np.cumsum(v0 * d + 0.5 * self.acc * d ** 2, axis=1)[:, :-1]], axis=1)
        mean_x = (x0 * d + 0.5 * v0 * d ** 2 + self.acc * d ** 3 / 6.0).sum(axis=1) / self.period
        self.v0 = v0
        self.x0 = x0 - mean_x[:, None]
        # plain-float copies for the scalar fast path
        self._starts_list = self.starts.tolist()
        self._acc_list = [tuple(c) for c in self.acc.T.tolist()]
        self._v0_list = [tuple(c) for c in self.v0.T.tolist()]
        self._x0_list = [tuple(c) for c in self.x0.T.tolist()]

    def _edges(self):
        return self.starts.copy()

    def _phase_time(self, t):
        tau = np.mod(t, self.period)
        # a time a hair before the period end belongs to the next period's first piece
        return np.where(tau > self.period * (1 - 1e-12), 0.0, tau)

    def _index(self, tau):
        # right-continuous; a time within 1e-12 T before an edge counts as after it
        i = np.searchsorted(self.starts, tau + 1e-12 * self.period, side="right") - 1
        return np.clip(i, 0, self.starts.size - 1)

    def _eval(self, tau, order):
        i = self._index(tau)
        s = tau - self.starts[i]
        s = np.maximum(s, 0.0)
        a = self.acc[:, i]
        if order == 2:
            return a[0], a[1]
        v = self.v0[:, i] + a * s
        if order == 1:
            return v[0], v[1]
        x = self.x0[:, i] + self.v0[:, i] * s + 0.5 * a * s * s
        return x[0], x[1]

    def _eval_scalar(self, t, order):
        T = self.period
        tau = t % T
        if tau > T * (1 - 1e-12):
            tau = 0.0
        i = max(bisect.bisect_right(self._starts_list, tau + 1e-12 * T) - 1, 0)
        ax, az = self._acc_list[i]
        if order == 2:
            return ax, az
        s = max(tau - self._starts_list[i], 0.0)
        vx, vz = self._v0_list[i]
        if order == 1:
            return vx + ax * s, vz + az * s
        x0, z0 = self._x0_list[i]
        return x0 + vx * s + 0.5 * ax * s * s, z0 + vz * s + 0.5 * az * s * s

    def accel_roots(self, cx, cz, level, t0, t1):
        # constant inside a smooth piece: a level is either never or always met
        return np.empty(0)

    def max_speed(self):
        # velocity is piecewise linear: extremes at the piece starts
        return float(np.max(np.hypot(self.v0[0], self.v0[1])))

    def max_abs_acceleration(self):
        return float(np.abs(self.acc[0]).max()), float(np.abs(self.acc[1]).max())


class SquareWaveAccel(PiecewiseConstantAccel):
    """Square-wave acceleration on both axes (report 2.2.1 and 2.2.2, Figures 4-7).

    a_x(t) = -acc_t sign(sin(w t)),  a_z(t) = -acc_n sign(sin(w t + phase)),
    i.e. the bang-bang counterpart of SineWaveform with the same phase
    convention (normal leads tangential by `phase` [deg]).

    Parameters: freq [Hz], acc_t and acc_n acceleration amplitudes [m/s^2],
    phase [deg].
    """

    def __init__(self, freq: float, acc_t: float, acc_n: float, phase: float = 0.0):
        T = 1.0 / freq
        # sign changes of sin(w t) at 0, T/2; of sin(w t + phase) at -phase/w, -phase/w + T/2
        frac = (-phase / 360.0) % 1.0
        fr = np.unique(np.round(np.array([0.0, 0.5, frac, (frac + 0.5) % 1.0]), 13) % 1.0)
        edges = fr * T
        d = np.diff(np.concatenate([edges, [T]]))
        mids = edges + 0.5 * d
        w = TWO_PI * freq
        ax = -acc_t * np.sign(np.sin(w * mids))
        az = -acc_n * np.sign(np.sin(w * mids + math.radians(phase)))
        super().__init__(d, ax, az)
        self.acc_t, self.acc_n, self.phase = float(acc_t), float(acc_n), float(phase)


class StickSlipWaveform(PiecewiseConstantAccel):
    """Asymmetric in-plane stick-slip waveform (report 2.1, Figure 1).

    The surface accelerates forward at a_forward for t_f (gentle enough for the
    part to follow, a_forward <= mu_s g), then backward at -a_backward for t_b
    (too hard to follow, a_backward > mu_s g), with a_forward t_f = a_backward t_b.
    Its velocity is an asymmetric triangle of zero mean between -v_peak and
    +v_peak, v_peak = a_forward t_f / 2 [m/s]. No normal motion.

    Parameters
    ----------
    freq : float
        Frequency [Hz].
    a_forward, a_backward : float
        Magnitudes of the forward and backward accelerations [m/s^2].
    Use ``from_peak_speed`` to give the peak speed and the forward-time fraction.
    """

    def __init__(self, freq: float, a_forward: float, a_backward: float):
        if a_forward <= 0 or a_backward <= 0:
            raise ValueError("accelerations must be positive")
        T = 1.0 / freq
        t_f = T * a_backward / (a_forward + a_backward)
        super().__init__([t_f, T - t_f], [a_forward, -a_backward])
        self.a_forward, self.a_backward = float(a_forward), float(a_backward)
        self.peak_speed = 0.5 * a_forward * t_f

    @classmethod
    def from_peak_speed(cls, freq: float, peak_speed: float, forward_fraction: float):
        """Stick-slip waveform of given peak speed [m/s] and forward-time fraction t_f/T in (0, 1)."""
        if not 0 < forward_fraction < 1:
            raise ValueError("forward_fraction must be in (0, 1)")
        T = 1.0 / freq
        dv = 2.0 * peak_speed
        return cls(freq, dv / (forward_fraction * T), dv / ((1 - forward_fraction) * T))


class CoulombPumpWaveform(PiecewiseConstantAccel):
    """In-plane Coulomb-pump waveform as described in report 2.1, Figure 2.

    Phase A: constant forward velocity +peak_speed (zero acceleration) for t_A;
    phase B: deceleration -accel for t_B down to -v_back;
    phase C: re-acceleration +accel for t_B back to +peak_speed.
    Zero mean velocity fixes t_B = sqrt(peak_speed T / accel) and
    v_back = accel t_B - peak_speed; it requires peak_speed <= accel T / 4
    (at equality t_A = 0 and the waveform becomes a symmetric triangle).

    Parameters: freq [Hz], peak_speed [m/s], accel [m/s^2]. No normal motion.
    """

    def __init__(self, freq: float, peak_speed: float, accel: float):
        T = 1.0 / freq
        if peak_speed <= 0 or accel <= 0:
            raise ValueError("peak_speed and accel must be positive")
        if peak_speed > accel * T / 4 * (1 + 1e-12):
            raise ValueError("peak_speed must be <= accel / (4 freq)")
        t_b = math.sqrt(peak_speed * T / accel)
        t_a = max(T - 2 * t_b, 0.0)
        super().__init__([t_a, t_b, t_b], [0.0, -accel, accel])
        self.peak_speed, self.accel = float(peak_speed), float(accel)
        self.back_speed = accel * t_b - peak_speed
        self.forward_fraction = t_a / T


# ---------------------------------------------------------------------------
class SampledWaveform(SurfaceMotion):
    """Periodic surface motion given by displacement samples.

    Parameters
    ----------
    period : float
        Period [s].
    x_samples, z_samples : array_like
        Displacements [m] at times k*period/N, k = 0..N-1 (one period, the
        sample at t = period is implied equal to the first one).

    Interpolant: periodic cubic spline of the displacement (scipy CubicSpline,
    bc_type='periodic'): C2, so the acceleration is continuous and piecewise
    linear; the knots are returned as breakpoints (jerk jumps there) and the
    level crossings of the acceleration are solved exactly on each piece.
    The mean velocity of the interpolant is zero by construction.
    """

    def __init__(self, period: float, x_samples, z_samples=None):
        x = np.asarray(x_samples, dtype=float)
        z = np.zeros_like(x) if z_samples is None else np.asarray(z_samples, dtype=float)
        if x.ndim != 1 or x.shape != z.shape or x.size < 4:
            raise ValueError("need at least 4 samples per axis, equal lengths")
        self.period = float(period)
        n = x.size
        self.knots = np.arange(n + 1) * (self.period / n)
        y = np.vstack([np.append(x, x[0]), np.append(z, z[0])]).T
        self._spline = CubicSpline(self.knots, y, bc_type="periodic", axis=0)

    def _edges(self):
        return self.knots[:-1].copy()

    def _eval(self, tau, order):
        y = self._spline(tau, order)
        return y[..., 0], y[..., 1]

    def accel_roots(self, cx, cz, level, t0, t1):
        # acceleration is linear inside a knot interval
        ax0, az0 = self.acceleration(t0)
        ax1, az1 = self.acceleration(t1)   # continuous: no one-sided limits needed
        f0 = cx * ax0 + cz * az0 - level
        f1 = cx * ax1 + cz * az1 - level
        if f0 == f1 or f0 * f1 > 0:
            return np.empty(0) if f1 != 0 else np.array([t1])
        r = t0 + (t1 - t0) * f0 / (f0 - f1)
        return np.array([r]) if t0 < r <= t1 else np.empty(0)


# ---------------------------------------------------------------------------
class PolynomialSurface(SurfaceMotion):
    """Along-track drive whose position is a piecewise polynomial (exact derivatives).

    ``pp`` is a scipy ``PPoly`` (or anything ``PPoly.from_spline`` accepts,
    e.g. a ``BSpline``) of x_s(t); z_s = 0. With ``period`` the polynomial
    must span exactly one period, [pp.x[0], pp.x[0] + period], and is
    repeated for all t; without, evaluation outside [pp.x[0], pp.x[-1]]
    raises ``ValueError``.
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
                    f"{float(x[-1] - x[0])!r} s, period {float(period)!r} s")
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

    def _call(self, t, order):
        x = self._derivs[order](self._reduce(t))
        return x, np.zeros_like(x)

    def _edges(self) -> np.ndarray:
        if self.period is None:
            return self._x.copy()
        return np.unique(np.mod(self._x, self.period))

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


class CallableSurface(SurfaceMotion):
    """Along-track drive given as three callables of time (x_s, v_x, a_x; z_s = 0).

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
        self._x, self._v, self._a = position, velocity, acceleration
        self.period = None if period is None else float(period)
        self._breaks = np.asarray(breakpoints, dtype=float).ravel()
        self._turns = None if turning_points is None else np.asarray(
            turning_points, dtype=float).ravel()
        self.max_step = max_step

    def _call(self, t, order):
        f = (self._x, self._v, self._a)[order]
        x = np.asarray(f(np.asarray(t, dtype=float)), dtype=float)
        return x, np.zeros_like(x)

    def _edges(self) -> np.ndarray:
        return np.unique(self._breaks)

    def pieces(self, t0: float, t1: float) -> Pieces:
        return sampled_pieces(self._x, self._v, self._a, t0, t1, breakpoints=self._breaks,
                              turning_points=self._turns, period=self.period,
                              max_step=self.max_step)


def sine_drive(amplitude: float, frequency: float, phase: float = 0.0) -> CallableSurface:
    """x_s = A sin(2 pi f t + phase): the usual harmonic drive [m, Hz, rad]."""
    if not (amplitude >= 0 and frequency > 0):
        raise ValueError("sine drive needs amplitude >= 0 and frequency > 0")
    w = TWO_PI * frequency
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
    too) and the position is piecewise quadratic with x_s(0) = 0.
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
