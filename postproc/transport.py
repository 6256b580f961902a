"""Conveying speed: how fast parts travel along the track."""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .base import AnalysisBase


class Transport(AnalysisBase):
    """Mean conveying velocity along the track (x) over whole vibration periods.

    A part's speed is its displacement over a window divided by the window's
    length; the window spans whole vibration periods (the most that fit between
    ``start`` and the last frame analysed, as nearly as the frames allow: below),
    so the answer does not depend on where in the cycle the run stops. Only parts present at
    both ends of the window count, so parts inserted or removed during the
    window are left out. Only the window's two frames are read.

    The window's ends are frames. It ends at the last frame analysed and starts
    at the frame, at or after ``start``, that puts the least distance from whole
    periods on each period it spans (the earliest such frame: the longest
    window; a distance below 1e-4 of a period counts as none). Frames that divide
    the period give whole periods exactly; frames that alias it (``output_dt``
    near or above the period, or not a divisor of it) give the whole number of
    periods that some number of frames spans, when one fits, else the least alias
    per period (the oscillation with the track adds at most amplitude x 2 pi x
    alias / window to a speed). A run that stopped between two outputs has a
    shorter last interval: the window ends at the frame before it when that
    window is closer to whole periods. ``alias`` reports what is left.

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
    ``alias``, the window's distance from whole periods [periods] (0 within
    1e-4 of a period, and without a frequency); ``ids`` of the parts counted,
    their ``velocities`` [m/s] and their ``mean_velocity`` (NaN if none).

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
        k0, k1, alias = whole_period_window(time, start, freq)
        if k1 <= k0:
            raise InputError(f"no time window: start {start} s is at or after the last frame "
                             f"({time[-1]} s)")
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
        r.alias = alias
        r.ids = common
        r.velocities = (x1 - x0) / span
        r.mean_velocity = float(r.velocities.mean()) if len(common) else float("nan")


# A window within this fraction of a period of whole periods spans whole periods (as the
# feed rate's whole-period intervals).
_PERIOD_TOLERANCE = 1e-4


def _best_start(time, k1: int, start: float, freq: float) -> tuple[int, float, float]:
    """(k0, alias, alias per period) of the window ending at frame ``k1`` (module
    docstring); k0 = -1 when no frame at or after ``start`` lies a period or more before."""
    slack = 1e-9 / freq  # the frame at start, to round-off
    k = np.nonzero(time[:k1] >= start - slack)[0]
    cycles = (time[k1] - time[k]) * freq
    whole = np.round(cycles)
    k, cycles, whole = k[whole >= 1], cycles[whole >= 1], whole[whole >= 1]
    if len(k) == 0:
        return -1, np.nan, np.inf
    off = np.abs(cycles - whole)
    off = np.where(off <= _PERIOD_TOLERANCE, 0.0, off)
    per_period = off / cycles
    best = int(np.argmin(per_period))  # the first minimum: the earliest frame, the longest window
    return int(k[best]), float(off[best]), float(per_period[best])


def whole_period_window(time, start: float, freq: float) -> tuple[int, int, float]:
    """(k0, k1, alias): the positions in ``time`` (the frames analysed, increasing) of the
    window's ends and its distance from whole periods [periods] (:class:`Transport`)."""
    time = np.asarray(time, dtype=float)
    n = len(time)
    k1 = n - 1
    if not freq > 0:
        return int(np.argmin(np.abs(time - start))), k1, 0.0
    ends = [k1]
    if n >= 3:  # a shorter (or longer) last interval: a run stopped between two outputs
        spacing = np.diff(time)
        if abs(spacing[-1] - np.median(spacing[:-1])) * freq > _PERIOD_TOLERANCE:
            ends.append(k1 - 1)
    found = []  # (alias per period, -end, start, end, alias) of each end's best window
    for end in ends:
        k0, off, per_period = _best_start(time, end, start, freq)
        if k0 >= 0:
            found.append((per_period, -end, k0, end, off))
    if not found:  # not a period after start: the window from start, whatever it spans
        k0 = int(np.argmin(np.abs(time - start)))
        cycles = (time[k1] - time[k0]) * freq
        return k0, k1, float(abs(cycles - np.round(cycles)))
    _, _, k0, k1, off = min(found)  # the least alias per period; the last frame on a tie
    return k0, k1, off
