"""The vibratory bowl feeder's geometry, its drive seen from the track, and its checks.

A bowl (decks/bowl_feeder.liggghts) is a cylinder of radius ``bowl_diameter / 2`` with a
conical bottom (down towards the wall by ``cone_angle``, so the pile moves outwards) and a
helical track on its inner wall: a shelf ``track_width`` wide rising at ``helix_angle``
(at its centre line) for ``turns`` turns, its floor tilted down towards the wall by
``cross_tilt``, with an optional lip ``lip_height`` along its open (inner) edge. Below the
first turn a riser closes the shelf down to the bottom (a real bowl's first turn is cut
into its wall), so no part wedges under the ramp. A side drop (the feeder lines' tooling,
on the helix) narrows the floor to ``drop_width`` from the wall between ``drop_from`` and
``drop_to`` (fractions of the helix's length): a part not against the wall falls back into
the bowl, as a real bowl returns its rejects to the bottom. A wiper (the feeder lines' too) is
a bar across the helix at ``wiper_at`` of its length whose underside follows the floor
``wiper_height`` above it: a part taller than that (stacked, on edge) is stopped by its
upstream face and pushed off the open edge back into the bowl. At its top the track goes on as a
straight chute, the helix's tangent, ``chute_length`` long, with a wall on both sides,
through a slot in the bowl's wall; parts leave over the chute's end.

Frame: z up the bowl's axis (the axis is x = y = 0), gravity -z; the track climbs
counter-clockwise seen from above (increasing polar angle theta), and ends at
theta = -90 degrees, so the chute runs along +x, at y = -(its centre line radius): the
outlet edge is the plane x = ``outlet_x`` (the chute's end), outside the bowl's wall there;
a part that leaves over it falls beside the bowl, below its bottom. The track starts
``turns`` turns (or a fraction of one) before that.

The drive (vibrofeed's bowl deck): the bowl turns about its axis by
theta_b(t) = (amp_t / r_mid) sin(w t) and rises by z_b(t) = amp_n sin(w t + phase), so
``amp_t`` is the tangential displacement amplitude at the track's centre line radius
r_mid, as a real bowl drive's torsional and vertical springs move it.
:func:`track_drive` projects this motion on the helix: the tangent of the track (up the
helix) and its normal see two sines of the same frequency, i.e. the linear track's
drive (amp_t, amp_n, phase, incline) the single-part models take.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ParameterError
from .feeders.records import Part, number
from .mesh import MeshBuilder, write_stl

THETA_END = -math.pi / 2  # the track's end: its tangent there is +x, the chute's direction
# Largest angle between the mesh's stations around the bowl [rad]: the wall's facets then
# deviate from the cylinder by R (1 - cos(STATION/2)) = 0.14 % of the radius (14 um in a
# 20 mm bowl). A moving mesh costs LIGGGHTS time per triangle at every step, so the bowl
# has no more triangles than its shape needs.
STATION = math.radians(6.0)
# A step of the first shelf lower than this fraction of the track's width above the bottom
# gets no face (a sliver; no part fits under it).
LOW_STEP = 0.02
# The wiper's bar along the centre line, in part sizes (as a feeder line's: long enough that a
# part cannot wedge under it tilted, short enough to stay a bar).
WIPER_LENGTH = 1.0
# The wiper's upstream face rises to this fraction of a pitch above the floor (under the next
# turn, which lies a pitch above), or to the wall's top where that is lower.
WIPER_REACH = 0.9


@dataclass(frozen=True)
class Bowl:
    """A bowl's geometry [m, deg] (see the module docstring)."""

    radius: float
    track_width: float
    helix_angle: float
    turns: float
    wall_height: float
    cone_angle: float = 0.0
    cross_tilt: float = 0.0
    lip_height: float = 0.0
    chute_length: float = 0.0
    drop_from: float = 0.0  # the side drop: fractions of the helix's length, ...
    drop_to: float = 0.0  # ... none when drop_to <= drop_from
    drop_width: float = 0.0  # the floor left over the drop, from the wall
    wiper_height: float = 0.0  # the wiper's underside above the floor (0: no wiper) ...
    wiper_at: float = 0.5  # ... its upstream face at this fraction of the helix's length ...
    wiper_length: float = 0.0  # ... and its bar this long along the centre line

    @property
    def r_mid(self) -> float:
        """The track's centre line radius."""
        return self.radius - self.track_width / 2

    @property
    def slope(self) -> float:
        """tan of the helix angle at the centre line."""
        return math.tan(math.radians(self.helix_angle))

    @property
    def pitch(self) -> float:
        """Rise per turn."""
        return 2 * math.pi * self.r_mid * self.slope

    @property
    def theta_start(self) -> float:
        return THETA_END - 2 * math.pi * self.turns

    @property
    def z_start(self) -> float:
        """The floor's height on the centre line where the track starts: the floor's outer
        edge on the bottom (at the wall, height 0), or higher when the bottom's cone is
        steeper than the floor's cross tilt, so that its inner edge meets the cone."""
        w, cone, tilt = self.track_width, _tan(self.cone_angle), _tan(self.cross_tilt)
        return max(w / 2 * tilt, w * cone - w / 2 * tilt)

    def floor_z(self, theta, r):
        """The track floor's height at polar angle ``theta`` [rad, from theta_start up to
        THETA_END] and radius ``r``: the helix on the centre line, the cross tilt across."""
        rise = self.pitch * (np.asarray(theta) - self.theta_start) / (2 * math.pi)
        return self.z_start + rise - (np.asarray(r) - self.r_mid) * _tan(self.cross_tilt)

    def bottom_z(self, r):
        """The bottom's height at radius ``r``: the cone, 0 at the wall."""
        return (self.radius - np.asarray(r)) * _tan(self.cone_angle)

    @property
    def end_z(self) -> float:
        """The track's centre line height at its end (the chute's start)."""
        return float(self.floor_z(THETA_END, self.r_mid))

    @property
    def top(self) -> float:
        """The wall's top: wall_height above the end's outer floor edge."""
        return float(self.floor_z(THETA_END, self.radius)) + self.wall_height

    @property
    def slot(self) -> float:
        """The angle past the track's end over which the chute passes through the wall [rad]:
        to where the chute's inner edge (radius r_mid - w/2 at the start) leaves the bowl."""
        return math.acos((self.radius - self.track_width) / self.radius)

    @property
    def outlet_x(self) -> float:
        """The chute's end (the outlet edge), at x = chute_length cos(helix_angle)."""
        return self.chute_length * math.cos(math.radians(self.helix_angle))

    @property
    def chute_exit_length(self) -> float:
        """The chute length at which its inner edge leaves the bowl (it must be longer)."""
        return self.radius * math.sin(self.slot) / math.cos(math.radians(self.helix_angle))

    def helix_point(self, theta, r=None) -> np.ndarray:
        """(..., 3) points of the track floor at ``theta`` and radius ``r`` (centre line)."""
        theta = np.asarray(theta, dtype=float)
        r = self.r_mid if r is None else np.asarray(r, dtype=float)
        return np.stack(np.broadcast_arrays(r * np.cos(theta), r * np.sin(theta),
                                            self.floor_z(theta, r)), axis=-1)

    def arc_length(self, theta) -> np.ndarray:
        """Path length along the centre line from the track's start to ``theta``."""
        return (np.asarray(theta) - self.theta_start) * self.r_mid / math.cos(math.radians(self.helix_angle))

    def theta_at(self, s) -> np.ndarray:
        """The polar angle [rad] at path length ``s`` [m] from the track's start along the
        centre line: :meth:`arc_length`'s inverse."""
        along = np.asarray(s, dtype=float) * math.cos(math.radians(self.helix_angle))
        return self.theta_start + along / self.r_mid

    @property
    def length(self) -> float:
        """The helix's centre line length (start to the chute)."""
        return float(self.arc_length(THETA_END))

    @property
    def first_turn_end(self) -> float:
        """The polar angle where the first turn ends (one turn past the start; past the track's
        end on a bowl of under a turn), with a rounding's slack: stations at or before it lie
        over the bottom, where the riser closes the shelf."""
        return self.theta_start + 2 * math.pi + 1e-12

    @property
    def stations(self) -> np.ndarray:
        """The track's stations: the mesh's floor edges, every STATION at most, from its
        start to its end."""
        return _stations(self.theta_start, THETA_END)

    @property
    def drop(self) -> tuple[float, float] | None:
        """The side drop's polar angles (start, end) [rad], each at the track's station nearest
        to its fraction of the helix (the mesh's floor changes width at a station); None
        without a drop."""
        if not self.drop_to > self.drop_from:
            return None
        t = self.stations
        n = len(t) - 1
        a, b = (int(round(f * n)) for f in (self.drop_from, self.drop_to))
        return (float(t[a]), float(t[b])) if b > a else None

    @property
    def wiper(self) -> tuple[float, float] | None:
        """The wiper's polar angles (its upstream face, its bar's end) [rad]; None without a
        wiper."""
        if not self.wiper_height > 0:
            return None
        t0 = self.theta_start + self.wiper_at * (THETA_END - self.theta_start)
        return t0, t0 + self.wiper_length * math.cos(math.radians(self.helix_angle)) / self.r_mid

    def wiper_top(self, r) -> np.ndarray:
        """The height the wiper's upstream face reaches at radius ``r``: WIPER_REACH of a
        pitch above the floor, or the wall's top where that is lower."""
        t0, _ = self.wiper
        return np.minimum(self.floor_z(t0, r) + WIPER_REACH * self.pitch, self.top)

    def width_at(self, theta) -> np.ndarray:
        """The floor's width from the wall at polar angle ``theta`` (on the helix): drop_width
        over the side drop (its start included, its end not), track_width elsewhere."""
        theta = np.asarray(theta, dtype=float)
        drop = self.drop
        if drop is None:
            return np.full(theta.shape, self.track_width)
        inside = (theta >= drop[0] - 1e-12) & (theta < drop[1] - 1e-12)
        return np.where(inside, self.drop_width, self.track_width)

    def height_at(self, s) -> np.ndarray:
        """The centre line's floor height at path coordinate ``s`` (:func:`path_coordinate`):
        z_start + s sin(helix_angle), up the helix and along the chute alike (the chute rises
        at the helix angle)."""
        return self.z_start + np.asarray(s, dtype=float) * math.sin(math.radians(self.helix_angle))


def _tan(deg: float) -> float:
    return math.tan(math.radians(deg))


def _stations(start: float, end: float, step: float = STATION) -> np.ndarray:
    n = max(1, math.ceil((end - start) / step - 1e-9))
    return np.linspace(start, end, n + 1)


def bowl_mesh(b: Bowl) -> tuple[np.ndarray, np.ndarray]:
    """The bowl at rest: bottom, riser, helical track (and lip), wall with the chute's
    slot, and the chute with its two walls; indexed triangles over shared vertices.

    Faces are oriented towards where the parts are (LIGGGHTS' mesh/surface contacts
    either side; the orientation only serves pictures)."""
    m = MeshBuilder()
    w, R = b.track_width, b.radius
    r_in = R - w
    # the stations around the bowl, shared by the bottom's rim and the wall (a closed seam):
    # every STATION from the track's end
    around = _stations(THETA_END, THETA_END + 2 * math.pi)
    # the slot ends at the first station past the chute's inner edge (a station of its own
    # there would leave a sliver of wall a degree or two wide)
    slot_end = float(around[np.searchsorted(around, THETA_END + b.slot - 1e-12)])
    # the bottom: a cone, exactly a fan of triangles from its apex to the rim
    apex = (0.0, 0.0, float(b.bottom_z(0.0)))
    for t0, t1 in zip(around[:-1], around[1:]):
        m.triangle(apex, (R * math.cos(t0), R * math.sin(t0), 0.0), (R * math.cos(t1), R * math.sin(t1), 0.0))
    # the track: floor (and lip) from its start to its end, its inner edge R - width (the
    # side drop's narrower floor between two stations)
    track = b.stations
    inner = R - b.width_at(0.5 * (track[:-1] + track[1:]))  # each segment's inner edge radius
    drop = b.drop or (None, None)
    for (t0, t1), ri in zip(zip(track[:-1], track[1:]), inner):
        a0, a1 = b.helix_point(t0, ri), b.helix_point(t1, ri)
        c0, c1 = b.helix_point(t0, R), b.helix_point(t1, R)
        # (normal up; a wide segment beside the drop has a corner where the narrow floor's edge
        # meets its end, so that the two share whole edges: no T-junction)
        if ri == r_in and t1 == drop[0]:
            m.polygon([a0, c0, c1, b.helix_point(t1, R - b.drop_width), a1])
        elif ri == r_in and t0 == drop[1]:
            m.polygon([c1, a1, a0, b.helix_point(t0, R - b.drop_width), c0])
        else:
            m.quad(a0, c0, c1, a1)
        if b.lip_height > 0 and ri == r_in:  # (no lip over the drop: it would hold the rejects)
            up = np.array([0.0, 0.0, b.lip_height])
            m.quad(a1, a0, a0 + up, a1 + up)

    # the riser under the first turn: from the bottom up to the floor's inner edge (an edge
    # less than LOW_STEP of the track's width above the bottom is its own foot: a face that
    # low would be a sliver LIGGGHTS refuses, and no part fits under it)
    low = LOW_STEP * w

    def foot(top: np.ndarray, bottom: float) -> np.ndarray:
        return top if top[2] - bottom <= low else np.array([top[0], top[1], bottom])

    first = track[track <= b.first_turn_end]
    for (t0, t1), ri in zip(zip(first[:-1], first[1:]), inner):
        top0, top1 = b.helix_point(t0, ri), b.helix_point(t1, ri)
        m.quad(foot(top0, float(b.bottom_z(ri))), foot(top1, float(b.bottom_z(ri))), top1, top0)
    # where the side drop narrows the first turn's shelf, a radial face closes it down to the
    # bottom at each end (check_bowl keeps the shelf there at least a part high)
    # (in rows at most ten times as high as the face is wide: a narrow step under a tall
    # shelf would otherwise be a sliver)
    for t in (b.drop or ()):
        if t <= b.first_turn_end:
            r_narrow = R - b.drop_width
            top_w, top_n = b.helix_point(t, r_in), b.helix_point(t, r_narrow)
            foot_w = np.array([top_w[0], top_w[1], float(b.bottom_z(r_in))])
            foot_n = np.array([top_n[0], top_n[1], float(b.bottom_z(r_narrow))])
            n = max(1, math.ceil(max(top_w[2] - foot_w[2], top_n[2] - foot_n[2])
                                 / (10 * (b.track_width - b.drop_width)) - 1e-9))
            k = np.linspace(0.0, 1.0, n + 1)[:, None]
            edge_w, edge_n = foot_w + k * (top_w - foot_w), foot_n + k * (top_n - foot_n)
            for j in range(n):
                m.quad(edge_w[j], edge_n[j], edge_n[j + 1], edge_w[j + 1])
    # the start's face: the first turn's shelf is solid, closed by a radial face at its start
    s_in, s_out = b.helix_point(b.theta_start, r_in), b.helix_point(b.theta_start, R)
    m.quad(foot(s_in, float(b.bottom_z(r_in))), foot(s_out, 0.0), s_out, s_in)
    # the wall in two bands all round, split at the slot's floor z_slot (the end's outer floor
    # edge), the upper one open over the slot: no long sliver of a face (LIGGGHTS refuses a
    # triangle whose smallest angle is below its curvature, about 0.26 deg)
    # (a tall bowl's lower band in rows at most ten stations' arcs high: its faces' smallest
    # angles stay above 5 deg)
    z_slot = float(b.floor_z(THETA_END, R))
    rows = np.linspace(0.0, z_slot, max(1, math.ceil(z_slot / (10 * R * STATION) - 1e-9)) + 1)
    for t0, t1 in zip(around[:-1], around[1:]):
        p0 = (R * math.cos(t0), R * math.sin(t0))
        p1 = (R * math.cos(t1), R * math.sin(t1))
        for z0, z1 in zip(rows[:-1], rows[1:]):
            m.quad((*p0, z0), (*p0, z1), (*p1, z1), (*p1, z0))
        if t0 >= slot_end - 1e-12:
            m.quad((*p0, z_slot), (*p0, b.top), (*p1, b.top), (*p1, z_slot))
    # the chute: the helix's tangent at its end, along +x at y = -r (floor, two walls)
    cos_a, sin_a = math.cos(math.radians(b.helix_angle)), math.sin(math.radians(b.helix_angle))
    end_in, end_out = b.helix_point(THETA_END, r_in), b.helix_point(THETA_END, R)
    n_chute = max(1, math.ceil(b.chute_length / (4 * w)))
    for s0, s1 in zip(np.linspace(0, b.chute_length, n_chute + 1)[:-1],
                      np.linspace(0, b.chute_length, n_chute + 1)[1:]):
        d0, d1 = np.array([s0 * cos_a, 0, s0 * sin_a]), np.array([s1 * cos_a, 0, s1 * sin_a])
        i0, i1, o0, o1 = end_in + d0, end_in + d1, end_out + d0, end_out + d1
        m.quad(i0, o0, o1, i1)
        up = np.array([0.0, 0.0, b.wall_height])
        m.quad(o0, o0 + up, o1 + up, o1)
        m.quad(i1, i1 + up, i0 + up, i0)
    # the wiper: a bar across the whole track (the side drop's stretch too), its underside
    # wiper_height above the floor from its face to its end, its upstream face up to
    # wiper_top; parts below its underside pass, taller ones are stopped and pushed inwards
    if b.wiper is not None:
        t0, t1 = b.wiper
        h = np.array([0.0, 0.0, b.wiper_height])
        u0, u1 = b.helix_point(t0, r_in) + h, b.helix_point(t0, R) + h
        m.quad(u0, u1, b.helix_point(t1, R) + h, b.helix_point(t1, r_in) + h)
        top_in, top_out = u0.copy(), u1.copy()
        top_in[2], top_out[2] = b.wiper_top(r_in), b.wiper_top(R)
        # (in rows at most ten times as high as the track is wide, as the drop's end faces)
        n = max(1, math.ceil(max(top_in[2] - u0[2], top_out[2] - u1[2]) / (10 * w) - 1e-9))
        k = np.linspace(0.0, 1.0, n + 1)[:, None]
        edge_in, edge_out = u0 + k * (top_in - u0), u1 + k * (top_out - u1)
        for j in range(n):
            m.quad(edge_out[j], edge_in[j], edge_in[j + 1], edge_out[j + 1])
    return m.mesh()


# ------------------------------------------------------------------ the drive on the track
@dataclass(frozen=True)
class TrackDrive:
    """The bowl's drive seen by a part on the track at radius ``r``: the linear deck's
    parameters (amplitudes [m], phase of the normal motion over the tangential one [deg],
    incline [deg]) and the radial (centripetal) acceleration the torsion adds at its peak
    [m/s^2], which the linear models leave out."""

    amp_t: float
    amp_n: float
    phase: float
    incline: float
    centripetal: float


def track_drive(amp_t: float, amp_n: float, phase: float, freq: float, helix_angle: float,
                r_mid: float, r: float | None = None) -> TrackDrive:
    """Project the bowl's motion on the helix at radius ``r`` (default the centre line).

    The bowl's point at radius r moves by (r/r_mid) amp_t sin(w t) along e_theta and by
    amp_n sin(w t + phase) along z. The helix at r rises at alpha_r, tan(alpha_r) =
    tan(helix_angle) r_mid / r; its tangent (up the helix) is cos(alpha_r) e_theta +
    sin(alpha_r) e_z, its normal -sin(alpha_r) e_theta + cos(alpha_r) e_z. As phasors
    (sin(w t) = 1, sin(w t + phase) = e^{i phase}): tangential T = u cos(a) + v sin(a),
    normal N = -u sin(a) + v cos(a) with u = (r/r_mid) amp_t, v = amp_n e^{i phase}; the
    linear drive is amp_t = |T|, amp_n = |N|, phase = arg N - arg T, incline = alpha_r. The
    torsion's centripetal acceleration r (theta_b')^2 peaks at r (amp_t w / r_mid)^2.
    """
    r = r_mid if r is None else r
    alpha = math.atan(math.tan(math.radians(helix_angle)) * r_mid / r)
    u = r / r_mid * amp_t
    v = amp_n * cmath.exp(1j * math.radians(phase))
    tangential = u * math.cos(alpha) + v * math.sin(alpha)
    normal = -u * math.sin(alpha) + v * math.cos(alpha)
    lead = 0.0
    if abs(tangential) > 0 and abs(normal) > 0:
        lead = math.degrees(cmath.phase(normal) - cmath.phase(tangential))
        lead = (lead + 180.0) % 360.0 - 180.0
    w = 2 * math.pi * freq
    return TrackDrive(abs(tangential), abs(normal), lead, math.degrees(alpha),
                      r * (amp_t * w / r_mid) ** 2)


# ------------------------------------------------------------------ checks
# The deck's parameters a bowl is built from (bowl_from), and those of its parts: what the
# prepare hook reads and write_bowl needs.
GEOMETRY = ("bowl_diameter", "track_width", "helix_angle", "turns", "wall_height", "cone_angle",
            "cross_tilt", "lip_height", "chute_length", "drop_from", "drop_to", "drop_width",
            "wiper_height", "wiper_at")
PART = ("part_size", "part_thickness", "shape", "size_spread")
# a box's further dimensions (shape 3, vibrofeed.parts), optional: the deck's defaults
BOX_PART = {"part_width": None, "bump_height": 0.0, "bump_diameter": 0.0, "bump_at": 0.5,
            "clump_spacing": 0.75}


def bowl_from(p: Mapping) -> Bowl:
    """The bowl of a deck's parameters (numbers or their strings; the optional ones default
    as the deck's do)."""
    def get(name, default=None):
        return number(p, name, default)

    return Bowl(radius=get("bowl_diameter") / 2, track_width=get("track_width"),
                helix_angle=get("helix_angle"), turns=get("turns"), wall_height=get("wall_height"),
                cone_angle=get("cone_angle", 0.0), cross_tilt=get("cross_tilt", 0.0),
                lip_height=get("lip_height", 0.0), chute_length=get("chute_length", 0.0),
                drop_from=get("drop_from", 0.0), drop_to=get("drop_to", 0.0),
                drop_width=get("drop_width", 0.0), wiper_height=get("wiper_height", 0.0),
                wiper_at=get("wiper_at", 0.5), wiper_length=WIPER_LENGTH * get("part_size", 0.0))


# The pre-fill's cubes along the track are this fraction of its width on a side (a cube of that
# side fits in the track's width however it is turned round the helix, :func:`fill_boxes`).
FILL_SIDE = 0.6


def widest_part(p: Mapping) -> float:
    """A part's width lying flat (vibrofeed.feeders.records.Part.widest)."""
    return Part.from_values(p).widest


def tallest_part(p: Mapping) -> float:
    """A part's height lying flat (a sphere's diameter, a chip's, disc's or box's thickness,
    a box's bump up)."""
    return Part.from_values(p).tallest


def stl_words(values: Mapping) -> dict:
    """An stl part's (shape 4) STL and clump knobs from ``values``, for Part.from_values."""
    names = ("part_file", "part_unit", "clump_method", "clump_spheres", "clump_resolution", "clump_overlap")
    return {k: values[k] for k in names if k in values}


def part_reach(p: Mapping) -> float:
    """A part's circumscribed radius (the deck's r_ext; Part.reach)."""
    return Part.from_values(p).reach


def check_bowl(p: Mapping[str, float]) -> None:
    """Relations between a bowl's parameters (decks/bowl_feeder.liggghts refuses the same
    for runs by hand); nothing for a deck that is not a bowl."""
    if any(name not in p for name in ("bowl_diameter", "track_width", "helix_angle", "turns",
                                      "wall_height", "part_size")):
        return  # not a bowl (or a partial set, as the parameter rules see one)
    b = bowl_from(p)
    wide, tall = widest_part(p), tallest_part(p)
    if p.get("n_parts", 1) <= 0 and p.get("n_track", 1) <= 0:
        raise ParameterError("n_parts=0 and n_track=0: no part in the bowl; set n_parts (the pile) "
                             "or n_track (along the track)")
    if b.turns <= 0:
        raise ParameterError(f"turns={b.turns:g} must be > 0: the track climbs at least part of a turn")
    if not 0 < b.helix_angle < 45:
        raise ParameterError(f"helix_angle={b.helix_angle:g} deg must be in (0, 45): the track climbs")
    if b.track_width < wide:
        raise ParameterError(f"track_width={b.track_width:g} m is narrower than a part ({wide:g} m across)")
    if b.track_width >= b.radius / 2:
        raise ParameterError(f"track_width={b.track_width:g} m is more than a quarter of bowl_diameter="
                             f"{2 * b.radius:g} m: the track would fill the bowl")
    if b.lip_height and b.lip_height >= b.pitch / 2:
        raise ParameterError(f"lip_height={b.lip_height:g} m reaches half way to the next turn")
    if b.pitch - max(b.lip_height, 0.0) < 3 * tall:
        lip = b.lip_height > 0  # (the lip stands in the room between turns)
        raise ParameterError(f"helix_angle={b.helix_angle:g} deg rises {b.pitch:.3g} m per turn"
                             + (f", and lip_height={b.lip_height:g} m leaves {b.pitch - b.lip_height:.3g} m "
                                "of it," if lip else ",")
                             + f" less than three parts ({3 * tall:.3g} m) above the turn below: parts "
                             "would jam between turns; "
                             + ("a lower lip, " if lip else "") + "a steeper helix or a wider bowl")
    if b.wall_height <= tall:
        raise ParameterError(f"wall_height={b.wall_height:g} m is no higher than a part ({tall:g} m)")
    reach = part_reach(p)
    room = min(FILL_SIDE * b.track_width, fill_height(b, reach, tall))
    if p.get("n_track", 0) > 0 and 2 * reach >= room:
        # (LIGGGHTS inserts a part's bounding sphere wholly inside a cube: it would stop with
        # "Unable to calculate region volume")
        raise ParameterError(f"n_track={p['n_track']:g}: a part turned at random needs {2 * reach:.3g} m "
                             f"(its clump's bounding sphere), more than the cubes along the track it is "
                             f"placed in ({room:.3g} m: {FILL_SIDE} track_width); put the parts in the "
                             f"pile (n_parts) or widen the track beyond {2 * reach / FILL_SIDE:.3g} m")
    if b.drop_from != 0 or b.drop_to != 0:  # a side drop asked for
        _check_drop(b, wide, tall)
    if b.wiper_height != 0:
        _check_wiper(b, tall)
    if b.chute_length <= b.chute_exit_length + wide:
        raise ParameterError(f"chute_length={b.chute_length:g} m ends inside the bowl: its inner edge "
                             f"leaves the wall after {b.chute_exit_length:.3g} m; make it longer than "
                             f"{b.chute_exit_length + wide:.3g} m")


def _check_drop(b: Bowl, wide: float, tall: float) -> None:
    """The side drop's refusals: a stretch of the helix, a floor that keeps one part and
    drops a second, and (in the first turn, over its riser) a shelf a part high."""
    if not 0 <= b.drop_from < b.drop_to <= 1:
        raise ParameterError(f"drop_from={b.drop_from:g}, drop_to={b.drop_to:g}: the side drop needs "
                             "0 <= drop_from < drop_to <= 1 (fractions of the helix's length)")
    if b.drop is None:
        raise ParameterError(f"drop_from={b.drop_from:g} and drop_to={b.drop_to:g} fall on one station "
                             f"of the helix's mesh ({math.degrees(b.stations[1] - b.stations[0]):.3g} deg "
                             "apart): a longer side drop")
    if not wide <= b.drop_width <= b.track_width - wide / 4:
        raise ParameterError(f"drop_width={b.drop_width:g} m must hold a part ({wide:g} m) and be a "
                             f"quarter part narrower than track_width={b.track_width:g} m (at most "
                             f"{b.track_width - wide / 4:.3g} m)")
    r_narrow = b.radius - b.drop_width
    for t in b.drop:
        if t <= b.first_turn_end:
            shelf = float(b.floor_z(t, r_narrow) - b.bottom_z(r_narrow))
            if shelf < tall:
                raise ParameterError(f"drop_from={b.drop_from:g}: the side drop starts where the first "
                                     f"turn's shelf is {shelf:.3g} m above the bottom, less than a part "
                                     f"({tall:g} m); start it further up the helix")


def _check_wiper(b: Bowl, tall: float) -> None:
    """The wiper's refusals: on the helix, a part lying flat passes under it, and its face
    stands above its underside."""
    if not 0 <= b.wiper_at < 1:
        raise ParameterError(f"wiper_at={b.wiper_at:g} must be in [0, 1) (a fraction of the helix's length)")
    if b.wiper[1] > THETA_END + 1e-12:
        raise ParameterError(f"wiper_at={b.wiper_at:g}: the wiper's bar ({b.wiper_length:g} m) runs past "
                             "the helix's end; lower wiper_at")
    if b.wiper_height < tall:
        raise ParameterError(f"wiper_height={b.wiper_height:g} m is lower than a part lying flat "
                             f"({tall:g} m): no part would pass the wiper")
    t0, _ = b.wiper
    room = float(min(b.wiper_top(r) - b.floor_z(t0, r) for r in (b.radius - b.track_width, b.radius)))
    if b.wiper_height >= room:
        raise ParameterError(f"wiper_height={b.wiper_height:g} m is not below the wiper's face, which "
                             f"rises {room:.3g} m above the floor (under the next turn or the wall's "
                             "top): the wiper would not exist")


def climb_advice(p: Mapping[str, float]) -> list[str]:
    """A warning when the single-part model says parts do not climb this bowl's helix under
    its drive (its speed up the centre line <= 0): a helix steeper than the drive allows.
    Empty for a deck that is not a bowl, or one the model cannot judge (a parameter missing)."""
    needed = ("bowl_diameter", "track_width", "helix_angle", "freq", "amp_t", "amp_n", "phase",
              "mu", "restitution", "part_size")
    if any(name not in p for name in needed):
        return []
    from .models.deck import transport  # scipy: loaded for a bowl only

    b = bowl_from(p)
    d = track_drive(number(p, "amp_t"), number(p, "amp_n"), number(p, "phase"), number(p, "freq"),
                    b.helix_angle, b.r_mid)
    try:
        speed = transport({**p, "amp_t": d.amp_t, "amp_n": d.amp_n, "phase": d.phase,
                           "incline": d.incline}).velocity
    except (KeyError, ValueError):
        return []
    if speed > 0:
        return []
    return [f"helix_angle={b.helix_angle:g} deg: the single-part model says parts do not climb this "
            f"helix under this drive ({speed * 1e3:.3g} mm/s up its centre line); a shallower helix, "
            "a larger amplitude or another phase"]


def chute_speed(p: Mapping[str, float], x: float):
    """The single-part model on a bowl's chute, x [m] along it from the slot
    (:mod:`vibrofeed.models.cross_shake`): the helix's drive along it, the torsion's x theta
    across it, a part sliding between its walls with the track's width less a part's
    (``part_size``: a chip square to the chute) of play. A :class:`~vibrofeed.models.
    cross_shake.ChuteState`; ValueError where the drive would make the part hop."""
    from .models.cross_shake import chute_drive, sliding_speed  # loaded for a bowl only

    b = bowl_from(p)
    along, across, normal = chute_drive(number(p, "amp_t"), number(p, "amp_n"), number(p, "phase"),
                                        b.helix_angle, b.r_mid, x)
    return sliding_speed(number(p, "freq"), along, across, normal, number(p, "mu"), b.helix_angle,
                         clearance=b.track_width - widest_part(p))


# Points along the chute at which its model is evaluated for a lone part's mean speed.
CHUTE_POINTS = 9


def chute_mean_speed(p: Mapping[str, float]) -> tuple[float | None, str]:
    """(speed [m/s], note) of a lone part crossing the chute by the model (:func:`chute_speed`):
    the chute's length over the time it takes, L / integral dx / v(x), from the slot to a part
    short of the outlet (trapezoids on CHUTE_POINTS points); 0 with a note where the part
    stalls (v <= 0 somewhere), None with a note where the drive makes it hop."""
    b = bowl_from(p)
    xs = np.linspace(0.0, b.chute_length - number(p, "part_size"), CHUTE_POINTS)
    try:
        v = np.array([chute_speed(p, float(x)).velocity for x in xs])
    except ValueError as exc:
        return None, f"the chute's model only slides: {exc}"
    if (v <= 0).any():
        return 0.0, f"a lone part stalls on the chute by x = {xs[np.argmax(v <= 0)]:.3g} m"
    return float((xs[-1] - xs[0]) / np.trapezoid(1 / v, xs)), ""


# ------------------------------------------------------------------ the prepare hook's part
def fill_height(b: Bowl, reach: float, tall: float) -> float:
    """How high the pre-fill's cubes along the track reach above its floor [m]: room for a part
    however it is turned (LIGGGHTS inserts its bounding sphere, radius ``reach``) two and a half
    times over, under the next turn (a pitch up, less a part ``tall`` and a half)."""
    return min(2.5 * 2 * reach, b.pitch - 1.5 * tall)


def fill_boxes(b: Bowl, size: float, height: float, start: float = 0.25) -> list[tuple]:
    """Cubes above the track's floor, one every cube side along its centre line, from
    ``start`` of a turn after the track's start, up the helix and along the chute to its
    end (a part's ``size`` short of it), none over the side drop or under the wiper and a
    cube's side either side of them: where parts are pre-placed along the track. Each
    (x0, x1, y0, y1, z0, z1): side 0.6 track_width (a cube of that side fits in the track's
    width however it is turned), from the highest floor point under it plus a twentieth of a
    part to ``height`` above. The cubes are LIGGGHTS block regions, square to x and y: round
    the helix they stand turned against it (:func:`_highest_floor`)."""
    side = FILL_SIDE * b.track_width
    half = side / 2
    dtheta = side / b.r_mid
    t0 = b.theta_start + 2 * math.pi * start + dtheta
    boxes = []

    def box(x, y, floor):
        z0 = floor + 0.05 * size
        return (x - half, x + half, y - half, y + half, z0, z0 + height)

    drop, wiper = b.drop, b.wiper
    for t in np.arange(t0, THETA_END - dtheta / 2, dtheta):
        if drop is not None and drop[0] - dtheta <= t <= drop[1] + dtheta:
            continue  # none over the side drop: its floor may not reach the centre line
        if wiper is not None and wiper[0] - dtheta <= t <= wiper[1] + dtheta:
            continue  # none under the wiper: a part placed there would sit on or across it
        c = b.helix_point(t)
        x, y = float(c[0]), float(c[1])
        boxes.append(box(x, y, _highest_floor(b, x - half, x + half, y - half, y + half, t)))
    # the chute: straight, rising at the helix angle, tilted across as the helix
    slope = math.tan(math.radians(b.helix_angle))
    # (from its end back, the last cube a part's size short of the outlet edge: the chute is
    # full at once, and a part that lands tipped and slides does not leave while the fill
    # settles, before the vibration and its outlet count start)
    for x in np.arange(b.outlet_x - size - half, side - 1e-12, -side)[::-1]:
        floor = b.end_z + (x + half) * slope + half * _tan(b.cross_tilt)
        boxes.append(box(float(x), -b.r_mid, floor))
    return boxes


def _highest_floor(b: Bowl, x0: float, x1: float, y0: float, y1: float, theta: float) -> float:
    """The helix floor's highest point over the rectangle [x0, x1] x [y0, y1] of the bowl's
    frame, near polar angle ``theta``.

    The floor is z = K theta - tan(cross_tilt) r + const (K = pitch / 2 pi): its gradient
    K e_theta / r - tan(cross_tilt) e_r never vanishes, so the highest point is on the
    rectangle's outline. Along a side, at distance h from the axis, write u for the distance
    from the foot of the perpendicular (r^2 = h^2 + u^2) and c = +-h for the sense the side
    turns about the axis (d theta / du = c / r^2): dz/du = K c / r^2 - tan(cross_tilt) u / r,
    zero where u r = q = K c / tan(cross_tilt), i.e. u^2 = 2 q^2 / (sqrt(c^4 + 4 q^2) + c^2), a
    maximum (u r grows with u); clamped to the side, with the corners, the candidates."""
    k, tilt = b.pitch / (2 * math.pi), _tan(b.cross_tilt)
    corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    points = list(corners)
    if tilt > 0:
        for (ax, ay), (bx, by) in zip(corners, corners[1:] + corners[:1]):
            side = math.hypot(bx - ax, by - ay)
            dx, dy = (bx - ax) / side, (by - ay) / side
            c = ax * dy - ay * dx  # the cross product p x d: the same all along the side
            q = k * c / tilt
            u = math.copysign(math.sqrt(2 * q * q / (math.sqrt(c ** 4 + 4 * q * q) + c * c)), q)
            s = min(max(u - (ax * dx + ay * dy), 0.0), side)
            points.append((ax + s * dx, ay + s * dy))
    x, y = np.array(points).T
    t = theta + np.mod(np.arctan2(y, x) - theta + math.pi, 2 * math.pi) - math.pi
    return float(np.max(b.floor_z(t, np.hypot(x, y))))


def write_bowl(values: Mapping[str, str], folder: Path) -> list[str]:
    """Write the bowl's mesh (``bowl.stl``) and return ``prepared.in`` lines: the derived
    geometry the deck reads and the regions along the track for its pre-fill."""
    p = {k: float(v) for k, v in values.items() if k in GEOMETRY + PART + tuple(BOX_PART)}
    p.update(stl_words(values))
    b = bowl_from(p)
    write_stl(*bowl_mesh(b), folder / "bowl.stl", "bowl")
    # room for a part however it is turned (LIGGGHTS inserts its bounding sphere), under
    # the next turn
    tall = tallest_part(p)
    boxes = fill_boxes(b, number(p, "part_size"), fill_height(b, part_reach(p), tall))
    lines = [f"variable bowl_{k} equal {float(v)!r}\n" for k, v in (
        ("r_mid", b.r_mid), ("pitch", b.pitch), ("top", b.top), ("end_z", b.end_z),
        ("outlet_x", b.outlet_x), ("length", b.length), ("theta_start", b.theta_start),
        ("slot", b.slot), ("fill_boxes", len(boxes)))]
    names = []
    for k, (x0, x1, y0, y1, z0, z1) in enumerate(boxes, 1):
        corners = " ".join(repr(float(c)) for c in (x0, x1, y0, y1, z0, z1))
        lines.append(f"region track_fill_{k} block {corners} units box\n")
        names.append(f"track_fill_{k}")
    if names:
        lines.append(f"region track_fill union {len(names)} {' '.join(names)} units box\n")
    return lines


# ------------------------------------------------------------------ where a part is along the track
def path_coordinate(b: Bowl, points) -> np.ndarray:
    """Where points (..., 3) of the bowl's frame (the bowl at rest) are along the track: the
    arc length along the helix's centre line from its start (``Bowl.arc_length``), then along
    the chute (the helix's length plus the distance along it); NaN for a point that is not
    over the track: in the pile (inside the track's inner edge, the side drop's over it),
    outside the bowl, or more
    than a turn above the floor under it (on no turn). On the helix, a point over the track
    (its radius within the track's width) belongs to the turn whose floor lies below it,
    less than a pitch down."""
    p = np.asarray(points, dtype=float)
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    r = np.hypot(x, y)
    theta = np.arctan2(y, x)
    out = np.full(r.shape, np.nan)
    ring = (r >= b.radius - b.track_width) & (r <= b.radius)
    # the turn below: from the lowest turn at this polar angle up, the first whose floor lies
    # under the point by less than a pitch (a part sinks into the floor by far less than w)
    best = np.full(r.shape, np.nan)
    for extra in range(int(math.ceil(b.turns)) + 1):
        t = b.theta_start + np.mod(theta - b.theta_start, 2 * math.pi) + 2 * math.pi * extra
        ok = ring & (t <= THETA_END + 1e-12) & (r >= b.radius - b.width_at(t))  # over its floor
        height = z - b.floor_z(t, r)
        hit = ok & (height >= -b.track_width) & (height < b.pitch) & np.isnan(best)
        best = np.where(hit, t, best)
    out = np.where(np.isnan(best), out, b.arc_length(best))
    # the chute: past the end's radial line, within its width, above its floor
    cos_a, sin_a = math.cos(math.radians(b.helix_angle)), math.sin(math.radians(b.helix_angle))
    along = x / cos_a
    floor = b.end_z + along * sin_a - (-y - b.r_mid) * _tan(b.cross_tilt)
    chute = (x >= 0) & (np.abs(y + b.r_mid) <= b.track_width / 2) & (z >= floor - b.track_width) \
        & (z < floor + b.pitch) & (along <= b.chute_length)
    return np.where(chute, b.length + along, out)
