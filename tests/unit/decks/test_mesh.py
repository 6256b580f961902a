"""Indexed meshes and their binary STL (vibrofeed.mesh): vertices are shared to 1e-12 m (0.0 and
-0.0 being one), a polygon is the fan from its first corner, and the STL holds the 80-byte header
line, the count and per face the unit normal of its corner order (zero when degenerate), the
corners and a zero attribute -- read back here byte by byte, with no STL library."""

import numpy as np
import pytest

from vibrofeed.mesh import STL_HEADER, MeshBuilder, stl_header, write_stl

# the binary STL's face record (the format's own layout, little-endian)
RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])


def read_stl(path):
    data = path.read_bytes()
    count = int.from_bytes(data[STL_HEADER:STL_HEADER + 4], "little")
    assert len(data) == STL_HEADER + 4 + RECORD.itemsize * count  # 50 bytes a face
    return data[:STL_HEADER], np.frombuffer(data[STL_HEADER + 4:], dtype=RECORD)


def test_a_vertex_is_shared_to_a_picometre_and_signed_zeros_are_one():
    b = MeshBuilder()
    # -0.0 (and what rounds to it) is stored as +0.0: the files hold no negative zeros
    assert b.vertex((-0.0, -1e-13, 0.0)) == b.vertex((0.0, 0.0, -0.0)) == 0
    # 2e-13 m apart (well inside the 1e-12 m rounding step, away from its edges): one vertex
    assert b.vertex((0.1, 0.2, 0.3)) == b.vertex((0.1 + 2e-13, 0.2 - 2e-13, 0.3)) == 1
    assert b.vertex((0.1 + 3e-12, 0.2, 0.3)) == 2  # 3 pm apart: another
    v, t = b.mesh()
    assert v.shape == (3, 3) and t.shape == (0, 3)
    assert v[0].tolist() == [0, 0, 0] and not np.signbit(v[0]).any()


def test_a_polygon_is_the_fan_from_its_first_corner():
    pentagon = [(0, 0, 0), (2, 0, 0), (3, 1, 0), (1, 2, 0), (-1, 1, 0)]
    b = MeshBuilder()
    b.polygon(pentagon)
    v, t = b.mesh()
    assert v.tolist() == [list(map(float, p)) for p in pentagon]  # in corner order
    assert t.tolist() == [[0, 1, 2], [0, 2, 3], [0, 3, 4]]
    assert t.dtype == np.int32


def test_a_polygon_of_two_corners_adds_nothing():
    # an edge has no face: neither triangles nor stray vertices in the mesh
    b = MeshBuilder()
    b.polygon([(0, 0, 0), (1, 0, 0)])
    v, t = b.mesh()
    assert v.shape == (0, 3) and t.shape == (0, 3)


def test_a_quad_is_two_triangles_and_a_face_of_zero_height_none():
    b = MeshBuilder()
    b.quad((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0))
    b.triangle((0, 0, 0), (1, 0, 0), (0, 0, 0))  # two corners one vertex: no face
    assert b.mesh()[1].tolist() == [[0, 1, 2], [0, 2, 3]]


def test_stl_header_is_one_line_naming_the_mesh():
    head = stl_header("bowl-2_v1.5")  # letters, digits and _-. are kept
    assert head == b"vibrofeed binary STL bowl-2_v1.5\n".ljust(80, b" ")
    assert stl_header("a 'b\"/c") == b"vibrofeed binary STL a__b__c\n".ljust(80, b" ")


@pytest.mark.parametrize("n", [57, 58, 59, 200])  # 21 + n characters: the line fits or is cut
def test_a_long_name_is_cut_to_fill_the_header_up_to_its_newline(n):
    head = stl_header("x" * n)
    line = ("vibrofeed binary STL " + "x" * n)[:79]  # 79 characters and the newline: 80 bytes
    assert len(head) == STL_HEADER
    assert head == (line + "\n").encode("ascii").ljust(80, b" ")


def test_stl_faces_carry_unit_normals_of_their_corner_order(tmp_path):
    # faces away from the origin, edges of a millimetre (|e1 x e2| ~ 1e-6 m^2, far below 1)
    v = np.array([
        [1.0, 2.0, 3.0], [1.002, 2.0, 3.0], [1.0, 2.003, 3.0],       # e1 x e2 = (0, 0, 6e-6)
        [0.5, -1.0, 2.0], [0.5, -0.999, 2.001], [0.502, -1.0, 2.0],  # (0, 2e-6, -2e-6)
        [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0],           # collinear: no area
    ])
    t = np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8], [0, 2, 1]])  # the last: the first reversed
    path = write_stl(v, t, tmp_path / "faces.stl", name="faces")
    assert path == tmp_path / "faces.stl"
    head, faces = read_stl(path)
    assert head == stl_header("faces") and len(faces) == 4
    expected = np.array([[0, 0, 1], [0, 1 / np.sqrt(2), -1 / np.sqrt(2)], [0, 0, 0], [0, 0, -1]])
    assert np.allclose(faces["normal"], expected, rtol=0, atol=1e-7)  # float32: 6e-8 at 1
    assert np.array_equal(faces["corners"], v[t].astype(np.float32))
    assert not faces["attribute"].any()


def test_an_empty_mesh_is_a_header_and_a_zero_count(tmp_path):
    head, faces = read_stl(write_stl(np.zeros((0, 3)), np.zeros((0, 3), int), tmp_path / "e.stl"))
    assert head == stl_header("vibrofeed") and len(faces) == 0
