"""Parts as bodies: LIGGGHTS spheres gathered into one row per part.

A plain sphere is its own part. A multisphere part (a chip or a disc made of
``n`` overlapping spheres that LIGGGHTS moves as one rigid clump) arrives as
``n`` atoms that share a molecule id (fix multisphere sets ``atom->molecule``
to the body's id); :func:`aggregate` turns them into one row: centre, mean
velocity, the body's angular velocity and mass, the enclosing
radius and the orientation, a unit quaternion fitted to the spheres' positions
(:func:`fit_quaternions`, Horn's closed form of the Kabsch least-squares fit).

Everything is vectorised over bodies: a bulk run hands over thousands of
parts per frame, and a Python loop per body per frame would cost more than
the engine's step.
"""

from __future__ import annotations

import numpy as np

from ..rotations import quaternion_matrices

IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


def quaternion_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4) ordered (w, x, y, z)."""
    return quaternion_matrices(q)


def fit_quaternions(template: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Orientation (B, 4) of B bodies: the rotation R that best carries the
    template's spheres onto the bodies' spheres, p_i - mean(p) = R (t_i - mean(t)).

    ``template`` (n, 3) and ``positions`` (B, n, 3) list the spheres in the same
    order. Horn's quaternion method: q is the eigenvector of the largest
    eigenvalue of a symmetric 4 x 4 matrix built from the cross-covariance; it
    is always a proper rotation (no reflection fix as with the SVD form) and
    exact to round-off for a rigid body. Returned with w >= 0. The template
    must not be collinear (a rotation about its line would be undetermined).
    """
    t = np.asarray(template, dtype=float)
    t = t - t.mean(axis=0)
    p = np.asarray(positions, dtype=float)
    p = p - p.mean(axis=1, keepdims=True)
    s = np.einsum("na,bnc->bac", t, p)  # S[a, c] = sum_i t_ia p_ic
    sxx, sxy, sxz = s[:, 0, 0], s[:, 0, 1], s[:, 0, 2]
    syx, syy, syz = s[:, 1, 0], s[:, 1, 1], s[:, 1, 2]
    szx, szy, szz = s[:, 2, 0], s[:, 2, 1], s[:, 2, 2]
    n = np.stack([
        np.stack([sxx + syy + szz, syz - szy, szx - sxz, sxy - syx], -1),
        np.stack([syz - szy, sxx - syy - szz, sxy + syx, szx + sxz], -1),
        np.stack([szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy], -1),
        np.stack([sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz], -1),
    ], -2)
    _, vectors = np.linalg.eigh(n)  # eigenvalues ascending: the last is the largest
    q = vectors[:, :, -1]
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def atom_parts(atoms: dict) -> dict:
    """Per-atom arrays (LIGGGHTS names) as the writer's part elements, one row an atom."""
    return {
        "id": atoms["id"], "species": atoms["type"], "radius": atoms["radius"],
        "mass": atoms["rmass"], "position": atoms["x"], "velocity": atoms["v"],
        "angular_velocity": atoms["omega"], "force": atoms["f"],
    }


def spheres(atoms: dict) -> dict:
    """Plain spheres as parts (each its own body, orientation the identity)."""
    return {**atom_parts(atoms), "orientation": np.broadcast_to(IDENTITY, (len(atoms["id"]), 4))}


def aggregate(atoms: dict, template: np.ndarray | None, n_spheres: int) -> tuple[dict, int]:
    """Multisphere atoms as one row per body; returns (parts, incomplete bodies).

    ``atoms`` holds per-atom ``id``, ``molecule`` (body id), ``type``,
    ``radius``, ``rmass``, ``x``, ``v``, ``omega`` of every atom (all
    ranks gathered). The template (n, 3+) lists the spheres in atom-id order
    (LIGGGHTS numbers a body's atoms in template order). Atoms of body -1
    (what is left of a body being deleted) are dropped. A body with fewer
    than ``n_spheres`` atoms (not seen: LIGGGHTS removes a body whole) keeps
    its sums and means but gets the identity orientation; their number is
    returned so that the caller can say so.
    """
    mol = np.asarray(atoms["molecule"], dtype=np.int64)
    # A body that lost a sphere (through the box floor, below the outlet) is removed by
    # fix multisphere: its other spheres get body -1 and are deleted at the next
    # re-neighbouring. Such fragments are no part (a frame between the two would count
    # them as one); a body lost anywhere else shows in the mass balance.
    whole = mol >= 0
    if not whole.all():
        atoms = {k: np.asarray(v)[whole] for k, v in atoms.items()}
        mol = mol[whole]
    aid = np.asarray(atoms["id"], dtype=np.int64)
    if len(mol) == 0:
        empty = {k: np.zeros((0, 3)) for k in ("position", "velocity", "angular_velocity", "force")}
        return {"id": np.zeros(0, np.int64), "species": np.zeros(0, np.int32),
                "radius": np.zeros(0), "mass": np.zeros(0), "orientation": np.zeros((0, 4)),
                **empty}, 0
    # by body, then atom id (= template order): one argsort of a combined key
    order = np.argsort(mol * (int(aid.max()) + 1) + aid)
    mol = mol[order]
    starts = np.r_[0, np.nonzero(np.diff(mol))[0] + 1]
    counts = np.diff(np.r_[starts, len(mol)])
    first = order[starts]  # one atom per body, for what every sphere of a body shares
    x = atoms["x"][order]
    centre = np.add.reduceat(x, starts, axis=0) / counts[:, None]
    reach = np.linalg.norm(x - np.repeat(centre, counts, axis=0), axis=1) + atoms["radius"][order]
    parts = {
        "id": mol[starts],
        "species": atoms["type"][first],
        "radius": np.maximum.reduceat(reach, starts),  # sphere about the centre enclosing the clump
        # fix multisphere gives every sphere of a clump the whole body's mass
        # (measured: each of a 300 x 300 x 150 um die's 9 spheres has rmass =
        # 3.1455e-8 kg, the die's mass), so the part's mass is one sphere's
        "mass": atoms["rmass"][first],
        "position": centre,
        # the mean of v_i = v_c + omega x (x_i - c) over the spheres is v_c: c is their mean
        "velocity": np.add.reduceat(atoms["v"][order], starts, axis=0) / counts[:, None],
        "angular_velocity": atoms["omega"][first],  # the same on every sphere of a body
        # not recorded: the spheres' f of a clump hold neither gravity nor the
        # whole contact force (measured: 1/9 of m g for a die resting on the
        # track, 0 in free fall), and the body's force is not reachable
        "force": np.full((len(starts), 3), np.nan),
    }
    orientation = np.tile(IDENTITY, (len(starts), 1))
    full = counts == n_spheres
    if template is not None and n_spheres > 1 and full.any():
        index = starts[full][:, None] + np.arange(n_spheres)
        orientation[full] = fit_quaternions(np.asarray(template)[:, :3], x[index])
    parts["orientation"] = orientation
    return parts, int((~full).sum())
