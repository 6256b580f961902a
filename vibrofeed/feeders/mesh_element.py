"""A mesh element: a track the designer drew in CAD and exported as an STL, with the path parts
follow along it; anywhere in a line after its first element.

The STL is read with trimesh in its own frame and unit (``unit``: metres per unit of the STL,
0.001 for millimetres as CAD exports them); ``path`` is the polyline parts follow, points on the
floor's centre line in the STL's frame and unit. vibrofeed places the mesh where the line needs
it: turned about z so that the path's first segment runs along +x (in plan), and moved so that
the path's start lies at the joint, ``step`` below the element before it at its high edge:
(x0, 0, -level). The path coordinate over it is x0 plus the arc length along the placed path
to a part's nearest point on it.

What is checked for it: the line's elements follow one another along x (the outlet counts a
part as out beyond the line's farthest x, ``outlet_x``; a reject is caught by the element over
whose x it fell), so the mesh must end at its path's end, nothing of it beyond and nothing
before its joint; its floor must lie under the whole path, with no hole a part falls through,
its triangles wound alike, the floor's normals up (towards the parts), and its size a feeder's
(1 mm to 1 m: a 100 m track is a millimetre STL read as metres). An element after it is placed
as after a straight section, on along +x from its path's end, centred on y = 0: so a mesh that
is not the last must end its path where it started across (y = 0 placed), heading along +x
(an S-bend and back, a detour; :data:`ALIGN`). Its path coordinate runs on from there: the
elements after it are ``path_length - (x1 - x0)`` further along the path than along x
(vibrofeed.feeders.Feeder.offsets).

Its tooling is what can stand on a floor it does not own: a **gate** (two walls centred on
the path close in at 45 degrees from ``gate.at`` to ``gate.width`` and follow the path to its
end, as a linear section's gate) and a **wiper** (a bar across the track at ``wiper.at``,
``wiper.height`` above the floor's centre line, one part long along the path, its upstream face
up to the tools' top): both built along the placed path, :data:`TOOL_TOP` above its floor, and
moved with the mesh; and an **air jet** (a linear section's: vibrofeed.feeders.records.Jet):
its camera senses parts crossing ``jet.at`` along the path (the driver measures their path
coordinate), its block lies along the path's direction at the camera (six planes: LIGGGHTS'
blocks are axis-aligned) and it blows ``jet.angle`` up and across to the path's left (+y where
the path heads along +x). A side drop and a slot cut the floor, which is the STL's: the
designer draws them in CAD (and the open side a jet blows parts over).

Its drive is a linear section's: a sine along x (the path's start direction) and along z (the
deck's wiggle and viblin), whatever the path's turns: on a bend, part of the stroke along x is
across the track. Its numbers in the deck's vocabulary are ``s<k>_*`` (:data:`KEYS`), with
``s<k>_kind = 2``; ``s<k>_file`` and ``s<k>_path`` are words (the STL's absolute path; the
path's coordinates, comma separated).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..errors import ParameterError
from ..line import WIPER_LENGTH
from ..mesh import MeshBuilder
from .linear import (
    block_planes,
    check_jet,
    jet_span,
    jet_throw,
    read_jet,
    sine_commands,
    turned_jet_commands,
    turned_jet_fix,
)
from .records import Camera, Drive, Gate, Jet, Part, Wiper, number

KIND_CODE = 2  # s<k>_kind: 0 a linear section, 1 a chute, 2 a mesh
UNITS = {"mm": 1e-3, "m": 1.0}
# description key -> (deck suffix, unit, meaning)
KEYS: dict[tuple[str, ...], tuple[str, str, str]] = {
    ("file",): ("file", "-", "mesh: the STL exported from CAD (its absolute path)"),
    ("unit",): ("unit", "m", "mesh: metres per unit of the STL and its path (millimetres: 0.001)"),
    ("path",): ("path", "-", "mesh: the path parts follow, x,y,z of each point in the STL's frame"),
    ("width",): ("width", "m", "mesh: its track's width between the walls"),
    ("step",): ("step", "m", "step down at the joint, to the mesh's floor at its path's start"),
    ("drive", "freq"): ("freq", "Hz", "mesh: vibration frequency"),
    ("drive", "amp_t"): ("amp_t", "m", "mesh: displacement amplitude along x, its path's start"),
    ("drive", "amp_n"): ("amp_n", "m", "mesh: displacement amplitude along z"),
    ("drive", "phase"): ("phase", "deg", "mesh: lead of its motion along z over the one along x"),
    ("gate", "width"): ("gate_width", "m", "mesh: its gate's walls close in to this, on the path (0: none)"),
    ("gate", "at"): ("gate_at", "-", "mesh: its gate's taper starts at this fraction of the path's length"),
    ("wiper", "height"): ("wiper_height", "m", "mesh: a bar across this high above the floor (0: none)"),
    ("wiper", "at"): ("wiper_at", "-", "mesh: the wiper's bar starts at this fraction of the path's length"),
    ("jet", "force"): ("jet_force", "N", "mesh: air jet's force on a part wholly in its block (0: no jet)"),
    ("jet", "at"): ("jet_at", "-", "mesh: air jet's camera at this fraction of the path's length"),
    ("jet", "keep"): ("jet_keep", "-", "mesh: the state the air jet passes (correct: as correct)"),
    ("jet", "delay"): ("jet_delay", "s", "mesh: air jet: from sensing a part to firing"),
    ("jet", "duration"): ("jet_duration", "s", "mesh: air jet: how long it fires"),
    ("jet", "offset"): ("jet_offset", "m", "mesh: air jet's block's centre along the path past the camera"),
    ("jet", "length"): ("jet_length", "m", "mesh: air jet's block along the path (0: one part size)"),
    ("jet", "angle"): ("jet_angle", "deg", "mesh: air jet's blow up, across to the path's left"),
    ("jet", "mode"): ("jet_mode", "-", "mesh: air jet: region (all in its block) or ideal (the sensed part)"),
    ("jet", "headway"): ("jet_headway", "s", "mesh: air jet fires at a part this soon after the last passed"),
}
# The tools a mesh element does not build, and why (module docstring).
NOT_HERE = {
    "side_drop": "a side drop cuts the floor, which is the STL's: draw it in CAD",
    "slot": "a slot cuts the floor, which is the STL's: draw it in CAD",
}
WORDS = ("file", "path", "jet_keep", "jet_mode")  # not numbers: the deck holds them as words
NEEDED = ("file", "unit", "path", "width")
# A feeder's track is 1 mm to 1 m long and across (after the unit).
SIZES = (1e-3, 1.0)
# How far the mesh may reach past its path's end or before its joint [m] (an STL holds
# single-precision coordinates: 1e-7 of 10 cm is 1e-8 m).
REACH = 1e-6
# A mesh followed by another element ends its path on y = 0 and heading along +x to within
# this [m] across and this [rad] (CAD's single-precision coordinates hold both far closer).
ALIGN = (1e-6, 1e-4)
# The tools' walls and faces reach this many part sizes above the floor's centre line, and
# their walls this many below it (into a floor tilted across).
TOOL_TOP, TOOL_SINK = 2.0, 0.5
# The floor is looked for under the path at these fractions of the width across it.
ACROSS = (-0.4, -0.2, 0.0, 0.2, 0.4)


def deck_name(k: int, key: tuple[str, ...]) -> str:
    return f"s{k}_{KEYS[key][0]}"


def path_text(points) -> str:
    """A path (N, 3) as the deck's word: its coordinates, comma separated."""
    return ",".join(repr(float(c)) for c in np.asarray(points, dtype=float).ravel())


@dataclass(frozen=True)
class MeshElement:
    """Element ``number`` (>= 2): a track from CAD (module docstring). ``path`` is
    the polyline in the STL's frame and unit, ``unit`` metres per unit of it."""

    kind = "mesh"
    moves = True
    number: int
    x0: float
    file: str
    unit: float
    path: tuple
    width: float
    drive: Drive
    step: float = 0.0
    level: float = 0.0  # below the first section's floor at the joint: the steps summed
    gate: Gate | None = None
    wiper: Wiper | None = None
    jet: Jet | None = None
    part_size: float = 0.0  # (the tools' height and the wiper's length: module docstring)
    side_drop = None

    @classmethod
    def from_values(cls, values: Mapping, k: int, x0: float = 0.0, level: float = 0.0,
                    part: Part | None = None) -> MeshElement:
        def get(key, default=None):
            return number(values, deck_name(k, key), default)

        size = part.size if part else number(values, "part_size")
        gate = wiper = None
        if get(("gate", "width"), 0.0) > 0:
            gate = Gate(width=get(("gate", "width")), at=get(("gate", "at"), 0.7))
        if get(("wiper", "height"), 0.0) > 0:
            wiper = Wiper(height=get(("wiper", "height")), at=get(("wiper", "at"), 0.5),
                          length=WIPER_LENGTH * size)

        name = deck_name(k, ("path",))
        try:
            flat = [float(c) for c in str(values.get(name, "")).split(",")]
        except ValueError:
            flat = []
        if len(flat) < 6 or len(flat) % 3 or not all(math.isfinite(c) for c in flat):
            raise ParameterError(f"{name}: give at least two points of three "
                                 "coordinates each, x, y, z in the STL's unit")
        if deck_name(k, ("file",)) not in values:
            raise ParameterError(f"the feeder needs the parameter {deck_name(k, ('file',))}")
        step = get(("step",), 0.0)
        drive = Drive(freq=get(("drive", "freq")), amp_t=get(("drive", "amp_t")),
                      amp_n=get(("drive", "amp_n")), phase=get(("drive", "phase"), 0.0))
        return cls(number=k, x0=x0, file=str(values[deck_name(k, ("file",))]), unit=get(("unit",)),
                   path=tuple(flat), width=get(("width",)), drive=drive, step=step, level=level + step,
                   gate=gate, wiper=wiper, jet=read_jet(values, k, get, part), part_size=size)

    # ---------------------------------------------------------------- the path
    @cached_property
    def _placing(self) -> tuple[np.ndarray, np.ndarray]:
        """(rotation (3, 3), shift (3,)): a point q of the STL goes to rotation @ (q unit) + shift."""
        p = np.asarray(self.path, dtype=float).reshape(-1, 3) * self.unit
        dx, dy = p[1, :2] - p[0, :2]
        a = -math.atan2(dy, dx) if (dx or dy) else 0.0
        turn = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0, 0, 1.0]])
        return turn, np.array([self.x0, 0.0, -self.level]) - turn @ p[0]

    def place(self, points) -> np.ndarray:
        """Points (..., 3) of the STL's frame, in its unit, in the deck's frame [m]."""
        turn, shift = self._placing
        return np.asarray(points, dtype=float) * self.unit @ turn.T + shift

    @cached_property
    def points(self) -> np.ndarray:
        """The path placed in the deck's frame (N, 3) [m]."""
        return self.place(np.asarray(self.path, dtype=float).reshape(-1, 3))

    @cached_property
    def _arc(self) -> np.ndarray:
        """The arc length at each path point from its start [m]."""
        return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(self.points, axis=0), axis=1))])

    @property
    def path_length(self) -> float:
        return float(self._arc[-1])

    @property
    def length(self) -> float:
        """Its length along the path [m] (its tools are placed at fractions of it)."""
        return self.path_length

    @property
    def x1(self) -> float:
        """Where its path ends along x (the outlet edge) [m]."""
        return float(self.points[-1, 0])

    @property
    def bounds(self) -> list[tuple[float, float]]:
        """Along the path: from its joint's x on by the path's length."""
        return [(self.x0, self.x0 + self.path_length)]

    @property
    def exit_band(self) -> tuple[float, float]:
        """Across its path's end, its track's width about it (y, the deck's frame) [m]."""
        y = float(self.points[-1, 1])
        return y - self.width / 2, y + self.width / 2

    @property
    def exit_width(self) -> float:
        """The width parts leave it through (the gate's, if it has one)."""
        return self.gate.width if self.gate else self.width

    def along(self, s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(point (n, 3), unit tangent in plan (n, 2), unit normal to its left in plan (n, 2)) of
        the placed path at arc lengths ``s`` (n,) [m] from its start (on the segment a point
        lies on; a path's corner belongs to the segment after it)."""
        _, d, at = self._on_path(s)
        t = d[:, :2] / np.linalg.norm(d[:, :2], axis=1)[:, None]
        return at, t, np.column_stack([-t[:, 1], t[:, 0]])

    def _on_path(self, s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(segment index (n,), the segment (n, 3), the point (n, 3)) of the placed path at arc
        lengths ``s`` (n,) [m] (:meth:`along`)."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        p, arc = self.points, self._arc
        i = np.clip(np.searchsorted(arc, s, side="right") - 1, 0, len(p) - 2)
        d = p[i + 1] - p[i]
        return i, d, p[i] + ((s - arc[i]) / np.linalg.norm(d, axis=1))[:, None] * d

    def _stretch(self, a: float, b: float) -> np.ndarray:
        """Arc lengths from ``a`` to ``b`` [m]: both and every corner of the path between."""
        inner = self._arc[(self._arc > a) & (self._arc < b)]
        return np.concatenate([[a], inner, [b]])

    def _offset(self, s, half) -> tuple[np.ndarray, np.ndarray]:
        """The points ``half`` [m] (n,) to either side of the path at arc lengths ``s`` (n,), mitred
        at its corners (the two segments' normals averaged, scaled to keep the distance):
        (left (n, 3), right (n, 3))."""
        at, _, n = self.along(s)
        corner = np.isin(s, self._arc[1:-1])
        if corner.any():  # (the segment before a corner: its normal joins the one after)
            _, _, before = self.along(np.asarray(s)[corner] - 1e-12)
            m = before + n[corner]
            m /= np.einsum("ij,ij->i", m, n[corner])[:, None]
            n = n.copy()
            n[corner] = m
        shift = np.column_stack([n * np.asarray(half, dtype=float)[:, None], np.zeros(len(at))])
        return at + shift, at - shift

    def tools_mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """Its gate's walls and its wiper's bar at rest in the deck's frame (module docstring):
        (vertices (V, 3), triangles (T, 3)), empty without tools."""
        b = MeshBuilder()
        top, sink = TOOL_TOP * self.part_size, TOOL_SINK * self.part_size
        g, w = self.gate, self.wiper
        if g is not None:
            start = g.at * self.length
            taper = g.taper(self.width)
            s = np.unique(np.concatenate([self._stretch(start, start + taper),
                                          self._stretch(start + taper, self.length)]))
            half = np.interp(s, [start, start + taper], [self.width / 2, g.width / 2])
            left, right = self._offset(s, half)
            for i in range(len(s) - 1):
                for side, wound in ((left, False), (right, True)):
                    q = [side[i] - [0, 0, sink], side[i + 1] - [0, 0, sink],
                         side[i + 1] + [0, 0, top], side[i] + [0, 0, top]]
                    b.quad(*(q[::-1] if wound else q))
        if w is not None:
            a = w.at * self.length
            s = self._stretch(a, a + w.length)
            left, right = self._offset(s, np.full(len(s), self.width / 2))
            up = np.array([0.0, 0.0, w.height])
            for i in range(len(s) - 1):  # underside (normal down), at the height over the path
                b.quad(right[i] + up, left[i] + up, left[i + 1] + up, right[i + 1] + up)
            b.quad(left[0] + up, right[0] + up, right[0] + [0, 0, top], left[0] + [0, 0, top])
        return b.mesh()

    @property
    def exit_level(self) -> float:
        """How far below the first section's floor its path ends [m]."""
        return float(-self.points[-1, 2])

    @property
    def exit_direction(self) -> tuple[float, float, float]:
        d = self.points[-1] - self.points[-2]
        return tuple(float(c) for c in d / np.linalg.norm(d))

    def coordinate(self, points, reach: float) -> np.ndarray:
        """Where points (..., 3) of the deck's frame are along the path: x0 plus the arc length
        to their nearest point on it (past its end, on along its last segment), NaN farther
        from it than ``reach`` [m]."""
        p = np.asarray(points, dtype=float)
        flat = p.reshape(-1, 3)
        a, b = self.points[:-1], self.points[1:]
        d = b - a
        dd = np.einsum("ij,ij->i", d, d)
        hi = np.ones(len(d))
        hi[-1] = np.inf  # past the end: on along the last segment, beyond the path's end
        best = np.full(len(flat), np.inf)
        out = np.full(len(flat), np.nan)
        for start in range(0, len(flat), 4096):  # (points x segments at a time)
            q = flat[start:start + 4096, None, :]
            t = np.clip(np.einsum("psj,sj->ps", q - a, d) / dd, 0.0, hi)
            gap = np.linalg.norm(q - (a + t[..., None] * d), axis=-1)
            gap = np.where(np.isnan(gap), np.inf, gap)
            i = np.argmin(gap, axis=1)
            rows = np.arange(len(i))
            best[start:start + len(i)] = gap[rows, i]
            out[start:start + len(i)] = self._arc[i] + t[rows, i] * np.sqrt(dd[i])
        return np.where(best <= reach, self.x0 + out, np.nan).reshape(p.shape[:-1])

    # ---------------------------------------------------------------- the mesh
    def _fail(self, key: tuple[str, ...], message: str) -> ParameterError:
        return ParameterError(f"{deck_name(self.number, key)}: {message}")

    @cached_property
    def stl(self):
        """The STL as trimesh reads it (its frame and unit; vertices merged)."""
        import trimesh

        if not os.path.isfile(self.file):  # (trimesh would take the name for STL text)
            raise self._fail(("file",), f"no such file: {self.file}"
                             + (" (a directory)" if os.path.isdir(self.file) else ""))
        try:
            mesh = trimesh.load_mesh(self.file, file_type="stl")
        except Exception as exc:  # (trimesh raises what its readers raise)
            reason = getattr(exc, "strerror", None) or (str(exc).splitlines() or [type(exc).__name__])[0]
            raise self._fail(("file",), f"cannot read {self.file} as an STL: {reason}") from None
        if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
            raise self._fail(("file",), f"{self.file} holds no triangles")
        return mesh

    @cached_property
    def placed(self):
        """The mesh placed in the deck's frame [m] (a trimesh.Trimesh)."""
        import trimesh

        return trimesh.Trimesh(self.place(self.stl.vertices), np.asarray(self.stl.faces), process=False)

    def mesh(self):
        """The mesh at rest in the deck's frame with its tools (:meth:`tools_mesh`): vertices
        (V, 3) [m], triangles (T, 3)."""
        v, t = np.asarray(self.placed.vertices, dtype=float), np.asarray(self.placed.faces, dtype=np.int32)
        tv, tt = self.tools_mesh()
        return np.concatenate([v, tv]), np.concatenate([t, tt + len(v)]).astype(np.int32)

    @property
    def lowest(self) -> float:
        """The mesh's lowest point at rest [m]."""
        return float(self.placed.vertices[:, 2].min())

    def floor_under(self, xy, above) -> tuple[np.ndarray, np.ndarray]:
        """(height [m], normal's z) of the first face under each point (n, 2) of the deck's frame,
        looking down from height ``above`` (n,); NaN where nothing is under it."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        origins = np.column_stack([xy, np.broadcast_to(above, len(xy))])
        down = np.tile([0.0, 0.0, -1.0], (len(xy), 1))
        hits, ray, face = self.placed.ray.intersects_location(origins, down, multiple_hits=False)
        z, up = np.full(len(xy), np.nan), np.full(len(xy), np.nan)
        if len(ray):
            z[ray], up[ray] = hits[:, 2], self.placed.face_normals[face, 2]
        return z, up

    def _walls_around(self, xy, z, across) -> np.ndarray:
        """Whether a wall stands within the width on either side of each point (n, 2) at
        height ``z`` (n,), looking across the path both ways (``across``: (n, 2) unit vectors)."""
        origins = np.column_stack([xy, z])
        found = []
        for sign in (1.0, -1.0):
            ways = np.column_stack([sign * across, np.zeros(len(xy))])
            hits, ray, _ = self.placed.ray.intersects_location(origins, ways, multiple_hits=False)
            near = np.zeros(len(xy), dtype=bool)
            if len(ray):
                near[ray] = np.linalg.norm(hits - origins[ray], axis=1) <= self.width
            found.append(near)
        return found[0] & found[1]

    def entry_z(self, y):
        """The floor's height at rest just after the joint at ``y`` [m] (within the walls)."""
        return self._floor_across(self.x0 + self.width / 100, self.points[0, 2], y)

    def exit_z(self, y):
        """The floor's height at rest just before its path's end at ``y`` [m] (within the walls):
        where an element after it steps down from."""
        return self._floor_across(self.x1 - self.width / 100, self.points[-1, 2], y)

    def _floor_across(self, x: float, z: float, y):
        """The floor's height at rest at ``x`` and ``y`` [m] (``y`` kept within the walls),
        looked for down from half the width above the path's height ``z`` there."""
        y = np.clip(np.asarray(y, dtype=float), -0.49 * self.width, 0.49 * self.width)
        xy = np.column_stack([np.broadcast_to(x, y.shape).ravel(), y.ravel()])
        got, _ = self.floor_under(xy, z + self.width / 2)
        return got.reshape(y.shape) if y.shape else float(got[0])

    def height_along(self, arc) -> np.ndarray:
        """The floor's height at rest on its centre line [m] at arc lengths ``arc`` from its start
        (its path's points lie there; level past its ends)."""
        return np.interp(np.asarray(arc, dtype=float), self._arc, self.points[:, 2])

    def arc_at_x(self, x) -> np.ndarray:
        """The arc length from its start [m] where its path first reaches the deck's ``x`` [m]
        (clipped to the path): where a part that fell from it at x left it, as far as x tells."""
        reach = np.maximum.accumulate(self.points[:, 0])  # (a path that turns back: first reached)
        return np.interp(np.asarray(x, dtype=float), reach, self._arc)

    # ---------------------------------------------------------------- the air jet
    @property
    def sensing(self) -> float:
        """Where the jet's camera senses the parts: its path coordinate [m]."""
        return self.x0 + self.jet.at * self.length

    def jet_span(self, size: float) -> tuple[float, float]:
        """The jet's block along the path [m] (its length 0: one part ``size``)."""
        return jet_span(self.jet, self.sensing, size)

    def jet_frame(self, size: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(the path's point at the block's centre (3,), its direction there (3,), its left
        (3,), all level): the block lies along that direction, straight (a bend within it is
        not followed)."""
        lo, hi = self.jet_span(size)
        at, t, n = self.along([(lo + hi) / 2 - self.x0])
        return at[0], np.array([t[0, 0], t[0, 1], 0.0]), np.array([n[0, 0], n[0, 1], 0.0])

    def jet_direction(self) -> tuple[float, float, float]:
        """The jet's unit direction: ``angle`` up from the horizontal, across to the path's left
        (+y where it heads along +x)."""
        _, _, left = self.jet_frame(self.part_size)
        a = math.radians(self.jet.angle)
        d = math.cos(a) * left + [0.0, 0.0, math.sin(a)]
        return tuple(float(c) for c in d)

    def jet_half_across(self, part: Part) -> float:
        """How far the jet's block reaches to either side of the path [m]: the walls and two parts
        beyond each."""
        return self.width / 2 + 2 * part.widest

    def jet_planes(self, part: Part) -> list[tuple[np.ndarray, np.ndarray]]:
        """The jet's block as six half-spaces (a point on each plane, its normal into the block)
        in the element's frame: along the path over :meth:`jet_span`, across the track and two
        parts beyond each wall, from below the path's floor there (by the normal amplitude and a
        part) to a part above its walls' top there or the tools' top, the higher (LIGGGHTS'
        blocks are axis-aligned: this one is turned with the path)."""
        lo, hi = self.jet_span(part.size)
        c, t, n = self.jet_frame(part.size)
        half_w = self.jet_half_across(part)
        bottom = c[2] - self.drive.amp_n - part.widest
        top = max(c[2] + TOOL_TOP * self.part_size, self.height_across(c, t, half_w)) \
            + self.drive.amp_n + part.widest
        return block_planes(c, t, n, (hi - lo) / 2, half_w, bottom, top)

    def jet_throw(self, part: Part, mass: float, g: float = 9.81) -> tuple[float, float]:
        """How fast [m/s] and how far beyond the track's side [m] the jet can throw a part of
        ``mass`` [kg] at most (vibrofeed.feeders.linear.jet_throw), across its block from the
        path's right wall."""
        planes = self.jet_planes(part)
        half = self.jet_half_across(part)
        height = float(planes[5][0][2] - planes[4][0][2])
        return jet_throw(self.jet, mass, self.jet.angle, half + self.width / 2, height,
                         half - self.width / 2, part.widest, g)

    def height_across(self, point, tangent, half: float) -> float:
        """The highest point of the placed mesh [m] in the vertical plane across the path through
        ``point`` (normal ``tangent``), within ``half`` [m] of it across: its walls' top there
        (the plane's height at ``point`` where nothing of the mesh is cut)."""
        import trimesh

        cut = trimesh.intersections.mesh_plane(self.placed, plane_normal=tangent, plane_origin=point)
        if not len(cut):
            return float(point[2])
        q = cut.reshape(-1, 3)
        near = np.abs((q - point) @ np.array([-tangent[1], tangent[0], 0.0])) <= half
        return float(q[near, 2].max()) if near.any() else float(point[2])

    def camera(self, part: Part, origin=(0.0, 0.0, 0.0)) -> Camera:
        """Where the driver senses parts for the jet (the element shifted by ``origin``): along
        its path (:meth:`coordinate`, within half its width and a part of it), the path's
        direction at the camera, up; below its lowest point by a part: falling."""
        o = np.asarray(origin, dtype=float)
        _, t, _ = self.along([self.sensing - self.x0])
        reach = self.width / 2 + part.size
        return Camera(at=self.sensing, tangent=(float(t[0, 0]), float(t[0, 1]), 0.0), up=(0.0, 0.0, 1.0),
                      z_floor=float(o[2]) + self.lowest - part.size,
                      along=lambda points: self.coordinate(np.asarray(points, dtype=float) - o, reach))

    def jet_commands(self, part: Part, origin=(0.0, 0.0, 0.0)) -> list[str]:
        """The jet's commands (none without one), as a linear section's
        (vibrofeed.feeders.linear.LinearSection.jet_commands) but for its block, the
        intersection of :meth:`jet_planes` (``s<k>_jet``, shifted by ``origin``), and its
        direction, across to the path's left at the camera."""
        if self.jet is None:
            return []
        o = np.asarray(origin, dtype=float)
        planes = [(point + o, normal) for point, normal in self.jet_planes(part)]
        _, _, left = self.jet_frame(part.size)
        s = f"s{self.number}"
        return turned_jet_commands(self.number, f"element {self.number}", self.jet.mode, planes, left,
                                   f"v_{s}_jet_force", f"v_{s}_jet_angle*PI/180")

    def jet_fix(self) -> str:
        """The jet's ``fix addforce`` (:meth:`jet_commands`; the driver removes and places it again,
        vibrofeed.engine.jets)."""
        return turned_jet_fix(self.number, self.jet.mode)

    # ---------------------------------------------------------------- the deck
    def name(self, key) -> str:
        key = (key,) if isinstance(key, str) else tuple(key)
        return deck_name(self.number, key) if key in KEYS else ".".join(key)

    def deck_commands(self) -> dict[str, list[str]]:
        """Its commands in the deck (vibrofeed.feeders.deck): a linear section's sine
        (:func:`vibrofeed.feeders.linear.sine_commands`), its lowest point and its run along x
        as numbers of its placed mesh, and the box widened to hold its bends."""
        s = f"s{self.number}"
        out = sine_commands(self.number)
        y = float(np.abs(self.placed.vertices[:, 1]).max())
        out["derived"] += [f"variable {s}_low equal {self.lowest!r}",
                           f"variable {s}_length equal {self.x1 - self.x0!r}",
                           "variable box_y delete",  # (the widest of the line and the mesh, and a part)
                           f"variable box_y equal (v_half_w+{y!r}+abs(v_half_w-{y!r}))/2+v_part_size"]
        return out

    # ---------------------------------------------------------------- checks
    def check(self, part: Part, last: bool = True) -> None:
        """The element on its own, judged on its placed mesh with trimesh (module docstring):
        a one-line ParameterError naming the element and its key."""
        if self.width < part.widest:
            raise self._fail(("width",), f"{self.width:g} m is narrower than a part ({part.widest:g} m "
                                         "across)")
        if self.unit not in UNITS.values():
            raise self._fail(("unit",), f"{self.unit:g} m per unit: an STL from CAD is in millimetres "
                                        "(unit = \"mm\", 0.001) or metres (\"m\", 1)")
        p = self.points
        if not np.linalg.norm(np.diff(p, axis=0), axis=1).all():
            raise self._fail(("path",), "two consecutive points of the path coincide")
        mesh = self.placed
        size = max(float(mesh.extents.max()), self.path_length)
        if not SIZES[0] <= size <= SIZES[1]:
            guess = "mm" if size > SIZES[1] else "m"
            raise self._fail(("unit",), f"the mesh is {float(mesh.extents.max()):.4g} m across and its path "
                                        f"{self.path_length:.4g} m long at {self.unit:g} m per unit; a "
                                        f"feeder's track is 1 mm to 1 m: is the unit {guess}?")
        if not mesh.is_winding_consistent:
            raise self._fail(("file",), "the mesh's triangles are not wound alike (inconsistent "
                                        "normals): export it again with its normals repaired")
        low, high = float(mesh.vertices[:, 0].min()), float(mesh.vertices[:, 0].max())
        if low < self.x0 - REACH:
            raise self._fail(("path",), f"the mesh reaches {(self.x0 - low) * 1e3:.3g} mm back past its "
                                        "joint (under the element before it): start the path at the "
                                        "mesh's start")
        if high > self.x1 + REACH:
            raise self._fail(("path",), f"the mesh reaches {(high - self.x1) * 1e3:.3g} mm beyond its "
                                        "path's end along x: the outlet (beyond the path's end) would "
                                        "take parts still on it; end the path at the mesh's farthest x")
        self._check_floor(part)
        self._check_tools(part)
        if self.jet is not None:
            check_jet(self, part)
        if not last:
            self._check_end()

    def _check_tools(self, part: Part) -> None:
        """Its gate and its wiper: a part passes them and they lie on its path."""
        g, w = self.gate, self.wiper
        if g is not None:
            if g.width < part.abreast:
                riding = " riding lengthwise" if part.abreast < part.widest else ""
                raise self._fail(("gate", "width"), f"{g.width:g} m is narrower than a part "
                                                    f"({part.abreast:g} m across{riding})")
            if g.width >= self.width:
                raise self._fail(("gate", "width"), f"{g.width:g} m must be narrower than its width "
                                                    f"({self.width:g} m; 0: no gate)")
            taper = g.taper(self.width)
            if not 0 <= g.at or g.at * self.length + taper > self.length:
                raise self._fail(("gate", "at"), f"{g.at:g}: the gate's 45 degree taper ({taper:g} m "
                                                 f"long) runs past its path's end ({self.length:.4g} m)")
        if w is not None:
            if w.height < part.tallest:
                raise self._fail(("wiper", "height"), f"{w.height:g} m is lower than a part's thickness "
                                                      f"({part.tallest:g} m): no part would pass the wiper")
            if w.height >= TOOL_TOP * part.size:
                raise self._fail(("wiper", "height"), f"{w.height:g} m: the tools stand {TOOL_TOP:g} part "
                                                      f"sizes ({TOOL_TOP * part.size:g} m) above the floor; "
                                                      "a bar that high sweeps nothing")
            if not 0 <= w.at or w.at * self.length + w.length > self.length:
                raise self._fail(("wiper", "at"), f"{w.at:g}: the wiper's bar ({w.length:g} m long) runs "
                                                  f"past its path's end ({self.length:.4g} m)")

    def _check_end(self) -> None:
        """A mesh with an element after it ends on the line's centre line, heading along +x
        (module docstring): the next element starts there."""
        end, d = self.points[-1], np.asarray(self.exit_direction)
        turn = math.degrees(math.atan2(abs(d[1]), d[0]))
        if abs(end[1]) > ALIGN[0] or math.radians(turn) > ALIGN[1]:
            raise self._fail(("path",), f"an element follows it, so its path must end where it started "
                                        f"across, heading as it started (the next element starts "
                                        f"there, along it); it ends {end[1] * 1e3:+.4g} mm across, "
                                        f"turned {turn:.3g} deg: bend it back (an S-bend and back) or "
                                        "make it the last element")

    def _check_floor(self, part: Part) -> None:
        """The floor under the path: found (the path on the mesh), facing up, whole (no hole a
        part falls through), at points along it at most half a part apart."""
        arc = self._arc
        n = max(2, math.ceil(self.path_length / (part.size / 2)))
        s = (np.arange(n) + 0.5) * self.path_length / n  # (clear of the open ends)
        i, d, _ = self._on_path(s)
        at, _, across = self.along(s)
        top = at[:, 2] + self.width / 2  # above the floor, below the walls' tops
        shown = np.asarray(self.path, dtype=float).reshape(-1, 3)  # (in the STL's frame for messages)

        def where(j):
            q = shown[i[j]] + (s[j] - arc[i[j]]) / np.linalg.norm(d[j]) * (shown[i[j] + 1] - shown[i[j]])
            return (f"{s[j] * 1e3:.3g} mm along the path (near {', '.join(f'{c:.4g}' for c in q)} "
                    "in the STL)")

        z, up = self.floor_under(at[:, :2], top)
        miss = []  # nothing within half the width under the path's point, at each place across
        for fraction in ACROSS:
            zs = z if fraction == 0 else self.floor_under(at[:, :2] + fraction * self.width * across, top)[0]
            miss.append(np.isnan(zs) | (zs < at[:, 2] - self.width / 2))
        miss = np.array(miss)
        # no floor anywhere across: between walls a hole, else the path has left the mesh
        walled = self._walls_around(at[:, :2], at[:, 2] + part.size / 2, across)
        if (miss.all(axis=0) & ~walled).any():
            j = int(np.argmax(miss.all(axis=0) & ~walled))
            raise self._fail(("path",), f"the path leaves the mesh at {where(j)}: no floor under it")
        if miss.any():
            j = int(np.argmax(miss.any(axis=0)))
            f = int(np.argmax(miss[:, j]))  # (the first place across where it misses)
            raise self._fail(("file",), f"the floor has a hole at {where(j)}, "
                                        f"{ACROSS[f] * self.width * 1e3:+.3g} mm across: parts would "
                                        "fall through")
        off = np.abs(z - at[:, 2]) > part.size / 2
        if off.any():
            j = int(np.argmax(off))
            raise self._fail(("path",), f"the path lies {(at[j, 2] - z[j]) * 1e3:+.3g} mm above the floor "
                                        f"at {where(j)}: its points lie on the floor's centre line")
        if (up <= 0).any():
            j = int(np.argmax(up <= 0))
            raise self._fail(("file",), f"the floor's normals face down under the path at {where(j)}: "
                                        "export it with the normals out of the solid (towards the parts)")
