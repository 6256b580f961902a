"""Read a vibrofeed H5MD result file.

>>> with Result("hop.h5") as r:
...     t, z = r.time, r.position[:, 0, 2]
...     print(r.parameters["freq"], r.surface_position[:, 2].max())

Arrays are read lazily on first access and cached. Slots of particles that do
not exist at a frame hold ``id == -1`` and NaN.
"""

from __future__ import annotations

from functools import cached_property

import h5py
import numpy as np

from . import layout as L


class ResultError(ValueError):
    """A file is not a readable vibrofeed result."""


class IncompleteResult(ResultError):
    """The run that wrote the file did not complete."""


def _text(value) -> str:
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.shape == ():
        return _text(value[()])
    return str(value)


class Result:
    """A result file. ``allow_incomplete=True`` also opens killed or failed runs."""

    def __init__(self, path, allow_incomplete: bool = False):
        self.path = str(path)
        try:
            self.file = h5py.File(self.path, "r")
        except OSError as exc:
            raise ResultError(f"{self.path}: cannot open as HDF5 ({exc})") from exc
        for required in ("h5md", L.PARTS, L.SURFACE, L.RUN):
            if required not in self.file:
                self.file.close()
                raise ResultError(f"{self.path}: not a vibrofeed result (no /{required})")
        status = self.status
        if status != L.STATUS_COMPLETE and not allow_incomplete:
            msg = self.message
            self.file.close()
            raise IncompleteResult(
                f"{self.path}: run status is {status!r}"
                + (f" ({msg})" if msg else "")
                + "; open with allow_incomplete=True to read the frames it holds")

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
    def deck_name(self) -> str:
        return _text(self.file[L.PARAMETERS]["deck"].attrs.get("name", ""))

    @property
    def liggghts_version(self) -> str:
        return _text(self.file[L.PARAMETERS]["liggghts_version"][()])

    @property
    def seed(self) -> int:
        return int(self.file[L.PARAMETERS]["seed"][()])

    # -- time series ----------------------------------------------------------------
    def _part(self, name: str) -> np.ndarray:
        return self.file[L.PARTS][name]["value"][()]

    @cached_property
    def step(self) -> np.ndarray:
        return self.file[L.PARTS]["position/step"][()]

    @cached_property
    def time(self) -> np.ndarray:
        return self.file[L.PARTS]["position/time"][()]

    @property
    def n_frames(self) -> int:
        return len(self.file[L.PARTS]["position/step"])

    @cached_property
    def ids(self) -> np.ndarray:
        """(frames, slots) particle ids, -1 where a slot is empty."""
        return self._part("id")

    @cached_property
    def position(self) -> np.ndarray:
        return self._part("position")

    @cached_property
    def velocity(self) -> np.ndarray:
        return self._part("velocity")

    @cached_property
    def angular_velocity(self) -> np.ndarray:
        return self._part("angular_velocity")

    @cached_property
    def force(self) -> np.ndarray:
        """(frames, slots, 3) total force on each particle [N]."""
        return self._part("force")

    @cached_property
    def radius(self) -> np.ndarray:
        return self._part("radius")

    @cached_property
    def mass(self) -> np.ndarray:
        return self._part("mass")

    @cached_property
    def species(self) -> np.ndarray:
        return self._part("species")

    @cached_property
    def surface_position(self) -> np.ndarray:
        return self.file[L.SURFACE]["position/value"][()]

    @cached_property
    def surface_velocity(self) -> np.ndarray:
        return self.file[L.SURFACE]["velocity/value"][()]

    @cached_property
    def part_ids(self) -> np.ndarray:
        """Every particle id that appears in the run, sorted."""
        ids = self.ids
        return np.unique(ids[ids != L.ID_FILL])

    def present(self) -> np.ndarray:
        """(frames,) number of particles present at each frame."""
        return (self.ids != L.ID_FILL).sum(axis=1)

    def track(self, part_id: int, quantity: str = "position"):
        """(time, values) of one particle over the frames where it exists."""
        frames, slots = np.nonzero(self.ids == part_id)
        if len(frames) == 0:
            raise KeyError(f"particle id {part_id} does not appear in {self.path}")
        values = getattr(self, quantity)[frames, slots]
        return self.time[frames], values

    # -- lifetime -------------------------------------------------------------------
    def close(self) -> None:
        if self.file.id.valid:
            self.file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self) -> str:
        return (f"Result({self.path!r}, deck={self.deck_name!r}, frames={self.n_frames}, "
                f"status={self.status!r})")
