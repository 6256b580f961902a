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
