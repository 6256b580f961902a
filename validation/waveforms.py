"""Periodic surface motions for the single-part transport models.

Surface frame (project convention): x along the track, z normal to the surface.
Every waveform gives the surface displacement, velocity and acceleration along x
and z at time t [s] (vectorised over t), its period [s], and the breakpoints
between which it is smooth, so that event finding never steps over a jump of
acceleration. All quantities are SI: m, m/s, m/s^2.

Waveforms provided
------------------
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

Every waveform also answers `accel_roots(cx, cz, level, t0, t1)`: the times in
(t0, t1] where cx a_x(t) + cz a_z(t) = level, for a window inside one smooth
piece. The transport model needs exactly these: loss of contact
(a_z = -g cos beta), the friction-cone boundaries and the turning points of the
relative velocity are all level crossings of a linear combination of the two
accelerations. They are analytic for the sine, trivial for constant pieces and
linear pieces (spline).
"""

from __future__ import annotations

import bisect
import math

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

TWO_PI = 2.0 * math.pi


class Waveform:
    """Base class of periodic surface motions.

    Subclasses set ``period`` [s] and implement ``_eval(tau, order)`` returning
    (x, z) derivatives of order 0, 1 or 2 at phase times tau in [0, period).
    """

    period: float

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

    def displacement(self, t):
        """Surface displacement (x_s, z_s) [m] at time(s) t [s]."""
        return self._call(t, 0)

    def velocity(self, t):
        """Surface velocity (v_x, v_z) [m/s] at time(s) t [s]."""
        return self._call(t, 1)

    def acceleration(self, t):
        """Surface acceleration (a_x, a_z) [m/s^2] at time(s) t [s].

        At a breakpoint of a piecewise waveform the right-hand (later) value is
        returned.
        """
        return self._call(t, 2)

    @property
    def freq(self) -> float:
        """Fundamental frequency [Hz]."""
        return 1.0 / self.period

    # -- structure --------------------------------------------------------
    def _edges(self) -> np.ndarray:
        """Breakpoints within one period, in [0, period). Smooth waveforms: none."""
        return np.empty(0)

    def breakpoints(self, t0: float, t1: float) -> np.ndarray:
        """Sorted times in (t0, t1) [s] between which the waveform is smooth.

        For piecewise waveforms these are where the acceleration may jump
        (or, for the spline, where its slope jumps); empty for smooth ones.
        """
        edges = self._edges()
        if edges.size == 0 or t1 <= t0:
            return np.empty(0)
        T = self.period
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
        brackets sign changes on 400 samples per period and refines them with
        brentq (it can miss a pair of roots closer than the sampling step);
        the concrete waveforms below override it with exact solutions.
        """
        n = max(8, int(math.ceil(400 * (t1 - t0) / self.period)))
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
                roots.append(brentq(f, a, b, xtol=1e-15 * self.period))
        return np.asarray(roots)

    def max_speed(self) -> float:
        """Largest surface speed |v| over a period [m/s] (sampled, for scales)."""
        ts = np.linspace(0.0, self.period, 1025)
        vx, vz = self.velocity(ts)
        return float(np.max(np.hypot(vx, vz)))

    def max_abs_acceleration(self):
        """(max |a_x|, max |a_z|) over a period [m/s^2] (sampled at 4097 points)."""
        ts = np.linspace(0.0, self.period, 4097)
        ax, az = self.acceleration(ts)
        return float(np.max(np.abs(ax))), float(np.max(np.abs(az)))


# ---------------------------------------------------------------------------
class SineWaveform(Waveform):
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
                   phase: float = 0.0, g: float = 9.81) -> "SineWaveform":
        """Build from dimensionless peak accelerations Gamma = amp w^2 / g.

        gamma_n, gamma_t : normal and tangential Gamma [-]; g [m/s^2].
        """
        w2 = (TWO_PI * freq) ** 2
        return cls(freq, gamma_t * g / w2, gamma_n * g / w2, phase)

    def gamma(self, g: float = 9.81) -> float:
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
        c = complex(cx * self.amp_t, 0.0) + cz * self.amp_n * complex(math.cos(self._phi), math.sin(self._phi))
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
class PiecewiseConstantAccel(Waveform):
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
class SampledWaveform(Waveform):
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
