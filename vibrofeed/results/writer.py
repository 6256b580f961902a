"""Write a run to an H5MD file, one frame at a time.

Frames are collected in memory and written in batches, each batch flushed to
disk at once, at most ``max_delay`` seconds (wall clock, default 0.25 s) after
the first frame in it was handed over; frames never rewrite what earlier
frames stored differently. So a run killed at any moment (even with SIGKILL)
leaves a file that opens and holds every frame computed up to a quarter of a
second before the kill. (Writing and flushing every small frame on its own
costs ~2 ms, more than LIGGGHTS takes to compute it for a few parts.) The file
says how the run ended in ``parameters/run@status``.

Particles can appear and disappear during a run (insertion at a feeder's
inlet, removal at its outlet). Each particle keeps a fixed *slot* (column)
while it exists; free slots hold ``id = -1`` and NaN, as H5MD's fill-value
convention prescribes, and are reused by later particles.
"""

from __future__ import annotations

import datetime as _dt
import getpass
import socket
import threading
import time as _time
from collections.abc import Mapping

import h5py
import numpy as np

from .. import __version__
from . import layout as L

_CHUNK_BYTES = 64 * 1024


def _fixed(s: str) -> np.bytes_:
    """A fixed-length string, as H5MD asks for its attributes."""
    return np.bytes_(str(s).encode("utf-8"))


def _now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def _number_or_text(value: str):
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


class SlotMap:
    """Assigns each particle id a stable column, reusing freed columns."""

    def __init__(self):
        self.slot_of: dict[int, int] = {}
        self.free: list[int] = []
        self.capacity = 0

    def assign(self, ids: np.ndarray) -> np.ndarray:
        """Columns for ``ids`` at this frame; ids absent now free their columns."""
        present = set(int(i) for i in ids)
        for gone in [i for i in self.slot_of if i not in present]:
            self.free.append(self.slot_of.pop(gone))
        self.free.sort(reverse=True)  # pop() then hands out the lowest column
        slots = np.empty(len(ids), dtype=np.int64)
        for k, pid in enumerate(ids):
            pid = int(pid)
            if pid not in self.slot_of:
                if self.free:
                    self.slot_of[pid] = self.free.pop()
                else:
                    self.slot_of[pid] = self.capacity
                    self.capacity += 1
            slots[k] = self.slot_of[pid]
        return slots


class ResultWriter:
    """Create an H5MD result file and append frames to it.

    Parameters
    ----------
    path:
        File to create (overwritten if it exists).
    deck_name, deck_path, deck_text:
        The deck that was run, stored verbatim.
    includes:
        ``{path relative to the deck's folder: text}`` of every file the deck
        includes, stored verbatim under ``parameters/includes``.
    variables:
        Every deck variable with the value used: ``{name: (value, unit,
        description, default)}``; values are strings as given to LIGGGHTS.
    derived:
        Values the deck derived from them (timestep, step counts, ...).
    engine_version:
        The LIGGGHTS version line.
    seed:
        The run's random seed.
    run_id:
        The run's identity (hash of deck, includes, parameters and version).
    capacity_hint:
        Expected largest number of particles, to size HDF5 chunks.
    """

    def __init__(self, path, *, deck_name: str, deck_path: str, deck_text: str,
                 includes: Mapping[str, str] | None = None, variables: Mapping[str, tuple],
                 derived: Mapping[str, float],
                 engine_version: str, seed: int | None, ranks: int = 1,
                 command: str = "", run_id: str = "", capacity_hint: int = 1,
                 max_delay: float = 0.25):
        self.path = str(path)
        self.slots = SlotMap()
        self.frames = 0          # frames handed over
        self.written = 0         # frames on disk
        self.max_delay = max_delay
        self._pending: list = []  # (step, time, {name: row}, surface_position, surface_velocity)
        self._pending_since = 0.0
        self._lock = threading.Lock()
        self._capacity = 0
        n_chunk = int(min(max(capacity_hint, 1), 4096))
        self._chunk_parts = n_chunk
        self._chunk_frames = int(max(1, min(1024, _CHUNK_BYTES // (8 * 3 * n_chunk))))

        self.file = h5py.File(self.path, "w")
        f = self.file
        self._write_h5md_metadata(f)
        self._write_parameters(f, deck_name, deck_path, deck_text, includes or {}, variables,
                               derived, engine_version, seed, ranks, command, run_id)
        self._create_time_series(f)
        # Dataset handles, looked up once.
        self._values = {name: f[L.PARTS][name]["value"] for name in L.PART_ELEMENTS}
        self._surface = {name: f[L.SURFACE][name]["value"] for name in L.SURFACE_ELEMENTS}
        self._step = f[L.PARTS]["position/step"]
        self._time = f[L.PARTS]["position/time"]
        f.flush()
        # Flush from a thread too, so a frame waits at most max_delay even when
        # the next one is long in coming (the engine releases the GIL).
        self._stop = threading.Event()
        self._flusher = threading.Thread(target=self._flush_when_due, daemon=True)
        self._flusher.start()

    def _flush_when_due(self) -> None:
        while not self._stop.wait(self.max_delay / 4):
            with self._lock:
                due = self._pending and _time.monotonic() - self._pending_since >= self.max_delay
            if due:
                self.flush()

    # -- creation ---------------------------------------------------------------
    @staticmethod
    def _write_h5md_metadata(f: h5py.File) -> None:
        h5md = f.create_group("h5md")
        h5md.attrs["version"] = np.array(L.H5MD_VERSION, dtype="i4")
        author = h5md.create_group("author")
        try:
            user = getpass.getuser()
        except (KeyError, OSError):
            user = "unknown"
        author.attrs["name"] = _fixed(user)
        creator = h5md.create_group("creator")
        creator.attrs["name"] = _fixed("vibrofeed")
        creator.attrs["version"] = _fixed(__version__)
        units = h5md.create_group("modules/units")
        units.attrs["version"] = np.array(L.UNITS_MODULE_VERSION, dtype="i4")
        units.attrs["system"] = _fixed("SI")

    @staticmethod
    def _write_parameters(f, deck_name, deck_path, deck_text, includes, variables, derived,
                          engine_version, seed, ranks, command, run_id) -> None:
        p = f.create_group(L.PARAMETERS)
        p.attrs["format"] = _fixed(L.FORMAT_NAME)
        p.attrs["format_version"] = np.array(L.FORMAT_VERSION, dtype="i4")
        deck = p.create_dataset("deck", data=deck_text, dtype=h5py.string_dtype())
        deck.attrs["name"] = deck_name
        deck.attrs["path"] = deck_path
        inc = p.create_group("includes")  # by path relative to the deck's folder
        for name, text in includes.items():
            inc.create_dataset(name.lstrip("/"), data=text, dtype=h5py.string_dtype())
        p.create_dataset("liggghts_version", data=engine_version, dtype=h5py.string_dtype())
        p.create_dataset("seed", data=np.int64(seed if seed is not None else -1))
        var = p.create_group("variables")
        for name, (value, unit, description, default) in variables.items():
            ds = var.create_dataset(name, data=_number_or_text(value))
            ds.attrs["unit"] = unit or ""
            ds.attrs["description"] = description or ""
            ds.attrs["default"] = str(default)
            ds.attrs["given"] = str(value) != str(default)
        der = p.create_group("derived")
        for name, value in derived.items():
            der.create_dataset(name, data=float(value))
        run = p.create_group("run")
        run.attrs["id"] = run_id
        run.attrs["status"] = L.STATUS_RUNNING
        run.attrs["message"] = ""
        run.attrs["started"] = _now()
        run.attrs["finished"] = ""
        run.attrs["ranks"] = int(ranks)
        run.attrs["command"] = command
        run.attrs["host"] = socket.gethostname()

    def _create_time_series(self, f: h5py.File) -> None:
        parts = f.create_group(L.PARTS)
        box = parts.create_group("box")
        box.attrs["dimension"] = np.int32(3)
        box.attrs["boundary"] = np.array([b"none"] * 3, dtype="S8")

        cf = self._chunk_frames
        step = time = None
        for name, (dtype, comps, unit) in L.PART_ELEMENTS.items():
            g = parts.create_group(name)
            shape, maxshape, chunks = (0, 0), (None, None), (cf, self._chunk_parts)
            if comps:
                shape, maxshape, chunks = shape + (comps,), maxshape + (comps,), chunks + (comps,)
            fill = self._fill(name, dtype)
            value = g.create_dataset("value", shape=shape, maxshape=maxshape, dtype=dtype,
                                     chunks=chunks, fillvalue=fill)
            if unit:
                value.attrs["unit"] = _fixed(unit)
            step, time = self._step_time(g, step, time)

        obs = f.create_group(L.SURFACE)
        for name, (dtype, comps, unit) in L.SURFACE_ELEMENTS.items():
            g = obs.create_group(name)
            value = g.create_dataset("value", shape=(0, comps), maxshape=(None, comps),
                                     dtype=dtype, chunks=(max(cf, 256), comps))
            value.attrs["unit"] = _fixed(unit)
            self._step_time(g, step, time)

    def _step_time(self, group, step, time):
        """Create step/time in the first element, hard-link them in the others."""
        if step is None:
            step = group.create_dataset("step", shape=(0,), maxshape=(None,), dtype="i8",
                                        chunks=(1024,))
            time = group.create_dataset("time", shape=(0,), maxshape=(None,), dtype="f8",
                                        chunks=(1024,))
            time.attrs["unit"] = _fixed(L.TIME_UNIT)
        else:
            group["step"] = step
            group["time"] = time
        return step, time

    @staticmethod
    def _fill(name: str, dtype: str):
        if name == "id":
            return L.ID_FILL
        if name == "species":
            return L.SPECIES_FILL
        return np.nan

    # -- frames -------------------------------------------------------------------
    def write_frame(self, step: int, time: float, parts: Mapping[str, np.ndarray],
                    surface_position, surface_velocity) -> None:
        """Hand over one frame; it reaches the disk within ``max_delay`` seconds.

        ``parts`` holds per-particle arrays with the same row order:
        ``id`` (required), ``species``, ``radius``, ``mass``, ``position``,
        ``velocity``, ``angular_velocity``, ``force``; rows may come in any order.
        """
        ids = np.asarray(parts["id"], dtype=np.int64)
        if len(np.unique(ids)) != len(ids):
            raise ValueError("duplicate particle ids in one frame")
        slots = self.slots.assign(ids)
        rows = {}
        for name, (dtype, comps, _) in L.PART_ELEMENTS.items():
            shape = (self.slots.capacity, comps) if comps else (self.slots.capacity,)
            row = np.full(shape, self._fill(name, dtype), dtype=dtype)
            if name in parts:
                row[slots] = np.asarray(parts[name], dtype=dtype)
            rows[name] = row
        with self._lock:
            if not self._pending:
                self._pending_since = _time.monotonic()
            self._pending.append((int(step), float(time), rows,
                                  np.asarray(surface_position, dtype="f8"),
                                  np.asarray(surface_velocity, dtype="f8")))
            self.frames += 1
            due = _time.monotonic() - self._pending_since >= self.max_delay
        if due:
            self.flush()

    def flush(self) -> None:
        """Write the frames handed over so far and flush the file."""
        with self._lock:
            self._write_pending()

    def _write_pending(self) -> None:
        if not self._pending or not self.file.id.valid:
            return
        if self.slots.capacity > self._capacity:
            self._grow(self.slots.capacity)
        k0, n = self.written, len(self._pending)
        for name, (dtype, comps, _) in L.PART_ELEMENTS.items():
            shape = (n, self._capacity, comps) if comps else (n, self._capacity)
            block = np.full(shape, self._fill(name, dtype), dtype=dtype)
            for i, frame in enumerate(self._pending):
                row = frame[2][name]
                block[i, :len(row)] = row  # frames before a growth are narrower
            self._append(self._values[name], k0, block)
        self._append(self._surface["position"], k0, np.array([f[3] for f in self._pending]))
        self._append(self._surface["velocity"], k0, np.array([f[4] for f in self._pending]))
        # step/time last: a frame counts once its step is there.
        self._append(self._time, k0, np.array([f[1] for f in self._pending], dtype="f8"))
        self._append(self._step, k0, np.array([f[0] for f in self._pending], dtype="i8"))
        self.written += n
        self._pending = []
        self.file.flush()

    @staticmethod
    def _append(ds, k, block) -> None:
        """Grow ``ds`` to hold ``block`` (frames along axis 0) from frame k on
        and write it there (low-level h5py: the high-level slicing costs ~0.1
        ms per call)."""
        block = np.ascontiguousarray(block, dtype=ds.dtype)
        dsid = ds.id
        dsid.set_extent((k + block.shape[0],) + ds.shape[1:])
        fspace = dsid.get_space()
        fspace.select_hyperslab((k,) + (0,) * (block.ndim - 1), block.shape)
        dsid.write(h5py.h5s.create_simple(block.shape), fspace, block)

    def _grow(self, capacity: int) -> None:
        """Widen the particle axis; earlier frames read the fill value there."""
        for ds in self._values.values():
            ds.resize(capacity, axis=1)
        self._capacity = capacity

    # -- end ------------------------------------------------------------------------
    def finish(self, status: str = L.STATUS_COMPLETE, message: str = "",
               wall_seconds: float | None = None) -> None:
        """Record how the run ended and close the file."""
        if status not in L.STATUSES:
            raise ValueError(f"unknown run status {status!r}")
        self.flush()
        with self._lock:
            mark_status(self.file, status, message, wall_seconds)
        self.close()

    def close(self) -> None:
        self._stop.set()
        if self._flusher.is_alive() and self._flusher is not threading.current_thread():
            self._flusher.join()
        with self._lock:
            if self.file.id.valid:
                self._write_pending()
                self.file.flush()
                self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if self.file.id.valid:
            if exc_type is None:
                self.finish()
            else:
                self.finish(L.STATUS_FAILED, f"{exc_type.__name__}: {exc}")


def mark_status(f: h5py.File, status: str, message: str = "",
                wall_seconds: float | None = None) -> None:
    """Set ``parameters/run`` status attributes of an open result file."""
    run = f[L.RUN]
    run.attrs["status"] = status
    run.attrs["message"] = message
    run.attrs["finished"] = _now()
    if wall_seconds is not None:
        run.attrs["wall_seconds"] = float(wall_seconds)
    f.flush()


def mark_file_status(path, status: str, message: str = "") -> bool:
    """Set the status of a result file on disk; False if it cannot be opened."""
    try:
        with h5py.File(path, "r+") as f:
            if L.RUN not in f:
                return False
            mark_status(f, status, message)
        return True
    except OSError:
        return False
