"""Pictures of a feeder line: each section of the track drawn where its own recorded motion
puts it (scene.track_mesh, which `vibrofeed render` and `vibrofeed export` draw), not the whole
track moved by section 1's.

A synthetic two-section line whose sections move differently at every frame: a vertex of
section k at frame j must sit at its rest position + section k's recorded displacement.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from helpers import parts
from vibrofeed.pictures import scene
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import Recording, ResultWriter

JOINT = 0.004
N_FRAMES = 4
EXACT = 1e-18  # m: rest + displacement, the same float64 sum on both sides


def rest_track():
    """Section 1's floor (x 0..JOINT, 4 vertices) then section 2's (JOINT..JOINT+3 mm, lower)."""
    v1 = np.array([[0, -6e-4, 0], [JOINT, -6e-4, 0], [JOINT, 6e-4, 0], [0, 6e-4, 0]], float)
    v2 = np.array([[JOINT, -6e-4, -5e-5], [JOINT + 3e-3, -6e-4, -5e-5], [JOINT + 3e-3, 6e-4, -5e-5],
                   [JOINT, 6e-4, -5e-5]])
    t = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
    return np.vstack([v1, v2]), np.vstack([t, t + 4])


SPLIT = np.repeat([1, 2], 4)


def motion(k):
    """((position, velocity) of section 1, of section 2) at frame k: changing with k, and at
    least 50 um apart along x and z at every frame."""
    s1 = (np.array([1e-5 * np.sin(k), 0.0, 1e-5 * np.cos(k)]), np.array([0.03 * k, 0.0, -0.02]))
    s2 = (np.array([-8e-5 + 1e-5 * np.cos(2 * k), 0.0, 7e-5 + 1e-5 * np.sin(3 * k)]),
          np.array([-0.05, 0.0, 0.01 * k]))
    return s1, s2


def line_file(path, split=True, sections=2):
    variables = {"freq": ("100", "Hz", "f", "100"), "sections": ("2", "-", "s", "1"),
                 "track_length": (repr(JOINT), "m", "l", "0.02"),
                 "part_size": ("3e-4", "m", "d", "3e-4")}
    w = ResultWriter(path, deck_name="synthetic_line", deck_path="synthetic_line.liggghts",
                     deck_text="# synthetic line\n", variables=variables, derived={"dt_used": 1e-6},
                     engine_version="LIGGGHTS (synthetic)", seed=1,
                     run_id=hashlib.sha256(str(path).encode()).hexdigest(),
                     recording=Recording(sections=sections, rejects=True),
                     outlet={"outlet_x": JOINT + 3e-3, "catch_z": -5e-4, "method": "synthetic"},
                     track=rest_track(), track_sections=SPLIT if split else None)
    for k in range(N_FRAMES):
        (p1, v1), (p2, v2) = motion(k)
        # part 1 on section 1 moving with it, part 2 on section 2 moving 1 cm/s faster than it
        p = parts([1, 2], [[2e-3, 0, 1.5e-4], [5e-3, 0, 1e-4]], radius=1.5e-4,
                  velocity=[v1, v2 + [0.01, 0, 0]])
        w.write_frame(10 * k, 1e-3 * k, p, p1, v1,
                      counts={"inserted": 2, "on_track": 2, "exited": 0, "rejected": 0, "lost": 0},
                      section_surfaces=[(p2, v2)] if sections == 2 else ())
    w.finish("complete")
    return path


def read_vtp(path):
    """(points, {point array name: values}) of a VTK XML PolyData file, read by VTK."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

    reader = vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    data = reader.GetOutput()
    pd = data.GetPointData()
    return (vtk_to_numpy(data.GetPoints().GetData()),
            {pd.GetArrayName(i): vtk_to_numpy(pd.GetArray(i)) for i in range(pd.GetNumberOfArrays())})


@pytest.fixture
def line(tmp_path):
    return line_file(tmp_path / "line.h5")


def test_each_section_of_the_track_sits_at_its_own_recorded_position(line):
    rest, triangles = rest_track()
    with Result(line) as r:
        for k in range(N_FRAMES):
            frame = scene.read_frame(r, k)
            (p1, v1), (p2, v2) = motion(k)
            vertices, tris = scene.track_mesh(r, frame)
            np.testing.assert_array_equal(tris, triangles)
            np.testing.assert_allclose(vertices[SPLIT == 1], rest[SPLIT == 1] + p1, rtol=0, atol=EXACT)
            np.testing.assert_allclose(vertices[SPLIT == 2], rest[SPLIT == 2] + p2, rtol=0, atol=EXACT)
            velocity = scene.track_velocity(r, frame)
            np.testing.assert_allclose(velocity[SPLIT == 1], np.tile(v1, (4, 1)), rtol=0, atol=1e-18)
            np.testing.assert_allclose(velocity[SPLIT == 2], np.tile(v2, (4, 1)), rtol=0, atol=1e-18)
            # the sections part: section 2 is not moved by section 1's displacement
            assert (np.abs((vertices - rest)[SPLIT == 2] - p1)[:, [0, 2]] > 4.9e-5).all()


def test_a_line_without_its_split_moves_with_section_1(tmp_path):
    """A line of format 1.3 did not say which vertex is whose: the track moves as the file says
    (observables/surface), section 2 unrecorded."""
    path = line_file(tmp_path / "old.h5", split=False, sections=1)
    rest, _ = rest_track()
    with Result(path) as r:
        frame = scene.read_frame(r, 2)
        (p1, _), _ = motion(2)
        np.testing.assert_allclose(scene.track_mesh(r, frame)[0], rest + p1, rtol=0, atol=EXACT)
        np.testing.assert_array_equal(frame.sections_position[1], np.zeros(3))  # unrecorded: at rest


def test_render_draws_the_sections_where_they_are(line):
    pytest.importorskip("pyvista")
    from vibrofeed.pictures.render import _Painter

    rest, _ = rest_track()
    with Result(line) as r:
        painter = _Painter(r, "speed", (64, 48), np.array([3]))
        try:
            vertices, _ = painter._floor(scene.read_frame(r, 3))  # what draw() hands to VTK
        finally:
            painter.close()
    (p1, _), (p2, _) = motion(3)
    np.testing.assert_allclose(vertices[SPLIT == 2], rest[SPLIT == 2] + p2, rtol=0, atol=EXACT)
    np.testing.assert_allclose(vertices[SPLIT == 1], rest[SPLIT == 1] + p1, rtol=0, atol=EXACT)


def test_export_moves_each_section_and_takes_velocities_relative_to_it(line, tmp_path):
    pytest.importorskip("pyvista")
    from vibrofeed.pictures.export import export

    done = export(Result(line), tmp_path / "out")
    assert done.frames == N_FRAMES
    rest, _ = rest_track()
    for k in range(N_FRAMES):
        (p1, v1), (p2, v2) = motion(k)
        points, fields = read_vtp(tmp_path / "out" / "line" / f"track_{k:06d}.vtp")
        np.testing.assert_array_equal(fields["section"], SPLIT)
        np.testing.assert_allclose(points[SPLIT == 2], rest[SPLIT == 2] + p2, rtol=0, atol=EXACT)
        np.testing.assert_allclose(points[SPLIT == 1], rest[SPLIT == 1] + p1, rtol=0, atol=EXACT)
        np.testing.assert_allclose(fields["velocity"][SPLIT == 2], np.tile(v2, (4, 1)), rtol=0, atol=1e-18)
        np.testing.assert_allclose(fields["speed"][SPLIT == 2], np.linalg.norm(v2), rtol=1e-15, atol=0)
        _, parts_fields = read_vtp(tmp_path / "out" / "line" / f"parts_{k:06d}.vtp")
        rel = dict(zip(parts_fields["id"].tolist(), parts_fields["velocity_rel"]))
        # part 1 rides section 1, part 2 moves 1 cm/s along x over section 2
        np.testing.assert_allclose(rel[1], [0, 0, 0], rtol=0, atol=1e-15)
        np.testing.assert_allclose(rel[2], [0.01, 0, 0], rtol=0, atol=1e-15)
