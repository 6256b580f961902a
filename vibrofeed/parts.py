"""Rectangular parts (shape 3, ``box``): an L x W x T chip component with an optional bump.

Body frame (the box frame): x along the length L (``part_size``), y along the width W
(``part_width``), z along the thickness T (``part_thickness``), the origin at the box's
centre; the +z face is the *marked* face. L >= W >= T. The optional feature is a **bump**:
a sphere of diameter ``bump_diameter`` whose top stands ``bump_height`` above the +z face
at x = ``bump_at`` L/2, y = 0 (``bump_height`` 0: no bump). It makes the +z face and the
+x end (for ``bump_at`` > 0) different from their opposites.

Three things live here:

* the solid's closed-form mass properties (:func:`mass_properties`): the box plus the
  spherical cap of the bump above the face (the rest of the bump's sphere is inside the
  box); mass, centre of mass and the inertia tensor about it, with the xz product an
  off-centre bump gives;
* the clump template the engine simulates (:func:`box_template`): spheres of one diameter
  d = T/2 on the box's surface lattice (a hollow shell: the engine is given the solid's
  mass and inertia, not the clump's), centres spanning (L-d, W-d, T-d), at most
  CLUMP_SPACING d apart, so at least three rows across every face; plus the bump's sphere;
* the clump's fidelity against the solid (:func:`clump_fidelity`), from the spheres'
  union integrated on a voxel grid, and the support a part gets from it.

What LIGGGHTS does with the template (src/fix_template_multisphere.cpp, post_create,
``mass ... inertia_tensor ... use_density``): it does not compute a centre of mass, it
takes the template's origin as the body's centre of mass (``calc_displace_xcm_x_body``,
"using xcm = 0/0/0"); it diagonalises the given tensor (``calc_eigensystem``,
MathExtra::jacobi, components read in the order xx xy xz yy yz zz) and stores the spheres
in its principal frame, and a body's recorded orientation (quaternion) is that principal
frame's. So the template is written about the solid's centre of mass and in the solid's
principal frame (:func:`principal_axes`), with the principal moments (a diagonal tensor,
on which jacobi makes no rotation): the recorded quaternion then rotates exactly the
template the result records. Without a bump, or with a centred one, that frame is the box
frame. An off-centre bump tilts the principal axes about y by :attr:`MassProperties.tilt`
(0.15 degrees for the 1.0 x 0.5 x 0.35 mm example with a 0.2 mm bump 0.05 mm high at
bump_at 0.5): body x then lies within that angle of the length, body z within it of the
marked face's normal; :func:`box_frame_orientation` turns recorded quaternions into the
box frame's exact rotation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import ParameterError

# Largest spacing of the clump's spheres, as a fraction of their diameter (as the chip's,
# vibrofeed.geometry.CLUMP_SPACING: the faces stay within 4 % of d of flat).
CLUMP_SPACING = 0.75
# The clump's sphere diameter as a fraction of the thickness (see box_template).
SPHERE_OF_THICKNESS = 0.5
# Most spheres a box's clump may have: a part costs as many spheres per step (the demo's box
# has 36 or 84), and a thin box's count grows as (L/T)(W/T) (a film of 1 um: 1e6 spheres).
MAX_CLUMP_SPHERES = 10_000


@dataclass(frozen=True)
class Box:
    """A box part's dimensions [m]: ``length`` L >= ``width`` W >= ``thickness`` T, and the
    bump (``bump_height`` 0: none; ``bump_at`` the bump centre's x as a fraction of L/2)."""

    length: float
    width: float
    thickness: float
    bump_height: float = 0.0
    bump_diameter: float = 0.0
    bump_at: float = 0.5
    spacing: float = CLUMP_SPACING  # the clump's largest sphere spacing, in sphere diameters

    @classmethod
    def of(cls, part) -> Box:
        """The box of a :class:`vibrofeed.feeders.records.Part` (shape 3)."""
        return cls(part.size, part.width, part.thickness, part.bump_height, part.bump_diameter,
                   part.bump_at, part.clump_spacing)

    @property
    def has_bump(self) -> bool:
        return self.bump_height > 0

    @property
    def bump_centre(self) -> np.ndarray:
        """The bump sphere's centre in the box frame (its top bump_height above the face)."""
        r = self.bump_diameter / 2
        return np.array([self.bump_at * self.length / 2, 0.0, self.thickness / 2 + self.bump_height - r])

    @property
    def sphere_diameter(self) -> float:
        """The clump's sphere diameter d (box_template)."""
        return SPHERE_OF_THICKNESS * self.thickness


def check_box(box: Box) -> None:
    """A one-line ParameterError for a box that cannot be built (names the parameters)."""
    L, W, T = box.length, box.width, box.thickness
    for name, value in (("part_size", L), ("part_width", W), ("part_thickness", T)):
        if not value > 0:
            raise ParameterError(f"{name}={value:g} m must be > 0 for a box (shape 3)")
    if not L >= W >= T:
        raise ParameterError(f"a box needs part_size >= part_width >= part_thickness (L >= W >= T), "
                             f"got {L:g} m, {W:g} m, {T:g} m")
    if not 0.5 <= box.spacing <= 1.0:
        raise ParameterError(f"clump_spacing={box.spacing:g} must be in [0.5, 1]: spheres further apart "
                             "than their diameter leave gaps a neighbour's sphere enters")
    if (n := clump_count(box)) > MAX_CLUMP_SPHERES:
        raise ParameterError(
            f"a box of {L:g} x {W:g} x {T:g} m is a clump of {n:.3g} spheres of part_thickness/2 "
            f"(at most {MAX_CLUMP_SPHERES}: each part costs as many spheres per step); a thicker "
            f"part_thickness or a larger clump_spacing (up to 1)")
    h, db, at = box.bump_height, box.bump_diameter, box.bump_at
    if h < 0 or db < 0:
        raise ParameterError(f"bump_height={h:g} m and bump_diameter={db:g} m must be >= 0")
    if h == 0:
        return
    if db <= 0:
        raise ParameterError(f"bump_height={h:g} m needs a bump_diameter > 0")
    if db > W:
        raise ParameterError(f"bump_diameter={db:g} m is wider than the face (part_width={W:g} m)")
    if h > db:
        raise ParameterError(f"bump_height={h:g} m exceeds bump_diameter={db:g} m: the bump is a "
                             "sphere, it protrudes at most its diameter")
    if not -1 <= at <= 1 or abs(at) * L / 2 + db / 2 > L / 2 * (1 + 1e-12):
        raise ParameterError(f"bump_at={at:g}: the bump (bump_diameter={db:g} m) reaches past the "
                             f"face's end; |bump_at| must be at most {1 - db / L:.3g}")
    if db - h > T * (1 + 1e-12):
        raise ParameterError(f"bump_diameter={db:g} m with bump_height={h:g} m: the bump's sphere "
                             f"reaches through the bottom face (part_thickness={T:g} m)")


# ------------------------------------------------------------------ closed forms
def cap_integrals(r: float, h: float) -> tuple[float, float, float, float]:
    """The spherical cap of height ``h`` of a sphere of radius ``r`` (the part beyond the
    plane r - h from its centre), unit density, about the sphere's centre, its axis z:
    (volume, its first moment along z, the second moments sum z^2 dV and sum x^2 dV), from
    the slices of area pi (r^2 - z^2) integrated from a = r - h to r."""
    a = r - h

    def between(f):
        return f(r) - f(a)

    volume = math.pi * between(lambda z: r * r * z - z ** 3 / 3)
    first = math.pi * between(lambda z: r * r * z * z / 2 - z ** 4 / 4)
    zz = math.pi * between(lambda z: r * r * z ** 3 / 3 - z ** 5 / 5)
    # a slice's polar moment pi (r^2 - z^2)^2 / 2, half of it about x
    xx = math.pi / 4 * between(lambda z: r ** 4 * z - 2 * r * r * z ** 3 / 3 + z ** 5 / 5)
    return volume, first, zz, xx


@dataclass(frozen=True)
class MassProperties:
    """A solid's mass [kg], centre of mass [m] (box frame) and inertia tensor [kg m^2] about
    it (box frame axes, I_ij = -sum x_i x_j dm off the diagonal, as LIGGGHTS takes it)."""

    mass: float
    com: np.ndarray
    inertia: np.ndarray

    @property
    def tilt(self) -> float:
        """The angle [deg] between the box frame and the principal frame (about y)."""
        axes = principal_frame(self.inertia)
        return math.degrees(math.acos(min(1.0, axes[0, 0])))


def mass_properties(box: Box, density: float) -> MassProperties:
    """The solid's (box + the bump's cap above the +z face) closed-form mass properties."""
    L, W, T = box.length, box.width, box.thickness
    m_box = density * L * W * T
    second = np.diag([L * L, W * W, T * T]) * m_box / 12  # sum x_i x_j dm about the box centre
    mass, moment = m_box, np.zeros(3)
    if box.has_bump:
        r = box.bump_diameter / 2
        volume, first, zz, xx = cap_integrals(r, box.bump_height)
        m_cap = density * volume
        s = box.bump_centre
        own = np.array([0.0, 0.0, density * first])  # sum p dm, p from the sphere's centre
        second = second + density * np.diag([xx, xx, zz]) + np.outer(s, own) + np.outer(own, s) \
            + m_cap * np.outer(s, s)
        mass += m_cap
        moment = moment + m_cap * s + own
    com = moment / mass
    about = second - mass * np.outer(com, com)
    inertia = np.trace(about) * np.eye(3) - about
    return MassProperties(mass, com, inertia)


def principal_frame(inertia: np.ndarray) -> np.ndarray:
    """(3, 3) rotation whose columns are the principal axes of ``inertia`` in its frame, each
    the one nearest the frame's x, y, z in turn, pointing the same way (right-handed): the
    identity for a diagonal tensor."""
    inertia = np.asarray(inertia, dtype=float)
    if np.allclose(inertia, np.diag(np.diag(inertia)), rtol=0, atol=1e-14 * np.abs(inertia).max()):
        return np.eye(3)
    _, vectors = np.linalg.eigh(inertia)
    order = [int(np.argmax(np.abs(vectors[k, :]))) for k in range(3)]
    axes = vectors[:, order]
    axes = axes * np.sign(np.diag(axes))
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return axes


def principal_axes(box: Box, density: float = 1.0) -> np.ndarray:
    """The solid's principal axes in the box frame (columns): the body frame's axes."""
    return principal_frame(mass_properties(box, density).inertia)


def engine_inertia(box: Box, density: float) -> tuple[float, list[float]]:
    """(mass, the six components xx xy xz yy yz zz of the inertia tensor in the body frame)
    that part_templates.liggghts gives particletemplate/multisphere: the principal moments,
    the products 0 (exactly: jacobi then keeps the template's frame)."""
    props = mass_properties(box, density)
    axes = principal_frame(props.inertia)
    body = axes.T @ props.inertia @ axes
    return props.mass, [body[0, 0], 0.0, 0.0, body[1, 1], 0.0, body[2, 2]]


def box_frame_orientation(quaternions, box: Box) -> np.ndarray:
    """The box frame's rotation matrices (N, 3, 3) from recorded quaternions (N, 4) w x y z
    (which rotate the principal body frame): R_box = R_q A^T, A the principal axes."""
    from .rotations import quaternion_matrices

    return quaternion_matrices(quaternions) @ principal_axes(box).T


# ------------------------------------------------------------------ the clump
def _axis(span: float, d: float, spacing: float = CLUMP_SPACING) -> np.ndarray:
    return np.linspace(-span / 2, span / 2, _rows(span, d, spacing))


def _rows(span: float, d: float, spacing: float) -> int:
    return max(2, math.ceil(span / (spacing * d) - 1e-9) + 1) if span > 0 else 1


def clump_count(box: Box) -> int:
    """How many spheres the box's clump has (box_template's shell, the bump's sphere with it),
    counted without building it."""
    d = box.sphere_diameter
    n = [_rows(e - d, d, box.spacing) for e in (box.length, box.width, box.thickness)]
    inner = math.prod(max(k - 2, 0) for k in n)
    return math.prod(n) - inner + box.has_bump


def box_template_box_frame(box: Box) -> np.ndarray:
    """The clump in the box frame, about the box's centre: (n, 4) x y z r (see box_template)."""
    d = box.sphere_diameter
    xs, ys, zs = (_axis(e - d, d, box.spacing) for e in (box.length, box.width, box.thickness))
    gx, gy, gz = np.meshgrid(xs, ys, zs, indexing="ij")
    ix, iy, iz = np.meshgrid(*(np.arange(len(a)) for a in (xs, ys, zs)), indexing="ij")
    shell = ((ix == 0) | (ix == len(xs) - 1) | (iy == 0) | (iy == len(ys) - 1)
             | (iz == 0) | (iz == len(zs) - 1))
    rows = np.column_stack([gx[shell], gy[shell], gz[shell], np.full(int(shell.sum()), d / 2)])
    if box.has_bump:
        rows = np.vstack([rows, [*box.bump_centre, box.bump_diameter / 2]])
    return rows


def box_template(box: Box) -> np.ndarray:
    """The box's clump template, (n, 4) x y z r [m], as particletemplate/multisphere reads it:
    about the solid's centre of mass, in its principal frame (the body frame, module doc).

    Spheres of one diameter d = T/2 on the surface of a lattice whose centres span
    (L-d, W-d, T-d), at most CLUMP_SPACING d apart along each edge: the clump's bounds are
    the box's, every face has at least three rows of spheres across it (T-d = d takes
    three at 0.75 d), so a part stands on a long side or an end as on a face; the edges are
    rounded to d/2. A hollow shell (no interior spheres): the engine is given the solid's
    mass and inertia. 84 spheres for 1.0 x 0.5 x 0.35 mm, 42 for 0.6 x 0.3 x 0.3 mm. The
    bump, when there is one, is the last row: its sphere of diameter bump_diameter."""
    rows = box_template_box_frame(box)
    props = mass_properties(box, 1.0)
    axes = principal_frame(props.inertia)
    out = rows.copy()
    out[:, :3] = (rows[:, :3] - props.com) @ axes
    return out


def box_reach(box: Box) -> float:
    """The clump's circumscribed radius [m] about the solid's centre of mass (the bump
    included): the farthest sphere's centre distance plus its radius."""
    rows = box_template(box)
    return float(np.max(np.linalg.norm(rows[:, :3], axis=1) + rows[:, 3]))


# ------------------------------------------------------------------ fidelity
def voxel_grid(box: Box, cells: int = 40):
    """Cell centres (box frame) of a grid over the solid: the box's L, W, T whole numbers of
    cells of about T/``cells`` each (its faces on cell faces), and more cells above up to
    the bump's top. Returns (x, y, z arrays, the cell's volume)."""
    top = box.bump_height if box.has_bump else 0.0
    axes, cell = [], 1.0
    for extent, above in ((box.length, 0.0), (box.width, 0.0), (box.thickness, top)):
        n = max(1, math.ceil(extent / (box.thickness / cells) - 1e-9))
        size = extent / n
        n += math.ceil(above / size - 1e-9)
        axes.append(-extent / 2 + (np.arange(n) + 0.5) * size)
        cell *= size
    return np.meshgrid(*axes, indexing="ij"), cell


def _moments(inside: np.ndarray, grid, cell: float) -> tuple[float, np.ndarray, np.ndarray]:
    """(volume, centroid, inertia tensor per unit density about the centroid) of cells."""
    pts = np.column_stack([g[inside] for g in grid])
    volume = len(pts) * cell
    com = pts.mean(axis=0)
    p = pts - com
    second = p.T @ p * cell
    return volume, com, np.trace(second) * np.eye(3) - second


def solid_inside(box: Box, grid) -> np.ndarray:
    """Which of the grid's points (box frame) lie in the solid (box + bump cap)."""
    x, y, z = grid
    half = (box.length / 2, box.width / 2, box.thickness / 2)
    inside = (np.abs(x) <= half[0]) & (np.abs(y) <= half[1]) & (np.abs(z) <= half[2])
    if box.has_bump:
        c, r = box.bump_centre, box.bump_diameter / 2
        inside |= ((x - c[0]) ** 2 + (y - c[1]) ** 2 + (z - c[2]) ** 2 <= r * r) & (z > half[2])
    return inside


def clump_inside(rows: np.ndarray, grid, core: tuple[float, float, float] | None = None) -> np.ndarray:
    """Which of the grid's points lie in the union of the spheres ``rows`` (and, given the
    half spans ``core`` of a shell's centres, in the cavity it encloses)."""
    x, y, z = grid
    inside = np.zeros(x.shape, dtype=bool)
    if core is not None:
        inside |= (np.abs(x) <= core[0]) & (np.abs(y) <= core[1]) & (np.abs(z) <= core[2])
    for cx, cy, cz, r in rows:
        inside |= (x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2 <= r * r
    return inside


def clump_fidelity(box: Box, cells: int = 40) -> dict:
    """How the clump differs from the solid's closed forms, and what supports it. The clump's
    body is its spheres' union with the cavity the shell encloses (the block of the
    centres, which no contact reaches) filled, integrated on a voxel grid of ``cells``
    cells across the thickness.

    Returns: ``spheres`` (count), ``sphere_diameter`` d [m], ``volume_error`` (relative,
    clump - solid), ``com_error`` (the centres of mass apart, over L), ``inertia_errors``
    (relative, of the three principal moments, in the order of the principal axes),
    ``edge_radius`` d/2 [m] (the edges' and corners' rounding), ``pivot_half_width`` [m]:
    for a part standing on a face, half the span of the sphere centres across it (the
    part tips about the outermost spheres' contact line, not the face's edge) keyed
    ``face_axis`` (the face's normal, x y z) and ``across`` (the direction it tips in):
    (L-d)/2 along x, (W-d)/2 along y, (T-d)/2 along z, against the solid's L/2, W/2, T/2
    (``face_half_width``)."""
    rows = box_template_box_frame(box)
    d = box.sphere_diameter
    core = tuple((e - d) / 2 for e in (box.length, box.width, box.thickness))
    grid, cell = voxel_grid(box, cells)
    volume, com, inertia = _moments(clump_inside(rows, grid, core), grid, cell)
    solid = mass_properties(box, 1.0)
    axes = principal_frame(solid.inertia)
    exact = np.diag(axes.T @ solid.inertia @ axes)
    clump = np.diag(axes.T @ inertia @ axes)
    spans = {"x": box.length - d, "y": box.width - d, "z": box.thickness - d}
    pivot = {f"{face}/{across}": spans[across] / 2 for face in "xyz" for across in "xyz" if across != face}
    full = {"x": box.length, "y": box.width, "z": box.thickness}
    return {
        "spheres": len(rows),
        "sphere_diameter": d,
        "volume_error": volume / solid.mass - 1,
        "com_error": float(np.linalg.norm(com - solid.com)) / box.length,
        "inertia_errors": clump / exact - 1,
        "edge_radius": d / 2,
        "pivot_half_width": pivot,
        "face_half_width": {k: full[k.split("/")[1]] / 2 for k in pivot},
    }
