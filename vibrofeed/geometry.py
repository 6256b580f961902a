"""Geometry of the bulk feeder: the track mesh, the catch face and the clump templates.

Frame (the deck's): x along the track (parts convey towards +x), y across, z normal to
the floor (floor at z = 0 at rest). The track runs from a back wall at x = 0 to the
outlet edge at x = track_length, which has no wall: parts fall off there. An optional
singulation gate narrows the walls at 45 degrees from ``gate_x`` to ``gate_width`` and
keeps them narrow to the outlet.

Meshes are indexed triangle sets ``(vertices (V, 3) float64 [m], triangles (T, 3) int32)``:
the floor and the walls share their edge vertices, so the only open edges of the track
are the outlet edge and the walls' top edges (LIGGGHTS' mesh/surface then sees one
connected surface, without seams between floor and walls). They are written as binary STL
(:func:`vibrofeed.mesh.write_stl`). Multisphere parts (chips, discs) are clumps of spheres of diameter
``part_thickness`` whose outline is the part's, given as ``(n, 4)`` rows x, y, z, r in
the body frame (the part's centre at the origin, its flat faces normal to z); boxes
(shape 3) are vibrofeed.parts' clumps, stl parts (shape 4) vibrofeed.stl_part's, both about
the solid's centre of mass.

:func:`prepare_bulk_feeder` is the prepare hook that decks/bulk_feeder.liggghts declares:
the runner calls it before a run (and ``vibrofeed prepare`` for a run by hand).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import ParameterError
from .feeders.deck import guard_lines, write_line_files
from .feeders.feeder import Feeder
from .feeders.records import number, shape_code
from .line import combined
from .mesh import MeshBuilder, write_stl, write_template
from .stl_part import stl_lines

# Largest spacing of a clump's spheres, as a fraction of their diameter: the faces stay
# within 4 % of the thickness of flat (the bumps between spheres are shallow).
CLUMP_SPACING = 0.75
# A part's catch face, written at unit size: the deck scales it to its width and places it
# below the outlet edge (fix mesh/surface ... scale ... move ...).
CATCH_LENGTH = 1.0


@dataclass
class Prepared:
    """What a deck's prepare hook made for one run.

    ``variables``: extra ``-var`` values for LIGGGHTS (e.g. ``mesh_dir``); ``track``:
    the track mesh at rest (vertices (V, 3) [m], triangles (T, 3) int32) or None;
    ``body_template``: (n, 4) x, y, z, r [m] of a clump's spheres in the body frame, in
    the order LIGGGHTS stores them (a body's atom ids follow the template), or None for
    plain spheres.
    """

    variables: dict[str, str] = field(default_factory=dict)
    track: tuple[np.ndarray, np.ndarray] | None = None
    body_template: np.ndarray | None = None

    def to_spec(self) -> dict:
        """The JSON-ready form the runner hands to the worker (spec["prepared"])."""
        track = None
        if self.track is not None:
            track = [self.track[0].tolist(), self.track[1].tolist()]
        template = None if self.body_template is None else self.body_template.tolist()
        return {"variables": dict(self.variables), "track": track, "body_template": template}


# ------------------------------------------------------------------ meshes
def wall_stations(track_length: float, track_width: float, gate_width: float = 0.0,
                  gate_x: float | None = None, spacing: float | None = None):
    """x stations along the track and the walls' half width at each.

    Uniform stations at most ``spacing`` apart (default: the track width, at most 1 mm),
    plus the gate's two kinks when there is a gate (0 < gate_width < track_width).
    """
    spacing = spacing or min(track_width, 1e-3)
    n = max(1, math.ceil(track_length / spacing - 1e-9))
    xs = np.linspace(0.0, track_length, n + 1)
    if not 0 < gate_width < track_width:
        return xs, np.full_like(xs, track_width / 2)
    gate_x = 0.7 * track_length if gate_x is None else gate_x
    taper_end = gate_x + (track_width - gate_width) / 2  # 45 degrees
    if not 0 <= gate_x < taper_end <= track_length:
        raise ParameterError(
            f"the gate does not fit on the track: its taper runs from x = {gate_x:g} m to "
            f"{taper_end:g} m, the track ends at {track_length:g} m; lower gate_at")
    xs = np.unique(np.round(np.concatenate([xs, [gate_x, taper_end]]), 12))
    half = np.interp(xs, [0.0, gate_x, taper_end, track_length],
                     [track_width / 2, track_width / 2, gate_width / 2, gate_width / 2])
    return xs, half


def track_mesh(track_length: float, track_width: float, wall_height: float,
               gate_width: float = 0.0, gate_x: float | None = None,
               spacing: float | None = None, cross_tilt: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The track: floor, two side walls and the back wall at x = 0, no wall at the
    outlet edge x = track_length. Floor and walls share vertices along their common
    edges (whole edges: no vertex lies inside another face's edge).

    ``cross_tilt`` [deg] tilts the floor across, down towards the wall at -y (as a
    single-file track keeps its parts against one wall): the floor is the plane
    z = -(track_width/2 - y) tan(cross_tilt), at 0 along the +y wall of the full
    width; the wall tops stay at ``wall_height``."""
    xs, half = wall_stations(track_length, track_width, gate_width, gate_x, spacing)
    slope = math.tan(math.radians(cross_tilt))

    def z(y):
        return -(track_width / 2 - y) * slope if slope else 0

    b = MeshBuilder()
    top = wall_height
    for x0, x1, h0, h1 in zip(xs[:-1], xs[1:], half[:-1], half[1:]):
        b.quad((x0, -h0, z(-h0)), (x1, -h1, z(-h1)), (x1, h1, z(h1)), (x0, h0, z(h0)))  # floor, +z
        b.quad((x0, h0, z(h0)), (x1, h1, z(h1)), (x1, h1, top), (x0, h0, top))  # y > 0
        b.quad((x1, -h1, z(-h1)), (x0, -h0, z(-h0)), (x0, -h0, top), (x1, -h1, top))
    w = half[0]
    b.quad((0, -w, z(-w)), (0, w, z(w)), (0, w, top), (0, -w, top))  # back wall, normal +x
    return b.mesh()


def catch_face(length: float = CATCH_LENGTH, width: float = 1.0,
               z: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A horizontal rectangle from x = 0 to ``length``, y in +-width/2, at height ``z``
    (normal -z: parts cross it downwards)."""
    b = MeshBuilder()
    h = width / 2
    b.quad((0, -h, z), (0, h, z), (length, h, z), (length, -h, z))
    return b.mesh()


# ------------------------------------------------------------------ clumps
def chip_template(edge: float, thickness: float) -> np.ndarray:
    """A flat square die (edge x edge x thickness) as a grid of spheres of diameter
    ``thickness`` in the plane z = 0. The centres span edge - thickness, so the clump's
    outline is the die's square; their spacing is at most CLUMP_SPACING x thickness."""
    span = max(edge - thickness, 0.0)  # a die no wider than thick: one sphere, at the centre
    n = max(2, math.ceil(span / (CLUMP_SPACING * thickness) - 1e-9) + 1) if span > 0 else 1
    c = np.linspace(-span / 2, span / 2, n)
    gx, gy = np.meshgrid(c, c, indexing="ij")
    return np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size), np.full(gx.size, thickness / 2)])


def disc_template(diameter: float, thickness: float) -> np.ndarray:
    """A flat disc (diameter x thickness): a centre sphere and rings of spheres of
    diameter ``thickness``; the outer ring's spheres touch the disc's rim."""
    rows = [[0.0, 0.0, 0.0, thickness / 2]]
    outer = (diameter - thickness) / 2
    n_rings = math.ceil(outer / (CLUMP_SPACING * thickness) - 1e-9) if outer > 0 else 0
    for k in range(1, n_rings + 1):
        rk = outer * k / n_rings
        m = max(6, math.ceil(2 * math.pi * rk / (CLUMP_SPACING * thickness) - 1e-9))
        for j in range(m):
            a = 2 * math.pi * j / m
            rows.append([rk * math.cos(a), rk * math.sin(a), 0.0, thickness / 2])
    return np.array(rows)


# ------------------------------------------------------------------ seeds
def _is_prime(n: int) -> bool:
    if n < 2:
        return False
    if n % 2 == 0:
        return n == 2
    return all(n % d for d in range(3, math.isqrt(n) + 1, 2))


def insertion_seeds(seed: int, count: int) -> list[int]:
    """``count`` distinct primes above 10000 and below 2**31 derived from ``seed``:
    LIGGGHTS' insertion and particle-template fixes take only such seeds. The mapping is
    periodic: ``seed`` and ``seed + 200 000`` give the same primes (2**31 holds no more
    starting points 9973 apart)."""
    base = 10007 + (seed % 200_000) * 9973
    out: list[int] = []
    n = base
    while len(out) < count:
        if _is_prime(n):
            out.append(n)
            n += 1009  # spread them out: neighbouring primes would do as well, but read alike
        n += 1
    return out


# ------------------------------------------------------------------ the hook
def box_lines(values: Mapping[str, str], folder: Path) -> tuple[list[str], np.ndarray | None]:
    """A box part's (shape 3, vibrofeed.parts) template file ``box.multisphere`` and
    prepared.in's lines of its sphere count, contact sphere, reach, mass and inertia tensor
    (the body frame's six components, xx xy xz yy yz zz); for other shapes the same
    variables at 0 (the decks read them for shape 3 only) and no file."""
    from .feeders.records import Part
    from .parts import Box, box_template, check_box, engine_inertia

    names = ["n_sph_box", "r_sph_box", "r_min_box", "r_ext_box", "m_box"] + [
        f"I_box_{c}" for c in ("xx", "xy", "xz", "yy", "yz", "zz")]
    if shape_code(values.get("shape", "0")) != 3:
        return [f"variable {n} equal 0\n" for n in names], None
    part = Part.from_values(values)
    box = Box.of(part)
    check_box(box)
    rows = box_template(box)
    write_template(rows, folder / "box.multisphere", "box")
    mass, inertia = engine_inertia(box, number(values, "density", 2330.0))
    numbers = [len(rows), box.sphere_diameter / 2, float(rows[:, 3].min()), part.reach, mass, *inertia]
    return [f"variable {n} equal {float(v)!r}\n" for n, v in zip(names, numbers)], rows


def _part_files(values: Mapping[str, str], folder: Path, hook: str, shape: int, size: float,
                thickness: float) -> tuple[list[str], np.ndarray | None]:
    """What every feeder deck's prepare hook writes for its parts: the catch face, the clump
    templates; and the first lines of its prepared.in (the templates' sphere counts, a box's
    mass and inertia, the insertion seeds). Returns (those lines, the body template of
    ``shape`` or None)."""
    write_stl(*catch_face(), folder / "catch.stl", "catch")
    templates = {"chip": chip_template(size, thickness), "disc": disc_template(size, thickness)}
    for name, rows in templates.items():
        write_template(rows, folder / f"{name}.multisphere", name)
    lines = [f"# written by vibrofeed.geometry.{hook} for one run\n"]
    lines += [f"variable n_sph_{name} equal {len(rows)}\n" for name, rows in templates.items()]
    box, box_rows = box_lines({**values, "shape": str(shape)}, folder)
    lines += box
    stl, stl_rows = stl_lines({**values, "shape": str(shape)}, folder)
    lines += stl
    seed = int(number(values, "seed")) if "seed" in values else 5489
    lines += [f"variable seed_{k} equal {p}\n" for k, p in enumerate(insertion_seeds(seed, 6), 1)]
    return lines, {0: None, 1: templates["chip"], 2: templates["disc"], 3: box_rows, 4: stl_rows}[shape]


def prepare_bulk_feeder(values: Mapping[str, str], folder: str | Path) -> Prepared:
    """Write the bulk feeder's geometry for one run into ``folder`` and describe it.

    Files: ``track.stl`` (the track at rest; a line's further sections: ``track_s2.stl``,
    ``track_s3.stl`` ..., vibrofeed.line, and the deck's generated ``line_*.in``,
    vibrofeed.feeders.deck), ``catch.stl`` (a unit catch face the deck scales and places),
    ``chip.multisphere`` and ``disc.multisphere`` (clump templates), ``prepared.in``
    (LIGGGHTS variables: the templates' sphere counts and the insertion seeds; the deck
    includes it, since a file-style variable crashes LIGGGHTS 3.8 at exit; and the
    refusal of a run by hand with other values than the geometry was written for).
    The feeder's sections and joints are checked first (vibrofeed.feeders).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("track_length", "track_width", "wall_height", "gate_width", "gate_at", "part_size",
                 "part_thickness"):
        number(values, name)  # (the track's own numbers have no neutral value)
    feeder = Feeder.from_values(values)
    feeder.check()
    first = feeder.elements[0]
    size, thickness = feeder.part.size, feeder.part.thickness
    gate = first.gate
    vertices, triangles = track_mesh(first.length, first.width, first.wall_height,
                                     gate.width if gate else 0.0,
                                     gate.at * first.length if gate else None,
                                     cross_tilt=first.cross_tilt)
    write_stl(vertices, triangles, folder / "track.stl", "track")
    lines, template = _part_files(values, folder, "prepare_bulk_feeder", feeder.part.shape, size,
                                  thickness)
    lines += guard_lines({**values, "shape": feeder.part.shape})
    (folder / "prepared.in").write_text("".join(lines))

    further = write_line_files(feeder, folder)
    if further:
        vertices, triangles = combined((vertices, triangles), *further)
    return Prepared(variables={"mesh_dir": str(folder.resolve())}, track=(vertices, triangles),
                    body_template=template)


def prepare_bowl_feeder(values: Mapping[str, str], folder: str | Path) -> Prepared:
    """Write the bowl feeder's geometry for one run into ``folder`` and describe it.

    Files: ``bowl.stl`` (the bowl at rest, vibrofeed.bowl), ``catch.stl``, the clump
    templates and ``prepared.in`` as for the bulk feeder, which here also holds the bowl's
    derived geometry (``bowl_*``) and the region ``track_fill`` of the pre-fill along the
    track. The bowl's parameters are checked first (vibrofeed.bowl.check_bowl).
    """
    from .bowl import BOX_PART, GEOMETRY, PART, bowl_from, bowl_mesh, check_bowl, stl_words, write_bowl

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    numbers = {name: number(values, name) for name in GEOMETRY + PART if name != "shape"}
    numbers["shape"] = shape_code(values.get("shape", "0"))
    numbers.update({name: number(values, name, default) for name, default in BOX_PART.items()
                    if default is not None or name in values})
    check_bowl({**numbers, **stl_words(values)})
    lines, template = _part_files(values, folder, "prepare_bowl_feeder", numbers["shape"],
                                  numbers["part_size"], numbers["part_thickness"])
    lines += write_bowl({k: str(v) for k, v in numbers.items()}, folder)
    # an exit line (sections >= 2): its elements and joints checked, their meshes and the
    # deck's line files written; a run by hand held to every value checked, as for a line
    feeder = Feeder.from_values(values)
    feeder.check()
    lines += guard_lines({**values, "shape": numbers["shape"]})
    (folder / "prepared.in").write_text("".join(lines))
    track = bowl_mesh(bowl_from(numbers))
    further = write_line_files(feeder, folder)
    if further:
        track = combined(track, *further)
    return Prepared(variables={"mesh_dir": str(folder.resolve())}, track=track, body_template=template)
