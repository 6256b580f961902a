"""Clusters of touching parts: connected components of the contact graph.

Two parts touch when their centres are at most ``r_i + r_j + tolerance``
apart (``tolerance`` > 0 also joins parts separated by a thin gap, < 0 asks
for an overlap). The pairs are found with a k-d tree (scipy's ``cKDTree``),
so a frame of N parts costs O(N log N), never the O(N^2) of all pairs; the
components come from ``scipy.sparse.csgraph``.

Multisphere parts (chips, discs) are not spheres: their circumscribed sphere
would join chips lying side by side a gap apart. :func:`clump_labels` builds
each body's spheres from the body template and its orientation and joins
bodies whose spheres touch.

>>> labels = cluster_labels(positions, radii, tolerance=1e-6)
>>> sizes = cluster_sizes(labels)            # {size: number of clusters}
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..rotations import quaternion_matrices  # noqa: F401 (re-exported)


def _touching_pairs(positions: np.ndarray, radii: np.ndarray, tolerance: float) -> np.ndarray:
    """(P, 2) index pairs i < j with |x_i - x_j| <= r_i + r_j + tolerance."""
    n = len(positions)
    reach = 2.0 * float(radii.max()) + tolerance if n else 0.0
    if n < 2 or reach < 0:
        return np.empty((0, 2), dtype=np.int64)
    # The tree's cut-off is the largest possible contact distance, widened by a
    # hair so that exactly touching pairs survive its own rounding; the exact
    # test per pair follows.
    from scipy.spatial import cKDTree  # here, not at import: the single-part summary never needs it (0.2 s)

    pairs = cKDTree(positions).query_pairs(reach * (1 + 1e-9) + 1e-300, output_type="ndarray")
    if len(pairs) == 0:
        return pairs.reshape(0, 2).astype(np.int64)
    i, j = pairs[:, 0], pairs[:, 1]
    d = np.sqrt(((positions[i] - positions[j]) ** 2).sum(axis=1))
    return pairs[d <= radii[i] + radii[j] + tolerance]


def _components(n: int, pairs: np.ndarray) -> np.ndarray:
    """Labels of the connected components of n nodes, numbered in the order of
    their lowest member (node 0 is in cluster 0, the next new one is 1, ...)."""
    if n == 0:
        return np.empty(0, dtype=np.int64)
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, raw = connected_components(graph, directed=False)
    # Canonical numbering: independent of scipy's internal order.
    first = np.full(raw.max() + 1, n, dtype=np.int64)
    np.minimum.at(first, raw, np.arange(n))
    rank = np.empty_like(first)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return rank[raw]


def _check(positions, radii) -> tuple[np.ndarray, np.ndarray]:
    positions = np.asarray(positions, dtype=float)
    radii = np.asarray(radii, dtype=float)
    if positions.ndim != 2 or positions.shape[1] != 3:
        raise InputError(f"positions must be (N, 3), got shape {positions.shape}")
    if radii.shape != (len(positions),):
        raise InputError(f"radii must be ({len(positions)},), got shape {radii.shape}")
    if not (np.isfinite(positions).all() and np.isfinite(radii).all()):
        raise InputError("positions and radii must be finite (select the parts present first)")
    return positions, radii


def cluster_labels(positions, radii, tolerance: float = 0.0) -> np.ndarray:
    """(N,) cluster label of each part: parts joined by a chain of touching
    pairs share a label. Labels run 0, 1, ... in the order of each cluster's
    first part, so equal configurations give equal labels.

    positions: (N, 3) centres [m]; radii: (N,) [m]; tolerance [m]: touching
    means centre distance <= r_i + r_j + tolerance.
    """
    positions, radii = _check(positions, radii)
    return _components(len(positions), _touching_pairs(positions, radii, float(tolerance)))


def clump_labels(centres, orientations, template, tolerance: float = 0.0) -> np.ndarray:
    """(N,) cluster label of each multisphere body, from its spheres.

    centres: (N, 3) body centres [m] (the mean of their spheres);
    orientations: (N, 4) quaternions (w, x, y, z) rotating the template into
    the simulation frame; template: (n, 4) x, y, z, r of the spheres in the
    body frame [m]. Bodies touch when any of their spheres touch.
    """
    centres, _ = _check(centres, np.zeros(len(np.asarray(centres))))
    template = np.asarray(template, dtype=float)
    n_bodies, n_spheres = len(centres), len(template)
    if n_bodies == 0:
        return np.empty(0, dtype=np.int64)
    spheres = _clump_spheres(centres, orientations, template)
    radii = np.broadcast_to(template[:, 3], (n_bodies, n_spheres)).ravel()
    pairs = _touching_pairs(spheres.reshape(-1, 3), radii, float(tolerance)) // n_spheres
    return _components(n_bodies, pairs[pairs[:, 0] != pairs[:, 1]])


def along_extents(orientations, template, direction) -> tuple[np.ndarray, np.ndarray]:
    """(front, back): how far each body of a template (n, 4) turned by its quaternion reaches
    from its centre along the unit ``direction`` and against it [m], exactly: its spheres'
    largest projection plus radius. A square chip of edge a lying square to the direction
    reaches a/2 either way; turned 45 degrees, (a/2 - r) sqrt(2) + r."""
    d = np.asarray(direction, dtype=float)
    n = len(orientations)
    proj = _clump_spheres(np.zeros((n, 3)), orientations, template) @ d  # (N, spheres)
    r = np.asarray(template, dtype=float)[:, 3]
    return (proj + r).max(axis=1), (r - proj).max(axis=1)


def _clump_spheres(centres, orientations, template) -> np.ndarray:
    """(N, n, 3) sphere centres of N bodies of a template (n, 4)."""
    offsets = template[:, :3] - template[:, :3].mean(axis=0)  # the centre is the spheres' mean
    return centres[:, None, :] + np.einsum("nij,kj->nki", quaternion_matrices(orientations), offsets)


def pairs_touch(a, b, radii_a=None, radii_b=None, orientations_a=None, orientations_b=None,
                template=None, tolerance: float = 0.0) -> np.ndarray:
    """(K,) whether part a[k] touches part b[k], for K pairs at once.

    Spheres: centres a, b (K, 3) and radii (K,). Clumps: centres, orientations
    (K, 4) and the template; they touch when any of their spheres touch.
    """
    a, b = np.asarray(a, dtype=float).reshape(-1, 3), np.asarray(b, dtype=float).reshape(-1, 3)
    if template is None:
        d = np.linalg.norm(a - b, axis=1)
        return d <= np.asarray(radii_a) + np.asarray(radii_b) + tolerance
    template = np.asarray(template, dtype=float)
    r = template[:, 3]
    offsets = template[:, :3] - template[:, :3].mean(axis=0)
    reach = 2 * float((np.linalg.norm(offsets, axis=1) + r).max()) + tolerance
    out = np.zeros(len(a), dtype=bool)
    near = np.nonzero(np.linalg.norm(a - b, axis=1) <= reach)[0]  # only these can touch
    for k in np.array_split(near, max(1, len(near) // 2048)):  # bounded memory
        if len(k) == 0:
            continue
        sa = _clump_spheres(a[k], np.asarray(orientations_a)[k], template)
        sb = _clump_spheres(b[k], np.asarray(orientations_b)[k], template)
        d = np.linalg.norm(sa[:, :, None, :] - sb[:, None, :, :], axis=-1)
        out[k] = (d <= r[:, None] + r[None, :] + tolerance).any(axis=(1, 2))
    return out


def cluster_sizes(labels) -> dict[int, int]:
    """{cluster size: number of clusters of that size}, sizes ascending."""
    labels = np.asarray(labels)
    if len(labels) == 0:
        return {}
    sizes, counts = np.unique(np.bincount(labels), return_counts=True)
    return {int(s): int(c) for s, c in zip(sizes, counts) if s > 0}
