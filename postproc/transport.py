"""Conveying speed: how fast parts travel along the track."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .base import AnalysisBase


class Transport(AnalysisBase):
    """Mean conveying velocity along the track (x) over whole vibration periods.

    A part's speed is its displacement over a window divided by the window's
    length; the window is the largest whole number of vibration periods that
    fits between ``start`` and the last frame analysed, so the answer does
    not depend on where in the cycle the run stops. Only parts present at
    both ends of the window count, so parts inserted or removed during the
    window are left out. Only the window's two frames are read.

    Parameters
    ----------
    result:
        The :class:`~vibrofeed.results.reader.Result` to analyse.
    start:
        Earliest time [s] of the window (a time, unlike ``run(start=...)``,
        which selects frames); default: the middle frame analysed.
    axis:
        Component of the position to follow (0: x, along the track).

    Results: ``window`` (t0, t1) [s] and ``window_frames`` (i0, i1);
    ``ids`` of the parts counted, their ``velocities`` [m/s] and their
    ``mean_velocity`` (NaN if none).

    >>> tr = Transport(result, start=0.1).run()
    >>> tr.results.mean_velocity, tr.results.velocities, tr.results.window
    """

    def __init__(self, result, start: float | None = None, axis: int = 0):
        super().__init__(result)
        self.start = start
        self.axis = axis

    def _compute(self, frames: np.ndarray) -> None:
        if len(frames) == 0:
            raise InputError("no time window: no frame selected")
        time = self.times
        freq = float(self.result.parameters.get("freq", 0.0))
        start = time[len(time) // 2] if self.start is None else self.start
        t1 = time[-1]
        if freq > 0:
            periods = np.floor((t1 - start) * freq + 1e-9)
            t0 = t1 - periods / freq if periods >= 1 else start
        else:
            t0 = start
        k0 = int(np.argmin(np.abs(time - t0)))
        k1 = len(time) - 1
        if k1 <= k0:
            raise InputError(f"no time window: start {start} s is at or after the last frame ({t1} s)")
        i0, i1 = int(frames[k0]), int(frames[k1])
        ids = self.result.read("id", frames=[i0, i1])
        x = self.result.read("position", frames=[i0, i1])[..., self.axis]
        # Each part's column at both ends (a slot freed during the window may
        # hold another part at its end).
        p0, p1 = np.nonzero(ids[0] >= 0)[0], np.nonzero(ids[1] >= 0)[0]
        common, a, b = np.intersect1d(ids[0][p0], ids[1][p1], assume_unique=True,
                                      return_indices=True)
        x0, x1 = x[0, p0[a]], x[1, p1[b]]
        span = time[k1] - time[k0]
        r = self.results
        r.window = (float(time[k0]), float(time[k1]))
        r.window_frames = (i0, i1)
        r.ids = common
        r.velocities = (x1 - x0) / span
        r.mean_velocity = float(r.velocities.mean()) if len(common) else float("nan")
