"""One box part placed on a plate in a chosen pose: the prepare hook of decks/box_on_plate.

Poses. The box frame (vibrofeed.parts: x along L, y along W, z along T) is turned so that
one of its axes stands vertical (``stand``: 0 flat, T vertical; 1 on its side, W
vertical; 2 on its end, L vertical) and one of the other two lies along the track x
(``facing``: 0 the longer of the two, 1 the shorter); the third lies along y. ``tilt``
[deg] then turns it about y, about the pivot under its +x edge (positive: the -x edge
lifts), for a release tilted for free rocking.

The part rests on its spheres' bottoms: the hook computes the centre of mass's height
above the plate at which the lowest sphere just touches it (no overlap, no gap), so a
standing part starts loaded by nothing but gravity and a tilted one on its pivot row.
The rocking geometry of a pose (vibrofeed.models.rocking.clump_pivot): b = (D_along - d)/2,
h = D_vertical / 2, with d the clump's sphere diameter (vibrofeed.parts.Box.sphere_diameter).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .errors import ParameterError
from .feeders.records import number
from .geometry import Prepared, box_lines
from .mesh import MeshBuilder, write_stl
from .rotations import matrix_quaternion

STANDS = {0: "flat", 1: "side", 2: "end"}
#: the box axis (0 x/L, 1 y/W, 2 z/T) standing vertical for each ``stand``
VERTICAL_AXIS = {0: 2, 1: 1, 2: 0}


def pose_axes(stand: int, facing: int) -> tuple[int, int]:
    """(the box axis along the track x, the box axis vertical) of a pose."""
    if stand not in STANDS or facing not in (0, 1):
        raise ParameterError(f"stand={stand} must be 0 (flat), 1 (side) or 2 (end) and facing={facing} "
                             "0 (the longer other side along the track) or 1 (the shorter)")
    vertical = VERTICAL_AXIS[stand]
    others = [k for k in range(3) if k != vertical]  # box axes in order L, W, T: longer first
    return others[facing], vertical


def pose_matrix(stand: int, facing: int, tilt: float = 0.0) -> np.ndarray:
    """The rotation (3, 3) carrying the box frame into the plate's frame: columns are the
    box axes' images; the pose, then ``tilt`` [deg] about y."""
    along, vertical = pose_axes(stand, facing)
    P = np.zeros((3, 3))
    P[:, along] = (1.0, 0.0, 0.0)
    P[:, vertical] = (0.0, 0.0, 1.0)
    k = 3 - along - vertical
    P[:, k] = np.cross(P[:, (k + 1) % 3], P[:, (k + 2) % 3])
    c, s = math.cos(math.radians(tilt)), math.sin(math.radians(tilt))
    Ry = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return Ry @ P


def pose_dims(values: Mapping[str, str]) -> tuple[float, float, float]:
    """(D_along, D_vertical, d) [m] of the deck's pose: the box's dimension along the track,
    its vertical one and the clump's sphere diameter."""
    from .parts import Box

    dims = [number(values, n) for n in ("part_size", "part_width", "part_thickness")]
    along, vertical = pose_axes(int(number(values, "stand")), int(number(values, "facing")))
    return dims[along], dims[vertical], Box(*dims).sphere_diameter


def tilt_angle(quaternions, stand: int, facing: int) -> tuple[np.ndarray, np.ndarray]:
    """(signed tilt about y [rad], the tilt of the pose's vertical axis from the plate's
    normal [rad]) of recorded orientations (N, 4), relative to the pose standing upright.
    The box's principal frame is its box frame (no bump)."""
    from .rotations import quaternion_matrices

    rel = quaternion_matrices(quaternions) @ pose_matrix(stand, facing).T
    signed = np.arctan2(rel[:, 0, 2], rel[:, 0, 0])
    total = np.arccos(np.clip(rel[:, 2, 2], -1.0, 1.0))
    return signed, total


def plate_mesh(length: float, width: float) -> tuple[np.ndarray, np.ndarray]:
    """A flat plate at z = 0, normal +z, centred on the origin, in squares of its width."""
    n = max(1, math.ceil(length / width - 1e-9))
    b = MeshBuilder()
    xs = np.linspace(-length / 2, length / 2, n + 1)
    h = width / 2
    for x0, x1 in zip(xs[:-1], xs[1:]):
        b.quad((x0, -h, 0.0), (x1, -h, 0.0), (x1, h, 0.0), (x0, h, 0.0))
    return b.mesh()


def prepare_box_on_plate(values: Mapping[str, str], folder: str | Path) -> Prepared:
    """Write one box part's clump and its plate for a run of decks/box_on_plate.

    Files in ``folder``: ``box.multisphere`` (vibrofeed.geometry.box_lines), ``plate.stl``
    (``plate_length`` long, 8 part lengths wide) and ``prepared.in``: the box's sphere
    count, mass and inertia (box_lines), the insertion quaternion ``q_w q_x q_y q_z`` of the
    pose, ``com_z`` (the centre of mass's height above the plate with the lowest sphere
    touching it), ``reach`` (the clump's circumscribed radius), ``plate_width`` and the
    three seeds."""
    from .geometry import insertion_seeds

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    box_values = {**values, "shape": "3", "bump_height": "0"}
    lines, rows = box_lines(box_values, folder)
    stand, facing = int(number(values, "stand")), int(number(values, "facing"))
    tilt = number(values, "tilt")
    R = pose_matrix(stand, facing, tilt)
    placed = rows[:, :3] @ R.T
    com_z = float(-(placed[:, 2] - rows[:, 3]).min())
    q = matrix_quaternion(R)
    reach = float(np.max(np.linalg.norm(rows[:, :3], axis=1) + rows[:, 3]))
    length = number(values, "part_size")
    plate_width = 8 * length
    plate_length = number(values, "plate_length")
    if not plate_length > 2 * reach:
        raise ParameterError(f"plate_length={plate_length:g} m must exceed the part ({2 * reach:g} m)")
    write_stl(*plate_mesh(plate_length, plate_width), folder / "plate.stl", "plate")
    seed = int(number(values, "seed")) if "seed" in values else 5489
    lines = ["# written by vibrofeed.poses.prepare_box_on_plate for one run\n", *lines]
    lines += [f"variable q_{c} equal {v!r}\n" for c, v in zip("wxyz", q.tolist())]
    lines += [f"variable com_z equal {com_z!r}\n", f"variable reach equal {reach!r}\n",
              f"variable plate_width equal {plate_width!r}\n",
              *[f"variable seed_{k} equal {p}\n" for k, p in enumerate(insertion_seeds(seed, 3), 1)]]
    (folder / "prepared.in").write_text("".join(lines))
    return Prepared(variables={"mesh_dir": str(folder.resolve())}, track=None, body_template=rows)
