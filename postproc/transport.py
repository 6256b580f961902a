"""Conveying speed: how fast parts travel along the track."""

from __future__ import annotations

import numpy as np


class Transport:
    """Mean conveying velocity along the track (x) over whole vibration periods.

    A part's speed is its displacement over a window divided by the window's
    length; the window is the largest whole number of vibration periods that
    fits between ``start`` and the last frame, so the result does not depend
    on where in the cycle the run stops. Only parts present at both ends of
    the window count.

    >>> t = Transport(start=0.1).compute(result)
    >>> t.mean_velocity, t.velocities, t.window
    """

    def __init__(self, start: float | None = None, axis: int = 0):
        self.start = start
        self.axis = axis

    def compute(self, result) -> "Transport":
        time = result.time
        freq = float(result.parameters.get("freq", 0.0))
        start = time[len(time) // 2] if self.start is None else self.start
        t1 = time[-1]
        if freq > 0:
            periods = np.floor((t1 - start) * freq + 1e-9)
            t0 = t1 - periods / freq if periods >= 1 else start
        else:
            t0 = start
        i0 = int(np.argmin(np.abs(time - t0)))
        i1 = len(time) - 1
        if i1 <= i0:
            raise ValueError(f"no time window: start {start} s is at or after the last frame ({t1} s)")
        ids0, ids1 = result.ids[i0], result.ids[i1]
        common = np.intersect1d(ids0[ids0 >= 0], ids1[ids1 >= 0])
        pos = result.position
        x0 = {int(i): pos[i0, s, self.axis] for s, i in enumerate(ids0) if i >= 0}
        x1 = {int(i): pos[i1, s, self.axis] for s, i in enumerate(ids1) if i >= 0}
        span = time[i1] - time[i0]
        self.window = (float(time[i0]), float(time[i1]))
        self.ids = common
        self.velocities = np.array([(x1[int(i)] - x0[int(i)]) / span for i in common])
        self.mean_velocity = float(self.velocities.mean()) if len(common) else float("nan")
        return self
