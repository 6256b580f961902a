"""Contact and flight of parts above a flat vibrating surface.

The gap of a part is the height of its lowest point above the surface plane,
``gap = z - radius - z_surface(t)``, for decks whose surface is the plane
z = 0 displaced by ``observables/surface/position`` (the single-part decks).
A multisphere part (a chip or disc: the result has a body template) is not a
sphere of its recorded ``radius`` (the sphere enclosing the clump): its lowest
point is its lowest sphere's, ``z + min_i ([R (t_i - mean t)]_z - r_i)`` with R
its orientation (FORMAT.md, "Parts are bodies"), and its ``force`` is not
recorded (NaN): its contact is told from the gap, as for results without force.

Flight events are reconstructed between frames rather than read off them, so
they do not depend on the frame spacing:

* between two frames an airborne part is ballistic (gravity only), and the
  surface motion is known at both frames (position and velocity, so a cubic
  Hermite interpolant follows it to ~A w^4 dt^4); the free-flight gap is then
  a cubic on each frame interval, and a landing is its first root after the
  last airborne frame, found exactly. A stiff contact lasts ~1 us, far less
  than a frame: such an impact shows up only as a jump in the part's velocity
  between two airborne frames, and is found the same way;
* a launch after a rebound is the root of the free flight traced back from
  the first airborne frame;
* a launch from sustained contact (lift-off) is tangential: equal position,
  velocity and acceleration, so the gap grows like (t - t_l)^3 and a gap
  threshold fires late. The normal contact force, however, falls through zero
  linearly (it follows m (g + a_n(t)) until lift-off), so lift-off is timed by
  extrapolating the contact force of the last frames in contact to zero. That
  needs the recorded ``force`` and the body forces of the deck (gravity along
  the incline, ``normal_force``), which come from the result's parameters.
  Without a recorded force, the gap tells contact (below a tolerance) and
  the lift-off is where the free flight seen after the contact, traced back
  over the frames of the contact, last meets the surface.

Following the surface between frames needs frames close enough: a cubic
through its position and velocity at frames ``h`` apart is off by up to
``A (w h)^4 / 384``, 1e-3 of its amplitude A at eight frames per period, and
frames a period apart see it at one phase (standing still). A result whose
surface moves normal to itself and whose frames are more than
:data:`MAX_FRAME_PERIODS` of a period apart is refused (``InputError``), not
analysed into flights it cannot resolve.

The model these events are compared with is the rigid part on a vibrating
plate of Khan & Sarma, "Vibratory Assembly Update: Part Transportation
Mechanics Analysis" (MIT Auto-ID Center), §2.3.2.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError, said
from ..models.constants import G
from ..rotations import quaternion_matrices
from .base import AnalysisBase


class Hermite:
    """The piecewise cubic Hermite interpolant of values ``y`` and slopes ``dy`` at knots ``t``:
    ``c`` (4, n - 1), each interval's cubic in s = t - t_i, highest power first (scipy's
    CubicHermiteSpline's coefficients). Written out here because importing
    scipy.interpolate costs 0.4 s of CPU, a fifth of a short single-part ``vibrofeed run``
    whose summary counts the hops."""

    def __init__(self, t, y, dy):
        self.t = np.asarray(t, dtype=float)
        y, dy = np.asarray(y, dtype=float), np.asarray(dy, dtype=float)
        h = np.diff(self.t)
        slope = np.diff(y) / h
        self.c = np.stack([(dy[:-1] + dy[1:] - 2 * slope) / h**2, (3 * slope - 2 * dy[:-1] - dy[1:]) / h,
                           dy[:-1], y[:-1]])

    def __call__(self, x, nu: int = 0):
        """The interpolant (``nu`` = 0) or its slope (1) at ``x``; beyond the knots, the end
        intervals' cubics carried on."""
        x = np.asarray(x, dtype=float)
        k = np.clip(np.searchsorted(self.t, x, side="right") - 1, 0, self.c.shape[1] - 1)
        s = x - self.t[k]
        c0, c1, c2, c3 = self.c[:, k]
        return ((c0 * s + c1) * s + c2) * s + c3 if nu == 0 else (3 * c0 * s + 2 * c1) * s + c2


def cubic_roots(c, t0: float, t1: float) -> np.ndarray:
    """The real roots in [t0, t1] of the cubic ``c`` (highest power first) in s = t - t0, as
    times, ascending (a touch, a double root, may come twice, a few 1e-8 of the interval apart)."""
    c = np.asarray(c, dtype=float)
    h = t1 - t0
    scale = np.abs(c) * np.array([h**3, h**2, h, 1.0])  # each term's size over the interval
    if not scale.any():
        return np.empty(0)
    lead = int(np.argmax(scale > 1e-14 * scale.max()))  # terms too small to matter dropped
    r = np.roots(c[lead:])
    r = r[np.abs(r.imag) <= 1e-6 * h].real  # a double root comes out with a small imaginary part
    return t0 + np.sort(np.clip(r[(r >= -1e-9 * h) & (r <= h * (1 + 1e-9))], 0, h))


LIFT_OFF_MIN_FRAMES = 3  # contact must last this many frames to count as sustained
# Longest frame interval [periods] over which the surface's motion is followed (module
# docstring): eight frames per period.
MAX_FRAME_PERIODS = 1 / 8


def lowest_depth(result, where, slots, radius) -> np.ndarray:
    """How far below its centre a part's lowest point lies [m] at the (frame, slot) pairs:
    its ``radius`` for a sphere; for a clump (the result's body template), its lowest
    sphere's bottom, its spheres turned by the part's orientation (module docstring)."""
    template = result.body_template
    if template is None:
        return radius
    t = np.asarray(template, dtype=float)
    offsets = t[:, :3] - t[:, :3].mean(axis=0)
    rot = quaternion_matrices(result.gather("orientation", where, slots))
    heights = np.einsum("nj,kj->nk", rot[:, 2, :], offsets)
    return (t[:, 3][None, :] - heights).max(axis=1)


def _normal_gravity(result) -> float:
    """Gravity's component into the surface [m/s^2] (the incline tilts it)."""
    g = result.derived.get("g", G)
    return g * math.cos(math.radians(float(result.parameters.get("incline", 0.0))))


def normal_contact_force(result, part_id: int, frames=None) -> np.ndarray | None:
    """Normal contact force on a part [N] at the frames where it exists (within
    a frame selection): recorded total force minus the deck's body forces;
    None if the result does not record the force."""
    where, slots = result.locate(part_id, frames)
    return _contact_force(result, where, slots)


def _contact_force(result, where, slots) -> np.ndarray | None:
    try:
        force = result.gather("force", where, slots)
        mass = result.gather("mass", where, slots)
    except KeyError:
        return None
    if len(force) and not np.isfinite(force[:, 2]).any():
        return None  # not recorded: the force of clumps is NaN (FORMAT.md, "Parts are bodies")
    press = float(result.parameters.get("normal_force", 0.0))
    return force[:, 2] + mass * _normal_gravity(result) + press


class Flights(AnalysisBase):
    """Lift-offs, rebounds, landings and flight durations of one part.

    Parameters
    ----------
    result:
        The :class:`~vibrofeed.results.reader.Result` to analyse.
    part_id:
        The part followed; default: the lowest id in the result.
    contact_tolerance:
        Gap [m] above which a frame counts as airborne when the result holds
        no force to tell contact from flight (nor does a clump's). Default:
        0.2 % of the part's radius (a clump's: of its spheres'), well above the
        elastic overlap under the part's weight. A finite gap of 0 m or more
        (else :class:`~vibrofeed.errors.InputError`).

    Results (after :meth:`run`): ``part_id``; ``time``, ``gap`` and
    ``contact_force`` (frames where the part exists; ``contact_force`` None
    without recorded force); ``landings`` [s] (every impact); ``takeoffs``
    [s] and ``takeoff_kinds`` ("lift-off" or "rebound") of every flight that
    starts in the record; ``flights`` (n, 2) [launch, landing] of the complete
    flights, their ``kinds`` and ``durations``; ``n_hops`` (complete flights);
    ``airborne_at_start`` (in flight at the first frame), ``in_flight_at_end`` (the launch [s] of
    a flight not landed by the last frame, else None); ``airborne_fraction`` (of the time
    recorded, the cut flights included), ``max_gap`` [m]; ``impacts`` (n, 3) [time, w_in, e]
    of every landing (relative normal speed before it, < 0, and the
    restitution realised there) and ``realised_restitution``.

    >>> fl = Flights(result).run()
    >>> fl.results.landings, fl.results.kinds, fl.results.realised_restitution
    """

    def __init__(self, result, part_id: int | None = None, contact_tolerance: float | None = None):
        if contact_tolerance is not None and not (
                math.isfinite(contact_tolerance) and contact_tolerance >= 0):
            raise InputError(f"contact_tolerance must be a gap of 0 m or more, got {said(contact_tolerance)}")
        super().__init__(result)
        self.part_id = part_id
        self.contact_tolerance = contact_tolerance

    def _compute(self, frames: np.ndarray) -> None:
        r = self.result
        part_id = int(r.part_ids[0]) if self.part_id is None else int(self.part_id)
        where, slots = r.locate(part_id, frames)
        if len(where) == 0:
            raise KeyError(f"particle id {part_id} does not appear in the frames analysed of {r.path}")
        t = r.time[where]
        z = r.gather("position", where, slots)[:, 2]
        vz = r.gather("velocity", where, slots)[:, 2]
        radius = r.gather("radius", where, slots)
        zs = r.read("surface_position", frames=where)[:, 2]
        vs = r.read("surface_velocity", frames=where)[:, 2]
        self._check_frames(t, zs, vs)
        depth = lowest_depth(r, where, slots, radius)
        gap = z - depth - zs
        g_n = _normal_gravity(r)
        fc = _contact_force(r, where, slots)
        sphere = radius if r.body_template is None else r.body_template[:, 3]
        tol = (0.002 * float(np.nanmax(sphere)) if self.contact_tolerance is None
               else self.contact_tolerance)
        # Touching: overlapping (gap <= 0) or pushed (a damped contact can pull
        # at the very end, so force alone is not enough, nor is the gap alone
        # for results without force).
        # Pushed: beyond the rounding of the body forces taken off the recorded force (a part's
        # weight ~1e-16 relative), which leaves a few ulp where the normal gravity is ~0 (a
        # track at -90 deg): as a push, they would hold a part that flew off in contact.
        if fc is not None:
            weight = float(np.nanmax(r.gather("mass", where, slots))) * r.derived.get("g", G)
            pushed = fc > 1e-9 * (weight + abs(float(r.parameters.get("normal_force", 0.0))))
        contact = (gap <= 0) | pushed if fc is not None else gap <= tol

        # Working state of the event search (neither settings nor answers).
        self._t, self._z, self._vz, self._r, self._g, self._fc = t, z, vz, depth, g_n, fc
        self._surface = Hermite(t, zs, vs) if len(t) > 1 else None
        # An impact: the part leaves again within a few contact times.
        self._max_impact = 20 * r.derived.get("t_contact", 1e-5)

        events = []  # (time, kind): "land", "lift-off", "rebound"
        n = len(t)
        i = 0
        while i < n - 1:
            if not contact[i] and not contact[i + 1]:
                # both frames free: ballistic unless an impact hides between them
                expected = vz[i] - g_n * (t[i + 1] - t[i])
                jump = vz[i + 1] - expected
                if jump > 1e-6 + 1e-3 * abs(vz[i]):
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

        res = self.results
        res.part_id, res.time, res.gap, res.contact_force = part_id, t, gap, fc
        res.landings = np.array([e[0] for e in events if e[1] == "land"])
        launches = [e for e in events if e[1] != "land"]
        res.takeoffs = np.array([e[0] for e in launches])
        res.takeoff_kinds = [e[1] for e in launches]
        flights, kinds = [], []
        for t_up, kind in launches:
            later = res.landings[res.landings > t_up]
            if len(later):
                flights.append((t_up, later[0]))
                kinds.append(kind)
        res.flights = np.array(flights).reshape(-1, 2)
        res.kinds = kinds
        res.durations = res.flights[:, 1] - res.flights[:, 0]
        res.n_hops = len(res.flights)
        # Airborne: the complete flights, and the flights the record cuts (one under way at the
        # first frame, one not landed by the last): a part that flies off counts as airborne.
        airborne, since = 0.0, t[0] if n else 0.0
        flying = bool(n) and not contact[0]
        res.airborne_at_start = flying
        for when, kind in sorted(events):  # at a tie the landing first, then the launch
            if kind == "land" and flying:
                airborne += when - since
            elif kind != "land" and not flying:
                since = when
            flying = kind != "land"
        res.in_flight_at_end = float(since) if flying else None
        if flying:
            airborne += t[-1] - since
        res.airborne_fraction = float(airborne / (t[-1] - t[0])) if n > 1 else 0.0
        res.max_gap = float(np.max(gap)) if n else float("nan")

    def _check_frames(self, t, zs, vs) -> None:
        """Refuse frames too far apart to follow a surface moving normal to itself (module
        docstring); a still surface is followed at any spacing."""
        freq = float(self.result.parameters.get("freq", 0.0))
        if len(t) < 2 or not freq > 0 or not (np.ptp(zs) > 0 or np.any(vs != 0)):
            return
        longest = float(np.max(np.diff(t)))
        if longest * freq > MAX_FRAME_PERIODS * (1 + 1e-9):
            raise InputError(
                f"flights: frames {longest * 1e3:.3g} ms apart cannot follow a surface vibrating at "
                f"{freq:g} Hz (period {1e3 / freq:.3g} ms): the events between frames need at least "
                f"{round(1 / MAX_FRAME_PERIODS)} frames per period (output_dt <= "
                f"{MAX_FRAME_PERIODS / freq:.3g} s)")

    def _conclude(self) -> None:
        res = self.results
        rows = [(t_land, self._w_in(t_land), self._restitution(k))
                for k, t_land in enumerate(res.landings)]
        res.impacts = np.array(rows).reshape(-1, 3)
        # The restitution this contact realises: the median over the impacts at
        # least half as fast as the fastest (slow touch-downs at the end of a
        # chattering sequence cannot rebound measurably); NaN without impacts.
        imp = res.impacts
        if len(imp):
            fast = imp[np.abs(imp[:, 1]) >= 0.5 * np.abs(imp[:, 1]).max()]
            res.realised_restitution = float(np.median(fast[:, 2]))
        else:
            res.realised_restitution = float("nan")

    # -- between frames ---------------------------------------------------------------
    def _free_gap(self, k: int, segment: int) -> np.ndarray:
        """Gap of a free flight through frame k on frame interval ``segment``:
        the parabola minus the surface's Hermite cubic, as a cubic in s - t_segment
        (highest power first)."""
        d = self._t[segment] - self._t[k]
        z, vz, g = self._z[k], self._vz[k], self._g
        surface = self._surface.c[:, segment]
        flight = np.array([0.0, -0.5 * g, vz - g * d, z + vz * d - 0.5 * g * d * d - self._r[k]])
        return flight - surface

    def _roots(self, k: int, segment: int) -> np.ndarray:
        return cubic_roots(self._free_gap(k, segment), self._t[segment], self._t[segment + 1])

    def _forward_root(self, i: int) -> float | None:
        """Landing after airborne frame i: first root of its free flight in [t_i, t_i+1]."""
        roots = self._roots(i, i)
        return float(roots[0]) if len(roots) else None

    def _backward_root(self, j: int) -> float | None:
        """Separation before airborne frame j: last root of its free flight in [t_j-1, t_j]."""
        roots = self._roots(j, j - 1)
        return float(roots[-1]) if len(roots) else None

    def _launch(self, a: int, b: int) -> tuple[float, str]:
        """Launch ending the contact that spans frames a..b.

        Sustained contact (at least LIFT_OFF_MIN_FRAMES frames): lift-off is
        where the normal contact force falls through zero, interpolated
        between the frames around it, or extrapolated from the last two if it
        is still positive at the last frame in contact. (LIGGGHTS' damped
        contact can pull briefly after that, so the part separates a little
        later; the model's lift-off is where the support vanishes.) Otherwise
        the root of the flight seen after the contact, traced back over its last
        interval; without a recorded force, over every interval of the contact
        back to its first frame (the gap of a tangential lift-off grows like
        (t - t_l)^3 and stays below the tolerance for many frames).
        """
        t, fc = self._t, self._fc
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
        if up is None and fc is None:
            for segment in range(b - 1, a - 1, -1):
                roots = self._roots(b + 1, segment)
                if len(roots):
                    up = float(roots[-1])
                    break
        return (float(up) if up is not None else float(t[b + 1])), "rebound"

    # -- impacts ----------------------------------------------------------------------
    def _w_in(self, t_land: float) -> float:
        """Relative normal speed just before a landing (< 0), carried from the
        last frame before it by free flight."""
        i = np.searchsorted(self._t, t_land) - 1
        return self._vz[i] - self._g * (t_land - self._t[i]) - self._surface(t_land, 1)

    def _restitution(self, k: int) -> float:
        """Restitution realised at the k-th landing: relative normal speed just
        after the impact over just before (0 if the part does not leave within
        20 contact times, the deck's ``t_contact``).

        Both are carried from the nearest airborne frames to the contact
        instants by free flight and the surface's interpolated motion.
        """
        res = self.results
        t_land = res.landings[k]
        later = res.takeoffs[res.takeoffs >= t_land]
        if not len(later) or later[0] - t_land > self._max_impact:
            return 0.0  # the part stayed on the surface
        t_up = later[0]
        nxt = res.landings[res.landings > t_land]
        if len(nxt) and nxt[0] < t_up:
            return 0.0
        t, g = self._t, self._g
        i = np.searchsorted(t, t_land) - 1   # last frame before the impact
        j = np.searchsorted(t, t_up)         # first frame after the separation
        if i < 0 or j >= len(t):
            return 0.0
        w_in = self._vz[i] - g * (t_land - t[i]) - self._surface(t_land, 1)
        w_out = self._vz[j] + g * (t[j] - t_up) - self._surface(t_up, 1)
        if w_in >= 0 or w_out <= 0:
            return 0.0
        return float(-w_out / w_in)
