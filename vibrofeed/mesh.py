"""Indexed triangle meshes: built over shared vertices, written as binary STL (numpy-stl).

The track of the bulk feeder (:mod:`vibrofeed.geometry`), a feeder line's further
sections (:mod:`vibrofeed.line`) and the bowl (:mod:`vibrofeed.bowl`) are built with these.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


class MeshBuilder:
    """Collects triangles over shared vertices (a vertex is shared when its coordinates
    agree to 1e-12 m)."""

    def __init__(self):
        self.vertices: list[tuple[float, float, float]] = []
        self.index: dict[tuple[float, float, float], int] = {}
        self.triangles: list[tuple[int, int, int]] = []

    def vertex(self, p) -> int:
        key = tuple(round(float(c), 12) + 0.0 for c in p)  # + 0.0: -0.0 and 0.0 are one vertex
        if key not in self.index:
            self.index[key] = len(self.vertices)
            self.vertices.append(key)
        return self.index[key]

    def triangle(self, a, b, c) -> None:
        """A triangle; none where two corners are one vertex (a face of zero height)."""
        t = tuple(self.vertex(p) for p in (a, b, c))
        if len(set(t)) == 3:
            self.triangles.append(t)

    def polygon(self, corners) -> None:
        """A convex planar polygon as a fan of triangles from its first corner (corners in
        order around it; collinear corners keep whole edges shared with neighbours)."""
        for k in range(1, len(corners) - 1):
            self.triangle(corners[0], corners[k], corners[k + 1])

    def quad(self, a, b, c, d) -> None:
        """Two triangles a-b-c, a-c-d (corners in order around the quad)."""
        self.triangle(a, b, c)
        self.triangle(a, c, d)

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        return (np.array(self.vertices, dtype=np.float64).reshape(-1, 3),
                np.array(self.triangles, dtype=np.int32).reshape(-1, 3))


def write_stl(vertices: np.ndarray, triangles: np.ndarray, path: str | Path,
              name: str = "vibrofeed") -> Path:
    """Write an indexed mesh as a binary STL (numpy-stl), normals from the corner order."""
    from stl import mesh as stl_mesh

    m = stl_mesh.Mesh(np.zeros(len(triangles), dtype=stl_mesh.Mesh.dtype), name=name)
    m.vectors[:] = vertices[triangles]
    m.update_normals()
    path = Path(path)
    m.save(str(path))
    return path
