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

A bulk feeder's run adds (FORMAT.md, "Bulk feeders"): the parts' orientation,
the outlet event table (:meth:`ResultWriter.write_events`), the mass balance
(``counts`` of :meth:`ResultWriter.write_frame`), the track mesh and the body
template; a feeder line also each further section's motion (``section_surfaces`` of
:meth:`ResultWriter.write_frame`), the section of each track vertex and its rejects; a
bowl its rotation. What a run records of its feeder is one :class:`Recording`, from the
feeder (:meth:`Recording.of`). Each is created only when the run has it, so the files of
other decks keep the layout they always had.
"""

from __future__ import annotations

import datetime as _dt
import getpass
import socket
import threading
import time as _time
from collections.abc import Mapping
from dataclasses import dataclass

import h5py
import numpy as np

from .. import __version__
from . import layout as L

_CHUNK_BYTES = 64 * 1024


def _fixed(s: str) -> np.bytes_:
    """A fixed-length string, as H5MD asks for the author, creator and boundary attributes."""
    return np.bytes_(str(s).encode("utf-8"))


def _ascii(obj, name: str, text: str) -> None:
    """A scalar variable-length ASCII string attribute, as the H5MD units module asks for."""
    obj.attrs.create(name, str(text), dtype=h5py.string_dtype("ascii"))


def set_unit(obj, unit: str) -> None:
    """The units module's ``unit`` attribute of a dataset, in its notation (``m s-1``)."""
    _ascii(obj, "unit", unit)


def _now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def _number_or_text(value: str):
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


class SlotMap:
    """Assigns each particle id a stable column, reusing freed columns.

    Vectorised (sorted id and slot arrays, ``np.searchsorted``): a bulk run
    hands over tens of thousands of ids per frame, and a Python loop over them
    would cost more than writing the frame.
    """

    def __init__(self):
        self._ids = np.empty(0, dtype=np.int64)    # sorted ids holding a slot
        self._slots = np.empty(0, dtype=np.int64)  # their slots
        self.free = np.empty(0, dtype=np.int64)    # free slots, ascending
        self.capacity = 0

    @property
    def slot_of(self) -> dict[int, int]:
        """``{id: slot}`` of the particles holding a slot now."""
        return dict(zip(self._ids.tolist(), self._slots.tolist()))

    def assign(self, ids: np.ndarray) -> np.ndarray:
        """Columns for ``ids`` at this frame; ids absent now free their columns.

        New ids take the lowest free columns in the order they come, then new
        columns at the end.
        """
        ids = np.asarray(ids, dtype=np.int64).ravel()
        last = getattr(self, "_last", None)
        if last is not None and np.array_equal(last[0], ids):
            return last[1].copy()  # the same parts in the same order (between re-sorts)
        order = np.argsort(ids)
        sorted_ids = ids[order]
        if len(ids) > 1 and np.any(sorted_ids[1:] == sorted_ids[:-1]):
            raise ValueError("duplicate particle ids in one frame")
        found = np.zeros(len(ids), dtype=bool)
        kept = np.zeros(len(self._ids), dtype=bool)
        slots_sorted = np.empty(len(ids), dtype=np.int64)
        if len(self._ids):
            pos = np.minimum(np.searchsorted(self._ids, sorted_ids), len(self._ids) - 1)
            found = self._ids[pos] == sorted_ids
            kept[pos[found]] = True
            slots_sorted[found] = self._slots[pos[found]]
        if not kept.all():
            self.free = np.sort(np.concatenate([self.free, self._slots[~kept]]))
        new = np.zeros(len(ids), dtype=bool)
        new[order[~found]] = True
        new_at = np.nonzero(new)[0]  # ascending: the order the new ids come in
        take = self.free[:len(new_at)]
        self.free = self.free[len(take):]
        extra = len(new_at) - len(take)
        slots = np.empty(len(ids), dtype=np.int64)
        slots[order[found]] = slots_sorted[found]
        slots[new_at] = np.concatenate([take, self.capacity + np.arange(extra, dtype=np.int64)])
        self.capacity += extra
        self._ids, self._slots = sorted_ids, slots[order]
        self._last = (ids.copy(), slots.copy())
        return slots


@dataclass(frozen=True)
class Recording:
    """What a run records of its feeder beyond every file's parts and section 1's surface
    (FORMAT.md, "Bulk feeders" and "Feeder lines"); each is created only when the run has it.

    sections:
        the sections whose motion is recorded: section 1 in ``L.SURFACE``, each further one in
        ``L.surface_path(k)`` (a line's, a bowl's exit line's); every frame then gives
        ``sections - 1`` ``section_surfaces``.
    rotating:
        the surface also turns about the z axis (a bowl): records ``L.ROTATION_ELEMENTS`` in
        ``L.SURFACE``; every frame then gives ``surface_rotation``.
    rejects:
        parts that leave over a side are caught: creates the reject table (``L.REJECTS``, the
        outlet's attributes) and records the ``rejected`` count (``L.LINE_COUNTS``).
    returns:
        the rejects come back to the inlet: records the ``returned`` count too
        (``L.RETURN_COUNTS``).
    jet:
        an air jet (an orienting station): creates its firing table (``L.JET``), filled by
        :meth:`ResultWriter.write_events` with ``path`` L.JET.
    """

    sections: int = 1
    rotating: bool = False
    rejects: bool = False
    returns: bool = False
    jet: bool = False

    def __post_init__(self):
        if int(self.sections) < 1:
            raise ValueError(f"sections must be >= 1, got {self.sections}")
        if self.returns and not self.rejects:
            raise ValueError("returns without a line: only a feeder line has rejects to return")

    @classmethod
    def of(cls, feeder, sections: int = 1, rotating: bool = False) -> Recording:
        """What a run of ``feeder`` records (vibrofeed.feeders.Feeder: its rejects, their
        return, its air jets; None: a deck without the feeders' vocabulary, which has none of
        them), whose deck defines the motion of ``sections`` sections and, ``rotating``, its
        surface's rotation: what the deck defines is what is recorded (vibrofeed.engine.worker
        reads both from it, and refuses a deck that defines fewer sections than the feeder has)."""
        if feeder is None:
            return cls(sections=sections, rotating=rotating)
        return cls(sections=sections, rotating=rotating, rejects=feeder.has_rejects,
                   returns=feeder.returns_rejects, jet=feeder.has_jets)


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
    track:
        ``(vertices (V, 3) [m], triangles (T, 3))``: the track mesh at rest in
        the simulation frame, stored under ``parameters/track``.
    body_template:
        ``(n, 4)`` x, y, z, r [m] of a clump's spheres in the body frame.
    outlet:
        ``{"outlet_x": m, "catch_z": m, "method": text}``: creates the (empty)
        outlet event table at once, so that a run in which no part leaves
        still has one. :meth:`write_events` creates it otherwise.
    recording:
        What the run records of its feeder (:class:`Recording`: its further sections' motion,
        the surface's rotation, the rejects, their return, an air jet's firings); the
        default records none of them.
    track_sections:
        ``(V,)`` the section (1-based) of each vertex of ``track``, stored as
        ``L.TRACK_SECTION``: at frame k a vertex sits at rest + its section's position.
    target_error:
        the feed rate's relative error the run stops at (``--target-error``), recorded as
        ``parameters/run@target_error``; :meth:`finish` records why it stopped.
    """

    def __init__(self, path, *, deck_name: str, deck_path: str, deck_text: str,
                 includes: Mapping[str, str] | None = None, variables: Mapping[str, tuple],
                 derived: Mapping[str, float],
                 engine_version: str, seed: int | None, ranks: int = 1,
                 command: str = "", run_id: str = "", capacity_hint: int = 1,
                 max_delay: float = 0.25, track=None, body_template=None,
                 outlet: Mapping | None = None, recording: Recording = Recording(),
                 track_sections=None, target_error: float | None = None,
                 description: Mapping | None = None):
        self.path = str(path)
        self.recording = recording
        self.slots = SlotMap()
        self.frames = 0          # frames handed over
        self.written = 0         # frames on disk
        self.max_delay = max_delay
        # (step, time, {name: row}, surface_pos, surface_vel, counts, further sections' (pos, vel),
        #  the rotation (angle, rate) or None)
        self._pending: list = []
        self._pending_events: list = []  # (table path, event table) handed over, not yet written
        self.events = 0          # events handed over
        self._pending_since = 0.0
        self._lock = threading.Lock()
        self._capacity = 0
        n_chunk = int(min(max(capacity_hint, 1), 4096))
        self._chunk_parts = n_chunk
        self._chunk_frames = int(max(1, min(1024, _CHUNK_BYTES // (8 * 3 * n_chunk))))
        self.sections = int(recording.sections)
        self.rotating = bool(recording.rotating)

        self.file = h5py.File(self.path, "w")
        f = self.file
        self._write_h5md_metadata(f)
        self._write_parameters(f, deck_name, deck_path, deck_text, includes or {}, variables,
                               derived, engine_version, seed, ranks, command, run_id)
        if target_error is not None:
            f[L.RUN].attrs["target_error"] = float(target_error)
        if description is not None:  # the feeder description the deck was generated from
            d = f[L.PARAMETERS].create_dataset("description", data=description["text"],
                                               dtype=h5py.string_dtype())
            d.attrs["name"], d.attrs["path"] = description["name"], description["path"]
        self._create_time_series(f)
        # Dataset handles, looked up once.
        self._values = {name: f[L.PARTS][name]["value"] for name in L.PART_ELEMENTS}
        # one {element: value dataset} per section, section 1 first
        self._surfaces = [{name: f[L.surface_path(k)][name]["value"] for name in L.SURFACE_ELEMENTS}
                          for k in range(1, self.sections + 1)]
        self._rotation = ({name: f[L.SURFACE][name]["value"] for name in L.ROTATION_ELEMENTS}
                          if self.rotating else None)
        self._edges = f[L.PARTS]["box/edges/value"]
        self._pbc = f[L.PARTS]["box/pbc/value"]
        self._step = f[L.PARTS]["position/step"]
        self._time = f[L.PARTS]["position/time"]
        self._counts: dict = {}  # mass-balance value datasets, once created
        self._count_names = L.MASS_BALANCE_COUNTS  # L.LINE_COUNTS once a frame has "rejected"
        self._tables: dict = {}  # event table path -> its datasets, once created
        if track is not None:
            self._write_track(f, *track)
            if track_sections is not None:
                self._write_track_sections(f, track_sections, len(track[0]))
        elif track_sections is not None:
            raise ValueError("track_sections without a track")
        if body_template is not None:
            template = np.asarray(body_template, dtype="f8")
            if template.ndim != 2 or template.shape[1] != 4:
                raise ValueError(f"body_template must be (n, 4) x, y, z, r, got {template.shape}")
            set_unit(f.create_dataset(L.BODY_TEMPLATE, data=template), "m")
        if outlet is not None:
            self._create_outlet(outlet)
        if recording.rejects:  # its reject table (empty until a part falls off) and count
            self._create_outlet(outlet or {}, L.REJECTS)
            self._count_names = L.RETURN_COUNTS if recording.returns else L.LINE_COUNTS
        if recording.jet:  # an air jet: its firings (empty until it fires)
            self._create_table(L.JET)
        f.flush()
        # Flush from a thread too, so a frame waits at most max_delay even when
        # the next one is long in coming (the engine releases the GIL).
        self._stop = threading.Event()
        self._flusher = threading.Thread(target=self._flush_when_due, daemon=True)
        self._flusher.start()

    def _flush_when_due(self) -> None:
        while not self._stop.wait(self.max_delay / 4):
            with self._lock:
                due = ((self._pending or self._pending_events)
                       and _time.monotonic() - self._pending_since >= self.max_delay)
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
        _ascii(units, "system", "SI")

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
        box.attrs["boundary"] = np.array([_fixed(b) for b in L.BOX_BOUNDARY], dtype="S8")

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
                set_unit(value, unit)
            step, time = self._step_time(g, step, time)
        edges = box.create_group("edges")  # step and time as the positions', as H5MD requires
        set_unit(edges.create_dataset("value", shape=(0, 3), maxshape=(None, 3), dtype="f8",
                                      chunks=(max(cf, 256), 3)), "m")
        self._step_time(edges, step, time)
        pbc = box.create_group("pbc")  # (layout.BOX_PBC: for znh5md)
        pbc.create_dataset("value", shape=(0, 3), maxshape=(None, 3), dtype="?", chunks=(max(cf, 256), 3))
        self._step_time(pbc, step, time)

        # each section's motion: H5MD time series sampled with the parts (hard-linked step, time)
        for k in range(1, self.sections + 1):
            obs = f.create_group(L.surface_path(k))
            elements = dict(L.SURFACE_ELEMENTS)
            if k == 1 and self.rotating:
                elements.update(L.ROTATION_ELEMENTS)
            for name, (dtype, comps, unit) in elements.items():
                g = obs.create_group(name)
                value = g.create_dataset("value", shape=(0, comps), maxshape=(None, comps),
                                         dtype=dtype, chunks=(max(cf, 256), comps))
                set_unit(value, unit)
                self._step_time(g, step, time)

    @staticmethod
    def _write_track(f: h5py.File, vertices, triangles) -> None:
        vertices = np.asarray(vertices, dtype="f8")
        triangles = np.asarray(triangles)
        if vertices.ndim != 2 or vertices.shape[1] != 3:
            raise ValueError(f"track vertices must be (V, 3), got {vertices.shape}")
        if triangles.ndim != 2 or triangles.shape[1] != 3 or triangles.dtype.kind not in "iu":
            raise ValueError(f"track triangles must be (T, 3) integers, got {triangles.shape} "
                             f"{triangles.dtype}")
        g = f.create_group(L.TRACK)
        set_unit(g.create_dataset("vertices", data=vertices), "m")
        g.create_dataset("triangles", data=triangles.astype("i4"))

    def _write_track_sections(self, f: h5py.File, sections, n_vertices: int) -> None:
        sections = np.asarray(sections)
        if sections.shape != (n_vertices,) or sections.dtype.kind not in "iu":
            raise ValueError(f"track_sections must be ({n_vertices},) integers, got {sections.shape} "
                             f"{sections.dtype}")
        if n_vertices and not (1 <= sections.min() and sections.max() <= self.sections):
            raise ValueError(f"track_sections must lie in 1..{self.sections} (the sections recorded)")
        f.create_dataset(L.TRACK_SECTION, data=sections.astype("i4"))

    def _create_outlet(self, attrs: Mapping, path: str = L.OUTLET) -> None:
        """An event table (the outlet's, or a line's rejects) with the outlet's attributes."""
        g = self._create_table(path)
        g.attrs["outlet_x"] = float(attrs.get("outlet_x", np.nan))
        g.attrs["catch_z"] = float(attrs.get("catch_z", np.nan))
        g.attrs["method"] = str(attrs.get("method", ""))

    def _create_table(self, path: str):
        """An empty event table of ``L.EVENT_TABLES[path]``; its group."""
        g = self.file.create_group(path)
        table = self._tables[path] = {}
        for name, (dtype, comps, unit) in L.EVENT_TABLES[path].items():
            shape, maxshape = ((0, comps), (None, comps)) if comps else ((0,), (None,))
            ds = g.create_dataset(name, shape=shape, maxshape=maxshape, dtype=dtype,
                                  chunks=(1024, comps) if comps else (1024,))
            if unit:
                set_unit(ds, unit)
            table[name] = ds
        return g

    def _create_counts(self) -> None:
        """The mass-balance series; frames written before read the fill -1."""
        for name in self._count_names:
            g = self.file.create_group(f"{L.MASS_BALANCE}/{name}")
            self._counts[name] = g.create_dataset(
                "value", shape=(self.written,), maxshape=(None,), dtype="i8", chunks=(1024,),
                fillvalue=-1)
            self._step_time(g, self._step, self._time)

    def _create_optional(self, name: str) -> None:
        """An optional per-part element; frames written before read its fill value."""
        dtype, comps, unit = L.OPTIONAL_PART_ELEMENTS[name]
        g = self.file[L.PARTS].create_group(name)
        value = g.create_dataset(
            "value", shape=(self.written, self._capacity, comps),
            maxshape=(None, None, comps), dtype=dtype,
            chunks=(self._chunk_frames, self._chunk_parts, comps), fillvalue=self._fill(name, dtype))
        if unit:
            set_unit(value, unit)
        self._step_time(g, self._step, self._time)
        self._values[name] = value

    def _step_time(self, group, step, time):
        """Create step/time in the first element, hard-link them in the others."""
        if step is None:
            step = group.create_dataset("step", shape=(0,), maxshape=(None,), dtype="i8",
                                        chunks=(1024,))
            time = group.create_dataset("time", shape=(0,), maxshape=(None,), dtype="f8",
                                        chunks=(1024,))
            set_unit(time, L.TIME_UNIT)
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
                    surface_position, surface_velocity, counts: Mapping[str, int] | None = None,
                    section_surfaces=(), surface_rotation=None) -> None:
        """Hand over one frame; it reaches the disk within ``max_delay`` seconds.

        ``parts`` holds per-particle arrays with the same row order:
        ``id`` (required), ``species``, ``radius``, ``mass``, ``position``,
        ``velocity``, ``angular_velocity``, ``force`` and optionally
        ``orientation`` (quaternions w, x, y, z); rows may come in any order.
        ``counts`` is the mass balance at this frame: ``{"inserted", "on_track",
        "exited", "lost"}`` (ints), ``"rejected"`` for a feeder line and ``"returned"`` for
        one that recirculates.
        ``surface_position``, ``surface_velocity`` are section 1's motion (3,) [m, m s-1];
        ``section_surfaces`` the further sections' ``(position, velocity)``, section 2 first,
        one per section beyond the first the writer records (``sections``);
        ``surface_rotation`` the rotating surface's ``(angle, angular_velocity)`` (3,) [rad,
        rad s-1] (a writer made ``rotating`` needs it, any other refuses it).
        """
        further = [(np.asarray(p, dtype="f8").reshape(3), np.asarray(v, dtype="f8").reshape(3))
                   for p, v in section_surfaces]
        if len(further) != self.sections - 1:  # before any state changes: the frame is refused
            raise ValueError(f"the writer records {self.sections} section(s): give the motion of "
                             f"{self.sections - 1} further section(s), got {len(further)}")
        if (surface_rotation is not None) != self.rotating:
            raise ValueError("a rotating surface's frame needs surface_rotation" if self.rotating
                             else "surface_rotation given, but the writer's surface does not rotate")
        rotation = None
        if surface_rotation is not None:
            rotation = tuple(np.asarray(x, dtype="f8").reshape(3) for x in surface_rotation)
        slots = self.slots.assign(parts["id"])  # refuses duplicate ids
        # (slots, values) per element, scattered into the batch's block when
        # written: one pass over the values here (a copy: the caller may reuse
        # its arrays), none over the whole slot axis
        rows = {"": slots}
        for name, (dtype, _, _) in (*L.PART_ELEMENTS.items(), *L.OPTIONAL_PART_ELEMENTS.items()):
            if name in parts:
                value = np.array(parts[name], dtype=dtype)
                if value.shape[0] != len(slots):
                    raise ValueError(f"parts[{name!r}] has {value.shape[0]} rows, id has {len(slots)}")
                rows[name] = value
        if counts is not None:
            missing = [c for c in self._count_names if c not in counts]
            if missing:
                raise ValueError(f"counts lacks {', '.join(missing)}")
            counts = np.array([int(counts[c]) for c in self._count_names], dtype=np.int64)
        with self._lock:
            if not self._pending and not self._pending_events:  # the batch's first item
                self._pending_since = _time.monotonic()
            self._pending.append((int(step), float(time), rows,
                                  np.asarray(surface_position, dtype="f8"),
                                  np.asarray(surface_velocity, dtype="f8"), counts, further, rotation))
            self.frames += 1
            due = _time.monotonic() - self._pending_since >= self.max_delay
        if due:
            self.flush()

    def write_events(self, events: Mapping[str, np.ndarray], path: str = L.OUTLET) -> None:
        """Hand over outlet events (parts that left the track), any number at once.

        ``events`` maps ``time`` (E,) [s], ``id`` (E,), ``position`` (E, 3) [m],
        ``velocity`` (E, 3) [m s-1] and ``orientation`` (E, 4) to arrays; they
        are written with the next frame (same delay, same flush). ``path``
        L.REJECTS: a feeder line's rejects, with ``section`` (E,) too; L.JET: a jet's
        firings (``L.JET_ELEMENTS``).
        """
        table = {}
        n = len(np.atleast_1d(events["id"]))
        for name, (dtype, comps, _) in L.EVENT_TABLES[path].items():
            if name == "orientation" and name not in events:  # plain spheres
                value = np.tile(np.asarray(L.IDENTITY_QUATERNION), (n, 1))
            else:
                value = np.asarray(events[name], dtype=dtype)
            value = value.reshape((n, comps) if comps else (n,))
            table[name] = value
        if n == 0:
            return
        with self._lock:
            if not self._pending and not self._pending_events:
                self._pending_since = _time.monotonic()
            self._pending_events.append((path, table))
            self.events += n

    def flush(self) -> None:
        """Write the frames handed over so far and flush the file."""
        with self._lock:
            self._write_pending()

    def _write_pending(self) -> None:
        if not self.file.id.valid or not (self._pending or self._pending_events):
            return
        events = {path: len(table["id"]) for path, table in self._tables.items()}
        try:
            self._write_batch()
        except BaseException:
            # A batch that could not be written (a full disk) is dropped whole: every series
            # back to the frames and events written before it, so that the file, once it can
            # be flushed again, holds those alone, each series as long as ``step``.
            self._pending, self._pending_events = [], []
            frames = [*self._values.values(), *self._counts.values(), self._edges, self._time,
                      self._step, *(ds for surface in self._surfaces for ds in surface.values()),
                      *(self._rotation.values() if self._rotation is not None else ())]
            try:
                for ds in frames:
                    ds.id.set_extent((self.written,) + ds.shape[1:])
                for path, table in self._tables.items():
                    for ds in table.values():
                        ds.id.set_extent((events.get(path, 0),) + ds.shape[1:])
            except Exception:  # the file is beyond repair; the first error says why
                pass
            raise

    def _write_batch(self) -> None:
        if self._pending_events:
            for path in dict.fromkeys(p for p, _ in self._pending_events):
                if path not in self._tables:
                    if path in L.OUTLET_TABLES:
                        self._create_outlet({"method": ""}, path)
                    else:
                        self._create_table(path)
                tables = [table for p, table in self._pending_events if p == path]
                for name, ds in self._tables[path].items():
                    self._append(ds, ds.shape[0], np.concatenate([table[name] for table in tables]))
            self._pending_events = []
        if not self._pending:
            self.file.flush()
            return
        for name in L.OPTIONAL_PART_ELEMENTS:
            if name not in self._values and any(name in frame[2] for frame in self._pending):
                self._create_optional(name)
        if not self._counts and any(frame[5] is not None for frame in self._pending):
            self._create_counts()
        if self.slots.capacity > self._capacity:
            self._grow(self.slots.capacity)
        k0, n = self.written, len(self._pending)
        for name, ds in self._values.items():
            dtype = ds.dtype
            block = np.full((n, *ds.shape[1:]), self._fill(name, dtype), dtype=dtype)
            for i, frame in enumerate(self._pending):
                value = frame[2].get(name)
                if value is not None:
                    block[i, frame[2][""]] = value
            self._append(ds, k0, block)
        if self._counts:
            counts = np.array([f[5] if f[5] is not None else np.full(len(self._count_names), -1)
                               for f in self._pending], dtype=np.int64)
            for j, name in enumerate(self._count_names):
                self._append(self._counts[name], k0, counts[:, j])
        for k, surface in enumerate(self._surfaces):
            motion = [(f[3], f[4]) if k == 0 else f[6][k - 1] for f in self._pending]
            self._append(surface["position"], k0, np.array([m[0] for m in motion]))
            self._append(surface["velocity"], k0, np.array([m[1] for m in motion]))
        if self._rotation is not None:
            self._append(self._rotation["angle"], k0, np.array([f[7][0] for f in self._pending]))
            self._append(self._rotation["angular_velocity"], k0, np.array([f[7][1] for f in self._pending]))
        self._append(self._edges, k0, np.tile(L.BOX_EDGES_PLACEHOLDER, (n, 1)))
        self._append(self._pbc, k0, np.tile(L.BOX_PBC, (n, 1)))
        # step/time last: a frame counts once its step is there.
        self._append(self._time, k0, np.array([f[1] for f in self._pending], dtype="f8"))
        self._append(self._step, k0, np.array([f[0] for f in self._pending], dtype="i8"))
        self.file.flush()  # the batch counts as written once on disk (a full disk: dropped)
        self.written += n
        self._pending = []

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

    def read_back(self):
        """The frames and events handed over so far, as a :class:`~.reader.Result` read
        through this writer's open file (flushed first): HDF5 without SWMR does not promise
        that a second open of a file being written sees it whole. Valid until the next frame;
        closing it leaves the file open."""
        from .reader import Result

        self.flush()
        return Result.borrow(self.file, self.path)

    # -- end ------------------------------------------------------------------------
    def finish(self, status: str = L.STATUS_COMPLETE, message: str = "",
               wall_seconds: float | None = None, stop_reason: str | None = None) -> None:
        """Record how the run ended (``stop_reason``: why the engine ended a run that
        reached its end, ``L.STOP_AT_END`` ...) and close the file."""
        if status not in L.STATUSES:
            raise ValueError(f"unknown run status {status!r}")
        self.flush()
        with self._lock:
            if stop_reason is not None:
                self.file[L.RUN].attrs["stop_reason"] = stop_reason
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
    except (OSError, RuntimeError):  # HDF5 reports a failed flush (a full disk) as RuntimeError
        return False
