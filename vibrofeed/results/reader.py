"""Read a vibrofeed H5MD result file, whole or by windows of frames.

>>> with Result("hop.h5") as r:
...     t, z = r.time, r.position[:, 0, 2]                   # whole arrays (small files)
...     x = r.read("position", frames=slice(100, None, 10))  # every 10th frame from 100
...     t1, v1 = r.track(1, "velocity")                      # one part, where it exists
...     print(r.parameters["freq"], r.surface_position[:, 2].max())

A file of many parts over many frames need not fit in memory: :meth:`Result.read`
reads a selection of frames and of slots of one field, :meth:`Result.frame`
and :meth:`Result.iter_frames` the parts present at a frame, and
:meth:`Result.track` one part's values without loading the other parts. The
whole-array properties (``position``, ``ids``, ...) read everything on first
access and keep it. Slots of particles that do not exist at a frame hold
``id == -1`` and NaN.

A bulk feeder's file adds (FORMAT.md, "Bulk feeders") the parts'
``orientation`` (read like any field; a file without it reads the identity
quaternion for every present part), the outlet events (:attr:`Result.outlet`),
the mass balance (:attr:`Result.mass_balance`), the track mesh
(:attr:`Result.track_mesh`) and the clump template (:attr:`Result.body_template`).
Files of format 1.2 and earlier, which kept the outlet table under
``observables/``, read alike. A feeder line's file records each section's motion
(:meth:`Result.section_surface`, :attr:`Result.n_sections`); ``surface_position`` and
``surface_velocity`` are section 1's, as for a single track.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import h5py
import numpy as np

from ..errors import IncompleteResult, ResultError  # noqa: F401  (importable from here too)
from ..feeders.feeder import element_count
from . import layout as L

# Frames read at once when scanning ids or iterating: blocks of at most this
# many slot values (32 MB of int64 ids), so memory stays bounded on big files.
_BLOCK_VALUES = 1 << 22
# A scattered frame selection is read as its bounding block when it covers at
# least this fraction of it (one contiguous read), else point by point.
_DENSE = 0.25
# read()'s names of a further section's motion: surface_s2_position, surface_s2_velocity, ...
_SECTION_FIELD = re.compile(r"surface_s(\d+)_(\w+)")


def _text(value) -> str:
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.shape == ():
        return _text(value[()])
    return str(value)


def _reason(exc: BaseException) -> str:
    """HDF5's own words for an h5py error, without h5py's wrapping: "Can't synchronously
    read data (wrong B-tree signature)" -> "wrong B-tree signature"."""
    text = str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc)
    text = text.splitlines()[0] if text else ""  # (HDF5 may add its stack of errors, one a line)
    while (m := re.fullmatch(r"[^(]*\((.*)\)", text.strip())) is not None:
        text = m.group(1)
    return text.strip() or type(exc).__name__


# What a user may hand a command that reads results by mistake, by its suffix: the inputs of a run.
INPUTS = {".toml": "a feeder description", ".liggghts": "a deck", ".in": "a LIGGGHTS input"}


def not_hdf5(path, exc: BaseException) -> str:
    """Why ``path`` is no result: HDF5's words, and for a run's input (a description, a deck) what
    it is and what makes a result of it."""
    what = INPUTS.get(Path(str(path)).suffix.lower())
    hint = f": {what}, not a result (vibrofeed run makes one of it)" if what else ""
    return f"cannot open as HDF5 ({_reason(exc)}){hint}"


def unreadable(exc: BaseException, path: str) -> ResultError | None:
    """The one-line error an h5py failure to read the file at ``path`` becomes, naming the
    file and the object (a damaged or cut file: "wrong B-tree signature", "truncated file",
    an object missing); None for any other exception (a bug, an output that cannot be
    written: left as it is)."""
    if isinstance(exc, ResultError):
        return exc
    found = damaged_object(exc, path)
    if found is None:
        return None
    where, reason = found
    return ResultError(f"{path}: cannot read {where} ({reason}): {DAMAGED}")


DAMAGED = "the file is damaged or was not written whole"


def damaged_object(exc: BaseException, path: str) -> tuple[str, str] | None:
    """(HDF5 path, HDF5's reason) of the object of the file at ``path`` that h5py failed to
    read when it raised ``exc``; None if ``exc`` is not such a failure. Whether it was reading
    ``path`` is told by the h5py objects of the frames the exception went through."""
    if not isinstance(exc, (OSError, RuntimeError, KeyError, ValueError)):
        return None
    if isinstance(exc, OSError) and exc.errno is not None:
        return None  # the operating system's error (a full disk, a permission): not the file's content
    where = None
    target = os.path.abspath(path)
    tb = exc.__traceback__
    while tb is not None:
        frame = tb.tb_frame
        if frame.f_globals.get("__name__", "").startswith("h5py"):
            for value in frame.f_locals.values():
                if isinstance(value, h5py.HLObject):
                    try:
                        same = value.id.valid and os.path.abspath(value.file.filename) == target
                        name = value.name
                    except Exception:  # (an object of a damaged file may not say its name)
                        same, name = False, None
                    if same:
                        where = name or "/"
        tb = tb.tb_next
    return None if where is None else (where, _reason(exc))


def _normalise(sel, n: int):
    """A selection along an axis of length n as an int, a forward slice or an int array."""
    if sel is None:
        return slice(0, n, 1)
    if isinstance(sel, (int, np.integer)):
        k = int(sel) + n * (int(sel) < 0)
        if not 0 <= k < n:
            raise IndexError(f"index {int(sel)} out of range for {n} entries")
        return k
    if isinstance(sel, slice):
        start, stop, step = sel.indices(n)
        if step > 0:
            return slice(start, max(start, stop), step)
        sel = np.arange(start, stop, step)  # h5py reads forwards only
    arr = np.asarray(sel)
    if arr.dtype == bool:
        if arr.shape != (n,):
            raise IndexError(f"boolean selection of length {arr.shape} for {n} entries")
        arr = np.nonzero(arr)[0]
    arr = arr.astype(np.int64).ravel()
    arr = arr + n * (arr < 0)
    if len(arr) and (arr.min() < 0 or arr.max() >= n):
        raise IndexError(f"indices out of range for {n} entries")
    return arr


def _read_axis0(ds, sel, rest: tuple) -> np.ndarray:
    """ds[sel, *rest] with sel normalised along axis 0 (the frames)."""
    if not isinstance(sel, np.ndarray):
        return ds[(sel, *rest)]
    if len(sel) == 0:
        shape = np.empty(ds.shape[1:])[rest].shape if rest else ds.shape[1:]
        return np.empty((0, *shape), dtype=ds.dtype)
    steps = np.diff(sel)
    if len(sel) == 1 or (steps[0] > 0 and (steps == steps[0]).all()):
        step = int(steps[0]) if len(sel) > 1 else 1
        return ds[(slice(int(sel[0]), int(sel[-1]) + 1, step), *rest)]
    unique, inverse = np.unique(sel, return_inverse=True)
    lo, hi = int(unique[0]), int(unique[-1]) + 1
    if len(unique) >= _DENSE * (hi - lo):
        block = ds[(slice(lo, hi), *rest)]
        return block[unique - lo][inverse]
    return ds[(unique, *rest)][inverse]  # h5py point selection: sorted, unique


@dataclass(frozen=True)
class Frame:
    """The parts present at one frame: their ``ids`` and ``slots``, and the
    fields asked for, one row per present part (``frame["position"]``)."""

    index: int
    time: float
    step: int
    ids: np.ndarray
    slots: np.ndarray
    fields: dict = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.fields[name]

    def __len__(self) -> int:
        return len(self.ids)


class _Whole:
    """A whole dataset as an attribute, read on first access and kept."""

    def __init__(self, attr: str, name: str, doc: str):
        self.attr, self.name, self.__doc__ = attr, name, doc

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        value = obj.read(self.name)
        obj.__dict__[self.attr] = value  # later reads hit the instance dict
        return value


class Result:
    """A result file. ``allow_incomplete=True`` also opens killed or failed runs.

    Whole arrays, read on first access and kept (one per field of the layout,
    see ``_whole_arrays``): ``time``, ``step``, ``ids``, ``position``,
    ``velocity``, ``angular_velocity``, ``force``, ``radius``, ``mass``,
    ``species``, ``orientation``, ``surface_position``, ``surface_velocity``.
    """

    _borrowed = False  # reading a file opened elsewhere (:meth:`borrow`): never closed here

    def __init__(self, path, allow_incomplete: bool = False):
        self.path = str(path)
        try:
            self.file = h5py.File(self.path, "r")
        except FileNotFoundError as exc:
            raise ResultError(f"{self.path}: no such file") from exc
        except OSError as exc:
            raise ResultError(f"{self.path}: {not_hdf5(self.path, exc)}") from exc
        try:
            for required in ("h5md", L.PARTS, L.SURFACE, L.RUN):
                if required not in self.file:
                    raise ResultError(f"{self.path}: not a vibrofeed result (no /{required})")
            status, msg = self.status, self.message
        except BaseException as exc:
            damage = unreadable(exc, self.path)
            self.file.close()
            if damage is None:
                raise
            raise damage from exc
        if status != L.STATUS_COMPLETE and not allow_incomplete:
            self.file.close()
            raise IncompleteResult(
                f"{self.path}: the run that wrote it did not complete (status {status}"
                + (f": {msg}" if msg else "") + ")")

    @classmethod
    def borrow(cls, file: h5py.File, path=None) -> Result:
        """A Result reading ``file``, an h5py file open elsewhere (a run's writer reading
        what it wrote so far): whatever its status; :meth:`close` leaves it open."""
        result = cls.__new__(cls)
        result.path, result.file, result._borrowed = str(path or file.filename), file, True
        return result

    # -- run ------------------------------------------------------------------------
    @property
    def status(self) -> str:
        return _text(self.file[L.RUN].attrs.get("status", ""))

    @property
    def message(self) -> str:
        return _text(self.file[L.RUN].attrs.get("message", ""))

    @property
    def run_info(self) -> dict:
        return {k: (_text(v) if isinstance(v, (bytes, str)) else v)
                for k, v in self.file[L.RUN].attrs.items()}

    @cached_property
    def parameters(self) -> dict:
        """Every deck variable: floats where numeric, else strings."""
        out = {}
        for name, ds in self.file[L.VARIABLES].items():
            v = ds[()]
            out[name] = _text(v) if isinstance(v, (bytes, str)) else float(v)
        return out

    @cached_property
    def derived(self) -> dict:
        return {name: float(ds[()]) for name, ds in self.file[L.DERIVED].items()}

    def units(self, name: str) -> str:
        return _text(self.file[L.VARIABLES][name].attrs.get("unit", ""))

    @property
    def deck_text(self) -> str:
        return _text(self.file[L.PARAMETERS]["deck"][()])

    @property
    def deck_includes(self) -> dict[str, str]:
        """``{path relative to the deck's folder: text}`` of the files the deck included."""
        group = self.file[L.PARAMETERS].get("includes")
        found: dict[str, str] = {}
        if group is not None:
            group.visititems(lambda name, obj: found.__setitem__(name, _text(obj[()]))
                             if hasattr(obj, "shape") else None)
        return found

    @property
    def description(self) -> str | None:
        """The feeder description (TOML text, docs/feeders.md) the run's deck was generated
        from, or None for a run of a deck."""
        found = self.file[L.PARAMETERS].get("description")
        return None if found is None else _text(found[()])

    @property
    def stop_reason(self) -> str:
        """Why the engine ended the run (``"t_end"``, ``"target error 0.03 reached: ..."``:
        see :func:`.layout.stopped_early`); '' when unrecorded (before format 1.5, or a run
        that did not reach its end)."""
        return _text(self.file[L.RUN].attrs.get("stop_reason", ""))

    @property
    def target_error(self) -> float | None:
        """The feed rate's relative error the run was to stop at (``--target-error``), or None."""
        value = self.file[L.RUN].attrs.get("target_error")
        return None if value is None else float(value)

    @property
    def run_id(self) -> str:
        """The run's identity (SHA-256 of deck, includes, parameters, version); '' if absent."""
        return _text(self.file[L.RUN].attrs.get("id", ""))

    @property
    def deck_name(self) -> str:
        return _text(self.file[L.PARAMETERS]["deck"].attrs.get("name", ""))

    @property
    def liggghts_version(self) -> str:
        return _text(self.file[L.PARAMETERS]["liggghts_version"][()])

    @property
    def seed(self) -> int:
        return int(self.file[L.PARAMETERS]["seed"][()])

    @property
    def format_version(self) -> tuple[int, int]:
        """(major, minor) of the file's format; (1, 0) when unrecorded (the first files)."""
        version = self.file[L.PARAMETERS].attrs.get("format_version")
        return (1, 0) if version is None else tuple(int(v) for v in np.ravel(version)[:2])

    # -- sections of a feeder line --------------------------------------------------
    @cached_property
    def n_sections(self) -> int:
        """The track's sections: one per element of its feeder (a line's ``sections``), else 1."""
        return element_count(self.parameters)

    def section_surface(self, section: int, frames=None) -> tuple[np.ndarray, np.ndarray]:
        """(position, velocity) of section ``section``'s motion (1-based) at a frame
        selection (as for :meth:`read`): (frames, 3) [m], [m s-1], displacement from its
        place at rest, in the simulation frame. Section 1 is ``surface_position`` and
        ``surface_velocity``; a further section of a file that does not record it (a line
        of format 1.3) raises ResultError."""
        if not 1 <= section <= self.n_sections:
            raise IndexError(f"section {section} out of range: {self.path} has {self.n_sections} "
                             f"section{'s' if self.n_sections > 1 else ''} (1 to {self.n_sections})")
        prefix = "surface" if section == 1 else f"surface_s{section}"
        return (self.read(f"{prefix}_position", frames), self.read(f"{prefix}_velocity", frames))

    @cached_property
    def track_sections(self) -> np.ndarray | None:
        """(V,) the section (1-based) of each vertex of :attr:`track_mesh`, or None when the
        file does not say (a single track: every vertex moves with ``surface_position``)."""
        ds = self.file.get(L.TRACK_SECTION)
        return None if ds is None else ds[()].astype(np.int64)

    # -- reading by window ----------------------------------------------------------
    FIELDS = (*L.PART_ELEMENTS, *L.OPTIONAL_PART_ELEMENTS, "surface_position", "surface_velocity",
              "surface_angle", "surface_angular_velocity", "time", "step")
    """Names :meth:`read` knows: the per-part elements (``ids`` is an alias of
    ``id``), the surface's motion (a rotating surface's angle and angular velocity about z
    too: zeros where the surface does not rotate) and the frames' time and step; a feeder
    line's further sections too, as ``surface_s<k>_position`` and ``surface_s<k>_velocity``."""

    def _dataset(self, name: str):
        """(dataset, per_part) of a field name; (None, True) for an optional
        per-part element the file does not hold."""
        name = "id" if name == "ids" else name
        if name in L.PART_ELEMENTS:
            return self.file[L.PARTS][name]["value"], True
        if name in L.OPTIONAL_PART_ELEMENTS:
            group = self.file[L.PARTS].get(name)
            return (None if group is None else group["value"]), True
        if name.startswith("surface_") and name[len("surface_"):] in L.SURFACE_ELEMENTS:
            return self.file[L.SURFACE][name[len("surface_"):]]["value"], False
        if name.startswith("surface_") and name[len("surface_"):] in L.ROTATION_ELEMENTS:
            group = self.file[L.SURFACE].get(name[len("surface_"):])
            return (None if group is None else group["value"]), False
        section = _SECTION_FIELD.fullmatch(name)
        if section and int(section[1]) >= 2 and section[2] in L.SURFACE_ELEMENTS:
            k = int(section[1])
            group = self.file.get(L.surface_path(k))
            if group is None:
                raise ResultError(f"{self.path} records no motion of section {k} ("
                                  + (f"format {'.'.join(map(str, self.format_version))}: a line's "
                                     "sections are recorded from format 1.4 on)"
                                     if k <= self.n_sections else f"it has {self.n_sections} "
                                     f"section{'s' if self.n_sections > 1 else ''})"))
            return group[section[2]]["value"], False
        if name in ("time", "step"):
            return self.file[L.PARTS]["position"][name], False
        raise KeyError(f"no field {name!r} in a vibrofeed result; known: {', '.join(self.FIELDS)}")

    def read(self, name: str, frames=None, slots=None) -> np.ndarray:
        """Values of field ``name`` at a selection of frames (and slots).

        ``frames`` and ``slots`` select as numpy does along the first and
        second axes: None (all), an int (the axis is dropped), a slice, a
        sequence of indices (any order, repeats allowed) or a boolean mask.
        Only the selected frames are read from the file.

        >>> r.read("position", frames=slice(0, None, 10))   # (frames/10, slots, 3)
        >>> r.read("id", frames=[0, -1])                     # first and last frame
        >>> r.read("surface_position", frames=-1)            # (3,)
        """
        ds, per_part = self._dataset(name)
        if ds is None and not per_part:  # a surface that does not rotate: zeros, one per frame
            times = self.read("time", frames)
            return np.zeros((*np.shape(times), 3))
        if ds is None:  # absent optional element: its default where a part is
            return self._default(name, self.read("id", frames, slots))
        f = _normalise(frames, ds.shape[0])
        if not per_part:
            if slots is not None:
                raise IndexError(f"{name!r} has no slots to select")
            return _read_axis0(ds, f, ())
        s = _normalise(slots, ds.shape[1])
        if isinstance(s, np.ndarray):  # h5py takes one list: read the slots' span, pick in memory
            lo, hi = (int(s.min()), int(s.max()) + 1) if len(s) else (0, 0)
            block = _read_axis0(ds, f, (slice(lo, hi),))
            return np.take(block, s - lo, axis=0 if isinstance(f, int) else 1)
        return _read_axis0(ds, f, (s,))

    def gather(self, name: str, frames, slots) -> np.ndarray:
        """Values of per-part field ``name`` at the pairs (frames[k], slots[k]).

        A part keeps its slot while it exists, so its pairs form runs of one
        slot over increasing frames: each run is one read of one column.
        """
        frames = np.asarray(frames, dtype=np.int64)
        slots = np.asarray(slots, dtype=np.int64)
        ds, per_part = self._dataset(name)
        if not per_part:
            raise KeyError(f"{name!r} is not a per-part field")
        if ds is None:
            return self._default(name, self.gather("id", frames, slots))
        out = np.empty((len(frames), *ds.shape[2:]), dtype=ds.dtype)
        if len(frames) == 0:
            return out
        cuts = np.nonzero((np.diff(slots) != 0) | (np.diff(frames) <= 0))[0] + 1
        for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(frames)]):
            out[a:b] = _read_axis0(ds, frames[a:b], (int(slots[a]),))
        return out

    @staticmethod
    def _default(name: str, ids: np.ndarray) -> np.ndarray:
        """An absent optional element read at ``ids``: identity where a part is, NaN elsewhere."""
        _, comps, _ = L.OPTIONAL_PART_ELEMENTS[name]
        out = np.full((*np.shape(ids), comps), np.nan)
        out[np.asarray(ids) != L.ID_FILL] = L.IDENTITY_QUATERNION
        return out

    def holds(self, name: str) -> bool:
        """Whether the file records field ``name``: an optional element such as a rotating
        surface's ``surface_angle`` (format 1.6) or the bodies' ``orientation``. Which feeder
        made it is the feeder's to say (vibrofeed.feeders), not the file's."""
        return self._dataset(name)[0] is not None

    def recorded(self, name: str, frames=None) -> bool:
        """Whether per-part field ``name`` holds values, judged at the first (selected) frame
        with parts: the force of clumps is NaN at every frame by design (FORMAT.md, "Bulk
        feeders"), that of spheres at none. True for a file without parts."""
        ds, per_part = self._dataset(name)
        if not per_part:
            raise KeyError(f"{name!r} is not a per-part field")
        if ds is None:
            return False
        if not np.issubdtype(ds.dtype, np.floating):
            return True
        for f in self.iter_frames(frames, fields=(name,)):
            if len(f):
                return bool(np.isfinite(f[name]).any())
        return True

    # -- bulk feeders ---------------------------------------------------------------
    @cached_property
    def outlet(self) -> dict[str, np.ndarray]:
        """The outlet events, one row per part that left the track: ``time`` (E,) [s],
        ``id`` (E,), ``position`` (E, 3) [m], ``velocity`` (E, 3) [m s-1],
        ``orientation`` (E, 4); empty arrays when the file has no event table."""
        return self._events(L.outlet_path(self.file), L.OUTLET_ELEMENTS)

    @cached_property
    def rejects(self) -> dict[str, np.ndarray]:
        """A feeder line's rejects, one row per part fallen off a side: as :attr:`outlet`,
        plus ``section`` (E,) (1-based); empty arrays when the file has no reject table."""
        return self._events(L.REJECTS if L.REJECTS in self.file else None, L.REJECT_ELEMENTS)

    @cached_property
    def jet_firings(self) -> dict[str, np.ndarray]:
        """A line's air jet firings, one row per part sensed in a state the jet does not keep
        (or too soon after the last it passed, its ``headway``):
        ``time`` (sensed), ``id``, ``section``, ``state`` (index into
        vibrofeed.orientation.STATES), ``start``, ``end`` (its window) [s], ``late`` (E,);
        empty arrays when the file has no jet table."""
        return self._events(L.JET if L.JET in self.file else None, L.JET_ELEMENTS)

    def _events(self, path: str | None, elements: dict) -> dict[str, np.ndarray]:
        group = None if path is None else self.file[path]
        out = {}
        for name, (dtype, comps, _) in elements.items():
            if group is not None and name in group:
                out[name] = group[name][()]
            else:
                out[name] = np.empty((0, comps) if comps else (0,), dtype=dtype)
        return out

    @property
    def outlet_plane(self) -> dict | None:
        """``{"outlet_x", "catch_z", "method"}`` of the outlet, or None without one."""
        where = L.outlet_path(self.file)
        if where is None:
            return None
        group = self.file[where]
        return {"outlet_x": float(group.attrs.get("outlet_x", np.nan)),
                "catch_z": float(group.attrs.get("catch_z", np.nan)),
                "method": _text(group.attrs.get("method", ""))}

    @cached_property
    def mass_balance(self) -> dict[str, np.ndarray] | None:
        """``{inserted, on_track, exited, lost}`` (and a feeder line's ``rejected``, and
        ``returned`` where it recirculates) -> (frames,) int64, or None when absent."""
        group = self.file.get(L.MASS_BALANCE)
        if group is None:
            return None
        return {name: group[name]["value"][()] for name in L.RETURN_COUNTS if name in group}

    @cached_property
    def track_mesh(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(vertices (V, 3) [m], triangles (T, 3) int32) of the track at rest, or None."""
        group = self.file.get(L.TRACK)
        if group is None:
            return None
        return group["vertices"][()], group["triangles"][()]

    @cached_property
    def body_template(self) -> np.ndarray | None:
        """(n, 4) x, y, z, r [m] of a clump's spheres in the body frame, or None."""
        ds = self.file.get(L.BODY_TEMPLATE)
        return None if ds is None else ds[()]

    @property
    def n_frames(self) -> int:
        return len(self.file[L.PARTS]["position/step"])

    @property
    def n_slots(self) -> int:
        """Width of the per-part arrays: the most particles present at once."""
        return self.file[L.PARTS]["id/value"].shape[1]

    # -- parts ----------------------------------------------------------------------
    def frame_indices(self, frames=None) -> np.ndarray:
        """The frame numbers a selection (as for :meth:`read`) stands for."""
        f = _normalise(frames, self.n_frames)
        if isinstance(f, slice):
            return np.arange(f.start, f.stop, f.step)
        return np.atleast_1d(np.asarray(f, dtype=np.int64))

    def _id_blocks(self, frames=None):
        """(frame numbers, ids) in blocks of bounded size, over a frame selection."""
        index = self.frame_indices(frames)
        if "ids" in self.__dict__:  # already in memory
            yield index, self.ids[index]
            return
        per_block = max(1, _BLOCK_VALUES // max(self.n_slots, 1))
        for a in range(0, len(index), per_block):
            block = index[a:a + per_block]
            yield block, self.read("id", frames=block)

    @cached_property
    def part_ids(self) -> np.ndarray:
        """Every particle id that appears in the run, sorted."""
        found = [np.unique(ids[ids != L.ID_FILL]) for _, ids in self._id_blocks()]
        return np.unique(np.concatenate(found)) if found else np.empty(0, dtype=np.int64)

    def present(self, frames=None) -> np.ndarray:
        """(frames,) number of particles present at each (selected) frame."""
        counts = [(ids != L.ID_FILL).sum(axis=1) for _, ids in self._id_blocks(frames)]
        return np.concatenate(counts) if counts else np.empty(0, dtype=np.int64)

    def locate(self, part_id: int, frames=None) -> tuple[np.ndarray, np.ndarray]:
        """(frames, slots) where particle ``part_id`` is, over a frame selection."""
        found_f, found_s = [], []
        for index, ids in self._id_blocks(frames):
            rows, cols = np.nonzero(ids == part_id)
            found_f.append(index[rows])
            found_s.append(cols)
        if not found_f:
            return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
        return np.concatenate(found_f), np.concatenate(found_s).astype(np.int64)

    def track(self, part_id: int, quantity: str = "position", frames=None):
        """(time, values) of one particle over the frames where it exists (within
        a frame selection); reads that particle's column of one field only."""
        where, slots = self.locate(part_id, frames)
        if len(where) == 0:
            raise KeyError(f"particle id {part_id} does not appear in {self.path}")
        return self.time[where], self.gather(quantity, where, slots)

    def frame(self, index: int, fields=("position",)) -> Frame:
        """The parts present at frame ``index`` with the ``fields`` asked for
        (per-part fields: one row per present part; surface fields: (3,))."""
        return next(self.iter_frames([index], fields))

    def iter_frames(self, frames=None, fields=("position",)):
        """:class:`Frame` after :class:`Frame` over a frame selection, read in blocks."""
        for index, ids in self._id_blocks(frames):
            values = {name: self.read(name, frames=index) for name in fields}
            per_part = {name: self._dataset(name)[1] for name in fields}
            for k, i in enumerate(index):
                slots = np.nonzero(ids[k] != L.ID_FILL)[0]
                per_frame = {name: (v[k][slots] if per_part[name] else v[k])
                             for name, v in values.items()}
                yield Frame(int(i), float(self.time[i]), int(self.step[i]), ids[k][slots],
                            slots, per_frame)

    # -- lifetime -------------------------------------------------------------------
    def close(self) -> None:
        if self.file.id.valid and not self._borrowed:
            self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        damage = unreadable(exc, self.path) if exc is not None else None  # (while the file is open)
        self.close()
        if damage is not None:  # an h5py error reading this file: one line naming it
            raise damage from exc

    def __repr__(self) -> str:
        return (f"Result({self.path!r}, deck={self.deck_name!r}, frames={self.n_frames}, "
                f"status={self.status!r})")


def _whole_arrays() -> dict:
    """attribute -> (field, docstring) of every whole array, from the layout."""
    out = {"time": ("time", "(frames,) simulated time of each frame [s]."),
           "step": ("step", "(frames,) engine step of each frame.")}
    for name, (_, comps, unit) in (*L.PART_ELEMENTS.items(), *L.OPTIONAL_PART_ELEMENTS.items()):
        shape = f"(frames, slots, {comps})" if comps else "(frames, slots)"
        unit = f" [{unit}]" if unit else ""
        out["ids" if name == "id" else name] = (name, f"{shape} {name} of each slot{unit}; "
                                                      "a fill value (-1 or NaN) where it is empty.")
    for name, (_, comps, unit) in L.SURFACE_ELEMENTS.items():
        out[f"surface_{name}"] = (f"surface_{name}", f"(frames, {comps}) {name} of the surface [{unit}].")
    return out


for _attr, (_field, _doc) in _whole_arrays().items():
    setattr(Result, _attr, _Whole(_attr, _field, _doc))
del _attr, _field, _doc
