"""One rigid part on a vibrating surface: stick, slip and flight with exact events.

Implements the single-part kinematics of the report (Khan & Sarma, "Vibratory
Assembly Update: Part Transportation Mechanics Analysis", sections 2.1-2.4) for
any periodic surface motion of `vibrofeed.models.surface`, independent of
LIGGGHTS, so that DEM trajectories can be overlaid on it.

Model (SI units; surface frame x along the track, z normal to the surface)
--------------------------------------------------------------------------
* The frame is inertial and inclined by `incline` beta [deg] (positive =
  conveying uphill along +x); gravity is g(-sin beta, -cos beta).
* Normal force while in contact: N = m (g cos beta + a_n(t)), a_n = z_s''.
  Contact is lost (launch) when N would become negative. N/m is called n(t).
* Coulomb friction with static mu_s and kinetic mu_k (mu_k <= mu_s):
  stick while |a_t + g sin beta| <= mu_s n (the tangential force the part
  needs to follow the surface lies inside the friction cone; report 2.1,
  2.2.1 "friction envelope"); slip with friction -mu_k N sign(u), u = relative
  tangential velocity. Slip -> stick when u reaches 0 AND the stick condition
  holds; otherwise slip reverses.
* Flight: free parabola (the report's h_p has a sign slip on gravity, corrected
  here: gravity pulls towards -z).
* Impact (gap closing): Newton restitution on the normal relative velocity,
  w+ = -e w (e = 0 is the report's completely inelastic impact). Tangential
  impulse: impulsive Coulomb friction, |J_t| <= mu_k |J_n|: it stops the
  relative tangential velocity if it can, otherwise reduces it by mu_k J_n.
  The part slides, it does not roll.
* After an e = 0 impact the part stays on the surface if n > 0, otherwise it
  is launched again at once (report 2.3: impact while a_s < -g).
* Chattering (e > 0): each bounce returns with e times the speed. When the
  remaining sequence would end within `chatter_tol` periods, it is summed as a
  geometric series under the (then locally constant) relative normal
  acceleration n: remaining time 2 e |w| / (n (1 - e)), remaining normal
  impulse (1 + e) e |w| / (1 - e); the friction impulse of the remaining
  bounces (<= mu_k times that) is applied at once, and the part rests on the
  surface afterwards ('rest' event). The error is of order chatter_tol^2 in
  time; the summation is only used when no breakpoint and no loss of contact
  (n = 0) falls inside the summed interval.

Events are found by root isolation on the analytic trajectories (see
`vibrofeed.models.roots`): flight is a parabola against the surface motion,
stick follows the surface, slip has a closed form in the surface velocity and
displacement. No fixed time grid is used for events.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .constants import G
from .roots import MERGE, all_roots, first_descent, first_negative_interval
from .surface import SurfaceMotion

PHASES = ("stick", "slip", "flight")


@dataclass(frozen=True)
class PartParams:
    """Contact parameters of the part.

    mu_s, mu_k : static and kinetic friction coefficients [-], mu_k <= mu_s.
    e : coefficient of normal restitution [-], 0 <= e < 1.
    mass : part mass [kg] (only scales the reported forces; the kinematics do
        not depend on it for rigid contact).
    """

    mu_s: float
    mu_k: float
    e: float = 0.0
    mass: float = 1.0

    def __post_init__(self):
        if not 0.0 <= self.mu_k <= self.mu_s:
            raise ValueError("need 0 <= mu_k <= mu_s (kinetic friction cannot exceed static)")
        if not 0.0 <= self.e < 1.0:
            raise ValueError("need 0 <= e < 1")
        if self.mass <= 0:
            raise ValueError("mass must be positive")


@dataclass
class Event:
    """A transition of the part's state.

    t : time [s]; kind : 'launch', 'impact', 'rest' (end of a summed chattering
    sequence), 'stick' or 'slip'; x, z [m], vx, vz [m/s]: part state after the
    event; info: details (e.g. relative velocities before an impact, slip
    direction).
    """

    t: float
    kind: str
    x: float
    z: float
    vx: float
    vz: float
    info: dict = field(default_factory=dict)


@dataclass
class _Segment:
    t0: float
    t1: float
    mode: str          # 'stick', 'slip', 'flight' or 'chatter' (summed bounces)
    x0: float
    z0: float
    vx0: float
    vz0: float
    s: int = 0         # slip direction: sign of the relative velocity
    x1: float = 0.0    # chatter only: end state
    vx1: float = 0.0


class PartOnSurface:
    """Event-driven integrator of one part on a vibrating surface.

    Parameters
    ----------
    waveform : SurfaceMotion
        Periodic surface motion.
    part : PartParams
        Friction and restitution.
    incline : float
        Track inclination beta [deg], positive = conveying uphill along +x.
    g : float
        Gravitational acceleration [m/s^2].
    chatter_tol : float
        Sum the remaining bounces of a chattering sequence once they would
        end within this fraction of a period [-].
    record : bool
        Keep the trajectory segments (needed for dense output).

    Use `start()` to place the part, `run(t_end)` to integrate; the state is
    in the attributes t, x, z, vx, vz, mode and the history in `events`.
    """

    def __init__(self, waveform: SurfaceMotion, part: PartParams, incline: float = 0.0,
                 g: float = G, chatter_tol: float = 1e-6, record: bool = True):
        self.wf = waveform
        self.part = part
        self.incline = float(incline)
        self.g = float(g)
        beta = math.radians(incline)
        self.g_t = g * math.sin(beta)
        self.g_n = g * math.cos(beta)
        if self.g_n <= 0:
            raise ValueError("incline must be within (-90, 90) deg")
        self.T = waveform.period
        self.xtol = 1e-14 * self.T
        self.chatter_tol = chatter_tol
        self.record = record
        self.events: list[Event] = []
        self.segments: list[_Segment] = []
        self.t = math.nan
        self.n_events = 0

    # ---------------------------------------------------------------- helpers
    def _n(self, t):
        """Normal force per unit mass needed to follow the surface, n = g_n + a_n [m/s^2]."""
        return self.g_n + self.wf.acceleration(t)[1]

    def _emit(self, kind, **info):
        self.n_events += 1
        self.events.append(Event(self.t, kind, self.x, self.z, self.vx, self.vz, info))

    # ------------------------------------------------------------ placement
    def start(self, t0: float = 0.0, x: float | None = None, z: float | None = None,
              vx: float | None = None, vz: float | None = None):
        """Place the part at time t0 [s].

        Default: resting on the surface (x = x_s(t0), z = z_s(t0)) with the
        surface velocity. If z is given above the surface the part starts in
        flight with velocity (vx, vz) [m/s] (default: the surface velocity).
        """
        xs, zs = self.wf.position(t0)
        vt, vn = self.wf.velocity(t0)
        self.t = float(t0)
        self.x = xs if x is None else float(x)
        self.z = zs if z is None else float(z)
        self.vx = vt if vx is None else float(vx)
        self.vz = vn if vz is None else float(vz)
        self.s = 0
        if self.z > zs:
            self.mode = "flight"
            return self
        if self.z < zs - 1e-12 * max(abs(zs), 1e-300):
            raise ValueError("part below the surface")
        self.z, self.vz = zs, max(self.vz, vn)
        if self.vz > vn:
            self.mode = "flight"
            return self
        u = self.vx - vt
        self._settle_contact(u == 0.0)
        return self

    # ------------------------------------------------------- state evolution
    def _eval_segment(self, seg: _Segment, t):
        """Part state (x, z, vx, vz) on a segment at time(s) t (analytic)."""
        wf = self.wf
        tau = np.asarray(t, dtype=float) - seg.t0
        if seg.mode == "flight":
            return (seg.x0 + seg.vx0 * tau - 0.5 * self.g_t * tau * tau,
                    seg.z0 + seg.vz0 * tau - 0.5 * self.g_n * tau * tau,
                    seg.vx0 - self.g_t * tau + 0 * tau,
                    seg.vz0 - self.g_n * tau + 0 * tau)
        (xs, zs), (vt, vn) = wf.position(t), wf.velocity(t)
        if seg.mode == "stick":
            xs0 = wf.position(seg.t0)[0]
            return seg.x0 + (xs - xs0), zs, vt, vn
        if seg.mode == "slip":
            k = seg.s * self.part.mu_k
            zs0 = wf.position(seg.t0)[1]
            vn0 = wf.velocity(seg.t0)[1]
            c = k * self.g_n + self.g_t
            vx = seg.vx0 - c * tau - k * (vn - vn0)
            x = seg.x0 + seg.vx0 * tau - 0.5 * c * tau * tau - k * (zs - zs0 - vn0 * tau)
            return x, zs, vx, vn
        # chatter: micro-bounces summed; part on the surface to O(bounce height)
        frac = tau / max(seg.t1 - seg.t0, 1e-300)
        vx = seg.vx0 + (seg.vx1 - seg.vx0) * frac
        x = seg.x0 + 0.5 * (seg.vx0 + vx) * tau
        return x, zs, vx, vn

    def _advance(self, t_new: float):
        seg = _Segment(self.t, t_new, self.mode, self.x, self.z, self.vx, self.vz, self.s)
        if t_new > self.t:
            x, z, vx, vz = self._eval_segment(seg, t_new)
            self.x, self.z, self.vx, self.vz = float(x), float(z), float(vx), float(vz)
            if self.mode != "flight":    # exactly on the surface
                self.z, self.vz = self.wf.position(t_new)[1], self.wf.velocity(t_new)[1]
            if self.record:
                self.segments.append(seg)
        self.t = t_new

    # --------------------------------------------------------- event finding
    def _next_flight_event(self, t1):
        t0, Z0, Vz, gn, wf = self.t, self.z, self.vz, self.g_n, self.wf

        def h(t):
            tau = t - t0
            return Z0 + Vz * tau - 0.5 * gn * tau * tau - wf.position(t)[1]

        def hp(t):
            return Vz - gn * (t - t0) - wf.velocity(t)[1]

        r2 = wf.accel_roots(0.0, 1.0, -gn, t0, t1)          # h'' = -n = 0
        r1 = all_roots(hp, t0, t1, r2, self.xtol)
        return first_descent(h, t0, t1, r1, self.xtol)

    def _launch_time(self, t1):
        r = self.wf.accel_roots(0.0, 1.0, -self.g_n, self.t, t1)
        tl, _ = first_negative_interval([self._n], self.t, t1, r, self.xtol)
        return tl

    def _next_slip_event(self, t1):
        t0, s, wf = self.t, self.s, self.wf
        k = s * self.part.mu_k
        c = k * self.g_n + self.g_t
        vn0 = wf.velocity(t0)[1]
        vx0 = self.vx

        def su(t):
            vt, vn = wf.velocity(t)
            return s * (vx0 - c * (t - t0) - k * (vn - vn0) - vt)

        r = wf.accel_roots(-1.0, -k, c, t0, t1)              # u' = 0
        t_stop = first_descent(su, t0, t1, r, self.xtol)
        t_launch = self._launch_time(t1 if t_stop is None else t_stop)
        if t_launch is not None:
            return t_launch, "launch"
        return (t_stop, "u0") if t_stop is not None else (None, None)

    def _next_stick_event(self, t1):
        wf, ms, gt, gn = self.wf, self.part.mu_s, self.g_t, self.g_n

        def c1(t):   # part would lag: a_t + g_t > mu_s n
            ax, az = wf.acceleration(t)
            return ms * (gn + az) - (ax + gt)

        def c2(t):   # part would lead: a_t + g_t < -mu_s n
            ax, az = wf.acceleration(t)
            return ms * (gn + az) + (ax + gt)

        roots = np.concatenate([
            wf.accel_roots(0.0, 1.0, -gn, self.t, t1),
            wf.accel_roots(-1.0, ms, gt - ms * gn, self.t, t1),
            wf.accel_roots(1.0, ms, -gt - ms * gn, self.t, t1)])
        ts, k = first_negative_interval([self._n, c1, c2], self.t, t1, roots, self.xtol)
        if ts is None:
            return None, None
        return ts, ("launch", "slip-", "slip+")[k]

    # -------------------------------------------------------- event handling
    def _settle_contact(self, rel_stopped: bool):
        """Choose stick/slip/flight for a part on the surface with zero normal relative velocity."""
        ax, az = self.wf.acceleration(self.t)
        n = self.g_n + az
        if n < 0.0:
            self.mode = "flight"
            self._emit("launch")
            return
        vt = self.wf.velocity(self.t)[0]
        u = 0.0 if rel_stopped else self.vx - vt
        if u == 0.0:
            self.vx = vt
            r = ax + self.g_t
            if abs(r) <= self.part.mu_s * n:
                self.mode, self.s = "stick", 0
                self._emit("stick")
                return
            self.mode, self.s = "slip", (-1 if r > 0 else 1)
        else:
            self.mode, self.s = "slip", (1 if u > 0 else -1)
        self._emit("slip", direction=self.s)

    def _impact(self):
        wf, e, mu = self.wf, self.part.e, self.part.mu_k
        vt, vn = wf.velocity(self.t)
        self.z = wf.position(self.t)[1]
        w = min(self.vz - vn, 0.0)            # normal relative velocity (approaching)
        u = self.vx - vt
        P = (1.0 + e) * (-w)                  # normal impulse per unit mass
        stopped = abs(u) <= mu * P
        self.vx = vt if stopped else self.vx - math.copysign(mu * P, u)
        self.vz = vn - e * w
        n = self._n(self.t)
        self._emit("impact", w=w, u=u, impulse_n=P * self.part.mass, rebound=bool(e > 0.0 and w < 0.0))
        if e > 0.0 and w < 0.0:
            if n > 0.0 and self._try_sum_chatter(-w, n, vt, stopped):
                return
            self.mode = "flight"
            return
        if n < 0.0:                            # e = 0: relaunched at once (report 2.3)
            self.mode = "flight"
            self._emit("launch")
            return
        self._settle_contact(stopped)

    def _try_sum_chatter(self, w_in, n, vt, stopped):
        """Sum the remaining bounces as a geometric series if they end soon enough."""
        e, wf = self.part.e, self.wf
        tau = 2.0 * e * w_in / (n * (1.0 - e))
        t_inf = self.t + tau
        if tau > self.chatter_tol * self.T:
            return False
        if wf.breakpoints(self.t, t_inf + 1e-12 * self.T).size:
            return False
        if wf.accel_roots(0.0, 1.0, -self.g_n, self.t, t_inf).size:
            return False
        p_rem = (1.0 + e) * e * w_in / (1.0 - e)   # impulse of the remaining bounces
        u1 = self.vx - vt
        vt_inf = wf.velocity(t_inf)[0]
        rel_stop = stopped or abs(u1) <= self.part.mu_k * p_rem
        vx_inf = vt_inf if rel_stop else self.vx - math.copysign(self.part.mu_k * p_rem, u1) - self.g_t * tau
        seg = _Segment(self.t, t_inf, "chatter", self.x, self.z, self.vx, self.vz, 0,
                       x1=self.x + 0.5 * (self.vx + vx_inf) * tau, vx1=vx_inf)
        if self.record and tau > 0:
            self.segments.append(seg)
        self.t, self.x, self.vx = t_inf, seg.x1, vx_inf
        self.z, self.vz = wf.position(t_inf)[1], wf.velocity(t_inf)[1]
        self._emit("rest", summed_time=tau, summed_impulse_n=p_rem * self.part.mass)
        self._settle_contact(rel_stop)
        return True

    # ------------------------------------------------------------------ run
    def run(self, t_end: float, stop_on: tuple[str, ...] = (), max_events: int | None = None):
        """Integrate up to t_end [s] (or until an event of a kind in stop_on).

        Returns self. Raises RuntimeError if more than max_events events occur
        (default: 2000 per period plus 10000), which signals a Zeno-like
        sequence the chatter summation could not close.
        """
        if math.isnan(self.t):
            self.start()
        if max_events is None:
            max_events = int(2000 * max(t_end - self.t, 0.0) / self.T) + 10000
        budget = self.n_events + max_events
        same_time, last_t = 0, None
        while self.t < t_end:
            t1 = min(t_end, self.wf.next_breakpoint(self.t), self.t + self.T)
            if t1 - self.t <= MERGE * self.xtol:
                # rounding-level sliver (e.g. a chunk end a few ulp after an
                # event): no event can be resolved in it, just move on
                self._advance(t1)
                continue
            if self.mode == "flight":
                te = self._next_flight_event(t1)
                kind = "impact" if te is not None else None
            elif self.mode == "slip":
                te, kind = self._next_slip_event(t1)
            else:
                te, kind = self._next_stick_event(t1)
            if te is None:
                self._advance(t1)
                continue
            self._advance(te)
            n0 = len(self.events)
            if kind == "impact":
                self._impact()
            elif kind == "launch":
                self.mode = "flight"
                self._emit("launch")
            elif kind == "u0":
                self.vx = self.wf.velocity(self.t)[0]
                self._settle_contact(True)
            else:  # leaving the friction cone while stuck
                self.mode, self.s = "slip", (-1 if kind == "slip-" else 1)
                self._emit("slip", direction=self.s)
            same_time = same_time + 1 if self.t == last_t else 0
            last_t = self.t
            if same_time > 20 or self.n_events > budget:
                raise RuntimeError(f"event cascade at t={float(self.t)} (mode {self.mode})")
            if stop_on and any(ev.kind in stop_on for ev in self.events[n0:]):
                break
        return self

    # --------------------------------------------------------------- output
    def sample(self, times) -> dict:
        """Part state at the given times [s] within the recorded history.

        Returns a dict of arrays: t, x, z, vx, vz (part, m and m/s), xs, zs,
        vxs, vzs (surface) and phase labels ('stick', 'slip', 'flight';
        summed chattering counts as flight).
        """
        if not self.segments:
            raise ValueError("nothing recorded (record=False or run() not called)")
        times = np.asarray(times, dtype=float)
        starts = np.array([s.t0 for s in self.segments])
        idx = np.clip(np.searchsorted(starts, times, side="right") - 1, 0, len(starts) - 1)
        out = {k: np.empty(times.shape) for k in ("x", "z", "vx", "vz")}
        phase = np.empty(times.shape, dtype=object)
        for i in np.unique(idx):
            sel = idx == i
            seg = self.segments[i]
            vals = self._eval_segment(seg, times[sel])
            for k, v in zip(("x", "z", "vx", "vz"), vals):
                out[k][sel] = v
            phase[sel] = "flight" if seg.mode == "chatter" else seg.mode
        (xs, zs), (vxs, vzs) = self.wf.position(times), self.wf.velocity(times)
        return dict(t=times, **out, xs=xs, zs=zs, vxs=vxs, vzs=vzs, phase=phase)


@dataclass
class Trajectory:
    """Simulated trajectory of a part (overlay-ready with DEM output).

    t [s]; x, z [m] and vx, vz [m/s]: part position and velocity in the
    inclined, non-vibrating frame whose origin is the surface's mean position;
    xs, zs, vxs, vzs: surface; phase: 'stick'/'slip'/'flight' per sample;
    events: list of Event (launch, impact, rest, stick, slip).
    """

    t: np.ndarray
    x: np.ndarray
    z: np.ndarray
    vx: np.ndarray
    vz: np.ndarray
    xs: np.ndarray
    zs: np.ndarray
    vxs: np.ndarray
    vzs: np.ndarray
    phase: np.ndarray
    events: list
    model: PartOnSurface

    def events_of(self, kind: str) -> list:
        """Events of one kind ('launch', 'impact', 'rest', 'stick', 'slip')."""
        return [ev for ev in self.events if ev.kind == kind]

    def at(self, times) -> dict:
        """Exact (analytic) part and surface state at arbitrary recorded times [s]."""
        return self.model.sample(times)


def simulate(waveform: SurfaceMotion, part: PartParams, n_periods: float = 10.0, incline: float = 0.0,
             g: float = G, t0: float = 0.0, samples_per_period: int = 100,
             initial: dict | None = None, chatter_tol: float = 1e-6) -> Trajectory:
    """Simulate one part on the vibrating surface and return its trajectory.

    Parameters
    ----------
    waveform : surface motion; part : PartParams (mu_s, mu_k, e, mass).
    n_periods : duration in periods of the waveform.
    incline : track inclination [deg]; g : gravity [m/s^2]; t0 : start time [s].
    samples_per_period : uniform output samples per period (event times are
        added to the output, so every transition appears as a sample).
    initial : optional dict with x, z, vx, vz for `PartOnSurface.start`
        (default: at rest relative to the surface at t0).
    chatter_tol : see PartOnSurface.

    Returns a Trajectory (report sections 2.1-2.3 model).
    """
    m = PartOnSurface(waveform, part, incline, g, chatter_tol)
    m.start(t0, **(initial or {}))
    t_end = t0 + n_periods * waveform.period
    m.run(t_end)
    n = int(round(samples_per_period * n_periods)) + 1
    grid = np.linspace(t0, t_end, n)
    ev_t = np.array([ev.t for ev in m.events if t0 <= ev.t <= t_end])
    times = np.unique(np.concatenate([grid, ev_t]))
    d = m.sample(times)
    return Trajectory(d["t"], d["x"], d["z"], d["vx"], d["vz"], d["xs"], d["zs"],
                      d["vxs"], d["vzs"], d["phase"], list(m.events), m)


@dataclass
class SteadyState:
    """Steady-state mean conveying velocity.

    velocity : mean part velocity along +x [m/s] over the last two averaging
        blocks (whole periods only, after the transient);
    block_velocities : mean velocity of each averaging block [m/s];
    change : |difference| between the last two block means [m/s];
    converged : change <= tolerance; n_periods : periods simulated.
    """

    velocity: float
    block_velocities: list
    change: float
    converged: bool
    n_periods: int


def mean_velocity(waveform: SurfaceMotion, part: PartParams, incline: float = 0.0, g: float = G,
                  n_transient: int = 20, n_block: int = 24, max_blocks: int = 20,
                  rtol: float = 1e-4, atol: float = 0.0, chatter_tol: float = 1e-6,
                  initial: dict | None = None) -> SteadyState:
    """Steady-state mean conveying velocity of a part [m/s] (report 2.2-2.3).

    Discards n_transient periods, then averages over blocks of n_block whole
    periods (24 covers period-1, 2, 3, 4, 6, 8 orbits exactly) until two
    consecutive block means differ by <= rtol * (peak surface speed) + atol,
    or max_blocks blocks were simulated (then converged=False, e.g. chaotic
    hopping; the value is still the mean of the last two blocks).
    """
    m = PartOnSurface(waveform, part, incline, g, chatter_tol, record=False)
    m.start(0.0, **(initial or {}))
    T = waveform.period
    m.run(n_transient * T)
    tol = rtol * waveform.max_speed() + atol
    blocks = []
    x_prev, t_prev = m.x, m.t
    for _ in range(max_blocks):
        m.run(t_prev + n_block * T)
        blocks.append((m.x - x_prev) / (m.t - t_prev))
        x_prev, t_prev = m.x, m.t
        if len(blocks) >= 2 and abs(blocks[-1] - blocks[-2]) <= tol:
            break
    change = abs(blocks[-1] - blocks[-2]) if len(blocks) >= 2 else math.inf
    v = 0.5 * (blocks[-1] + blocks[-2]) if len(blocks) >= 2 else blocks[-1]
    return SteadyState(v, blocks, change, change <= tol, n_transient + len(blocks) * n_block)
