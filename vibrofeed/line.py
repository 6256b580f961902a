"""The meshes of a line's further sections: a track after the one before, a step down,
with its own walls and tooling.

A line is the bulk feeder (decks/bulk_feeder.liggghts) with ``sections`` >= 2: section 1
is the bulk feeder's track (vibrofeed.geometry.track_mesh), each further section k
follows the one before along x with the ``s<k>_*`` parameters (docs/feeder-lines.md);
which sections there are and where each lies is the feeder's (vibrofeed.feeders).

Frame: the deck's. Section k runs from its joint ``x0`` to ``x1 = x0 + length``,
centred on y = 0. Its floor lies ``step`` (the steps of the joints before it summed) below
section 1's at its high edge (y = +w/2) and, with a cross tilt, descends towards the
wall at y = -w/2 (parts are kept against that wall, the reference wall):
``z(y) = -step - (w/2 - y) tan(cross_tilt)``. The wall at -w/2 runs the whole section;
the wall at +w/2 is missing over the side drop, where the floor narrows to
``drop_width`` from the reference wall and parts not against it fall off the open
side. The wiper is a bar across the track whose underside follows the floor at
``wiper_height``: a part taller than that (stacked, on edge) is swept back; turned
``wiper_skew`` degrees from straight across, the bar runs downstream from the reference wall
(where its upstream face stands at ``wiper_at``) to the far wall, and pushes such a part
towards the far wall as the track conveys it against the bar. A slot is a
hole in the floor, ``slot_width`` across, its centre ``slot_offset`` from the reference wall,
from ``slot_from`` to ``slot_to``: the floor is split into strips along its edges and the
strips over it are left out, so a part narrower than the slot where it rides falls through
while one lying across it bridges it (docs/feeders.md). A gate brings both walls in at 45
degrees to ``gate_width``, centred, from ``gate_at`` to the section's end, as on section 1 (the
floor beyond its walls is left out; the side drop and slot, placed from the reference wall, lie
before it; a wiper's bar spans the walls where it stands).

Meshes are indexed triangle sets as in :mod:`vibrofeed.geometry`, with shared vertices
along common edges (floor and walls form one surface, without seams).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError
from .mesh import MeshBuilder

# The wiper's bar along x, in part sizes: long enough that a part cannot wedge under it
# tilted, short enough to stay a bar.
WIPER_LENGTH = 1.0
# A skewed wiper's largest turn from straight across [deg]: at 75 its upstream face runs 3.7
# track widths along the track; towards 90 it would lie along the track, a wall.
MAX_SKEW = 75.0
# The slot's default place: along the reference wall (its centre half its width from it, no
# floor between wall and slot). A part riding the wall falls through it only if its footprint
# lies wholly over it: past a ledge, a part on its side tips over about the ledge's edge and
# lands lying flat across the slot, bridging it (a 0.4 x 0.25 x 0.1 mm box did past a ledge
# 3/8 of its thickness wide). A part lying flat against the wall then bridges it when its
# centre lies beyond the slot, over the floor: the slot narrower than half its width across.


def slot_offset(width: float) -> float:
    """The default distance from the reference wall to the centre of a slot ``width`` across:
    the slot along the wall."""
    return width / 2


@dataclass(frozen=True)
class Section:
    """A further section's mesh geometry [m, deg]. ``drop_from``/``drop_to`` and ``wiper_at`` are
    fractions of the section's length (a drop with drop_to <= drop_from, or a wiper with
    height 0, is absent)."""

    x0: float
    length: float
    width: float
    wall_height: float
    step: float
    cross_tilt: float = 0.0
    drop_from: float = 0.0
    drop_to: float = 0.0
    drop_width: float = 0.0
    wiper_height: float = 0.0
    wiper_at: float = 0.5
    wiper_length: float = 0.0
    wiper_skew: float = 0.0  # deg from straight across (vibrofeed.feeders.records.Wiper)
    slot_from: float = 0.0
    slot_to: float = 0.0
    slot_width: float = 0.0
    slot_offset: float = 0.0  # its centre from the reference wall at y = -w/2
    gate_width: float = 0.0  # both walls come in to this, centred
    gate_at: float = 0.7

    @property
    def x1(self) -> float:
        return self.x0 + self.length

    @property
    def has_drop(self) -> bool:
        return self.drop_to > self.drop_from and 0 < self.drop_width < self.width

    @property
    def has_wiper(self) -> bool:
        return self.wiper_height > 0

    @property
    def has_gate(self) -> bool:
        return 0 < self.gate_width < self.width

    @property
    def gate_x(self) -> tuple[float, float]:
        """The gate's taper along x: both walls come in at 45 degrees from the first to the
        second, by (width - gate_width)/2 each, and stay there to the section's end."""
        a = self.x0 + self.gate_at * self.length
        return a, a + (self.width - self.gate_width) / 2

    def half_width(self, x) -> np.ndarray:
        """How far either wall stands from the centre line at ``x`` [m] (the gate's taper)."""
        if not self.has_gate:
            return self.width / 2 + 0.0 * np.asarray(x, dtype=float)
        return np.interp(x, self.gate_x, [self.width / 2, self.gate_width / 2])

    @property
    def has_slot(self) -> bool:
        return self.slot_to > self.slot_from and self.slot_width > 0

    def floor_z(self, y):
        """Height of the floor at rest at ``y`` [m]."""
        return -self.step - (self.width / 2 - np.asarray(y, dtype=float)) * math.tan(
            math.radians(self.cross_tilt))

    @property
    def lowest(self) -> float:
        """The floor's lowest point at rest (at the reference wall) [m]."""
        return float(self.floor_z(-self.width / 2))

    @property
    def drop_x(self) -> tuple[float, float]:
        return self.x0 + self.drop_from * self.length, self.x0 + self.drop_to * self.length

    @property
    def wiper_x(self) -> tuple[float, float]:
        """The wiper's footprint along x: its upstream face at the reference wall, and the end
        of its bar at the far wall (a skewed bar's run across included)."""
        a = self.x0 + self.wiper_at * self.length
        return a, a + self.wiper_reach

    @property
    def wiper_reach(self) -> float:
        """How far along x the wiper reaches from its upstream face at the reference wall [m]: its
        bar's length and a skewed bar's run across."""
        return self.wiper_length + self.wiper_run

    @property
    def wiper_run(self) -> float:
        """How far downstream a skewed bar's upstream face runs from wall to wall [m]."""
        if self.wiper_skew == 0:
            return 0.0
        return 2 * float(self.half_width(self.x0 + self.wiper_at * self.length)) * math.tan(
            math.radians(self.wiper_skew))

    @property
    def slot_x(self) -> tuple[float, float]:
        return self.x0 + self.slot_from * self.length, self.x0 + self.slot_to * self.length

    @property
    def slot_y(self) -> tuple[float, float]:
        """The slot's edges across [m] (the frame's y)."""
        a = -self.width / 2 + self.slot_offset - self.slot_width / 2
        return a, a + self.slot_width


def _stations(s: Section, spacing: float | None) -> np.ndarray:
    """x stations: uniform at most ``spacing`` apart (default the width, at most 1 mm) and
    every kink of the tooling."""
    spacing = spacing or min(s.width, 1e-3)
    n = max(1, math.ceil(s.length / spacing - 1e-9))
    xs = [np.linspace(s.x0, s.x1, n + 1)]
    if s.has_drop:
        xs.append(np.array(s.drop_x))
    if s.has_wiper:
        xs.append(np.array(s.wiper_x))
    if s.has_slot:
        xs.append(np.array(s.slot_x))
    if s.has_gate:
        xs.append(np.array(s.gate_x))
    return np.unique(np.round(np.concatenate(xs), 12))


def section_mesh(s: Section, spacing: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A further section at rest: floor (without the slot), the reference wall (y = -w/2), the
    other wall except over the side drop, and the wiper. No wall at the joint (parts arrive over
    it from section 1) nor at the outlet edge. The floor is strips between every edge across
    (the drop's, the slot's) over the whole section, so the strips beside the slot and its ends
    share their vertices with the rest: one surface, without seams."""
    if s.has_drop and not s.x0 <= s.drop_x[0] < s.drop_x[1] <= s.x1:
        raise ParameterError("the side drop does not fit on its section: 0 <= drop_from < "
                             "drop_to <= 1")
    if s.has_wiper and not s.x0 <= s.wiper_x[0] < s.wiper_x[1] <= s.x1:
        raise ParameterError("the wiper does not fit on its section: lower its wiper_at")
    if s.has_gate and not s.x0 <= s.gate_x[0] < s.gate_x[1] <= s.x1:
        raise ParameterError("the gate's taper does not fit on its section: lower its gate_at")
    if s.has_slot:
        if not s.x0 <= s.slot_x[0] < s.slot_x[1] <= s.x1:
            raise ParameterError("the slot does not fit on its section: 0 <= slot_from < slot_to <= 1")
        if not -s.width / 2 <= s.slot_y[0] < s.slot_y[1] <= s.width / 2:
            raise ParameterError("the slot does not fit across its section: slot_offset +- "
                                 "slot_width/2 must lie between the walls")
    xs = _stations(s, spacing)
    lo, hi = -s.width / 2, s.width / 2
    inner = lo + s.drop_width  # the drop's open edge
    top = -s.step + s.wall_height
    a, b = s.drop_x if s.has_drop else (math.inf, math.inf)
    sa, sb = s.slot_x if s.has_slot else (math.inf, math.inf)
    ya, yb = s.slot_y if s.has_slot else (math.inf, math.inf)
    # every edge across, on every stretch (the vertices along them are shared)
    narrow = s.gate_width / 2  # the gate's walls, past its taper
    ga = s.gate_x[1] if s.has_gate else math.inf
    ys = sorted({lo, hi} | ({inner} if s.has_drop else set()) | ({ya, yb} if s.has_slot else set())
                | ({-narrow, narrow} if s.has_gate else set()))
    b_ = MeshBuilder()
    z = s.floor_z
    for x0, x1 in zip(xs[:-1], xs[1:]):
        dropping = s.has_drop and a <= x0 and x1 <= b
        slotted = s.has_slot and sa <= x0 and x1 <= sb
        for y0, y1 in zip(ys[:-1], ys[1:]):  # floor, normal +z
            if (dropping and y0 >= inner) or (slotted and ya <= y0 and y1 <= yb) or \
                    (ga <= x0 + 1e-12 and (y0 >= narrow or y1 <= -narrow)):  # (none beyond the walls)
                continue
            b_.quad((x0, y0, z(y0)), (x1, y0, z(y0)), (x1, y1, z(y1)), (x0, y1, z(y1)))
        h0, h1 = s.half_width(x0), s.half_width(x1)  # (the walls, where a gate brings them in)
        b_.quad((x1, -h1, z(-h1)), (x0, -h0, z(-h0)), (x0, -h0, top), (x1, -h1, top))  # reference wall
        if not dropping:
            b_.quad((x0, h0, z(h0)), (x1, h1, z(h1)), (x1, h1, top), (x0, h0, top))
    if s.has_wiper:
        w0, w1 = s.wiper_x
        half = float(s.half_width(w1))  # between the walls (a gate narrows them along x)
        y0, y1 = -half, half
        h = s.wiper_height
        run = s.wiper_run  # (a skewed bar lies before or past a gate's taper: the check's)
        u0, u1 = w0, w0 + run  # its upstream face at either wall
        e0, e1 = w1 - run, w1  # its bar's end at either wall
        # underside (normal -z), parallel to the floor at height h
        b_.quad((u0, y0, z(y0) + h), (u1, y1, z(y1) + h), (e1, y1, z(y1) + h), (e0, y0, z(y0) + h))
        # upstream face (normal upstream), from the underside to the wall tops
        b_.quad((u1, y1, z(y1) + h), (u0, y0, z(y0) + h), (u0, y0, top), (u1, y1, top))
    return b_.mesh()


def combined(*meshes: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Several meshes as one indexed set (each keeps its own vertices)."""
    vertices, triangles, offset = [], [], 0
    for v, t in meshes:
        vertices.append(v)
        triangles.append(t + offset)
        offset += len(v)
    return np.concatenate(vertices), np.concatenate(triangles).astype(np.int32)
