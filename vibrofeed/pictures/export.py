"""Write a result as a ParaView time series: ``DIR/RUN.pvd`` and VTK files per frame.

LIGGGHTS users look at their runs in ParaView; ``File > Open`` on the ``.pvd``
gives a time series whose every step is a multiblock of

- ``parts`` (``RUN/parts_NNNNNN.vtp``): one point per part with the fields
  ``id``, ``species``, ``radius``, ``diameter``, ``mass``, ``velocity``,
  ``speed``, ``velocity_rel`` (relative to the track under the part: a feeder line's
  section 2 from the joint at ``track_length`` on), ``angular_velocity``,
  ``force`` (only where the result records it: not for clumps, whose force
  is NaN by design; an all-NaN array gets NaN ranges that ParaView cannot
  read back), ``orientation`` (quaternion w, x, y, z) and glyph-ready arrays:
  ``normal`` and ``axis_x`` (the body's face normal and first in-plane axis,
  for the Glyph filter's orientation), ``shape_tensor`` (R diag(extents):
  ParaView's Tensor Glyph filter with Glyph Type Box, "Extract Eigenvalues"
  off and Scale Factor 1 draws each part's oriented box, checked with
  ParaView 5.11);
- ``shapes`` (``RUN/shapes_NNNNNN.vtp``): the parts' real shapes as triangles
  (spheres, chips as boxes, discs as cylinders), with ``id``, ``speed`` and
  ``velocity`` on their points, ready to colour;
- ``track`` (``RUN/track_NNNNNN.vtp``): the track mesh at the frame's surface
  position, with the surface velocity and speed on its points (runs without a track mesh
  have no track block); a feeder line's sections each at their own recorded position and
  velocity, and ``section`` (1-based) on the points.

The active attributes are set so that ParaView colours and draws glyphs
without picking arrays by hand: scalars ``speed`` in every block (ParaView
colours the series by it only when all blocks share it), vectors ``velocity``,
tensors ``shape_tensor`` (parts), normals ``Normals`` (shapes).

The outlet events, when the run has them, go to ``RUN_outlet.vtp`` (one point
per exit, at the crossing, with ``time``, ``id``, ``velocity``,
``orientation``, active scalars ``time``). Every frame's VTK file carries its
time as the field ``TimeValue``; the outlet file does not (it holds every
event, and a time of its own would add a step to ParaView's animation).
"""

from __future__ import annotations

import time as _time
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import OutputError, UsageError
from .render import write_whole
from .scene import (
    FrameData,
    body_axes,
    part_sections,
    part_shape,
    read_frame,
    shape_mesh,
    shape_tensors,
    track_mesh,
    track_velocity,
    vertex_sections,
)


@dataclass(frozen=True)
class Exported:
    """What :func:`export` wrote: the ``.pvd``, the number of frames and of files, the seconds spent."""

    pvd: Path
    frames: int
    files: int
    seconds: float


def _polydata(points: np.ndarray, triangles: np.ndarray | None = None):
    """vtkPolyData of points, as vertices (triangles None) or as a triangle mesh.

    Built with VTK directly: a frame may hold no part, and its files must still
    carry every array (empty) so that ParaView keeps the same fields over time.
    """
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData

    points = np.ascontiguousarray(points, dtype=float).reshape(-1, 3)
    data = vtkPolyData()
    vtk_points = vtkPoints()
    vtk_points.SetData(numpy_to_vtk(points, deep=True))
    data.SetPoints(vtk_points)
    if triangles is None:
        connectivity, size = np.arange(len(points)), 1
    else:
        connectivity, size = np.asarray(triangles).ravel(), 3
    offsets = np.arange(0, len(connectivity) + 1, size)
    cells = vtkCellArray()
    cells.SetData(numpy_to_vtkIdTypeArray(offsets.astype(np.int64), deep=True),
                  numpy_to_vtkIdTypeArray(connectivity.astype(np.int64), deep=True))
    (data.SetVerts if triangles is None else data.SetPolys)(cells)
    return data


def _add(data, name: str, values, field: bool = False) -> None:
    """Add a named point array (or a field array) to a vtkPolyData; empty arrays included."""
    from vtkmodules.util.numpy_support import numpy_to_vtk

    values = np.asarray(values)
    if values.dtype.kind in "iu":
        values = values.astype(np.int64)
    components = int(np.prod(values.shape[1:]))  # 1 for scalars
    array = numpy_to_vtk(np.ascontiguousarray(values.reshape(len(values), components)), deep=True)
    array.SetName(name)
    (data.GetFieldData() if field else data.GetPointData()).AddArray(array)


def _write_vtp(mesh, path: Path, time: float | None) -> None:
    """Binary, zlib-compressed VTK XML PolyData with the time (if any) as field ``TimeValue``.

    VTK writes into a string and Python writes it to the file (:func:`.render.write_whole`):
    VTK's XML writer writing to a file crashes the process on a full disk (a segfault)."""
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    if time is not None:
        _add(mesh, "TimeValue", np.array([time]), field=True)
    writer = vtkXMLPolyDataWriter()
    writer.WriteToOutputStringOn()
    writer.SetInputData(mesh)
    writer.SetDataModeToBinary()  # inline base64: the string is text
    writer.SetCompressorTypeToZLib()
    if writer.Write() != 1:
        raise OutputError(f"VTK could not write {path}")
    text = writer.GetOutputString()
    write_whole(path, text if isinstance(text, bytes) else text.encode("ascii"))


def parts_points(frame: FrameData, shape, force: bool = True, sections=None):
    """The parts of a frame as points with their fields (see the module's docstring);
    ``force=False`` leaves out the force (a result that does not record it); ``sections``:
    (N,) each part's row in ``frame.sections_velocity`` (default: section 1's)."""
    mesh = _polydata(frame.position)
    under = frame.sections_velocity[np.zeros(len(frame), int) if sections is None else sections]
    normal, axis_x = body_axes(frame, shape)
    fields = {
        "id": frame.ids, "species": frame.species,
        "radius": frame.radius, "diameter": 2 * frame.radius, "mass": frame.mass,
        "velocity": frame.velocity, "speed": frame.speed,
        "velocity_rel": frame.velocity - under,
        "angular_velocity": frame.angular_velocity, "force": frame.force,
        "orientation": frame.orientation, "normal": normal, "axis_x": axis_x,
        "shape_tensor": shape_tensors(frame, shape)}
    if not force:
        del fields["force"]
    for name, values in fields.items():
        _add(mesh, name, values)
    point_data = mesh.GetPointData()
    point_data.SetActiveScalars("speed")
    point_data.SetActiveVectors("velocity")
    point_data.SetActiveTensors("shape_tensor")
    return mesh


def parts_shapes(frame: FrameData, shape):
    """The parts' real shapes as one triangle mesh, with per-part values on the points."""
    shapes = shape_mesh(frame, shape)
    mesh = _polydata(shapes.points, shapes.triangles)
    _add(mesh, "id", frame.ids[shapes.owner])
    _add(mesh, "speed", frame.speed[shapes.owner])
    _add(mesh, "velocity", frame.velocity[shapes.owner])
    _add(mesh, "Normals", shapes.normals)
    mesh.GetPointData().SetActiveNormals("Normals")  # ParaView shades the shapes with them
    mesh.GetPointData().SetActiveScalars("speed")
    mesh.GetPointData().SetActiveVectors("velocity")
    return mesh


def _dataset(collection, time: float, part: int, name: str, file: str) -> None:
    ET.SubElement(collection, "DataSet", timestep=repr(float(time)), group="", part=str(part),
                  name=name, file=file)


def _write_outlet(result, path: Path) -> bool:
    events = result.outlet
    if len(events["time"]) == 0:
        return False
    mesh = _polydata(events["position"])
    for name in ("time", "id", "velocity", "orientation"):
        _add(mesh, name, events[name])
    mesh.GetPointData().SetActiveScalars("time")
    mesh.GetPointData().SetActiveVectors("velocity")
    _write_vtp(mesh, path, None)
    return True


def export(result, folder, every: int = 1, shapes: bool = True, progress=None) -> Exported:
    """Write ``folder/RUN.pvd`` and its VTK files for every ``every``-th frame of a Result.

    ``shapes=False`` leaves out the parts' triangle meshes (the points keep
    every field). ``progress(n)`` is called after each frame.
    """
    if every < 1:
        raise UsageError(f"--every must be >= 1, got {every}")
    start = _time.perf_counter()
    folder = Path(folder)
    stem = Path(result.path).stem
    # The folders and files this export adds: one that fails (a full disk) removes them
    # again, rather than leave a series without its .pvd filling the disk.
    made = [d for d in (folder / stem, *(folder / stem).parents) if not d.exists()]
    added: list[Path] = []
    try:
        (folder / stem).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create {folder / stem}: {exc}") from exc
    try:
        pvd, frames, files = _export(result, folder, stem, every, shapes, progress, added)
    except BaseException:
        for path in added:
            path.unlink(missing_ok=True)
        for d in made:  # deepest first; one that holds other files stays
            try:
                d.rmdir()
            except OSError:
                break
        raise
    return Exported(pvd, frames, files, _time.perf_counter() - start)


def _export(result, folder: Path, stem: str, every: int, shapes: bool, progress,
            added: list[Path]) -> tuple[Path, int, int]:
    """:func:`export`'s writing: (the .pvd, frames, files written); ``added`` gets each file
    written where there was none."""

    def put(path: Path, write, *args):
        """``write(*args)``, which writes ``path``."""
        fresh = not path.exists()
        done = write(*args)
        if fresh and path.exists():
            added.append(path)
        return done

    shape = part_shape(result.parameters, result.body_template)
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    collection = ET.SubElement(root, "Collection")
    frames = np.arange(0, result.n_frames, every)
    force = result.recorded("force", frames)
    files = 0
    for k in frames:
        frame = read_frame(result, int(k))
        blocks = [("parts", parts_points(frame, shape, force, part_sections(result, frame)))]
        if shapes:
            blocks.append(("shapes", parts_shapes(frame, shape)))
        placed = track_mesh(result, frame)
        if placed is not None:
            track = _polydata(*placed)
            velocity = track_velocity(result, frame)  # each vertex its own section's
            _add(track, "velocity", velocity)
            _add(track, "speed", np.linalg.norm(velocity, axis=1))
            if len(frame.sections_velocity) > 1:
                _add(track, "section", vertex_sections(result) + 1)
            # every block's active scalars are "speed": ParaView colours the whole series by it
            track.GetPointData().SetActiveScalars("speed")
            track.GetPointData().SetActiveVectors("velocity")
            blocks.append(("track", track))
        for part, (name, mesh) in enumerate(blocks):
            relative = f"{stem}/{name}_{int(k):06d}.vtp"
            put(folder / relative, _write_vtp, mesh, folder / relative, frame.time)
            _dataset(collection, frame.time, part, name, relative)
            files += 1
        if progress:
            progress(1)
    outlet = folder / f"{stem}_outlet.vtp"
    if put(outlet, _write_outlet, result, outlet):
        files += 1
    ET.indent(root)
    pvd = folder / f"{stem}.pvd"
    # written last, whole or not at all: the series is there once its .pvd is
    put(pvd, write_whole, pvd, ET.tostring(root, encoding="utf-8", xml_declaration=True))
    return pvd, len(frames), files + 1
