"""A result as a plain H5MD trajectory for molecular-dynamics tools (``vibrofeed export --format h5md-md``).

The result file itself follows H5MD 1.1 and opens in any H5MD reader that
takes what the specification allows. Two things it allows are beyond some
readers: lengths in metres (MDAnalysis knows no unit ``m``) and a particle
axis with holes (a slot freed by a part that left and later reused: znh5md and
ASE expect the particles present at a frame to come first). This export writes
what they read, still to the letter of H5MD 1.1:

- one particle group ``particles/trajectory`` (the name MDAnalysis looks for
  when it builds its topology from the file alone);
- at each frame, the parts present in ascending id, then padding up to the
  most parts present at once: ``id = -1`` (the fill value: no particle),
  ``species = 0`` (LIGGGHTS types start at 1; ASE reads 0 as a dummy atom) and
  NaN in every float element. A row is not one part over time: ``id`` says
  which part it holds;
- lengths (``position``, ``radius``, the box edges, the surface's
  displacement) in nanometres (``nm``), every other quantity in the SI units of
  the result (``m s-1``, ``rad s-1``, ``N``, ``kg``, ``s``);
- ``box/pbc``, the periodicity per axis as a time series (all false): not an
  H5MD item, which H5MD allows, for znh5md;
- the observables of the result (surface motion, a feeder line's further sections'
  motion as ``surface_s<k>``, mass balance) as time series, and the result's run id and
  path as attributes of ``parameters``.

A per-part element the result holds no value of (the force on clumps, NaN by
design) is left out.

HDF5 writes through a file object of vibrofeed's (:class:`_Sink`), never to the disk
itself: HDF5 meeting a full disk floods stderr with error stacks and crashes the
process when h5py closes the file; through the sink a full disk is one error
(:class:`~vibrofeed.errors.OutputError`) and no file.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

import h5py
import numpy as np

from .. import __version__
from ..disk import free_bytes, mount_point
from ..errors import OutputError
from . import layout as L
from .writer import _ascii, _fixed, set_unit

NM_PER_M = 1e9
_BLOCK_VALUES = 1 << 21  # values per element packed in memory before a write (16 MB of float64)
FORMAT_NAME = "h5md-md"
GROUP = "particles/trajectory"
# element -> (source field, scale, unit, fill) in the order they are written
ELEMENTS = {
    "id": ("id", None, None, L.ID_FILL),
    "species": ("species", None, None, 0),
    "position": ("position", NM_PER_M, "nm", np.nan),
    "velocity": ("velocity", 1.0, "m s-1", np.nan),
    "force": ("force", 1.0, "N", np.nan),
    "angular_velocity": ("angular_velocity", 1.0, "rad s-1", np.nan),
    "orientation": ("orientation", 1.0, None, np.nan),
    "radius": ("radius", NM_PER_M, "nm", np.nan),
    "mass": ("mass", 1.0, "kg", np.nan),
}
SURFACE_UNITS = {"position": (NM_PER_M, "nm"), "velocity": (1.0, "m s-1")}


def _time_series(group, name, frames_shape, dtype, fill, unit, step, time):
    g = group.create_group(name)
    value = g.create_dataset("value", shape=frames_shape, dtype=dtype, fillvalue=fill,
                             chunks=True)
    if unit:
        set_unit(value, unit)
    if step is None:
        step = g.create_dataset("step", data=np.empty(0, dtype="i8"), maxshape=(None,))
        time = g.create_dataset("time", data=np.empty(0, dtype="f8"), maxshape=(None,))
        set_unit(time, L.TIME_UNIT)
    else:
        g["step"], g["time"] = step, time
    return value, step, time


def export_md(result, path, every: int = 1) -> Path:
    """Write every ``every``-th frame of a Result to ``path`` (see the module's docstring).

    The file is written as ``path.part`` and renamed when complete, so ``path`` is never a
    partial export. A full disk is an :class:`OutputError` naming it, before any writing
    when the folder has less room than the particle data alone."""
    path = Path(path)
    part = path.with_name(path.name + ".part")
    index = np.arange(0, result.n_frames, every)
    n_rows = int(result.present(index).max()) if len(index) else 0
    names = [name for name in ELEMENTS if result.recorded(ELEMENTS[name][0], index)]
    need = len(index) * n_rows * sum(_row_bytes(name) for name in names)
    free = free_bytes(path.parent)
    if free is not None and free < need:
        raise OutputError(f"cannot write {path}: no space left on {mount_point(path.parent)} (the export "
                          f"needs at least {need / 1e6:.3g} MB, {free / 1e6:.3g} MB free)")
    try:
        with _Sink(part) as sink:
            _write(result, sink, index, n_rows, names, every)
        if sink.error is not None:
            why = (f"no space left on {mount_point(path.parent)}" if sink.error.errno == errno.ENOSPC
                   else sink.error.strerror or str(sink.error))
            raise OutputError(f"cannot write {path}: {why}")
        part.replace(path)
    except BaseException:
        part.unlink(missing_ok=True)
        raise
    return path


def _row_bytes(name: str) -> int:
    """Bytes of one row (one part at one frame) of element ``name``."""
    source = ELEMENTS[name][0]
    dtype, comps, _ = L.PART_ELEMENTS.get(source) or L.OPTIONAL_PART_ELEMENTS[source]
    return np.dtype(dtype).itemsize * max(comps, 1)


class _Sink:
    """The export's file as h5py's "fileobj" driver sees it: HDF5 never meets a failed write.

    HDF5 writing to a full disk itself prints error stacks and crashes the process (a
    segfault) when h5py closes the file. Building the file in memory avoids that but needs
    as much memory as the export (gigabytes for a long run of thousands of parts); the sink
    writes to the disk as HDF5 goes, memory stays at the exporter's blocks. The first
    write the disk refuses becomes :attr:`error`; it and every later write are kept in
    memory (reads see them), so HDF5 goes on and closes the file cleanly, the exporter
    stops at its next block (:func:`_write`) and :func:`export_md` reports the error and
    removes the file. Memory then holds only what HDF5 wrote after the disk filled.
    """

    def __init__(self, path: Path):
        self.fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_TRUNC, 0o666)
        self.pos = self.size = 0
        self.error: OSError | None = None
        self.kept: list[tuple[int, bytes]] = []  # (offset, data) written after the error

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        os.close(self.fd)

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        self.pos = offset + {os.SEEK_SET: 0, os.SEEK_CUR: self.pos, os.SEEK_END: self.size}[whence]
        return self.pos

    def tell(self) -> int:
        return self.pos

    def write(self, data) -> int:
        data = memoryview(data).cast("B")
        if self.error is None:
            try:
                done = 0
                while done < len(data):
                    done += os.pwrite(self.fd, data[done:], self.pos + done)
            except OSError as exc:
                self.error = exc
        if self.error is not None:
            self.kept.append((self.pos, bytes(data)))
        self.pos += len(data)
        self.size = max(self.size, self.pos)
        return len(data)

    def read(self, n: int = -1) -> bytes:
        n = self.size - self.pos if n < 0 else n
        out = bytearray(n)  # what the disk does not hold reads as zeros (HDF5's own drivers')
        try:
            got = os.pread(self.fd, n, self.pos)
            out[:len(got)] = got
        except OSError as exc:
            self.error = self.error or exc
        for at, data in self.kept:  # in the order written: later writes win
            lo, hi = max(at, self.pos), min(at + len(data), self.pos + n)
            if lo < hi:
                out[lo - self.pos:hi - self.pos] = data[lo - at:hi - at]
        self.pos += n
        return bytes(out)

    def truncate(self, size: int) -> int:
        if self.error is None:
            try:
                os.ftruncate(self.fd, size)
            except OSError as exc:
                self.error = exc
        self.size = size
        return size

    def flush(self) -> None:
        pass


def _write(result, sink: _Sink, index: np.ndarray, n_rows: int, names: list[str],
           every: int) -> None:
    """Write the export through ``sink``; stop early once it met an error (the file is dropped)."""
    # h5py's "fileobj" driver: HDF5 reads and writes through the sink
    with h5py.File(sink, "w") as f:
        h5md = f.create_group("h5md")
        h5md.attrs["version"] = np.array(L.H5MD_VERSION, dtype="i4")
        for group, attrs in (("author", {"name": _text_attr(result.file["h5md/author"], "name")}),
                             ("creator", {"name": "vibrofeed", "version": __version__})):
            g = h5md.create_group(group)
            for key, value in attrs.items():
                g.attrs[key] = _fixed(value)
        units = h5md.create_group("modules/units")
        units.attrs["version"] = np.array(L.UNITS_MODULE_VERSION, dtype="i4")
        _ascii(units, "system", "SI")

        parts = f.create_group(GROUP)
        box = parts.create_group("box")
        box.attrs["dimension"] = np.int32(3)
        box.attrs["boundary"] = np.array([_fixed(b) for b in L.BOX_BOUNDARY], dtype="S8")
        edges, step, time = _time_series(box, "edges", (len(index), 3), "f8", 0.0, "nm", None, None)
        step.resize((len(index),))
        time.resize((len(index),))
        step[:] = result.read("step", frames=index)
        time[:] = result.read("time", frames=index)
        edges[:] = np.asarray(L.BOX_EDGES_PLACEHOLDER) * NM_PER_M
        pbc = _time_series(box, "pbc", (len(index), 3), "?", False, None, step, time)[0]
        pbc[:] = np.array(L.BOX_PBC)  # (as in the result: for znh5md)
        values = {}
        for name in names:
            source, _, unit, fill = ELEMENTS[name]
            dtype, comps, _ = L.PART_ELEMENTS.get(source) or L.OPTIONAL_PART_ELEMENTS[source]
            shape = (len(index), n_rows, comps) if comps else (len(index), n_rows)
            values[name] = _time_series(parts, name, shape, dtype, fill, unit, step, time)[0]
        # frames are packed in memory and written in blocks (one HDF5 write per element and
        # block: a write per frame costs more than the packing)
        per_block = max(1, _BLOCK_VALUES // max(3 * n_rows, 1))
        frames = result.iter_frames(index, fields=[ELEMENTS[n][0] for n in names])
        for k0 in range(0, len(index), per_block):
            k1 = min(len(index), k0 + per_block)
            blocks = {name: np.full((k1 - k0, *ds.shape[1:]), ds.fillvalue, dtype=ds.dtype)
                      for name, ds in values.items()}
            for k in range(k1 - k0):
                frame = next(frames)
                order = np.argsort(frame.ids, kind="stable")
                for name in names:
                    source, scale, _, _ = ELEMENTS[name]
                    rows = frame[source][order]
                    blocks[name][k, :len(order)] = rows if scale is None else rows * scale
            for name, block in blocks.items():
                if sink.error is not None:  # the disk is full: the rest would only fill memory
                    return
                values[name][k0:k1] = block

        obs = f.create_group("observables")
        for k in range(1, result.n_sections + 1):
            if k > 1 and L.surface_path(k) not in result.file:
                continue  # a line of format 1.3: its further sections' motion is unrecorded
            surface = obs.create_group(L.surface_path(k).rpartition("/")[2])
            motion = result.section_surface(k, frames=index)
            for (name, (scale, unit)), values in zip(SURFACE_UNITS.items(), motion):
                ds = _time_series(surface, name, (len(index), 3), "f8", np.nan, unit, step, time)[0]
                ds[:] = values * scale
            if k == 1 and result.holds("surface_angle"):  # a rotation about z: radians in every unit system
                for name, (_, _, unit) in L.ROTATION_ELEMENTS.items():
                    ds = _time_series(surface, name, (len(index), 3), "f8", np.nan, unit, step, time)[0]
                    ds[:] = result.read(f"surface_{name}", frames=index)
        counts = result.mass_balance
        if counts is not None:
            balance = obs.create_group("mass_balance")
            for name, series in counts.items():
                ds = _time_series(balance, name, (len(index),), "i8", -1, None, step, time)[0]
                ds[:] = series[index]

        p = f.create_group("parameters")
        p.attrs["format"] = _fixed(FORMAT_NAME)
        p.attrs["source"] = str(result.path)
        p.attrs["source_run_id"] = result.run_id
        p.attrs["every"] = int(every)


def _text_attr(group, name: str) -> str:
    value = group.attrs.get(name, "")
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)
