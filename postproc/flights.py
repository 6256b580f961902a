"""Contact and flight of parts above a flat vibrating surface.

The gap of a part is the height of its lowest point above the surface plane,
``gap = z - radius - z_surface(t)``, for decks whose surface is the plane
z = 0 displaced by ``observables/surface/position`` (the single-part decks).

Flight events are reconstructed between frames rather than read off them, so
they do not depend on the frame spacing:

* between two frames an airborne part is ballistic (gravity only), and the
  surface motion is known at both frames (position and velocity, so a cubic
  Hermite interpolant follows it to ~A w^4 dt^4); a landing is the first root
  of the part's free-flight gap after the last airborne frame. A stiff contact
  lasts ~1 us, far less than a frame: such an impact shows up only as a jump in
  the part's velocity between two airborne frames, and is found the same way;
* a launch after a rebound is the root of the free flight traced back from
  the first airborne frame;
* a launch from sustained contact (lift-off) is tangential: equal position,
  velocity and acceleration, so the gap grows like (t - t_l)^3 and a gap
  threshold fires late. The normal contact force, however, falls through zero
  linearly (it follows m (g + a_n(t)) until lift-off), so lift-off is timed by
  extrapolating the contact force of the last frames in contact to zero. That
  needs the recorded ``force`` and the body forces of the deck (gravity along
  the incline, ``normal_force``), which come from the result's parameters.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

LIFT_OFF_MIN_FRAMES = 3  # contact must last this many frames to count as sustained


def _normal_gravity(result) -> float:
    """Gravity's component into the surface [m/s^2] (the incline tilts it)."""
    g = result.derived.get("g", 9.81)
    return g * math.cos(math.radians(float(result.parameters.get("incline", 0.0))))


def normal_contact_force(result, part_id: int) -> np.ndarray | None:
    """(frames,) normal contact force on a part [N]: recorded total force minus
    the deck's body forces; None if the result does not allow it."""
    try:
        _, force = result.track(part_id, "force")
        _, mass = result.track(part_id, "mass")
    except (KeyError, AttributeError):
        return None
    press = float(result.parameters.get("normal_force", 0.0))
    return force[:, 2] + mass * _normal_gravity(result) + press


def _hermite(t0, t1, y0, y1, v0, v1):
    """Cubic through (t0, y0, v0) and (t1, y1, v1), as a function of t."""
    h = t1 - t0

    def f(t):
        s = (t - t0) / h
        h00, h10 = 2 * s ** 3 - 3 * s ** 2 + 1, s ** 3 - 2 * s ** 2 + s
        h01, h11 = -2 * s ** 3 + 3 * s ** 2, s ** 3 - s ** 2
        return h00 * y0 + h10 * h * v0 + h01 * y1 + h11 * h * v1
    return f


def _first_root(f, a: float, b: float, from_end: bool = False, samples: int = 64) -> float | None:
    """First root of f in [a, b] (last one if ``from_end``), by sampling then brentq."""
    ts = np.linspace(a, b, samples + 1)
    ys = np.array([f(t) for t in ts])
    pairs = range(samples - 1, -1, -1) if from_end else range(samples)
    for k in pairs:
        if ys[k] == 0:
            return float(ts[k])
        if ys[k] * ys[k + 1] < 0:
            return float(brentq(f, ts[k], ts[k + 1], xtol=1e-15 * max(abs(b), 1.0)))
    return None


class Flights:
    """Lift-offs, rebounds, landings and flight durations of one part.

    Parameters
    ----------
    contact_tolerance:
        Gap [m] above which a frame counts as airborne when the result holds
        no force to tell contact from flight. Default: 0.2 % of the part's
        radius, well above the elastic overlap under the part's weight.

    Results (after :meth:`compute`): ``time``, ``gap`` and ``contact_force``
    (frames,); ``landings`` [s] (every impact); ``takeoffs`` [s] and
    ``takeoff_kinds`` ("lift-off" or "rebound") of every flight that starts in
    the record; ``flights`` (n, 2) [launch, landing] of the complete flights,
    their ``kinds`` and ``durations``; ``n_hops``, ``airborne_fraction``,
    ``max_gap`` [m]; :meth:`restitution` of an impact.
    """

    def __init__(self, contact_tolerance: float | None = None):
        self.contact_tolerance = contact_tolerance

    def compute(self, result, part_id: int | None = None) -> "Flights":
        if part_id is None:
            part_id = int(result.part_ids[0])
        t, pos = result.track(part_id, "position")
        _, vel = result.track(part_id, "velocity")
        _, radius = result.track(part_id, "radius")
        frames = np.isin(result.time, t)
        zs, vs = result.surface_position[frames, 2], result.surface_velocity[frames, 2]
        gap = pos[:, 2] - radius - zs
        g_n = _normal_gravity(result)
        fc = normal_contact_force(result, part_id)
        tol = 0.002 * float(np.nanmax(radius)) if self.contact_tolerance is None else self.contact_tolerance
        # Touching: overlapping (gap <= 0) or pushed (a damped contact can pull
        # at the very end, so force alone is not enough, nor is the gap alone
        # for results without force).
        contact = (gap <= 0) | (fc > 0) if fc is not None else gap <= tol

        self.part_id, self.time, self.gap, self.contact_force = part_id, t, gap, fc
        self._z, self._vz, self._zs, self._vs, self._r, self._g = (
            pos[:, 2], vel[:, 2], zs, vs, radius, g_n)
        # An impact: the part leaves again within a few contact times.
        self._max_impact = 20 * result.derived.get("t_contact", 1e-5)

        events = []  # (time, kind): "land", "lift-off", "rebound"
        n = len(t)
        i = 0
        while i < n - 1:
            if not contact[i] and not contact[i + 1]:
                # both frames free: ballistic unless an impact hides between them
                expected = self._vz[i] - g_n * (t[i + 1] - t[i])
                jump = self._vz[i + 1] - expected
                if jump > 1e-6 + 1e-3 * abs(self._vz[i]):
                    land = self._forward_root(i)
                    up = self._backward_root(i + 1)
                    if land is not None:
                        events.append((land, "land"))
                        events.append((max(up if up is not None else land, land), "rebound"))
                i += 1
                continue
            if not contact[i] and contact[i + 1]:
                land = self._forward_root(i)
                events.append((land if land is not None else t[i + 1], "land"))
                i += 1
                continue
            if contact[i]:
                j = i
                while j + 1 < n and contact[j + 1]:
                    j += 1
                if j + 1 >= n:
                    break  # still in contact at the end
                events.append(self._launch(i, j))
                i = j + 1
                continue
            i += 1

        self.landings = np.array([e[0] for e in events if e[1] == "land"])
        launches = [e for e in events if e[1] != "land"]
        self.takeoffs = np.array([e[0] for e in launches])
        self.takeoff_kinds = [e[1] for e in launches]
        flights, kinds = [], []
        for t_up, kind in launches:
            later = self.landings[self.landings > t_up]
            if len(later):
                flights.append((t_up, later[0]))
                kinds.append(kind)
        self.flights = np.array(flights).reshape(-1, 2)
        self.kinds = kinds
        self.durations = self.flights[:, 1] - self.flights[:, 0]
        self.n_hops = len(self.flights)
        self.airborne_fraction = float(self.durations.sum() / (t[-1] - t[0])) if n > 1 else 0.0
        self.max_gap = float(np.max(gap)) if n else float("nan")
        return self

    # -- between frames ---------------------------------------------------------------
    def _surface(self, i: int):
        t = self.time
        return _hermite(t[i], t[i + 1], self._zs[i], self._zs[i + 1], self._vs[i], self._vs[i + 1])

    def _free_gap(self, k: int, segment: int):
        """Gap of a free flight through frame k, on the frame interval ``segment``."""
        t, z, vz, r, g = self.time[k], self._z[k], self._vz[k], self._r[k], self._g
        surface = self._surface(segment)
        return lambda s: z + vz * (s - t) - 0.5 * g * (s - t) ** 2 - r - surface(s)

    def _forward_root(self, i: int) -> float | None:
        """Landing after airborne frame i: first root of its free flight in (t_i, t_i+1]."""
        return _first_root(self._free_gap(i, i), self.time[i], self.time[i + 1])

    def _backward_root(self, j: int) -> float | None:
        """Separation before airborne frame j: last root of its free flight in [t_j-1, t_j)."""
        return _first_root(self._free_gap(j, j - 1), self.time[j - 1], self.time[j], from_end=True)

    def _launch(self, a: int, b: int) -> tuple[float, str]:
        """Launch ending the contact that spans frames a..b.

        Sustained contact (at least LIFT_OFF_MIN_FRAMES frames): lift-off is
        where the normal contact force falls through zero, interpolated
        between the frames around it, or extrapolated from the last two if it
        is still positive at the last frame in contact. (LIGGGHTS' damped
        contact can pull briefly after that, so the part separates a little
        later; the model's lift-off is where the support vanishes.)
        """
        t, fc = self.time, self.contact_force
        if fc is not None and b - a + 1 >= LIFT_OFF_MIN_FRAMES:
            drops = np.nonzero((fc[a:b] > 0) & (fc[a + 1:b + 1] <= 0))[0]
            if len(drops):
                c = a + drops[-1]
                t_zero = t[c] + fc[c] / (fc[c] - fc[c + 1]) * (t[c + 1] - t[c])
                return float(t_zero), "lift-off"
            if fc[b - 1] > fc[b] > 0:
                slope = (fc[b] - fc[b - 1]) / (t[b] - t[b - 1])
                return float(min(max(t[b] - fc[b] / slope, t[b]), t[b + 1])), "lift-off"
        up = self._backward_root(b + 1)
        return (float(up) if up is not None else float(t[b + 1])), "rebound"

    # -- impacts ----------------------------------------------------------------------
    def impacts(self) -> np.ndarray:
        """(n, 3) [time, w_in, e] of every landing: relative normal speed
        before the impact (< 0) and the restitution realised there."""
        rows = []
        for k, t_land in enumerate(self.landings):
            i = np.searchsorted(self.time, t_land) - 1
            w_in = self._vz[i] - self._g * (t_land - self.time[i]) - _hermite_velocity(self, i, t_land)
            rows.append((t_land, w_in, self.restitution(k)))
        return np.array(rows).reshape(-1, 3)

    def realised_restitution(self) -> float:
        """The restitution this contact realises: the median over the impacts
        at least half as fast as the fastest (slow touch-downs at the end of a
        chattering sequence cannot rebound measurably); NaN without impacts."""
        imp = self.impacts()
        if not len(imp):
            return float("nan")
        fast = imp[np.abs(imp[:, 1]) >= 0.5 * np.abs(imp[:, 1]).max()]
        return float(np.median(fast[:, 2]))

    def restitution(self, k: int = 0) -> float:
        """Restitution realised at the k-th landing: relative normal speed just
        after the impact over just before (0 if the part does not leave within
        20 contact times, the deck's ``t_contact``).

        Both are carried from the nearest airborne frames to the contact
        instants by free flight and the surface's recorded motion.
        """
        t_land = self.landings[k]
        later = self.takeoffs[self.takeoffs >= t_land]
        if not len(later) or later[0] - t_land > self._max_impact:
            return 0.0  # the part stayed on the surface
        t_up = later[0]
        nxt = self.landings[self.landings > t_land]
        if len(nxt) and nxt[0] < t_up:
            return 0.0
        t, g = self.time, self._g
        i = np.searchsorted(t, t_land) - 1   # last frame before the impact
        j = np.searchsorted(t, t_up)         # first frame after the separation
        if i < 0 or j >= len(t):
            return 0.0
        w_in = self._vz[i] - g * (t_land - t[i]) - _hermite_velocity(self, i, t_land)
        w_out = self._vz[j] + g * (t[j] - t_up) - _hermite_velocity(self, j - 1, t_up)
        if w_in >= 0 or w_out <= 0:
            return 0.0
        return float(-w_out / w_in)


def _hermite_velocity(fl: Flights, i: int, s: float) -> float:
    """Surface velocity at time s within frame interval i (derivative of the Hermite cubic)."""
    t0, t1 = fl.time[i], fl.time[i + 1]
    h = t1 - t0
    u = (s - t0) / h
    y0, y1, v0, v1 = fl._zs[i], fl._zs[i + 1], fl._vs[i], fl._vs[i + 1]
    return ((6 * u ** 2 - 6 * u) * y0 + (3 * u ** 2 - 4 * u + 1) * h * v0
            + (-6 * u ** 2 + 6 * u) * y1 + (3 * u ** 2 - 2 * u) * h * v1) / h
