"""Orientations as the result files store them: unit quaternions (w, x, y, z)
that carry the body frame into the simulation frame (FORMAT.md)."""

from __future__ import annotations

import numpy as np


def quaternion_matrices(q) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of quaternions (..., 4) ordered (w, x, y, z).

    Quaternions are normalised first; a NaN or zero one (an empty slot, a part
    without orientation) gives the identity.
    """
    q = np.array(q, dtype=float)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    bad = ~np.isfinite(norm) | (norm == 0)
    q = np.where(bad, np.array([1.0, 0.0, 0.0, 0.0]), q / np.where(bad, 1.0, norm))
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def matrix_quaternion(matrix) -> np.ndarray:
    """The unit quaternion (w, x, y, z), w >= 0, of a rotation matrix (3, 3): the eigenvector
    of the largest eigenvalue of Bar-Itzhack's symmetric 4 x 4 matrix (robust to a matrix a
    little off orthogonal)."""
    m = np.asarray(matrix, dtype=float)
    k = np.array([[m[0, 0] - m[1, 1] - m[2, 2], 0, 0, 0],
                  [m[0, 1] + m[1, 0], m[1, 1] - m[0, 0] - m[2, 2], 0, 0],
                  [m[0, 2] + m[2, 0], m[1, 2] + m[2, 1], m[2, 2] - m[0, 0] - m[1, 1], 0],
                  [m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1], m[0, 0] + m[1, 1] + m[2, 2]]])
    values, vectors = np.linalg.eigh(k / 3.0)  # (eigh reads the lower triangle)
    x, y, z, w = vectors[:, np.argmax(values)]
    return np.array([w, x, y, z]) * (1 if w >= 0 else -1)


def quaternion_product(q, p) -> np.ndarray:
    """The quaternions q * p (N, 4), (w, x, y, z): turning by p (4,) first, then by each q."""
    w1, x1, y1, z1 = np.moveaxis(np.asarray(q, dtype=float).reshape(-1, 4), -1, 0)
    w2, x2, y2, z2 = p
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=-1)
