"""`vibrofeed export`: a ParaView time series that reads back as the result file says.

The .pvd is parsed as XML (what ParaView's PVD reader reads: a Collection of
DataSets with timestep, part and file), every VTK file is read back with VTK's
own XML reader, and positions, fields, orientation and the moving track are
compared with the result file.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from helpers import parts, vibrofeed, write_bulk_result, write_result
from vibrofeed.pictures import scene
from vibrofeed.results.reader import Result

pytest.importorskip("pyvista")

TRACK = (np.array([[0, -1e-3, 0], [0.02, -1e-3, 0], [0.02, 1e-3, 0], [0, 1e-3, 0]], float),
         np.array([[0, 1, 2], [0, 2, 3]], np.int32))


def chip_run(path, n_frames=4):
    """Chips that come and go (slots reused), tilted by random quaternions, on a moving track;
    one outlet event."""
    rng = np.random.default_rng(3)
    frames, surface = [], []
    for k in range(n_frames):
        ids = np.array([1, 2, 3]) if k < 2 else np.array([3, 4])  # 1, 2 leave; 4 arrives
        n = len(ids)
        p = parts(ids, rng.uniform(0, 0.02, (n, 3)), radius=2.2e-4,
                  velocity=rng.normal(0, 0.01, (n, 3)))
        q = rng.normal(size=(n, 4))
        p["orientation"] = q / np.linalg.norm(q, axis=1, keepdims=True)
        frames.append((10 * k, 0.005 * k, p))
        surface.append((np.array([1e-4 * np.sin(k), 0, 5e-5 * np.cos(k)]),
                        np.array([0.01 * k, 0, -0.02 * k])))
    events = {"time": np.array([0.012]), "id": np.array([1]), "position": np.array([[0.0201, 0, -3e-4]]),
              "velocity": np.array([[0.04, 0, -0.1]]), "orientation": np.array([[1.0, 0, 0, 0]])}
    variables = {"freq": ("100", "Hz", "vibration frequency", "100"), "shape": ("1", "", "shape", "0"),
                 "part_size": ("3e-4", "m", "part size", "3e-4"),
                 "part_thickness": ("1e-4", "m", "thickness", "1e-4")}
    return write_bulk_result(path, frames, events=events, track=TRACK, variables=variables,
                             surface=surface)



def same(a, b):
    """Equal up to float64 rounding: the VTK files keep doubles. 1e-15 in the unit of what is
    compared (m, m/s, s; unit vectors and quaternions), whose scale is 1e-4..1: numpy's default
    atol=1e-8 is a tenth of a micro-part's gap, and its rtol=1e-5 is 0.2 um at 2 cm."""
    return np.allclose(a, b, rtol=0, atol=1e-15)
def read_vtp(path):
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

    reader = vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    data = reader.GetOutput()
    points = vtk_to_numpy(data.GetPoints().GetData()) if data.GetPoints() else np.empty((0, 3))
    pd = data.GetPointData()
    fields = {pd.GetArrayName(i): vtk_to_numpy(pd.GetArray(i)) for i in range(pd.GetNumberOfArrays())}
    stamp = data.GetFieldData().GetArray("TimeValue")
    time = None if stamp is None else vtk_to_numpy(stamp)[0]
    return points, fields, time, data


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    from vibrofeed.pictures.export import export

    folder = tmp_path_factory.mktemp("export")
    path = chip_run(folder / "chips.h5")
    done = export(Result(path), folder / "out")
    return path, folder / "out", done


def test_pvd_is_a_collection_of_every_frame(exported):
    path, out, done = exported
    assert done.pvd == out / "chips.pvd" and done.frames == 4
    root = ET.parse(done.pvd).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    assert root.get("byte_order") == "LittleEndian"
    datasets = root.find("Collection").findall("DataSet")
    assert len(datasets) == 4 * 3
    with Result(path) as r:
        times = r.time
    for t in times:
        rows = [d for d in datasets if float(d.get("timestep")) == t]
        assert [(d.get("part"), d.get("name")) for d in rows] == [("0", "parts"), ("1", "shapes"),
                                                                  ("2", "track")]
        for d in rows:
            f = out / d.get("file")
            assert f.is_file() and not d.get("file").startswith("/")  # relative: the folder moves
            assert read_vtp(f)[2] == t


def test_parts_read_back_as_in_the_result(exported):
    path, out, _ = exported
    with Result(path) as r:
        shape = scene.part_shape(r.parameters, r.body_template)
        for k in range(r.n_frames):
            frame = scene.read_frame(r, k)
            points, f, _, data = read_vtp(out / "chips" / f"parts_{k:06d}.vtp")
            assert data.GetNumberOfVerts() == len(frame)  # points ParaView shows as they are
            order = np.argsort(f["id"])
            mine = np.argsort(frame.ids)
            assert np.array_equal(f["id"][order], frame.ids[mine])
            assert same(points[order], frame.position[mine])
            assert same(f["velocity"][order], frame.velocity[mine])
            assert same(f["speed"][order], np.linalg.norm(frame.velocity[mine], axis=1))
            assert same(f["velocity_rel"][order], frame.velocity[mine] - frame.surface_velocity)
            assert same(f["orientation"][order], frame.orientation[mine])
            assert same(f["radius"][order], frame.radius[mine])
            rot = scene.rotation_matrices(frame.orientation[mine])
            assert same(f["normal"][order], rot[:, :, 2])
            assert same(f["axis_x"][order], rot[:, :, 0])
            # The shape tensor's columns (VTK stores one after the other) are the box's
            # edges: R diag(size, size, thickness).
            tensor = f["shape_tensor"][order].reshape(-1, 3, 3).transpose(0, 2, 1)
            assert same(tensor, rot * np.array([3e-4, 3e-4, 1e-4]))
            assert shape.kind == "chip"


def test_shapes_and_moving_track(exported):
    path, out, _ = exported
    with Result(path) as r:
        for k in range(r.n_frames):
            frame = scene.read_frame(r, k)
            points, f, _, data = read_vtp(out / "chips" / f"shapes_{k:06d}.vtp")
            assert data.GetNumberOfPolys() == 12 * len(frame)  # one box per chip
            for part_id, centre in zip(frame.ids, frame.position):
                assert same(points[f["id"] == part_id].mean(axis=0), centre)
            track, tf, _, _ = read_vtp(out / "chips" / f"track_{k:06d}.vtp")
            assert same(track, TRACK[0] + frame.surface_position)
            assert same(tf["velocity"], frame.surface_velocity)
            np.testing.assert_allclose(tf["speed"], np.linalg.norm(frame.surface_velocity),
                                       rtol=1e-12, atol=0)


def test_outlet_events(exported):
    _, out, _ = exported
    points, f, time, _ = read_vtp(out / "chips_outlet.vtp")
    assert time is None  # every event in one file: no time step of its own in ParaView
    assert same(points, [[0.0201, 0, -3e-4]]) and list(f["id"]) == [1]
    assert same(f["time"], [0.012])


def test_pyvista_reads_the_series(exported):
    import pyvista as pv

    path, out, _ = exported
    reader = pv.get_reader(str(out / "chips.pvd"))
    with Result(path) as r:
        assert same(reader.time_values, r.time)
        reader.set_active_time_point(3)
        blocks = reader.read()
        assert len(blocks) == 3
        assert blocks[0].n_points == len(scene.read_frame(r, 3))


def test_result_without_track_or_orientation_and_every(tmp_path):
    from vibrofeed.pictures.export import export

    path = write_result(tmp_path / "plain.h5", [(k, 0.01 * k, parts([1, 2], [[k * 1e-3, 0, 5e-4],
                                                                            [0, 1e-3, 5e-4]]))
                                                 for k in range(5)])
    done = export(Result(path), tmp_path / "o", every=2, shapes=False)
    datasets = ET.parse(done.pvd).getroot().find("Collection").findall("DataSet")
    assert [(float(d.get("timestep")), d.get("name")) for d in datasets] == \
        [(0.0, "parts"), (0.02, "parts"), (0.04, "parts")]
    points, f, _, _ = read_vtp(tmp_path / "o" / "plain" / "parts_000004.vtp")
    assert same(points[f["id"] == 1], [[4e-3, 0, 5e-4]])
    assert same(f["orientation"], [1, 0, 0, 0])
    assert same(f["shape_tensor"].reshape(-1, 3, 3), np.eye(3) * 1e-3)  # sphere: diameter
    assert not (tmp_path / "o" / "plain_outlet.vtp").exists()


def test_command_line(tmp_path):
    path = chip_run(tmp_path / "run.h5", n_frames=2)
    proc = vibrofeed("export", path, "-o", tmp_path / "pv", check=True)
    assert "wrote" in proc.stdout and (tmp_path / "pv" / "run.pvd").is_file()
    assert len(list((tmp_path / "pv" / "run").glob("*.vtp"))) == 2 * 3


@pytest.mark.parametrize("fail_at", [1, 4, 8])
def test_a_failed_export_removes_what_it_added(tmp_path, monkeypatch, fail_at):
    """A full disk at the first file, mid-series or at the .pvd (the 8th file: 2 frames x 3
    blocks, the outlet, the .pvd): the files and folders the export made are removed, what was
    in the folder before stays."""
    import errno

    from vibrofeed.pictures import export as E

    path = chip_run(tmp_path / "run.h5", n_frames=2)
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    real, calls = E.write_whole, []

    def write_whole(target, data):
        calls.append(target)
        if len(calls) == fail_at:
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(target, data)

    monkeypatch.setattr(E, "write_whole", write_whole)
    with pytest.raises(OSError, match="No space left"):
        E.export(Result(path), out / "pv")
    assert [p.name for p in out.iterdir()] == ["notes.txt"]
    assert len(calls) == fail_at and (calls[-1].name == "run.pvd") == (fail_at == 8)
    # into a folder that already held the series: the older files stay, the new ones go
    monkeypatch.setattr(E, "write_whole", real)
    E.export(Result(path), out)
    before = sorted(p.relative_to(out) for p in out.rglob("*"))
    (out / "run" / "parts_000001.vtp").unlink()
    calls.clear()
    monkeypatch.setattr(E, "write_whole", write_whole)
    with pytest.raises(OSError):
        E.export(Result(path), out)
    after = sorted(p.relative_to(out) for p in out.rglob("*"))
    assert set(after) <= set(before) and (out / "run.pvd").exists() and (out / "run").is_dir()
