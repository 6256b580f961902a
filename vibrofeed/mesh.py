"""Indexed triangle meshes: built over shared vertices, written as binary STL.

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
        key = tuple(round(float(c), 12) + 0.0 for c in p)  # + 0.0: a -0.0 is kept (and written) as 0.0
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


# A binary STL's 80-byte header. LIGGGHTS reads an STL's first line as text (up to the first
# newline byte) before it decides the file is binary, and refuses a quote in it: without a
# newline in the header that line runs on into the triangle count and the coordinates, and a
# count of 39 (+ 256 k) triangles, whose first byte is a quote, stopped a run. A header line of
# its own ends that line inside the header, and no "solid" at its start keeps it binary.
STL_HEADER = 80


def stl_header(name: str) -> bytes:
    """The 80 bytes that open a binary STL: one line naming the mesh, padded with spaces."""
    words = "".join(c if c.isalnum() or c in "_-." else "_" for c in name)
    line = f"vibrofeed binary STL {words}"[:STL_HEADER - 1] + "\n"
    return line.encode("ascii").ljust(STL_HEADER, b" ")


def write_stl(vertices: np.ndarray, triangles: np.ndarray, path: str | Path,
              name: str = "vibrofeed") -> Path:
    """Write an indexed mesh as a binary STL (little-endian float32), unit normals from the
    corner order (zero for a degenerate face), the header :func:`stl_header`."""
    corners = np.asarray(vertices, dtype=np.float64)[np.asarray(triangles)]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    normal = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
    record = np.zeros(len(corners), dtype=[("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)),
                                           ("attribute", "<u2")])
    record["normal"], record["corners"] = normal, corners
    path = Path(path)
    with open(path, "wb") as f:
        f.write(stl_header(name))
        f.write(np.uint32(len(record)).astype("<u4").tobytes())
        f.write(record.tobytes())
    return path


def write_template(rows: np.ndarray, path: str | Path, name: str) -> Path:
    """A clump template as LIGGGHTS' particletemplate/multisphere reads it (x y z r per
    line; used with ``scale 1``)."""
    path = Path(path)
    np.savetxt(path, rows, fmt="%.17g", header=f"{name}: x y z r [m], {len(rows)} spheres")
    return path
