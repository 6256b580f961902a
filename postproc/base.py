"""The one shape of every analysis: configure, run over frames, read ``results``.

The pattern is MDAnalysis' ``AnalysisBase``: an analysis is built with the
result it analyses and its settings, :meth:`AnalysisBase.run` walks a
selection of frames (``start``, ``stop``, ``step`` as frame indices, like a
slice) and the answers land in ``results``, never beside the settings::

    tr = Transport(result, start=0.1).run()
    tr.results.mean_velocity, tr.results.window

A subclass sets its settings in ``__init__`` (after ``super().__init__``)
and fills ``self.results`` through hooks that :meth:`run` calls in order:

* ``_prepare()``: before the frames (allocate, read what every frame needs);
* either ``_compute(frames)``, vectorised over the selected frame indices
  (for analyses that read windows: a transport speed needs two frames), or
  ``_single_frame()`` once per frame, with ``self._frame_index`` (position in
  the selection) and ``self._frame`` (a :class:`~vibrofeed.results.reader.Frame`
  holding the fields named in ``_frame_fields``);
* ``_conclude()``: after the frames (reduce, normalise).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..values import to_json


class Results(dict):
    """The answers of an analysis: a dict whose keys are also attributes.

    >>> r = Results(mean_velocity=0.02)
    >>> r.mean_velocity == r["mean_velocity"]
    True
    """

    def __init__(self, *args, **kwargs):
        super().__init__()
        self.update(*args, **kwargs)

    def __setitem__(self, key, value) -> None:
        if not isinstance(key, str) or not key.isidentifier() or hasattr(dict, key):
            raise KeyError(f"{key!r} cannot name a result (not an identifier, or a dict method)")
        super().__setitem__(key, value)

    def update(self, *args, **kwargs) -> None:
        for key, value in dict(*args, **kwargs).items():
            self[key] = value

    def __getattr__(self, name: str):
        try:
            return self[name]
        except KeyError:
            raise AttributeError(f"no result {name!r}; results are: {', '.join(self)}") from None

    def __setattr__(self, name: str, value) -> None:
        self[name] = value

    def __delattr__(self, name: str) -> None:
        try:
            del self[name]
        except KeyError:
            raise AttributeError(name) from None

    def __dir__(self):
        return [*super().__dir__(), *self]

    def __reduce__(self):  # pickle as a plain mapping (attribute access would find no keys yet)
        return type(self), (dict(self),)


class AnalysisBase:
    """Base of the analyses of a result file (see the module's docstring).

    After :meth:`run`: ``frames`` (the frame indices analysed), ``times``
    (their times [s]), ``n_frames`` and ``results``.
    """

    #: Fields read for each frame when the subclass uses ``_single_frame``.
    _frame_fields: tuple[str, ...] = ("position",)

    def __init__(self, result):
        self._result = result
        self.results = Results()

    @property
    def result(self):
        """The result file analysed."""
        return self._result

    def run(self, start: int | None = None, stop: int | None = None, step: int | None = None,
            frames=None) -> AnalysisBase:
        """Analyse frames ``start:stop:step`` (frame indices, as a slice), or
        the frame indices ``frames``; returns ``self``."""
        if frames is not None and (start, stop, step) != (None, None, None):
            raise InputError("give either frames or start/stop/step, not both")
        n = self._result.n_frames
        if frames is None:
            if step is not None and step <= 0:
                raise InputError(f"frame step must be positive, not {step}")
            self.frames = np.arange(n)[slice(start, stop, step)]
        else:
            self.frames = self._result.frame_indices(frames)
        self.n_frames = len(self.frames)
        self.times = self._result.time[self.frames]
        self.results = Results()
        self._prepare()
        self._compute(self.frames)
        self._conclude()
        return self

    # -- hooks --------------------------------------------------------------------------
    def _prepare(self) -> None:
        """Before the frames."""

    def _compute(self, frames: np.ndarray) -> None:
        """All selected frames at once; by default one ``_single_frame`` per frame."""
        it = self._result.iter_frames(frames, self._frame_fields)
        for self._frame_index, self._frame in enumerate(it):
            self._single_frame()

    def _single_frame(self) -> None:
        raise NotImplementedError(f"{type(self).__name__} defines neither _compute nor _single_frame")

    def _conclude(self) -> None:
        """After the frames."""

    # -- views ----------------------------------------------------------------------
    def as_dict(self, keys=None) -> dict:
        """The results (or the ``keys`` of them) as JSON-ready values."""
        chosen = self.results if keys is None else {k: self.results[k] for k in keys}
        return to_json(chosen)

    def __repr__(self) -> str:
        state = f"{self.n_frames} frames" if hasattr(self, "n_frames") else "not run"
        return f"<{type(self).__name__} of {self._result!r}, {state}>"
