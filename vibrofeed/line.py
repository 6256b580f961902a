"""Feeder lines: a bulk track followed by a faster section with its own drive and tooling.

A line is the bulk feeder (decks/bulk_feeder.liggghts) with ``sections=2``: section 1 is
the bulk feeder's track with its own vocabulary (``track_length``, ``track_width``,
``gate_*``, ``freq``, ``amp_t`` ...), section 2 follows it along x with the ``s2_*``
parameters (docs/feeder-lines.md). With ``sections=1`` (the default) nothing here is used.

Frame: the deck's. Section 2 runs from the joint ``x0 = track_length`` to the outlet edge
``x1 = x0 + s2_length``, centred on y = 0 as section 1. Its floor lies ``s2_step`` below
section 1's at its high edge (y = +w/2) and, with a cross tilt, descends towards the
wall at y = -w/2 (parts are kept against that wall, the reference wall):
``z(y) = -step - (w/2 - y) tan(cross_tilt)``. The wall at -w/2 runs the whole section;
the wall at +w/2 is missing over the side drop, where the floor narrows to
``s2_drop_width`` from the reference wall and parts not against it fall off the open
side. The wiper is a bar across the track whose underside follows the floor at
``s2_wiper_height``: a part taller than that (stacked, on edge) is swept back.

Meshes are indexed triangle sets as in :mod:`vibrofeed.geometry`, with shared vertices
along common edges (floor and walls form one surface, without seams).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError
from .mesh import MeshBuilder, write_stl

# The wiper's bar along x, in part sizes: long enough that a part cannot wedge under it
# tilted, short enough to stay a bar.
WIPER_LENGTH = 1.0


@dataclass(frozen=True)
class Section:
    """Section 2's geometry [m, deg]. ``drop_from``/``drop_to`` and ``wiper_at`` are
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

    @property
    def x1(self) -> float:
        return self.x0 + self.length

    @property
    def has_drop(self) -> bool:
        return self.drop_to > self.drop_from and 0 < self.drop_width < self.width

    @property
    def has_wiper(self) -> bool:
        return self.wiper_height > 0

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
        a = self.x0 + self.wiper_at * self.length
        return a, a + self.wiper_length


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
    return np.unique(np.round(np.concatenate(xs), 12))


def section_mesh(s: Section, spacing: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Section 2 at rest: floor, the reference wall (y = -w/2), the other wall except over
    the side drop, and the wiper. No wall at the joint (parts arrive over it from section 1)
    nor at the outlet edge."""
    if s.has_drop and not s.x0 <= s.drop_x[0] < s.drop_x[1] <= s.x1:
        raise ParameterError("the side drop does not fit on section 2: 0 <= s2_drop_from < "
                             "s2_drop_to <= 1")
    if s.has_wiper and not s.x0 <= s.wiper_x[0] < s.wiper_x[1] <= s.x1:
        raise ParameterError("the wiper does not fit on section 2: lower s2_wiper_at")
    xs = _stations(s, spacing)
    lo, hi = -s.width / 2, s.width / 2
    inner = lo + s.drop_width  # the drop's open edge
    top = -s.step + s.wall_height
    a, b = s.drop_x if s.has_drop else (math.inf, math.inf)
    b_ = MeshBuilder()
    z = s.floor_z
    for x0, x1 in zip(xs[:-1], xs[1:]):
        dropping = s.has_drop and a <= x0 and x1 <= b
        if dropping:
            ys = [lo, inner]
        elif s.has_drop:
            ys = [lo, inner, hi]  # shares the drop's edge vertices
        else:
            ys = [lo, hi]
        for y0, y1 in zip(ys[:-1], ys[1:]):  # floor, normal +z
            b_.quad((x0, y0, z(y0)), (x1, y0, z(y0)), (x1, y1, z(y1)), (x0, y1, z(y1)))
        b_.quad((x1, lo, z(lo)), (x0, lo, z(lo)), (x0, lo, top), (x1, lo, top))  # reference wall
        if not dropping:
            b_.quad((x0, hi, z(hi)), (x1, hi, z(hi)), (x1, hi, top), (x0, hi, top))
    if s.has_wiper:
        w0, w1 = s.wiper_x
        ys = np.linspace(lo, hi, 2)
        h = s.wiper_height
        for y0, y1 in zip(ys[:-1], ys[1:]):
            # underside (normal -z), parallel to the floor at height h
            b_.quad((w0, y0, z(y0) + h), (w0, y1, z(y1) + h), (w1, y1, z(y1) + h), (w1, y0, z(y0) + h))
            # upstream face (normal -x), from the underside to the wall tops
            b_.quad((w0, y1, z(y1) + h), (w0, y0, z(y0) + h), (w0, y0, top), (w0, y1, top))
    return b_.mesh()


def combined(*meshes: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Several meshes as one indexed set (each keeps its own vertices)."""
    vertices, triangles, offset = [], [], 0
    for v, t in meshes:
        vertices.append(v)
        triangles.append(t + offset)
        offset += len(v)
    return np.concatenate(vertices), np.concatenate(triangles).astype(np.int32)


# ------------------------------------------------------------------ parameters
def _get(p: Mapping, name: str, default: float = 0.0) -> float:
    return float(p.get(name, default))


def section_from(p: Mapping) -> Section:
    """Section 2 of a line from the deck's parameters (numbers or their strings)."""
    return Section(
        x0=_get(p, "track_length"), length=_get(p, "s2_length"), width=_get(p, "s2_width"),
        wall_height=_get(p, "s2_wall_height"), step=_get(p, "s2_step"),
        cross_tilt=_get(p, "s2_cross_tilt"), drop_from=_get(p, "s2_drop_from"),
        drop_to=_get(p, "s2_drop_to"), drop_width=_get(p, "s2_drop_width"),
        wiper_height=_get(p, "s2_wiper_height"), wiper_at=_get(p, "s2_wiper_at", 0.5),
        wiper_length=WIPER_LENGTH * _get(p, "part_size"))


def section_drive(p: Mapping, k: int) -> dict:
    """The parameters with section ``k``'s drive (1-based) as the deck's ``freq``,
    ``amp_t``, ``amp_n``, ``phase`` and ``waveform``: what a model of one part alone on
    that section takes (section 2 runs a sine)."""
    if k == 1:
        return dict(p)
    return {**p, "freq": p["s2_freq"], "amp_t": p["s2_amp_t"], "amp_n": p["s2_amp_n"],
            "phase": p["s2_phase"], "waveform": 0}


def joint_motion(p: Mapping[str, float]) -> tuple[float, float]:
    """How far the floors at the joint move apart at most [m]: normal (dz) and along the
    track (dx). Sines of one frequency: the amplitude of their difference, sqrt(a1^2 + a2^2
    - 2 a1 a2 cos(phase1 - phase2)) normal, |amp_t - s2_amp_t| along (both start at
    sin(w t)); of two frequencies: the sum of the amplitudes (the phases drift)."""
    a1, a2 = p.get("amp_n", 0.0), p.get("s2_amp_n", 0.0)
    b1, b2 = p.get("amp_t", 0.0), p.get("s2_amp_t", 0.0)
    if p.get("freq", 0.0) != p.get("s2_freq", 0.0):
        return a1 + a2, b1 + b2
    dphi = math.radians(p.get("phase", 0.0) - p.get("s2_phase", 0.0))
    return math.sqrt(max(a1 * a1 + a2 * a2 - 2 * a1 * a2 * math.cos(dphi), 0.0)), abs(b1 - b2)


def joint_steps(p: Mapping[str, float]) -> tuple[float, float]:
    """The step down from section 1's floor to section 2's at the joint, at rest, at its
    least and its most across section 1's exit [m]: both floors are planes tilted down
    towards -y (``cross_tilt``, ``s2_cross_tilt``), so the step is linear in y and its
    extremes lie at the exit's two ends."""
    s = section_from(p)
    w1 = p.get("track_width", 0.0)
    exit_width = p["gate_width"] if p.get("gate_width", 0.0) > 0 else w1
    t1 = math.tan(math.radians(p.get("cross_tilt", 0.0)))
    t2 = math.tan(math.radians(s.cross_tilt))
    steps = [s.step + (s.width / 2 - y) * t2 - (w1 / 2 - y) * t1 for y in (-exit_width / 2, exit_width / 2)]
    return min(steps), max(steps)


def check_line(p: Mapping[str, float]) -> None:
    """Relations between a line's parameters (``sections`` > 1), one-line errors; the
    deck refuses the same for runs by hand."""
    recirculate = p.get("recirculate", 0.0)
    if recirculate not in (0, 1):
        raise ParameterError(f"recirculate={recirculate:g} must be 0 (rejects removed) or 1 "
                             "(returned to the inlet)")
    if p.get("return_delay", 0.0) < 0:
        raise ParameterError(f"return_delay={p['return_delay']:g} s must be >= 0")
    if int(p.get("sections", 1)) <= 1:
        if recirculate:
            raise ParameterError("recirculate=1: a single track has no rejects to return; "
                                 "a line (sections=2) has")
        return
    size, shape = p["part_size"], int(p.get("shape", 0))
    widest = size * (1 + p.get("size_spread", 0.0)) if shape == 0 else size
    thickness = widest if shape == 0 else p.get("part_thickness", size)
    s = section_from(p)
    exit_width = p["gate_width"] if p.get("gate_width", 0.0) > 0 else p["track_width"]
    if s.width < widest:
        raise ParameterError(f"s2_width={s.width:g} m is narrower than a part ({widest:g} m across)")
    if s.width < exit_width:
        raise ParameterError(
            f"s2_width={s.width:g} m is narrower than section 1's exit ({exit_width:g} m): the "
            "sections do not join (parts would fall at the joint); narrow section 1 with its gate")
    dz, dx = joint_motion(p)
    low, high = joint_steps(p)
    if low <= dz:
        raise ParameterError(
            f"s2_step={s.step:g} m: the joint must step down by more than the floors move apart "
            f"normal to them ({dz:.3g} m: amp_n, s2_amp_n, phases), or section 2's floor rises above "
            "section 1's and parts catch its edge"
            + (f" (with the cross tilts the step is {low:.3g} m at its least)" if low != s.step else ""))
    if high >= thickness:
        raise ParameterError(f"s2_step={s.step:g} m is not a small step: keep it below a part's "
                             f"thickness ({thickness:g} m)"
                             + (f" (with the cross tilts it is {high:.3g} m at its most)"
                                if high != s.step else ""))
    if dx >= size / 2:
        raise ParameterError(f"the joint opens by up to {dx:.3g} m along the track (amp_t, s2_amp_t), "
                             f"more than half a part ({size / 2:g} m): parts would fall into it")
    radius = thickness / 2
    if s.wall_height <= radius:
        raise ParameterError(f"s2_wall_height={s.wall_height:g} m is no higher than a part's centre "
                             f"({radius:g} m): parts would leave over the walls")
    if s.wiper_height > 0:
        if s.wiper_height < thickness:
            raise ParameterError(f"s2_wiper_height={s.wiper_height:g} m is lower than a part's "
                                 f"thickness ({thickness:g} m): no part would pass the wiper")
        if s.wiper_height >= s.wall_height:
            raise ParameterError(f"s2_wiper_height={s.wiper_height:g} m is not below the walls "
                                 f"(s2_wall_height={s.wall_height:g} m): the wiper would not exist")
        if s.wiper_at * s.length + WIPER_LENGTH * size > s.length:
            raise ParameterError(f"s2_wiper_at={s.wiper_at:g}: the wiper's bar ({WIPER_LENGTH * size:g} "
                                 "m long) runs past the outlet edge; lower s2_wiper_at")
    if s.drop_to > s.drop_from:
        if not 0 < s.drop_width < s.width:
            raise ParameterError(f"s2_drop_width={s.drop_width:g} m must be > 0 and narrower than "
                                 f"s2_width={s.width:g} m (the side drop narrows the track)")
        if s.drop_width < 0.5 * widest:
            raise ParameterError(f"s2_drop_width={s.drop_width:g} m is less than half a part "
                                 f"({widest / 2:g} m): every part would fall off the drop")
    if p.get("hamaker", 0.0) > 0 or p.get("air_viscosity", 0.0) > 0:
        raise ParameterError("hamaker and air_viscosity act on section 1's floor only: a line "
                             "(sections=2) runs without them in this version")
    if p.get("waveform", 0) != 0:
        raise ParameterError("a line (sections=2) drives both sections with sines (waveform=0) in "
                             "this version")


def write_sections(values: Mapping[str, str], folder) -> tuple[np.ndarray, np.ndarray] | None:
    """The prepare hook's part for a line: section 2's mesh at rest as ``track_s2.stl`` in
    ``folder``; returns it (None for a single section)."""
    if int(float(values.get("sections", "1"))) <= 1:
        return None
    mesh = section_mesh(section_from(values))
    write_stl(*mesh, folder / "track_s2.stl", "track_s2")
    return mesh
