"""Validate a result file against the layout in FORMAT.md (``vibrofeed check``),
and look for results that cannot be physical (FORMAT.md, "What check checks")."""

from __future__ import annotations

import math
from dataclasses import dataclass

import h5py
import numpy as np

from ..errors import ParameterError, said
from ..feeders.bowl import TURN_NAMES, Turn
from ..feeders.feeder import Feeder, element_count
from ..limits import JET_THROW, MIN_SPEED_LIMIT, SPEED_FACTOR
from ..models.constants import G
from . import layout as L
from .reader import DAMAGED, _text, damaged_object, not_hdf5


@dataclass(frozen=True)
class Problem:
    level: str  # "error" or "warning"
    where: str  # HDF5 path
    message: str

    def __str__(self) -> str:
        return f"{self.level}: /{self.where}: {self.message}"


@dataclass
class Report:
    path: str
    problems: list
    frames: int = 0
    parts: int = 0
    status: str = ""

    @property
    def ok(self) -> bool:
        return not any(p.level == "error" for p in self.problems)


def numeric_parameters(f: h5py.File) -> dict[str, float]:
    """The file's deck variables that are numbers (strings of numbers included)."""
    variables = f.get(L.VARIABLES)
    out = {}
    for name, ds in (variables.items() if isinstance(variables, h5py.Group) else ()):
        try:
            out[name] = float(_text(ds[()]) if ds.dtype.kind in "SOU" else ds[()])
        except (TypeError, ValueError):
            pass
    return out


def feeder_of_numbers(params: dict[str, float]) -> Feeder | None:
    """The feeder a file's numeric parameters describe, or None: not a feeder's vocabulary (a
    deck of one's own, a synthetic file's few numbers), or values no feeder is made of."""
    try:
        return Feeder.from_values(params)
    except (ParameterError, KeyError, ValueError, ArithmeticError):
        return None


def format_version(f: h5py.File) -> tuple[int, int]:
    version = f[L.PARAMETERS].attrs.get("format_version") if L.PARAMETERS in f else None
    try:
        return tuple(int(v) for v in np.ravel(version)[:2]) if version is not None else (1, 0)
    except (TypeError, ValueError):
        return (1, 0)


class _Checker:
    def __init__(self, f: h5py.File, allow_incomplete: bool):
        self.f = f
        self.allow_incomplete = allow_incomplete
        self.problems: list[Problem] = []
        self.frames = 0
        params = numeric_parameters(f)
        # the feeder its parameters describe, read once (None: not a feeder's vocabulary)
        self.feeder = feeder_of_numbers(params)
        # the sections whose motion the file records (format 1.4 on): one per element of its
        # feeder (FORMAT.md, "Feeder lines")
        self.sections = element_count(params)
        self.records_sections = format_version(f) >= L.SECTIONS_SINCE

    @property
    def further_sections(self) -> range:
        """The sections after the first whose motion the file records (2 ... sections): a
        line's, a bowl's exit line's; none for a single track or a bowl alone."""
        return range(2, self.sections + 1)

    def error(self, where, message):
        self.problems.append(Problem("error", where, message))

    def warn(self, where, message):
        self.problems.append(Problem("warning", where, message))

    def need(self, path, kind=None) -> bool:
        obj = self.f.get(path)
        if obj is None:
            self.error(path, "missing")
            return False
        if kind is not None and not isinstance(obj, kind):
            self.error(path, f"must be a {'group' if kind is h5py.Group else 'dataset'}")
            return False
        return True

    def need_text_attr(self, path, name):
        obj = self.f[path]
        if name not in obj.attrs:
            self.error(path, f"attribute '{name}' missing")
        elif not _text(obj.attrs[name]):
            self.error(path, f"attribute '{name}' is empty")

    # -- sections -----------------------------------------------------------------
    def h5md(self):
        if not self.need("h5md", h5py.Group):
            return
        version = self.f["h5md"].attrs.get("version")
        if version is None or list(np.ravel(version)) != list(L.H5MD_VERSION):
            self.error("h5md", f"attribute 'version' must be {list(L.H5MD_VERSION)}, got {version}")
        if self.need("h5md/author", h5py.Group):
            self.need_text_attr("h5md/author", "name")
        if self.need("h5md/creator", h5py.Group):
            self.need_text_attr("h5md/creator", "name")
            self.need_text_attr("h5md/creator", "version")

    def time_series(self, path, comps, unit, n_parts=None):
        """Check one time-dependent element; return its value dataset or None."""
        if not self.need(path, h5py.Group):
            return None
        ok = all(self.need(f"{path}/{k}", h5py.Dataset) for k in ("step", "time", "value"))
        if not ok:
            return None
        g = self.f[path]
        step, time, value = g["step"], g["time"], g["value"]
        n = len(step)
        if len(time) != n or value.shape[0] != n:
            self.error(path, f"step ({n}), time ({len(time)}) and value ({value.shape[0]}) "
                             "frame counts differ")
        if step.dtype.kind not in "iu":
            self.error(f"{path}/step", "must be of integer type")
        expected_rank = 1 + (n_parts is not None) + (comps > 0)
        if value.ndim != expected_rank:
            self.error(f"{path}/value", f"rank {value.ndim}, expected {expected_rank}")
        elif comps and value.shape[-1] != comps:
            self.error(f"{path}/value", f"last dimension {value.shape[-1]}, expected {comps}")
        if unit and _text(value.attrs.get("unit", "")) != unit:
            self.error(f"{path}/value", f"unit attribute must be '{unit}'")
        if _text(time.attrs.get("unit", "")) != L.TIME_UNIT:
            self.error(f"{path}/time", f"unit attribute must be '{L.TIME_UNIT}'")
        s, t = step[()], time[()]
        if n > 1 and np.any(np.diff(s) <= 0):
            self.error(f"{path}/step", "not strictly increasing")
        if n > 1 and np.any(np.diff(t) < 0):
            self.error(f"{path}/time", "not monotonically increasing")
        return value

    def box_pbc(self, box, periodic: list) -> None:
        """box/pbc, when present: a time series with the positions' step, saying at every
        frame what `boundary` says (for readers that take the periodicity from it)."""
        where = f"{L.PARTS}/box/pbc"
        value = box["pbc"].get("value") if isinstance(box["pbc"], h5py.Group) else None
        if not isinstance(value, h5py.Dataset) or value.ndim != 2 or value.shape[1:] != (3,) \
                or value.dtype.kind != "b":
            self.error(where, "must be a time series of 3 booleans per frame")
            return
        step, step0 = box["pbc"].get("step"), self.f.get(f"{L.PARTS}/position/step")
        if step0 is not None and (step is None or len(step) != len(step0) or len(value) != len(step0)
                                  or not np.array_equal(step[()], step0[()])):
            self.error(where, "must be sampled with the positions (their step)")
        elif not (value[()] == np.array(periodic)).all():
            axes = ", ".join(f"{a} {'periodic' if p else 'none'}" for a, p in zip("xyz", periodic))
            self.error(where, f"disagrees with the box's boundary ({axes})")

    def particles(self):
        if not self.need(L.PARTS, h5py.Group):
            return 0
        if self.need(f"{L.PARTS}/box", h5py.Group):
            box = self.f[f"{L.PARTS}/box"]
            if int(box.attrs.get("dimension", -1)) != 3:
                self.error(f"{L.PARTS}/box", "attribute 'dimension' must be 3")
            boundary = [_text(b) for b in np.ravel(box.attrs.get("boundary", []))]
            if len(boundary) != 3 or any(b not in ("none", "periodic") for b in boundary):
                self.error(f"{L.PARTS}/box",
                           f"attribute 'boundary' must be 3 of none/periodic, got {boundary}")
            elif "pbc" in box:  # (optional: files before it have none)
                self.box_pbc(box, [b == "periodic" for b in boundary])
        values = {}
        for name, (_, comps, unit) in L.PART_ELEMENTS.items():
            v = self.time_series(f"{L.PARTS}/{name}", comps, unit, n_parts=True)
            if v is not None:
                values[name] = v
        step0 = self.f.get(f"{L.PARTS}/position/step")
        if step0 is not None:
            self.frames = len(step0)
            for name in values:
                other = self.f[f"{L.PARTS}/{name}/step"]
                if len(other) != self.frames or not np.array_equal(other[()], step0[()]):
                    self.error(f"{L.PARTS}/{name}/step", "differs from position/step")
        shapes = {v.shape[:2] for v in values.values()}
        if len(shapes) > 1:
            self.error(L.PARTS, f"elements disagree on (frames, slots): {sorted(shapes)}")
            return 0
        if "id" not in values:
            return 0
        ids = values["id"]
        if ids.fillvalue != L.ID_FILL:
            self.error(f"{L.PARTS}/id/value", f"fill value must be {L.ID_FILL}, got {ids.fillvalue}")
        ids = ids[()]
        # every frame at once (a loop over frames cost more than the rest of a short run's check)
        ordered = np.sort(ids, axis=1)
        twice = ((ordered[:, 1:] == ordered[:, :-1]) & (ordered[:, 1:] != L.ID_FILL)).any(axis=1)
        negative = ((ids < 0) & (ids != L.ID_FILL)).any(axis=1)
        if twice.any():
            self.error(f"{L.PARTS}/id/value", f"frame {int(np.argmax(twice))}: duplicate ids")
        elif negative.any():
            self.error(f"{L.PARTS}/id/value",
                       f"frame {int(np.argmax(negative))}: negative id other than the fill value")
        if "position" in values:
            pos = values["position"][()]
            empty, live = ids == L.ID_FILL, ids != L.ID_FILL
            if np.any(np.isfinite(pos[empty])):
                self.error(f"{L.PARTS}/position/value", "empty slots (id -1) must hold NaN")
            if np.any(~np.isfinite(pos[live])):
                self.error(f"{L.PARTS}/position/value", "an existing particle has a non-finite position")
        self.orientation(ids)
        self.live = (ids != L.ID_FILL).sum(axis=1)
        live_ids = ids[ids != L.ID_FILL]
        return len(np.unique(live_ids))

    # -- bulk feeders: optional sections, checked when present ----------------------
    def orientation(self, ids):
        path = f"{L.PARTS}/orientation"
        if path not in self.f:
            return
        _, comps, unit = L.OPTIONAL_PART_ELEMENTS["orientation"]
        v = self.time_series(path, comps, unit, n_parts=True)
        if v is None:
            return
        if v.shape[:2] != ids.shape:
            self.error(f"{path}/value", f"(frames, slots) {v.shape[:2]}, id has {ids.shape}")
            return
        if not np.array_equal(self.f[f"{path}/step"][()], self.f[f"{L.PARTS}/position/step"][()]):
            self.error(f"{path}/step", "differs from position/step")
        q = v[()]
        live = ids != L.ID_FILL
        if np.any(np.isfinite(q[~live])):
            self.error(f"{path}/value", "empty slots (id -1) must hold NaN")
        norm = np.linalg.norm(q[live], axis=-1)
        if np.any(~np.isfinite(norm)) or np.any(np.abs(norm - 1) > 1e-6):
            self.error(f"{path}/value", "an existing part's orientation is not a unit quaternion")

    def outlet(self, group: str | None = None):
        """The outlet's event table (format 1.3, or observables/outlet before), or a feeder
        line's rejects (``group`` L.REJECTS); its length."""
        where = L.outlet_path(self.f) if group is None else (group if group in self.f else None)
        if where is None or not self.need(where, h5py.Group):
            return 0
        g = self.f[where]
        for name in L.OUTLET_ATTRIBUTES:
            if name not in g.attrs:
                self.error(where, f"attribute '{name}' missing")
        n = None
        table = {}
        elements = L.REJECT_ELEMENTS if group == L.REJECTS else L.OUTLET_ELEMENTS
        for name, (_, comps, unit) in elements.items():
            path = f"{where}/{name}"
            if not self.need(path, h5py.Dataset):
                continue
            ds = g[name]
            expected = (comps,) if comps else ()
            if ds.ndim != 1 + bool(comps) or ds.shape[1:] != expected:
                self.error(path, f"shape {ds.shape}, expected (E{', ' + str(comps) if comps else ''})")
                continue
            if unit and _text(ds.attrs.get("unit", "")) != unit:
                self.error(path, f"unit attribute must be '{unit}'")
            if n is not None and ds.shape[0] != n:
                self.error(where, "the event datasets differ in length")
                return 0
            n = ds.shape[0]
            table[name] = ds[()]
        if "id" in table and len(np.unique(table["id"])) != len(table["id"]):
            self.error(f"{where}/id", "a part left the track more than once")
        for name, values in table.items():
            if values.dtype.kind == "f" and np.any(~np.isfinite(values)):
                self.error(f"{where}/{name}", "non-finite values")
        if "orientation" in table and len(table["orientation"]):
            norm = np.linalg.norm(table["orientation"], axis=1)
            if np.any(np.abs(norm - 1) > 1e-6):
                self.error(f"{where}/orientation", "not unit quaternions")
        return n or 0

    def mass_balance(self, events: int, status: str, rejects: int = 0):
        """The counts must add up, and no part may be lost (FORMAT.md, "Mass balance");
        a feeder line's counts its rejects too (L.LINE_COUNTS)."""
        if L.MASS_BALANCE not in self.f:
            return
        line = "rejected" in self.f[L.MASS_BALANCE]
        returns = "returned" in self.f[L.MASS_BALANCE]
        names = L.RETURN_COUNTS if returns else L.LINE_COUNTS if line else L.MASS_BALANCE_COUNTS
        counts = {}
        for name in names:
            path = f"{L.MASS_BALANCE}/{name}"
            v = self.time_series(path, 0, None)
            if v is None:
                continue
            if v.shape[0] != self.frames:
                self.error(path, f"{v.shape[0]} frames, particles have {self.frames}")
                continue
            if v.dtype.kind not in "iu":
                self.error(f"{path}/value", "must be of integer type")
            if self.frames and not np.array_equal(self.f[f"{path}/step"][()],
                                                  self.f[f"{L.PARTS}/position/step"][()]):
                self.error(f"{path}/step", "not sampled at the particle frames")
            counts[name] = v[()].astype(np.int64)
        if len(counts) != len(names) or self.frames == 0:
            return
        if any(np.any(c < 0) for c in counts.values()):
            self.error(L.MASS_BALANCE, "negative counts (frames without a mass balance)")
            return
        lost = np.nonzero(counts["lost"])[0]
        if len(lost):
            k = int(lost[0])
            self.error(f"{L.MASS_BALANCE}/lost",
                       f"{int(counts['lost'][k])} part(s) lost at frame {k} (t = "
                       f"{self.f[f'{L.PARTS}/position/time'][k]:g} s): they disappeared without "
                       "an outlet event")
        gone = counts["exited"] + counts.get("rejected", 0)  # left the track: still falling, or removed
        for name in ("inserted", "exited", "rejected", "returned")[:2 + line + returns]:
            if np.any(np.diff(counts[name]) < 0):
                self.error(f"{L.MASS_BALANCE}/{name}", "decreases")
        if returns and np.any(counts["returned"] > counts["rejected"]):
            self.error(f"{L.MASS_BALANCE}/returned", "more parts returned to the inlet than rejected")
        if np.any(counts["inserted"] != counts["on_track"] + gone + counts["lost"]):
            self.error(L.MASS_BALANCE, "inserted differs from on_track + exited + "
                                       f"{'rejected + ' if line else ''}lost")
        # present parts are on the track or falling (exited, not yet removed)
        live = getattr(self, "live", None)
        if live is not None and len(live) == self.frames:
            falling = live - counts["on_track"]
            if np.any(falling < 0) or np.any(falling > gone):
                self.error(L.MASS_BALANCE, "on_track does not match the parts present "
                                           "(on_track <= present <= on_track + exited"
                                           f"{' + rejected' if line else ''})")
        if status == L.STATUS_COMPLETE and int(counts["exited"][-1]) != events:
            self.error(f"{L.MASS_BALANCE}/exited",
                       f"{int(counts['exited'][-1])} exited at the last frame, {events} outlet events")
        if line and status == L.STATUS_COMPLETE and int(counts["rejected"][-1]) != rejects:
            self.error(f"{L.MASS_BALANCE}/rejected",
                       f"{int(counts['rejected'][-1])} rejected at the last frame, {rejects} reject events")

    def track(self):
        if L.TRACK in self.f and self.need(L.TRACK, h5py.Group):
            for name in ("vertices", "triangles"):
                self.need(f"{L.TRACK}/{name}", h5py.Dataset)
            if {"vertices", "triangles"} <= set(self.f[L.TRACK]):
                v, t = self.f[L.TRACK]["vertices"], self.f[L.TRACK]["triangles"]
                if v.ndim != 2 or v.shape[1] != 3 or np.any(~np.isfinite(v[()])):
                    self.error(f"{L.TRACK}/vertices", "must be (V, 3) finite")
                elif t.ndim != 2 or t.shape[1] != 3 or t.dtype.kind not in "iu":
                    self.error(f"{L.TRACK}/triangles", "must be (T, 3) integers")
                elif t.shape[0] and (t[()].min() < 0 or t[()].max() >= v.shape[0]):
                    self.error(f"{L.TRACK}/triangles", "index a vertex that does not exist")
                if _text(v.attrs.get("unit", "")) != "m":
                    self.error(f"{L.TRACK}/vertices", "unit attribute must be 'm'")
                self.track_sections(v.shape[0])
        if L.BODY_TEMPLATE in self.f:
            b = self.f[L.BODY_TEMPLATE]
            if not isinstance(b, h5py.Dataset) or b.ndim != 2 or b.shape[1] != 4:
                self.error(L.BODY_TEMPLATE, "must be an (n, 4) dataset: x, y, z, r")
            elif np.any(~np.isfinite(b[()])) or np.any(b[()][:, 3] <= 0):
                self.error(L.BODY_TEMPLATE, "non-finite values or radii <= 0")

    def track_sections(self, n_vertices: int):
        """A line's split of the track into sections (FORMAT.md, "Feeder lines")."""
        if L.TRACK_SECTION not in self.f:
            if self.further_sections and self.records_sections:
                self.error(L.TRACK_SECTION, f"missing: a line of {self.sections} sections must say "
                                            "which section each track vertex belongs to")
            return
        ds = self.f[L.TRACK_SECTION]
        if not isinstance(ds, h5py.Dataset) or ds.shape != (n_vertices,) or ds.dtype.kind not in "iu":
            self.error(L.TRACK_SECTION, f"must be ({n_vertices},) integers: one section per vertex")
        elif n_vertices and (ds[()].min() < 1 or ds[()].max() > self.sections):
            self.error(L.TRACK_SECTION, f"sections must lie in 1..{self.sections}")

    def surface(self):
        """Each section's motion: section 1's in every file, the further ones in a line's."""
        for k in range(1, self.sections + 1):
            path = L.surface_path(k)
            if k > 1 and path not in self.f:
                message = (f"missing: section {k}'s motion (the line has {self.sections} sections; "
                           "its sine drive must be recorded)")
                if self.records_sections:
                    self.error(path, message)
                else:  # format 1.3 lines did not record it: they still read
                    self.warn(path, f"{message}, not recorded before format 1.4")
                continue
            self.section_surface(path)
        observables = self.f.get("observables")
        for name in (observables if isinstance(observables, h5py.Group) else ()):
            k = name[len("surface_s"):] if name.startswith("surface_s") else ""
            if k.isdigit() and not 2 <= int(k) <= self.sections:
                self.error(f"observables/{name}", f"the motion of a section the run does not have "
                                                  f"(sections = {self.sections})")

    def section_surface(self, group: str):
        elements = dict(L.SURFACE_ELEMENTS)
        g = self.f.get(group)
        rotation = [n for n in L.ROTATION_ELEMENTS if isinstance(g, h5py.Group) and n in g]
        if rotation and group != L.SURFACE:
            self.error(f"{group}/{rotation[0]}", "only the first section's surface may rotate")
        elif rotation and len(rotation) < len(L.ROTATION_ELEMENTS):
            missing = [n for n in L.ROTATION_ELEMENTS if n not in rotation]
            self.error(group, f"a rotating surface records {', '.join(L.ROTATION_ELEMENTS)}: "
                              f"{', '.join(missing)} missing")
        elif rotation:
            elements.update(L.ROTATION_ELEMENTS)
        for name, (_, comps, unit) in elements.items():
            path = f"{group}/{name}"
            v = self.time_series(path, comps, unit)
            if v is None:
                continue
            if v.shape[0] != self.frames:
                self.error(path, f"{v.shape[0]} frames, particles have {self.frames}")
            elif self.frames and not np.array_equal(self.f[f"{path}/step"][()],
                                                    self.f[f"{L.PARTS}/position/step"][()]):
                self.error(f"{path}/step", "not sampled at the particle frames")
            if v.shape[0] and np.any(~np.isfinite(v[()])):
                self.error(f"{path}/value", "non-finite values")

    def parameters(self):
        if not self.need(L.PARAMETERS, h5py.Group):
            return ""
        for name in ("deck", "liggghts_version", "seed"):
            self.need(f"{L.PARAMETERS}/{name}", h5py.Dataset)
        if f"{L.PARAMETERS}/deck" in self.f and not _text(self.f[f"{L.PARAMETERS}/deck"][()]).strip():
            self.error(f"{L.PARAMETERS}/deck", "deck text is empty")
        if f"{L.PARAMETERS}/liggghts_version" in self.f:
            if "LIGGGHTS" not in _text(self.f[f"{L.PARAMETERS}/liggghts_version"][()]):
                self.error(f"{L.PARAMETERS}/liggghts_version", "does not name a LIGGGHTS version")
        if self.need(L.VARIABLES, h5py.Group):
            if len(self.f[L.VARIABLES]) == 0:
                self.error(L.VARIABLES, "no deck variables recorded")
            for name, ds in self.f[L.VARIABLES].items():
                if "unit" not in ds.attrs:
                    self.error(f"{L.VARIABLES}/{name}", "attribute 'unit' missing")
        self.need(L.DERIVED, h5py.Group)
        if not self.need(L.RUN, h5py.Group):
            return ""
        rid = _text(self.f[L.RUN].attrs.get("id", ""))
        if len(rid) != 64 or any(c not in "0123456789abcdef" for c in rid):
            self.warn(L.RUN, "attribute 'id' (the run's SHA-256 identity) missing or malformed: "
                             "--reuse cannot recognise this run")
        status = _text(self.f[L.RUN].attrs.get("status", ""))
        if status not in L.STATUSES:
            self.error(L.RUN, f"unknown status '{said(status)}'")
        elif status != L.STATUS_COMPLETE:
            msg = _text(self.f[L.RUN].attrs.get("message", ""))
            hint = {L.STATUS_RUNNING: "the run was killed or is still going"}.get(status, msg)
            text = f"run status is '{said(status)}'" + (f": {hint}" if hint else "")
            (self.warn if self.allow_incomplete else self.error)(L.RUN, text)
        self.stop()
        return status

    def stop(self):
        """Why the run ended and its target error, where recorded (optional in format 1.5)."""
        attrs = self.f[L.RUN].attrs
        target = attrs.get("target_error")
        if target is not None and not (np.ndim(target) == 0 and np.asarray(target).dtype.kind == "f"
                                       and 0 < float(target) < 1):
            self.error(L.RUN, f"attribute 'target_error' must be a number in (0, 1), got {said(target)}")
        if "stop_reason" not in attrs:
            return
        reason = _text(attrs["stop_reason"])
        if not reason.startswith((L.STOP_AT_END, L.STOP_AT_TARGET)):
            self.error(L.RUN, f"attribute 'stop_reason' must start with '{L.STOP_AT_END}' or "
                              f"'{L.STOP_AT_TARGET}', got '{said(reason)}'")
        elif L.stopped_early(reason) and target is None:
            self.error(L.RUN, "attribute 'stop_reason' says the target error was reached, but the "
                              "run records no 'target_error'")


# Frames read at once by the physical checks (values of one float element).
_BLOCK_VALUES = 2_000_000
# A line's further sections must sit where their sine drive puts them to this fraction of the
# amplitude (the velocity: of the peak speed): the recorded motion is the engine's closed form
# of it, to float rounding (~1e-12 of the amplitude over 10^7 steps), so 1e-6 leaves room for
# rounding and still finds a drive recorded 1e-5 off. Plus an absolute floor for a drive of
# amplitude 0 (the values are then 0 to rounding).
DRIVE_RTOL = 1e-6
DRIVE_ATOL = {"position": 1e-15, "velocity": 1e-12}  # m, m/s


def sine_drive(freq, amp_t, amp_n, phase, dt, step, time, amp_c=0.0, phase_c=0.0):
    """((n, 3) position [m], (n, 3) velocity [m/s]) of a section under LIGGGHTS' sine movers at
    ``step`` (n,) and ``time`` (n,) [s], from where it was placed at t = 0 (amp_n sin(phi) along
    z, amp_c sin(phi_c) along y; FORMAT.md, "Feeder lines").

    wiggle (x) and viblin (z) move the mesh by v(t_j) dt at each step j = 1..n, v = A w cos(w t
    + phi), so x(n) = A w dt sum_j cos(j th + phi), th = w dt, which sums to
    A w dt sin(n th / 2) cos((n + 1) th / 2 + phi) / sin(th / 2) (as the deck's surface_* of
    include/surface_motion.liggghts); the velocity is the movers' v(t) itself."""
    step = np.asarray(step, dtype=float)
    time = np.asarray(time, dtype=float)
    w = 2 * math.pi * freq
    phi = math.radians(phase)
    half = w * dt / 2
    gain = w * dt / math.sin(half) if half else 0.0  # 2 (1 + th^2/24 ...): the sum's scale
    ramp = np.sin(step * half)
    x = amp_t * gain * ramp * np.cos((step + 1) * half)
    vx = amp_t * w * np.cos(w * time)

    def viblin(amp, lead):  # (z and y: placed at amp sin(lead), then the movers' sum)
        return (amp * math.sin(lead) + amp * gain * ramp * np.cos((step + 1) * half + lead),
                amp * w * np.cos(w * time + lead))

    y, vy = viblin(amp_c, math.radians(phase_c))
    z, vz = viblin(amp_n, phi)
    return np.column_stack([x, y, z]), np.column_stack([vx, vy, vz])


class _Physics:
    """The physical checks of one file whose layout checked out."""

    def __init__(self, c: _Checker):
        self.c, self.f = c, c.f
        self.p = numeric_parameters(self.f)

    def _motions(self, element: str) -> list[np.ndarray]:
        """Every recorded section's ``element`` (position or velocity), (frames, 3) each."""
        out = []
        for k in range(1, self.c.sections + 1):
            path = f"{L.surface_path(k)}/{element}/value"
            ds = self.f.get(path)
            if isinstance(ds, h5py.Dataset) and ds.ndim == 2 and ds.shape[0] and ds.shape[1] == 3:
                out.append(ds[()])
        return out

    def step(self) -> None:
        """A fixed dt beyond the contact's limits (vibrofeed.parameters)."""
        from ..parameters import step_beyond_contact

        try:
            problem = step_beyond_contact(self.p)
        except (KeyError, ValueError, ZeroDivisionError, OverflowError):
            return
        if problem:
            insisted = " (run with dt_unchecked=1)" if self.p.get("dt_unchecked") else ""
            self.c.error(f"{L.VARIABLES}/dt", f"{problem}{insisted}: the contacts were not resolved")

    def surface_speed(self) -> float:
        """The surface's peak speed [m/s], of the fastest section: recorded, or of the sines
        the parameters give (section k >= 2 of a line: the s<k>_* drive)."""
        peak = 0.0
        for k in range(1, self.c.sections + 1):
            prefix = "" if k == 1 else f"s{k}_"
            peak = max(peak, 2 * math.pi * self.p.get(f"{prefix}freq", 0.0) * math.hypot(
                self.p.get(f"{prefix}amp_t", 0.0), self.p.get(f"{prefix}amp_n", 0.0)))
        for v in self._motions("velocity"):
            v = np.linalg.norm(v, axis=-1)
            if np.isfinite(v).all():
                peak = max(peak, float(v.max()))
        return peak

    def drives(self) -> None:
        """Each further section of a line moved as its sine drive says (FORMAT.md, "What check
        checks": Drives). The movers (LIGGGHTS' wiggle along x, viblin along z) add v(t_j) dt
        at every step j, so after n steps a section is displaced by the Riemann sum of its
        velocity, whose closed form :func:`sine_drive` gives; it departs from the continuous
        x = A_t sin(w t), z = A_n sin(w t + phi) by at most A w dt (1 + w dt / 24)."""
        step = self.f.get(f"{L.PARTS}/position/step")
        time = self.f.get(f"{L.PARTS}/position/time")
        if step is None or time is None or len(step) == 0:
            return
        step, time = step[()], time[()]
        dt = self.time_step(step, time)
        feeder = self.c.feeder  # (None, not a feeder's vocabulary: every section is taken as driven)
        self.first_cross_stroke(step, time, dt)
        for k in self.c.further_sections:
            motion = [self.f.get(f"{L.surface_path(k)}/{e}/value") for e in ("position", "velocity")]
            if any(not isinstance(m, h5py.Dataset) or m.shape != (len(step), 3) for m in motion):
                continue  # missing or misshapen: reported with the layout
            where = L.surface_path(k)
            if feeder is not None and k <= len(feeder.elements) and not feeder.moves(k):
                # an undriven element (a chute) stands still
                zero = np.zeros((len(step), 3))
                for element, got in zip(("position", "velocity"), motion):
                    self.against_drive(f"{where}/{element}/value", f"section {k}'s {element} (a chute, "
                                       "which does not move)", got[()], zero, DRIVE_ATOL[element],
                                       "m" if element == "position" else "m/s", time)
                continue
            names = [f"s{k}_{n}" for n in L.SECTION_DRIVE]
            missing = [n for n in names if n not in self.p]
            if missing:
                self.c.error(where, f"section {k}'s drive ({', '.join(missing)}) is not among the "
                                    "recorded parameters: its motion cannot be verified")
                continue
            if dt is None:
                self.c.error(where, "no time step recorded (derived/dt_used): section "
                                    f"{k}'s motion cannot be verified")
                continue
            drive = [self.p[n] for n in names]
            cross = [self.p.get(f"s{k}_{n}", 0.0) for n in L.SECTION_CROSS]
            expected = sine_drive(*drive, dt, step, time, *cross)
            amp = max(abs(drive[1]), abs(drive[2]), abs(cross[0]))
            omega = 2 * math.pi * drive[0]
            for element, got, want, scale, unit in (
                    ("position", motion[0][()], expected[0], amp, "m"),
                    ("velocity", motion[1][()], expected[1], amp * omega, "m/s")):
                self.against_drive(f"{where}/{element}/value", f"section {k}'s {element}", got, want,
                                   DRIVE_RTOL * scale + DRIVE_ATOL[element], unit, time)

    def first_cross_stroke(self, step, time, dt: float | None) -> None:
        """Section 1's cross stroke (``amp_c``, a third viblin mover along y): its y motion as
        :func:`sine_drive` gives it (x and z follow the waveform's own contract)."""
        amp_c = self.p.get("amp_c", 0.0)
        motion = [self.f.get(f"{L.SURFACE}/{e}/value") for e in ("position", "velocity")]
        if not amp_c or dt is None or "freq" not in self.p or \
                any(not isinstance(m, h5py.Dataset) or m.shape != (len(step), 3) for m in motion):
            return
        want = sine_drive(self.p["freq"], 0.0, 0.0, 0.0, dt, step, time, amp_c, self.p.get("phase_c", 0.0))
        omega = 2 * math.pi * self.p["freq"]
        for element, got, expected, scale, unit in (
                ("position", motion[0][:, 1:2], want[0], abs(amp_c), "m"),
                ("velocity", motion[1][:, 1:2], want[1], abs(amp_c) * omega, "m/s")):
            self.against_drive(f"{L.SURFACE}/{element}/value", f"section 1's cross-track {element}",
                               got, expected[:, 1:2], DRIVE_RTOL * scale + DRIVE_ATOL[element], unit, time)

    def against_drive(self, path: str, what: str, got, want, tol: float, unit: str, time) -> None:
        """An error at the first frame where recorded motion ``got`` departs from its drive's
        ``want`` (frames, 3) by more than ``tol`` (NaN fails too)."""
        off = np.abs(got - want).max(axis=1)
        bad = np.nonzero(~(off <= tol))[0]
        if len(bad):
            j = int(bad[0])
            self.c.error(path, f"{what} at frame {j} (t = {time[j]:g} s) is "
                               f"{np.array2string(got[j], precision=4)} {unit}, its drive gives "
                               f"{np.array2string(want[j], precision=4)} {unit} (off by {off[j]:.3g}, "
                               f"beyond {tol:.3g} {unit}: {DRIVE_RTOL:g} of the amplitude)")

    def time_step(self, step: np.ndarray, time: np.ndarray) -> float | None:
        """The run's step [s]: derived/dt_used, else time over step."""
        ds = self.f.get(f"{L.DERIVED}/dt_used")
        if isinstance(ds, h5py.Dataset) and ds.shape == ():
            dt = float(ds[()])
            if math.isfinite(dt) and dt > 0:
                return dt
        moved = step > 0
        if moved.any():
            dt = float(np.median(time[moved] / step[moved]))
            return dt if math.isfinite(dt) and dt > 0 else None
        return None

    def bowl_drive(self) -> None:
        """A rotating surface (the bowl) turned and lifted as its drive says (FORMAT.md, "What
        check checks": Drives): riggle and viblin add the rate's step sums as wiggle does, so
        the angle is :func:`sine_drive`'s x for the amplitude amp_t / r_mid [rad] and the lift
        its z; the rates are the movers' own."""
        g = self.f.get(L.SURFACE)
        if not isinstance(g, h5py.Group) or "angle" not in g:
            return
        step = self.f.get(f"{L.PARTS}/position/step")
        time = self.f.get(f"{L.PARTS}/position/time")
        if step is None or time is None or len(step) == 0:
            return
        step, time = step[()], time[()]
        motion = {e: g.get(f"{e}/value") for e in ("angle", "angular_velocity", "position", "velocity")}
        if any(not isinstance(m, h5py.Dataset) or m.shape != (len(step), 3) for m in motion.values()):
            return  # missing or misshapen: reported with the layout
        missing = [n for n in TURN_NAMES if n not in self.p]
        if missing:
            self.c.error(L.SURFACE, f"the bowl's drive ({', '.join(missing)}) is not among the "
                                    "recorded parameters: its motion cannot be verified")
            return
        dt = self.time_step(step, time)
        if dt is None:
            self.c.error(L.SURFACE, "no time step recorded (derived/dt_used): the bowl's motion "
                                    "cannot be verified")
            return
        turn = Turn.from_values(self.p)  # (the bowl element's: its drive turns it about z)
        theta_amp = turn.angle
        pos, vel = sine_drive(turn.freq, theta_amp, turn.lift, turn.phase, dt, step, time)
        omega = 2 * math.pi * turn.freq
        zero = np.zeros_like(pos[:, 0])
        for element, want, scale, unit, atol in (
                ("angle", np.column_stack([zero, zero, pos[:, 0]]), theta_amp, "rad", 1e-15),
                ("angular_velocity", np.column_stack([zero, zero, vel[:, 0]]), theta_amp * omega,
                 "rad/s", 1e-12),
                ("position", np.column_stack([zero, zero, pos[:, 2]]), turn.lift, "m",
                 DRIVE_ATOL["position"]),
                ("velocity", np.column_stack([zero, zero, vel[:, 2]]), turn.lift * omega, "m/s",
                 DRIVE_ATOL["velocity"])):
            self.against_drive(f"{L.SURFACE}/{element}/value", f"the bowl's {element}",
                               motion[element][()], want, DRIVE_RTOL * scale + atol, unit, time)

    def run(self) -> None:
        self.step()
        self.drives()
        self.bowl_drive()
        if not all(f"{L.PARTS}/{n}/value" in self.f for n in ("id", "position", "velocity", "mass")):
            return
        ids = self.f[f"{L.PARTS}/id/value"]
        pos, vel = self.f[f"{L.PARTS}/position/value"], self.f[f"{L.PARTS}/velocity/value"]
        mass, time = self.f[f"{L.PARTS}/mass/value"], self.f[f"{L.PARTS}/position/time"][()]
        frames, slots = ids.shape[:2] if ids.ndim == 2 else (0, 0)
        if frames == 0 or pos.shape[:2] != (frames, slots) or vel.shape[:2] != (frames, slots):
            return
        track = self.f.get(f"{L.TRACK}/vertices")
        track = track[()] if track is not None and track.ndim == 2 and track.shape[1] == 3 else None
        first = pos[0][ids[0] != L.ID_FILL]
        heights = [z for z in (first[:, 2] if len(first) else ()) if math.isfinite(z)] + [0.0]
        if track is not None and len(track):
            heights += [float(track[:, 2].min()), float(track[:, 2].max())]
        height = max(heights) - min(heights)
        v_surface = self.surface_speed()
        limit = max(MIN_SPEED_LIMIT, SPEED_FACTOR * v_surface + math.sqrt(2 * G * height))
        region = None
        if track is not None and len(track):  # the track's box, a track's size around it
            lo, hi = track.min(axis=0), track.max(axis=0)
            margin = float((hi - lo).max())
            jet = self.f.get(f"{L.JET}/time")
            if jet is not None and len(jet):  # a part an air jet blew off flies farther before it
                margin *= JET_THROW  # falls to the catch plane
            margin += self._surface_travel()
            region = (lo - margin, hi + margin)
        boundary = [_text(b) for b in np.ravel(self.f[f"{L.PARTS}/box"].attrs.get("boundary", []))] \
            if f"{L.PARTS}/box" in self.f else []
        jumps = "periodic" not in boundary
        block = max(1, _BLOCK_VALUES // max(3 * slots, 1))
        found = set()
        prev = None  # (ids, positions) of the frame before the block
        for a in range(0, frames, block):
            b = min(frames, a + block)
            i, x, v, m = ids[a:b], pos[a:b], vel[a:b], mass[a:b]
            live = i != L.ID_FILL
            self._speeds(i, v, live, a, time, limit, found)
            if "mass" not in found:
                self._masses(i, m, live, a, time, found)
            if region is not None and "region" not in found:
                self._region(i, x, live, a, time, region, found)
            if jumps and "jump" not in found:
                if prev is not None:
                    i, x, live = (np.concatenate([prev[0], i]), np.concatenate([prev[1], x]),
                                  np.concatenate([prev[0] != L.ID_FILL, live]))
                    start = a - 1
                else:
                    start = a
                self._jumps(i, x, live, start, time, limit, found)
            prev = (ids[b - 1:b], pos[b - 1:b])

    def _surface_travel(self) -> float:
        """The largest displacement of any section [m]."""
        travel = 0.0
        for d in self._motions("position"):
            d = np.abs(d)
            if np.isfinite(d).all():
                travel = max(travel, float(d.max()))
        return travel

    def _speeds(self, ids, v, live, a, time, limit, found) -> None:
        speed = np.where(live, np.linalg.norm(np.nan_to_num(v, nan=0.0), axis=-1), 0.0)
        if "speed" not in found and np.any(speed > limit):
            k, j = np.unravel_index(int(np.argmax(speed > limit)), speed.shape)
            found.add("speed")
            self.c.error(f"{L.PARTS}/velocity/value",
                         f"part {int(ids[k, j])} moves at {speed[k, j]:.3g} m/s at frame {a + k} "
                         f"(t = {time[a + k]:g} s), beyond the {limit:.3g} m/s any part can reach "
                         "(100 x the surface's peak speed + free fall from the scene's height)")

    def _masses(self, ids, m, live, a, time, found) -> None:
        # (No energy rule: with finite, positive masses the kinetic energy per kg is a
        # mass-weighted mean of v^2 / 2, beyond limit^2 / 2 only where a speed is beyond the
        # limit, which the speed rule reports.)
        m = np.asarray(m, float)
        bad = live & ~(np.isfinite(m) & (m > 0))
        if np.any(bad):
            k, j = np.unravel_index(int(np.argmax(bad)), bad.shape)
            found.add("mass")
            self.c.error(f"{L.PARTS}/mass/value",
                         f"part {int(ids[k, j])} has a mass of {float(m[k, j]):.3g} kg at frame "
                         f"{a + k} (t = {time[a + k]:g} s): a part's mass is finite and positive")

    def _region(self, ids, x, live, a, time, region, found) -> None:
        lo, hi = region
        with np.errstate(invalid="ignore"):
            out = live & np.any((x < lo) | (x > hi), axis=-1)
        if np.any(out):
            k, j = np.unravel_index(int(np.argmax(out)), out.shape)
            found.add("region")
            self.c.error(f"{L.PARTS}/position/value",
                         f"part {int(ids[k, j])} is at {np.array2string(x[k, j], precision=3)} m at "
                         f"frame {a + k} (t = {time[a + k]:g} s), far outside the track "
                         f"(a track's size around it)")

    def _jumps(self, ids, x, live, start, time, limit, found) -> None:
        if len(ids) < 2:
            return
        same = live[1:] & live[:-1] & (ids[1:] == ids[:-1])
        dt = np.diff(time[start:start + len(ids)])[:, None]
        with np.errstate(invalid="ignore"):
            step = np.linalg.norm(x[1:] - x[:-1], axis=-1)
            bad = same & (step > 1.5 * limit * dt + 1e-9)
        if np.any(bad):
            k, j = np.unravel_index(int(np.argmax(bad)), bad.shape)
            found.add("jump")
            self.c.error(f"{L.PARTS}/position/value",
                         f"part {int(ids[k + 1, j])} moves {step[k, j]:.3g} m between frames "
                         f"{start + k} and {start + k + 1}, faster than the {limit:.3g} m/s any "
                         "part can reach")


def check_file(path, allow_incomplete: bool = False) -> Report:
    """Check a file; ``Report.ok`` is False if any error was found."""
    try:
        f = h5py.File(path, "r")
    except FileNotFoundError:
        return Report(str(path), [Problem("error", "", "no such file")])
    except OSError as exc:
        return Report(str(path), [Problem("error", "", not_hdf5(path, exc))])
    with f:
        c, parts, status = None, 0, ""
        try:
            c = _Checker(f, allow_incomplete)
            c.h5md()
            parts = c.particles()
            c.surface()
            status = c.parameters()
            events = c.outlet()
            c.mass_balance(events, status, c.outlet(L.REJECTS))
            c.track()
            if str(path).endswith(".part") and status == L.STATUS_COMPLETE:  # FORMAT.md: never both
                (c.warn if allow_incomplete else c.error)(L.RUN,
                                                          "a .part file says 'complete': never renamed")
            _Physics(c).run()
        except Exception as exc:  # a damaged file: this file fails, the others are still checked
            found = damaged_object(exc, str(path))
            if found is None:
                raise
            where, reason = found
            damage = Problem("error", where.lstrip("/"), f"cannot read ({reason}): {DAMAGED}")
            if c is None:
                return Report(str(path), [damage])
            c.problems.append(damage)
        return Report(str(path), c.problems, frames=c.frames, parts=parts, status=status)
