"""Vertical vibratory transport: a part squeezed against a vertically moving surface.

Model of Yako, Nowak, Yuan & Salisbury, "Vertical Vibratory Transport of
Grasped Parts Using Impacts" (ICRA 2024), section "Dynamics". A part of mass m
is pressed with a normal force F_n against a surface moving vertically as
z_s(t), z up; Coulomb friction with static and kinetic coefficients
mu_s >= mu_k; gravity g. With A_s = mu_s F_n / m and A_k = mu_k F_n / m:

* sticking: z_p' = z_s', possible while  -A_s - g <= z_s'' <= A_s - g;
* slipping: z_p'' = A_k sgn(z_s' - z_p') - g.

The surface is any ``SurfaceMotion`` (``vibrofeed.models.surface``); its
along-track coordinate x is the z here, as in the decks, where a wall at
incline = 90 moves up along x.

Events are located exactly, not by a fixed-step check. The surface is cut into
pieces on which its acceleration is continuous and monotone
(``SurfaceMotion.pieces``). While stuck, leaving the stick band is a level
crossing of z_s'' (at most one per piece). While slipping, the part's
acceleration a_p is constant, so its motion is an exact parabola and the
relative velocity w = z_s' - z_p' has w' = z_s'' - a_p: w is unimodal on each
piece, its extremum is a level crossing of z_s'', and its return to zero is a
bracketed root (``roots.stick_exit``, ``roots.slip_end``). All roots are
refined by Brent's method to ~1e-14 s on the surface's own (analytic or
piecewise-polynomial) formulas.

Transitions:

* stick -> slip when z_s'' leaves the band: above it the surface outruns
  the part (slip with sgn = +1), below it the surface drops away (sgn = -1);
* slip -> stick when w returns to zero and z_s'' is inside the band there;
  if it is outside, the part keeps slipping with the sign set by the side
  (``roots.stick_decision``).

Feasibility (Yako et al., section "Vertical Vibratory Transport Is
Difficult"): holding the part on a surface at rest needs F_n > m g / mu_s, and
making it slip downwards needs a surface acceleration beyond the lower band
edge, a_max > mu_s F_n / m + g, which then exceeds 2 g; ``check_feasible``
tests both and says which fails and by how much.

The two-level drive (``surface.two_level_drive``) has a closed-form
transport rate, derived in ``two_level_transport``; the event-driven model is
tested against it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .constants import G
from .roots import slip_end, stick_decision, stick_exit
from .surface import CallableSurface, SurfaceMotion, two_level_down_time

__all__ = [
    "Contact",
    "Phase",
    "VerticalTrajectory",
    "PeriodicTransport",
    "TwoLevelTransport",
    "check_feasible",
    "as_surface",
    "simulate",
    "periodic_transport",
    "two_level_transport",
]


@dataclass(frozen=True)
class Contact:
    """Part and grasp: mass [kg], normal force [N], friction coefficients, g [m/s^2]."""

    mass: float
    normal_force: float
    mu_s: float
    mu_k: float
    g: float = G

    def __post_init__(self):
        values = dict(mass=self.mass, normal_force=self.normal_force, mu_s=self.mu_s,
                      mu_k=self.mu_k, g=self.g)
        for name, value in values.items():
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {float(value)}")
        if self.mass <= 0:
            raise ValueError(f"mass must be > 0, got {float(self.mass)}")
        if self.normal_force < 0 or self.mu_s < 0 or self.mu_k < 0 or self.g < 0:
            raise ValueError("normal_force, mu_s, mu_k and g must be >= 0")
        if self.mu_k > self.mu_s:
            # With mu_k > mu_s a part released at zero relative velocity would
            # slip with more friction than could hold it: no consistent Coulomb law.
            raise ValueError(f"need mu_k <= mu_s, got mu_k={float(self.mu_k)} > mu_s={float(self.mu_s)}")

    @property
    def stick_upper(self) -> float:
        """Largest surface acceleration the part can follow: mu_s F_n/m - g."""
        return self.mu_s * self.normal_force / self.mass - self.g

    @property
    def stick_lower(self) -> float:
        """Most negative surface acceleration the part can follow: -mu_s F_n/m - g."""
        return -self.mu_s * self.normal_force / self.mass - self.g

    def slip_acceleration(self, direction: int) -> float:
        """Part acceleration while slipping with sgn(z_s' - z_p') = direction."""
        return direction * self.mu_k * self.normal_force / self.mass - self.g


def check_feasible(mass: float, normal_force: float, mu_s: float, a_max: float,
                   g: float = G) -> dict:
    """Check the two necessary conditions of upward transport (Yako et al.).

    ``a_max`` is the largest downward surface acceleration magnitude
    [m/s^2]. Raises ``ValueError`` naming every bound that fails and by how
    much; otherwise returns the margins (positive numbers, same units).
    """
    if not (mass > 0 and mu_s > 0 and normal_force >= 0 and g > 0):
        raise ValueError("need mass > 0, mu_s > 0, normal_force >= 0, g > 0")
    failures = []
    f_min = mass * g / mu_s
    if not normal_force > f_min:
        short = f_min - normal_force
        failures.append(
            f"normal force too small: F_n = {normal_force:.4g} N must exceed "
            f"m g / mu_s = {f_min:.4g} N (short by {short:.3g} N, {100 * short / f_min:.1f} %); "
            f"the part slides down even on a surface at rest")
    a_min = mu_s * normal_force / mass + g
    if not a_max > a_min:
        short = a_min - a_max
        failures.append(
            f"peak surface acceleration too small: a_max = {a_max:.4g} m/s^2 "
            f"({a_max / g:.3g} g) must exceed mu_s F_n / m + g = {a_min:.4g} m/s^2 "
            f"({a_min / g:.3g} g) (short by {short:.3g} m/s^2, {short / g:.3g} g); "
            f"the surface cannot drop away from the part")
    if failures:
        raise ValueError("vertical transport infeasible: " + "; ".join(failures))
    return {"normal_force_margin": normal_force - f_min, "acceleration_margin": a_max - a_min}


@dataclass(frozen=True)
class Phase:
    """One stick or slip interval. Stuck: z_p = z_s + offset. Slip: a parabola."""

    t0: float
    t1: float
    stuck: bool
    z0: float
    v0: float
    accel: float  # part acceleration while slipping (unused when stuck)
    offset: float  # z_p - z_s while stuck (unused when slipping)


@dataclass
class VerticalTrajectory:
    """Part motion of the vertical model: exact phases plus arrays sampled at ``t``.

    ``t, z, v, stuck`` are the part's time [s], position [m], velocity [m/s]
    and stuck flag at the requested output times.
    """

    phases: list[Phase]
    surface: SurfaceMotion
    t: np.ndarray = field(default=None)
    z: np.ndarray = field(default=None)
    v: np.ndarray = field(default=None)
    stuck: np.ndarray = field(default=None)

    @property
    def t_start(self) -> float:
        return self.phases[0].t0

    @property
    def t_end(self) -> float:
        return self.phases[-1].t1

    def sample(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Part position, velocity and stuck flag at times t (within the run)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if t.size and (t.min() < self.t_start - 1e-12 or t.max() > self.t_end + 1e-12):
            raise ValueError("sample times outside the simulated interval")
        starts = np.array([p.t0 for p in self.phases])
        k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.phases) - 1)
        stuck = np.array([p.stuck for p in self.phases])[k]
        tau = t - starts[k]
        z0 = np.array([p.z0 for p in self.phases])[k]
        v0 = np.array([p.v0 for p in self.phases])[k]
        acc = np.array([p.accel for p in self.phases])[k]
        z = z0 + v0 * tau + 0.5 * acc * tau ** 2
        v = v0 + acc * tau
        if stuck.any():
            off = np.array([p.offset for p in self.phases])[k]
            z[stuck] = self.surface.position(t[stuck])[0] + off[stuck]
            v[stuck] = self.surface.velocity(t[stuck])[0]
        return z, v, stuck

    def stuck_time(self, t_a: float | None = None, t_b: float | None = None) -> float:
        """Time spent stuck within [t_a, t_b] (default: the whole run)."""
        t_a = self.t_start if t_a is None else t_a
        t_b = self.t_end if t_b is None else t_b
        return sum(max(0.0, min(p.t1, t_b) - max(p.t0, t_a)) for p in self.phases if p.stuck)

    @property
    def stuck_fraction(self) -> float:
        return self.stuck_time() / (self.t_end - self.t_start)

    def net_speed(self, period: float, skip_periods: int = 1) -> float:
        """Mean part velocity over whole periods, after ``skip_periods`` of transient."""
        n = math.floor((self.t_end - self.t_start) / period * (1 + 1e-12)) - skip_periods
        if n < 1:
            raise ValueError("run too short for one whole period after the transient")
        t_a = self.t_start + skip_periods * period
        t_b = t_a + n * period
        z, _, _ = self.sample([t_a, min(t_b, self.t_end)])
        return float(z[1] - z[0]) / (n * period)


def as_surface(motion):
    """A surface usable by ``simulate``.

    A ``SurfaceMotion`` passes through; any other object with ``position``,
    ``velocity`` and ``acceleration`` of one coordinate (callables of t) is
    wrapped as a ``CallableSurface`` using its optional ``breakpoints``,
    ``turning_points``, ``period`` and ``max_step`` attributes. A sampled
    measured motion becomes a surface through
    ``replay.trials.fit_position(t, z).surface``.
    """
    if isinstance(motion, SurfaceMotion):
        return motion
    missing = [n for n in ("position", "velocity", "acceleration") if not hasattr(motion, n)]
    if missing:
        raise TypeError(f"surface motion lacks {', '.join(missing)}")
    return CallableSurface(motion.position, motion.velocity, motion.acceleration,
                           breakpoints=getattr(motion, "breakpoints", ()),
                           turning_points=getattr(motion, "turning_points", None),
                           period=getattr(motion, "period", None),
                           max_step=getattr(motion, "max_step", None))


def simulate(surface, contact: Contact, t_end: float, t_start: float = 0.0,
             z0: float | None = None, v0: float | None = None, t_eval=None,
             max_phases: int = 1_000_000) -> VerticalTrajectory:
    """Part motion on ``surface`` over [t_start, t_end] with exact stick/slip events.

    ``surface``: a ``SurfaceMotion`` (its along-track axis), or any object
    with position, velocity and acceleration (see ``as_surface``). The part starts at z0
    (default: the surface position) with velocity v0 (default: the surface
    velocity). It starts stuck when v0 equals the surface velocity and the
    surface acceleration is inside the stick band. ``t_eval``: output times
    (default: 1001 uniform times plus every event).
    """
    if not t_end > t_start:
        raise ValueError(f"need t_end > t_start, got [{t_start}, {t_end}]")
    surface = as_surface(surface)
    P = surface.pieces(t_start, t_end)
    lo, hi = contact.stick_lower, contact.stick_upper
    tol = 1e-9 * (abs(lo) + abs(hi)) + 1e-12  # m/s^2, roundoff of a_s at an event
    t = float(t_start)
    z = float(surface.position(t)[0]) if z0 is None else float(z0)
    v_s = P.local(0, t, 1)
    v = v_s if v0 is None else float(v0)
    from_zero = abs(v - v_s) <= 1e-12 * max(1.0, abs(v_s))
    if from_zero:
        v = v_s
        mode = stick_decision(P, 0, t, lo, hi, tol)
    else:
        mode = 1 if v_s > v else -1
    i = 0
    phases: list[Phase] = []
    zero_length = 0
    while t < t_end:
        if len(phases) >= max_phases:
            raise RuntimeError(f"more than {max_phases} stick/slip phases")
        if mode == 0:
            offset = z - P.local(i, t, 0)
            hit = stick_exit(P, i, t, lo, hi, held=True)
            t1, j, side = (t_end, P.n - 1, 0) if hit is None else hit
            phases.append(Phase(t, t1, True, z, v, 0.0, offset))
            z, v = P.local(j, t1, 0) + offset, P.local(j, t1, 1)
            mode = side
            from_zero = True
        else:
            a_p = contact.slip_acceleration(mode)
            hit = slip_end(P, i, t, v, mode, a_p, tol, from_zero)
            t1, j = (t_end, P.n - 1) if hit is None else hit
            tau = t1 - t
            phases.append(Phase(t, t1, False, z, v, a_p, 0.0))
            z = z + v * tau + 0.5 * a_p * tau * tau
            v = P.local(j, t1, 1)  # equal velocities by definition of the event
            if hit is not None:
                if t1 >= P.edges[j + 1] and j + 1 < P.n:
                    j += 1  # decide with the acceleration after the edge
                mode = stick_decision(P, j, t1, lo, hi, tol)
            from_zero = True
        # Guard against chattering: many events at the same instant.
        zero_length = zero_length + 1 if t1 <= t else 0
        if zero_length > 4:
            raise RuntimeError(f"stick/slip chattering at t = {float(t)} s")
        t, i = t1, j
    if t_eval is None:
        grid = np.linspace(t_start, t_end, 1001)
        t_eval = np.unique(np.concatenate((grid, [p.t0 for p in phases], [t_end])))
    traj = VerticalTrajectory(phases=phases, surface=surface)
    traj.t = np.asarray(t_eval, dtype=float)
    traj.z, traj.v, traj.stuck = traj.sample(traj.t)
    return traj


@dataclass(frozen=True)
class PeriodicTransport:
    """Steady transport under a periodic drive."""

    net_speed: float  # m/s, mean part velocity over whole periods
    displacement_per_period: float  # m
    stuck_fraction: float  # of the averaged periods


def periodic_transport(surface, contact: Contact, n_periods: int = 4,
                       skip_periods: int = 1) -> PeriodicTransport:
    """Simulate ``n_periods`` of a periodic drive and average after the transient."""
    period = getattr(surface, "period", None)
    if not period:
        raise ValueError("periodic_transport needs a surface with a period")
    if n_periods <= skip_periods:
        raise ValueError("n_periods must exceed skip_periods")
    traj = simulate(surface, contact, t_end=n_periods * period, t_eval=[0.0])
    speed = traj.net_speed(period, skip_periods)
    t_a = skip_periods * period
    stuck = traj.stuck_time(t_a, n_periods * period) / ((n_periods - skip_periods) * period)
    return PeriodicTransport(speed, speed * period, stuck)


@dataclass(frozen=True)
class TwoLevelTransport:
    """Closed-form steady transport of the two-level drive (see two_level_transport)."""

    displacement_per_period: float  # m
    net_speed: float  # m/s
    stuck_fraction: float
    catch_delay: float  # s, from the end of the drop to re-sticking
    t_down: float  # s
    period: float  # s


def two_level_transport(a_up: float, t_up: float, a_down: float,
                        contact: Contact) -> TwoLevelTransport:
    """Closed-form net transport of the two-level drive (``two_level_drive``).

    Drive: z_s'' = +a_up for t_up, then -a_down for t_down = a_up t_up / a_down
    (zero mean acceleration: the surface velocity is periodic). Write
    A_s = mu_s F_n/m, A_k = mu_k F_n/m, and b = A_k + g.

    1. Slow rise. If a_up <= A_s - g the stick band holds the rise: a part
       stuck at its start rides along with the surface (else ValueError: this
       closed form does not cover slipping during the rise).
    2. No slip at all if a_down <= A_s + g: the drop stays inside the band,
       the part sticks forever and the net displacement is 0.
    3. Drop (a_down > A_s + g). At its start (tau = 0, both at velocity V)
       the surface falls away: sgn(z_s' - z_p') = -1, so the part accelerates
       at -A_k - g = -b. Relative velocity w = z_s' - z_p' = -(a_down - b) tau,
       negative through the whole drop since a_down > A_s + g >= b. At its end
       w_d = -(a_down - b) t_down.
    4. Catch. In the next rise w' = a_up + b > 0, so w = w_d + (a_up + b) tau'
       returns to 0 at tau_c = (a_down - b) t_down / (a_up + b). Since
       a_down t_down = a_up t_up, tau_c <= t_up <=> -b t_down <= b t_up, always
       true: the catch always happens within the next rise (never in the drop,
       where w keeps falling). There a_s = a_up lies in the band, so the part
       sticks until the next drop, and the cycle repeats exactly.
    5. Displacement. The part gains on the surface d(z_p - z_s)/dt = -w:
       during the drop  int_0^t_down (a_down - b) tau dtau
                        = (a_down - b) t_down^2 / 2,
       during the catch int_0^tau_c [(a_down - b) t_down - (a_up + b) tau'] dtau'
                        = (a_down - b)^2 t_down^2 / (2 (a_up + b)).
       The surface motion is periodic, so the part's net rise per period is
       the sum:  Delta = (a_down - b) t_down^2 (a_up + a_down) / (2 (a_up + b)),
       net speed Delta / T with T = t_up + t_down, stuck fraction
       (t_up - tau_c) / T.
    Started stuck at the beginning of a rise, the part follows this cycle
    from its first drop on: z_p(t + T) = z_p(t) + Delta for t >= t_up.
    """
    t_down = two_level_down_time(a_up, t_up, a_down)
    period = t_up + t_down
    if a_up > contact.stick_upper:
        raise ValueError(
            f"closed form needs sticking during the rise: a_up = {a_up:.4g} m/s^2 "
            f"exceeds mu_s F_n/m - g = {contact.stick_upper:.4g} m/s^2")
    if a_down <= -contact.stick_lower:
        return TwoLevelTransport(0.0, 0.0, 1.0, 0.0, t_down, period)
    b = contact.mu_k * contact.normal_force / contact.mass + contact.g
    catch = (a_down - b) * t_down / (a_up + b)
    delta = (a_down - b) * t_down ** 2 * (a_up + a_down) / (2.0 * (a_up + b))
    return TwoLevelTransport(delta, delta / period, (t_up - catch) / period, catch,
                             t_down, period)
