"""A designer's own part (shape 4, ``stl``): a watertight STL of the solid, simulated as a clump
of spheres that the CLUMP library makes (clump-python, the Python port of the CLUMP code of
Angelidakis et al.: Euclidean distance transform, Favier, Ferellec-McDowell).

Three things live here, as vibrofeed.parts has them for boxes:

* the solid's mass properties from the STL with trimesh (:func:`solid`): volume, centre of
  mass and inertia tensor of the closed surface (watertight, wound alike, 10 um to 10 mm
  across after its ``unit``), and its principal frame;
* the clump template the engine simulates (:func:`template`): the STL handed to CLUMP's
  method, its spheres written about the solid's centre of mass in the solid's principal
  frame. The engine is given the solid's mass and principal moments (a diagonal tensor),
  not the clump's, for the reason vibrofeed.parts gives: LIGGGHTS' particletemplate/
  multisphere takes the template's origin as the centre of mass and keeps the template's
  frame when the tensor is diagonal;
* the clump's fidelity to the solid (:func:`fidelity`): the spheres' union volume, centre of
  mass and principal moments on a voxel grid against the STL's, and how far the STL's
  surface lies from the clump's (points sampled on it).

The body frame is the solid's principal frame: x the axis of the smallest principal moment,
z that of the largest, y the third (right-handed), each axis pointing the way its largest
component in the STL's frame points. For a box L x W x T (L > W > T) that is the box frame
of vibrofeed.parts: x along L, z across T. A part's recorded orientation (quaternion) turns
this frame. With two equal moments (a cylinder, a square plate) the two axes are any pair in
their plane: eigh's.

The sizes the decks use (part_size, part_width, part_thickness) are the extents of the
solid's bounding box in its principal frame, largest to smallest (:func:`sizes`); they are
derived, not given (vibrofeed.parameters.resolve writes them).
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import math
import os
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from .errors import ParameterError
from .mesh import write_template
from .values import number

SHAPE = 4
UNITS = {"mm": 1e-3, "m": 1.0}
METHODS = {"euclidean": 0, "favier": 1, "ferellec-mcdowell": 2}
METHOD_NAMES = {code: name for name, code in METHODS.items()}
# A micro-part is 10 um to 10 mm across (after the unit): outside, the unit is wrong.
SIZES = (1e-5, 1e-2)
# The deck's names of the part's words and numbers, with their defaults.
DEFAULTS = {"part_unit": 1e-3, "clump_method": 0, "clump_spheres": 60, "clump_resolution": 20,
            "clump_overlap": 0.8}
NAMES = ["part_file", *DEFAULTS]
# Ferellec-McDowell's random choice of vertices: fixed, so that a part is one clump.
SEED = 1


@dataclass(frozen=True)
class StlPart:
    """The STL part: ``file`` (absolute path), ``unit`` (metres per unit of the STL), the CLUMP
    ``method`` (0 euclidean, 1 favier, 2 ferellec-mcdowell) and its knobs: ``spheres`` (how
    many: Euclidean's N, Favier's N, Ferellec-McDowell's share of the vertices as a count),
    ``resolution`` (cells across the solid's smallest extent: Euclidean's voxels ``div``, the
    other methods' surface refinement), ``overlap`` (Euclidean's overlap of the radii, [0, 1))."""

    file: str
    unit: float = 1e-3
    method: int = 0
    spheres: int = 60
    resolution: int = 20
    overlap: float = 0.8

    @classmethod
    def of(cls, values: Mapping) -> StlPart:
        file = str(values.get("part_file", "") or "").strip()
        if not file or file == "none":
            raise ParameterError("an stl part (shape 4) needs its STL: part_file (a description's "
                                 "[parts] file)")
        get = {name: number(values, name, default) for name, default in DEFAULTS.items()}
        return cls(file=file, unit=get["part_unit"], method=int(get["clump_method"]),
                   spheres=int(get["clump_spheres"]), resolution=int(get["clump_resolution"]),
                   overlap=get["clump_overlap"])

    @property
    def method_name(self) -> str:
        return METHOD_NAMES.get(self.method, str(self.method))


def check_part(part: StlPart) -> None:
    """A one-line ParameterError for knobs out of range (the STL itself: :func:`solid`)."""
    if part.unit not in UNITS.values():
        raise ParameterError(f"part_unit={part.unit:g} m per unit: an STL is in millimetres (unit = "
                             "\"mm\", 0.001) or metres (\"m\", 1)")
    if part.method not in METHOD_NAMES:
        raise ParameterError(f"clump_method={part.method}: 0 euclidean, 1 favier, 2 ferellec-mcdowell")
    if not 1 <= part.spheres <= 2000:
        raise ParameterError(f"clump_spheres={part.spheres} must be 1 to 2000")
    if not 4 <= part.resolution <= 200:
        raise ParameterError(f"clump_resolution={part.resolution} must be 4 to 200 cells across the "
                             "part's smallest extent")
    if not 0 <= part.overlap < 1:
        raise ParameterError(f"clump_overlap={part.overlap:g} must be in [0, 1)")


# ------------------------------------------------------------------ the solid
@dataclass(frozen=True)
class Solid:
    """The STL's solid [m]: ``volume`` [m^3], ``com`` (its centre of mass in the STL's frame),
    ``axes`` (3, 3) the principal axes in the STL's frame (columns: body x, y, z),
    ``moments`` (3,) the principal moments per unit density [m^5], ascending, and ``body``
    (a trimesh.Trimesh: the solid in the body frame, about its centre of mass)."""

    volume: float
    com: np.ndarray
    axes: np.ndarray
    moments: np.ndarray
    body: object

    @property
    def extents(self) -> np.ndarray:
        """The bounding box's extents along body x, y, z [m]."""
        return np.asarray(self.body.extents, dtype=float)


def _fingerprint(file: str) -> str:
    try:
        data = Path(file).read_bytes()
    except OSError as exc:
        raise ParameterError(f"part_file {file}: cannot read it: {exc.strerror}") from None
    return hashlib.sha256(data).hexdigest()


def solid(part: StlPart) -> Solid:
    """The solid of ``part``'s STL (module docstring), checked: one-line ParameterError naming
    the file when it cannot be read, holds no closed surface, is wound inconsistently or is not
    a micro-part's size at its unit."""
    return _solid(part.file, part.unit, _fingerprint(part.file))


@lru_cache(maxsize=16)
def _solid(file: str, unit: float, _digest: str) -> Solid:
    import trimesh

    name = os.path.basename(file)
    try:
        mesh = trimesh.load_mesh(file, file_type="stl")
    except Exception as exc:  # (trimesh raises what its readers raise)
        reason = getattr(exc, "strerror", None) or (str(exc).splitlines() or [type(exc).__name__])[0]
        raise ParameterError(f"part_file {name}: cannot read it as an STL: {reason}") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ParameterError(f"part_file {name} holds no triangles")
    if not mesh.is_winding_consistent:
        raise ParameterError(f"part_file {name}: its triangles are not wound alike (inconsistent "
                             "normals): export it again with its normals repaired")
    if not mesh.is_watertight:
        raise ParameterError(f"part_file {name} is not watertight (its surface has open edges): a part "
                             "is a closed solid; close the holes and export it again")
    mesh = mesh.copy()
    mesh.apply_scale(unit)
    size = float(mesh.extents.max())
    if not SIZES[0] <= size <= SIZES[1]:
        guess = "mm" if size > SIZES[1] else "m"
        raise ParameterError(f"part_file {name} is {size:.4g} m across at {unit:g} m per unit; a "
                             f"micro-part is 10 um to 10 mm: is the unit {guess}?")
    if mesh.volume < 0:  # wound inwards: the normals point into the solid
        mesh.invert()
    com = np.asarray(mesh.center_mass, dtype=float)
    inertia = np.asarray(mesh.moment_inertia, dtype=float) / mesh.density  # per unit density
    moments, axes = np.linalg.eigh(inertia)
    for k in range(3):  # each axis towards its largest component
        if axes[int(np.argmax(np.abs(axes[:, k]))), k] < 0:
            axes[:, k] = -axes[:, k]
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    body = trimesh.Trimesh((np.asarray(mesh.vertices) - com) @ axes, np.asarray(mesh.faces), process=False)
    return Solid(float(mesh.volume), com, axes, moments, body)


def sizes(part: StlPart) -> tuple[float, float, float]:
    """(part_size, part_width, part_thickness) [m]: the principal bounding box's extents,
    largest to smallest."""
    e = sorted(solid(part).extents, reverse=True)
    return float(e[0]), float(e[1]), float(e[2])


# ------------------------------------------------------------------ the clump
def template(part: StlPart) -> np.ndarray:
    """The clump template, (n, 4) x y z r [m], about the solid's centre of mass in its
    principal frame, as CLUMP's method made it (module docstring)."""
    check_part(part)
    return _template(part, _fingerprint(part.file)).copy()


@lru_cache(maxsize=16)
def _template(part: StlPart, digest: str) -> np.ndarray:
    body = _solid(part.file, part.unit, digest).body
    # CLUMP works on an STL file; in millimetres its numbers are of order 1
    scale = 1e3
    mesh = body.copy()
    mesh.apply_scale(scale)
    with tempfile.TemporaryDirectory(prefix="vibrofeed-clump-") as tmp:
        stl = os.path.join(tmp, "part.stl")
        with contextlib.redirect_stdout(io.StringIO()):  # (CLUMP prints its progress)
            if part.method == 0:
                rows = _euclidean(mesh, stl, part)
            else:
                import trimesh

                # Favier and Ferellec-McDowell place spheres from the surface's vertices: a
                # surface with vertices everywhere, at most the resolution's cell apart
                edge = float(mesh.extents.min()) / part.resolution
                vertices, faces = trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, edge)
                fine = trimesh.Trimesh(vertices, faces)
                fine.export(stl)
                if part.method == 1:
                    from CLUMP import GenerateClump_Favier

                    _, clump = GenerateClump_Favier(stl, part.spheres)
                else:
                    from CLUMP import GenerateClump_Ferellec_McDowell

                    share = min(1.0, part.spheres / len(fine.vertices))
                    rmin = edge / 2
                    _, clump = GenerateClump_Ferellec_McDowell(stl, 0.0, rmin, rmin / 4, share, seed=SEED)
                rows = np.column_stack([clump.positions, np.ravel(clump.radii)])
    rows = np.asarray(rows, dtype=float)
    rows /= scale
    keep = rows[:, 3] > 0
    if not keep.any():
        raise ParameterError(f"part_file {os.path.basename(part.file)}: CLUMP's {part.method_name} made "
                             "no sphere; raise clump_resolution")
    return rows[keep]


def _euclidean(mesh, stl: str, part: StlPart) -> np.ndarray:
    """CLUMP's Euclidean distance transform on ``mesh`` (centred on its bounding box), its
    spheres moved back into ``mesh``'s frame. CLUMP gives centres about the voxel image's middle
    ((index - half the padded image's size + 1) cells); the image's cell 0 lies at the voxel
    grid's origin, two padding cells in: the shift between the two is the grid's, computed from
    the same voxelisation (trimesh's, deterministic)."""
    from CLUMP import GenerateClump_Euclidean_3D

    centre = np.asarray(mesh.bounds, dtype=float).mean(axis=0)
    mesh = mesh.copy()
    mesh.apply_translation(-centre)
    mesh.export(stl)
    import trimesh

    again = trimesh.load_mesh(stl)  # (what CLUMP reads: single-precision coordinates)
    pitch = float(np.min(again.extents)) / part.resolution
    grid = again.voxelized(pitch=pitch, method="subdivide").fill()
    padded = np.array(grid.matrix.shape) + 4
    offset = np.asarray(grid.transform, dtype=float)[:3, 3] + (padded / 2 - 3) * pitch
    _, clump = GenerateClump_Euclidean_3D(stl, part.spheres, 0.0, part.resolution, part.overlap)
    return np.column_stack([clump.positions + offset + centre, np.ravel(clump.radii)])


def engine_inertia(part: StlPart, density: float) -> tuple[float, list[float]]:
    """(mass, xx xy xz yy yz zz of the inertia tensor in the body frame): the solid's, the
    products 0 (the principal frame)."""
    s = solid(part)
    m = density * s.moments
    return density * s.volume, [float(m[0]), 0.0, 0.0, float(m[1]), 0.0, float(m[2])]


def reach(rows: np.ndarray) -> float:
    """The clump's circumscribed radius [m] about the centre of mass."""
    return float(np.max(np.linalg.norm(rows[:, :3], axis=1) + rows[:, 3]))


def part_reach(part: StlPart) -> float:
    return reach(template(part))


# ------------------------------------------------------------------ fidelity
def fidelity(part: StlPart, cells: int = 60, samples: int = 4000) -> dict:
    """How the clump differs from the solid. The union of the spheres is integrated on a grid
    of ``cells`` cells along the largest extent (body frame) covering both; the solid's figures
    are trimesh's (exact for the closed surface). Distances are sampled at ``samples`` points
    spread over the STL's surface: each point's distance to the union's surface (its signed
    distance to the nearest sphere's, min_i |p - c_i| - r_i).

    Returns ``spheres``, ``r_min``, ``r_max`` [m], ``volume_error`` (relative, union - solid),
    ``com_offset`` [m] (the union's centre of mass from the solid's), ``inertia_errors``
    (relative, of the principal moments about the body axes x, y, z), ``surface_max``,
    ``surface_mean`` [m] (of |distance|), ``size`` [m] (the largest extent, the scale of the
    figures) and ``cell`` [m] (the grid's)."""
    import trimesh

    rows = template(part)
    s = solid(part)
    lo = np.minimum(s.body.bounds[0], (rows[:, :3] - rows[:, 3:]).min(axis=0))
    hi = np.maximum(s.body.bounds[1], (rows[:, :3] + rows[:, 3:]).max(axis=0))
    h = float(np.max(hi - lo)) / cells
    axes = [lo[k] + (np.arange(math.ceil((hi[k] - lo[k]) / h)) + 0.5) * h for k in range(3)]
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    inside = np.zeros(len(pts), dtype=bool)
    for x, y, z, r in rows:
        inside |= np.einsum("ij,ij->i", pts - (x, y, z), pts - (x, y, z)) <= r * r
    p = pts[inside]
    volume = len(p) * h ** 3
    com = p.mean(axis=0)
    q = p - com
    second = q.T @ q * h ** 3
    inertia = np.trace(second) * np.eye(3) - second
    surface, _ = trimesh.sample.sample_surface_even(s.body, samples, seed=SEED)
    gap = np.full(len(surface), np.inf)
    for x, y, z, r in rows:
        gap = np.minimum(gap, np.linalg.norm(surface - (x, y, z), axis=1) - r)
    return {
        "spheres": len(rows),
        "r_min": float(rows[:, 3].min()),
        "r_max": float(rows[:, 3].max()),
        "volume_error": volume / s.volume - 1,
        "com_offset": float(np.linalg.norm(com)),
        "inertia_errors": np.diag(inertia) / s.moments - 1,
        "surface_max": float(np.abs(gap).max()),
        "surface_mean": float(np.abs(gap).mean()),
        "size": float(s.extents.max()),
        "cell": h,
    }


def fidelity_line(part: StlPart, f: dict | None = None) -> str:
    """The fidelity in one line (what ``vibrofeed prepare`` prints)."""
    f = fidelity(part) if f is None else f
    e = f["inertia_errors"]
    return (f"{os.path.basename(part.file)} as {f['spheres']} spheres ({part.method_name}, radii "
            f"{f['r_min'] * 1e6:.3g}-{f['r_max'] * 1e6:.3g} um): volume {f['volume_error']:+.1%}, "
            f"centre of mass {f['com_offset'] * 1e6:.3g} um off, principal moments "
            f"{e[0]:+.1%} {e[1]:+.1%} {e[2]:+.1%}, surface {f['surface_mean'] * 1e6:.3g} um mean, "
            f"{f['surface_max'] * 1e6:.3g} um at most from the clump's "
            f"(part {f['size'] * 1e6:.4g} um across)")


# ------------------------------------------------------------------ prepared.in
VARIABLES = ["n_sph_stl", "r_sph_stl", "r_min_stl", "r_ext_stl", "m_stl"] + [
    f"I_stl_{c}" for c in ("xx", "xy", "xz", "yy", "yz", "zz")]


def stl_lines(values: Mapping[str, str], folder: Path) -> tuple[list[str], np.ndarray | None]:
    """An stl part's template file ``stl.multisphere`` and prepared.in's lines of its sphere
    count, largest and smallest sphere radius, reach, mass and inertia tensor (body frame);
    for other shapes the same variables at 0 and no file."""
    if number(values, "shape", 0) != SHAPE:  # (resolved values: the shape's code)
        return [f"variable {n} equal 0\n" for n in VARIABLES], None
    part = StlPart.of(values)
    rows = template(part)
    write_template(rows, Path(folder) / "stl.multisphere", "stl")
    mass, inertia = engine_inertia(part, number(values, "density", 2330.0))
    numbers = [len(rows), float(rows[:, 3].max()), float(rows[:, 3].min()), reach(rows), mass, *inertia]
    return [f"variable {n} equal {float(v)!r}\n" for n, v in zip(VARIABLES, numbers)], rows
