"""What a picture of one frame shows, as plain arrays (numpy only).

:func:`read_frame` takes the parts present at a frame and the surface's motion
from a :class:`~vibrofeed.results.reader.Result`; :func:`part_shape` tells
which real shape the parts have (from the deck's ``shape``, ``part_size`` and
``part_thickness`` and the body template); :func:`shape_mesh` builds the
triangles of every part at once (one template shape, rotated by each part's
quaternion and moved to its centre) and :func:`track_mesh` the track placed at
the frame's surface position: a feeder line's track section by section, each
moved by its own recorded motion (:func:`vertex_sections`). The renderer and the
exporter hand these arrays to VTK; nothing here draws.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..rotations import quaternion_matrices

# The deck's integer codes of `shape` (LIGGGHTS compares numbers, not strings).
SHAPE_CODES = {0: "sphere", 1: "chip", 2: "disc", 3: "box"}

# Facets of the drawn shapes: enough for round outlines at a picture's scale,
# few enough that a thousand parts stay a few hundred thousand triangles.
SPHERE_RESOLUTION = (16, 10)  # around, pole to pole
DISC_RESOLUTION = 24          # around

FIELDS = ("position", "velocity", "angular_velocity", "force", "radius", "mass", "species")


@dataclass(frozen=True)
class PartShape:
    """The real shape of the parts of a run.

    kind: ``sphere``, ``chip`` (a flat square die: a box ``size`` x ``size`` x
    ``thickness``), ``disc`` (a cylinder of diameter ``size`` and height
    ``thickness``) or ``box`` (``size`` x ``width`` x ``thickness`` along body x, y, z:
    vibrofeed.parts); ``axis``: the body-frame axis (0, 1, 2) normal to a chip's or disc's
    faces. Spheres take each part's own radius.
    """

    kind: str = "sphere"
    size: float = 0.0
    thickness: float = 0.0
    axis: int = 2
    width: float = 0.0

    def extents(self) -> np.ndarray:
        """(3,) edge lengths of the shape's box in the body frame [m] (chips, discs, boxes)."""
        if self.kind == "box":
            return np.array([self.size, self.width, self.thickness])
        out = np.full(3, self.size)
        out[self.axis] = self.thickness
        return out


@dataclass(frozen=True)
class FrameData:
    """The parts present at one frame (one row each) and the surface's motion."""

    index: int
    n_frames: int
    time: float
    ids: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    force: np.ndarray
    radius: np.ndarray
    mass: np.ndarray
    species: np.ndarray
    orientation: np.ndarray      # (N, 4) unit quaternions (w, x, y, z)
    surface_position: np.ndarray  # (3,) [m] section 1's (a single track's) displacement
    surface_velocity: np.ndarray  # (3,) [m s-1]
    # (S, 3) every section's displacement and velocity, row k - 1 for section k (row 0 is
    # surface_*); a section whose motion the file does not record reads 0 (at rest). None: as
    # surface_* (one section).
    section_position: np.ndarray | None = None
    section_velocity: np.ndarray | None = None
    # a rotating surface (the bowl): its angle [rad] and rate [rad s-1] about z through the origin
    surface_angle: float = 0.0
    surface_rate: float = 0.0

    def __len__(self) -> int:
        return len(self.ids)

    @property
    def speed(self) -> np.ndarray:
        """(N,) |velocity| [m s-1] in the simulation (lab) frame."""
        return np.linalg.norm(self.velocity, axis=1)

    @property
    def sections_position(self) -> np.ndarray:
        """(S, 3) every section's displacement [m] (one row for a single track)."""
        return self.surface_position[None] if self.section_position is None else self.section_position

    @property
    def sections_velocity(self) -> np.ndarray:
        """(S, 3) every section's velocity [m s-1] (one row for a single track)."""
        return self.surface_velocity[None] if self.section_velocity is None else self.section_velocity


def _shape_name(value) -> str:
    """The shape's name from the deck variable: an integer code (as float or text) or a name."""
    if isinstance(value, str) and value.strip().lower() in SHAPE_CODES.values():
        return value.strip().lower()
    try:
        return SHAPE_CODES[int(round(float(value)))]
    except (TypeError, ValueError, KeyError):
        return "sphere"


def part_shape(parameters: dict, template: np.ndarray | None = None) -> PartShape:
    """The parts' shape from the run's deck variables and its body template.

    A run without ``shape`` (the single-part deck) has spheres. For chips and
    discs the flat axis is the template's thinnest one (the templates lie in
    the body's z = 0 plane), and the template's extent stands in for a size
    the deck does not declare.
    """
    kind = _shape_name(parameters.get("shape", 0))
    if kind == "sphere":
        return PartShape()
    extents, axis = None, 2
    if template is not None and len(template):
        t = np.asarray(template, dtype=float)
        extents = t[:, :3].max(axis=0) - t[:, :3].min(axis=0) + 2 * t[:, 3].max()
        axis = int(np.argmin(extents))
    size = parameters.get("part_size")
    thickness = parameters.get("part_thickness")
    if kind == "box":  # its body frame is the box's (x along L, z through T): no axis to find
        width = float(parameters.get("part_width", thickness))
        return PartShape(kind, float(size), float(thickness), 2, width)
    if not isinstance(size, float):
        size = float(np.max(extents)) if extents is not None else 0.0
    if not isinstance(thickness, float):
        thickness = float(extents[axis]) if extents is not None else size / 3
    return PartShape(kind, size, thickness, axis)


def rotation_matrices(quaternions: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations of quaternions (N, 4) = (w, x, y, z); NaN or zero rows give identity."""
    return quaternion_matrices(np.asarray(quaternions, dtype=float).reshape(-1, 4))


def read_frame(result, index: int) -> FrameData:
    """The parts present at frame ``index`` (negative counts from the end) of a Result."""
    n = result.n_frames
    if not -n <= index < n:
        from ..errors import UsageError

        raise UsageError(f"frame {index} out of range: {result.path} has {n} frames "
                         f"(0 to {n - 1}, or -1 for the last)")
    index %= n
    frame = result.frame(index, fields=FIELDS)
    try:
        orientation = result.read("orientation", frames=index, slots=frame.slots)
    except KeyError:  # a result without bodies: every part is a sphere, unrotated
        orientation = np.tile((1.0, 0.0, 0.0, 0.0), (len(frame), 1))
    position, velocity = section_motion(result, index)
    # (zeros for a surface that does not turn)
    angle = float(result.read("surface_angle", frames=index)[2])
    rate = float(result.read("surface_angular_velocity", frames=index)[2])
    return FrameData(
        index=index, n_frames=n, time=frame.time, ids=frame.ids,
        orientation=np.asarray(orientation, dtype=float).reshape(len(frame), 4),
        surface_position=position[0], surface_velocity=velocity[0],
        section_position=position, section_velocity=velocity, surface_angle=angle, surface_rate=rate,
        **{name: frame[name] for name in FIELDS})


def section_motion(result, frames) -> tuple[np.ndarray, np.ndarray]:
    """(position, velocity) of every section at ``frames`` (an int: (S, 3) each; else
    (S, frames, 3)): section 1's ``surface_*`` first, then a line's further sections; a section
    the file does not record (a line of format 1.3) stays at rest (0)."""
    from ..results import layout as L

    position, velocity = [], []
    for k in range(1, result.n_sections + 1):
        if k == 1 or L.surface_path(k) in result.file:
            p, v = result.section_surface(k, frames=frames)
        else:
            p = v = np.zeros_like(position[0])
        position.append(np.asarray(p, dtype=float))
        velocity.append(np.asarray(v, dtype=float))
    return np.stack(position), np.stack(velocity)


# -- template shapes: (points (V, 3), triangles (F, 3), normals (V, 3)) in the body frame -----
# The normals come with the shapes (exact, outward) so that drawing a frame of many parts
# needs no normal computation on the whole mesh: they turn with the parts.
def unit_sphere(around: int = SPHERE_RESOLUTION[0], rings: int = SPHERE_RESOLUTION[1]):
    """A UV sphere of radius 1: two poles and ``rings - 1`` rings of ``around`` points."""
    theta = np.linspace(0, np.pi, rings + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, around, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring_pts = np.column_stack([(np.sin(t) * np.cos(p)).ravel(), (np.sin(t) * np.sin(p)).ravel(),
                                np.cos(t).ravel()])
    points = np.vstack([[0, 0, 1], ring_pts, [0, 0, -1]])
    south = len(points) - 1
    k = np.arange(around)
    nxt = (k + 1) % around
    tris = [np.column_stack([np.zeros(around, int), 1 + k, 1 + nxt])]
    for r in range(rings - 2):
        a, b = 1 + r * around, 1 + (r + 1) * around
        tris += [np.column_stack([a + k, b + k, b + nxt]), np.column_stack([a + k, b + nxt, a + nxt])]
    last = 1 + (rings - 2) * around
    tris.append(np.column_stack([last + k, np.full(around, south), last + nxt]))
    return points, np.vstack(tris), points.copy()


def box(extents):
    """A box of edge lengths ``extents`` centred at 0: 4 points per face (sharp edges), 12 triangles."""
    h = np.asarray(extents, dtype=float) / 2
    points, tris, normals = [], [], []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for sign in (-1.0, 1.0):
            corners = np.zeros((4, 3))
            corners[:, axis] = sign * h[axis]
            corners[:, u] = np.array([-1, 1, 1, -1]) * h[u]
            corners[:, v] = np.array([-1, -1, 1, 1]) * h[v]
            base = len(points) * 4
            quad = [[0, 1, 2], [0, 2, 3]] if sign > 0 else [[0, 2, 1], [0, 3, 2]]  # outward
            points.append(corners)
            normals.append(np.tile(np.eye(3)[axis] * sign, (4, 1)))
            tris += [[base + i for i in t] for t in quad]
    return np.vstack(points), np.array(tris), np.vstack(normals)


def cylinder(diameter: float, height: float, axis: int = 2, around: int = DISC_RESOLUTION):
    """A closed cylinder along body axis ``axis``: side rings and separate cap points."""
    phi = np.linspace(0, 2 * np.pi, around, endpoint=False)
    radial = np.column_stack([np.cos(phi), np.sin(phi), np.zeros(around)])
    ring = radial[:, :2] * diameter / 2
    k = np.arange(around)
    nxt = (k + 1) % around
    pts, tris, normals = [], [], []
    for z in (-height / 2, height / 2):  # side: bottom ring 0..n-1, top ring n..2n-1
        pts.append(np.column_stack([ring, np.full(around, z)]))
        normals.append(radial)
    tris += [np.column_stack([k, nxt, around + nxt]), np.column_stack([k, around + nxt, around + k])]
    for z, outward in ((-height / 2, -1), (height / 2, 1)):  # caps: a centre and a ring
        base = sum(len(p) for p in pts)
        pts.append(np.vstack([[0, 0, z], np.column_stack([ring, np.full(around, z)])]))
        normals.append(np.tile([0.0, 0.0, outward], (around + 1, 1)))
        fan = np.column_stack([np.full(around, base), base + 1 + k, base + 1 + nxt])
        tris.append(fan if outward > 0 else fan[:, [0, 2, 1]])
    # A cyclic permutation of the columns (a rotation) takes local z to the body axis.
    shift = (axis + 1) % 3
    return (np.roll(np.vstack(pts), shift, axis=1), np.vstack(tris),
            np.roll(np.vstack(normals), shift, axis=1))


def template_mesh(shape: PartShape):
    """(points, triangles, normals) of one part in its body frame; spheres have radius 1
    (scaled per part)."""
    if shape.kind in ("chip", "box"):
        return box(shape.extents())
    if shape.kind == "disc":
        return cylinder(shape.size, shape.thickness, shape.axis)
    return unit_sphere()


@dataclass(frozen=True)
class PartsMesh:
    """Every part's real shape at a frame, as one triangle mesh.

    ``owner`` is each point's row in the frame, to spread per-part values over
    the points (``values[owner]``); ``normals`` are the outward unit normals at
    the points (for shading).
    """

    points: np.ndarray     # (N*V, 3) [m]
    triangles: np.ndarray  # (N*F, 3)
    owner: np.ndarray      # (N*V,)
    normals: np.ndarray    # (N*V, 3)


def shape_mesh(frame: FrameData, shape: PartShape) -> PartsMesh:
    """The parts of a frame with their real shapes, placed and oriented."""
    points, tris, normals = template_mesh(shape)
    n, v = len(frame), len(points)
    if shape.kind == "sphere":
        placed = points[None, :, :] * frame.radius[:, None, None]
        turned = np.broadcast_to(normals, (n, v, 3))
    else:
        rot = rotation_matrices(frame.orientation)
        placed = np.einsum("nij,vj->nvi", rot, points)
        turned = np.einsum("nij,vj->nvi", rot, normals)
    placed = placed + frame.position[:, None, :]
    triangles = tris[None, :, :] + (np.arange(n) * v)[:, None, None]
    return PartsMesh(placed.reshape(-1, 3), triangles.reshape(-1, 3), np.repeat(np.arange(n), v),
                     np.ascontiguousarray(turned).reshape(-1, 3))


def vertex_sections(result) -> np.ndarray | None:
    """(V,) each track vertex's row in :attr:`FrameData.sections_position` (its section - 1), or
    None without a track mesh. A file that does not split its track (a single track, a line of
    format 1.3) moves every vertex with section 1, as the file says the track moves."""
    mesh = result.track_mesh
    if mesh is None:
        return None
    split = result.track_sections
    if split is None:
        return np.zeros(len(mesh[0]), dtype=np.int64)
    return np.asarray(split, dtype=np.int64) - 1


def track_mesh(result, frame: FrameData):
    """(vertices, triangles) of the track at the frame (its rest mesh turned by the surface's
    angle about z, for a bowl, then moved by the surface position: each vertex by its own
    section's), or None when the run has no track mesh (the single-part deck's plane)."""
    rows = vertex_sections(result)
    if rows is None:
        return None
    vertices, triangles = result.track_mesh
    return (_turned(np.asarray(vertices, dtype=float), frame.surface_angle, rows == 0)
            + frame.sections_position[rows], np.asarray(triangles))


def _turned(points: np.ndarray, angle: float, which=None) -> np.ndarray:
    """``points`` (V, 3) turned by ``angle`` [rad] about the z axis through the origin (only
    those ``which`` says: section 1's, the bowl, not an exit line's)."""
    if angle == 0.0:
        return points
    c, s = np.cos(angle), np.sin(angle)
    turned = np.column_stack([c * points[:, 0] - s * points[:, 1], s * points[:, 0] + c * points[:, 1],
                              points[:, 2]])
    return turned if which is None else np.where(np.asarray(which)[:, None], turned, points)


def track_velocity(result, frame: FrameData) -> np.ndarray | None:
    """(V, 3) the velocity of each track vertex at the frame [m s-1]: its section's, plus a
    bowl's rate x r at the vertex where it turns."""
    rows = vertex_sections(result)
    if rows is None:
        return None
    velocity = frame.sections_velocity[rows]
    if frame.surface_rate:
        placed = _turned(np.asarray(result.track_mesh[0], dtype=float), frame.surface_angle)
        turning = (rows == 0)[:, None]  # (the bowl's; an exit line's sections do not turn)
        velocity = velocity + turning * frame.surface_rate * np.column_stack(
            [-placed[:, 1], placed[:, 0], np.zeros(len(placed))])
    return velocity


def part_sections(result, frame: FrameData) -> np.ndarray:
    """(N,) each part's row in :attr:`FrameData.sections_velocity`: the element whose stretch
    of track holds its x (vibrofeed.feeders.Feeder.element_at_x: the parts past the outlet
    edge the last one's); 0 for a single track."""
    from ..postproc.path import feeder_of

    rows = np.zeros(len(frame), dtype=np.int64)
    feeder = feeder_of(result.parameters) if len(frame.sections_velocity) > 1 else None
    if feeder is not None:
        rows = np.clip(feeder.element_at_x(frame.position[:, 0]), 0, len(frame.sections_velocity) - 1)
    return rows


def floor_patch(frame: FrameData, xy_range=None, margin: float = 5.0):
    """A horizontal rectangle at the surface's height, for runs without a track mesh.

    It spans ``xy_range`` = (xmin, xmax, ymin, ymax) when given, else the parts'
    x and y ranges widened by ``margin`` mean radii.
    """
    if xy_range is not None:
        lo, hi = np.array(xy_range[0::2], dtype=float), np.array(xy_range[1::2], dtype=float)
    else:
        pad = margin * (float(np.mean(frame.radius)) if len(frame) else 1e-3)
        if len(frame):
            lo = frame.position[:, :2].min(axis=0) - pad
            hi = frame.position[:, :2].max(axis=0) + pad
        else:
            lo, hi = np.full(2, -pad), np.full(2, pad)
    z = float(frame.surface_position[2])
    vertices = np.array([[lo[0], lo[1], z], [hi[0], lo[1], z], [hi[0], hi[1], z], [lo[0], hi[1], z]])
    return vertices, np.array([[0, 1, 2], [0, 2, 3]])


def body_axes(frame: FrameData, shape: PartShape) -> tuple[np.ndarray, np.ndarray]:
    """(normal, in-plane x) unit vectors of each part in the simulation frame: the body axis
    normal to a chip's faces and the first other body axis (glyph orientation arrays)."""
    rot = rotation_matrices(frame.orientation)
    return rot[:, :, shape.axis], rot[:, :, (shape.axis + 1) % 3]


def shape_tensors(frame: FrameData, shape: PartShape) -> np.ndarray:
    """(N, 9) the matrix R diag(extents) of each part, column after column as VTK stores
    tensors: its columns are the body axes scaled by the box's edges, so a unit cube glyph
    transformed by it (ParaView's Tensor Glyph with "Extract Eigenvalues" off) is the
    part's box; spheres get their diameter on every axis."""
    rot = rotation_matrices(frame.orientation)
    if shape.kind == "sphere":
        scale = (2 * frame.radius)[:, None] * np.ones((1, 3))
    else:
        scale = np.broadcast_to(shape.extents(), (len(frame), 3))
    return (rot * scale[:, None, :]).transpose(0, 2, 1).reshape(len(frame), 9)
