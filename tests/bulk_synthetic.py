"""Synthetic bulk-feeder results whose answers are known by construction.

A straight track from x = 0 (the inlet) to ``outlet_x`` vibrates along x as
``amp sin(2 pi freq t)``; every part rides it (its x in the simulation frame
is its track coordinate plus the track's displacement) and moves along the
track at its own constant speed. Part k is given the time it crosses the
outlet; it enters at the inlet (x = 0) when its schedule puts it there after
the first frame (else it is on the track from the start), leaves over the edge
at its exit time (one outlet event, exact), is seen falling beyond the edge at
the first frame at or after that (flying on at twice its speed), and is gone
from the next one. Parts whose exit
time is after the last frame stay on the track.
"""

from __future__ import annotations

import numpy as np

from helpers import write_bulk_result

OUTLET_X = 0.02
CATCH_Z = -3e-4
RADIUS = 1.5e-4
G = 9.81


def feeder(path, frame_times, exit_times, speed=0.02, amp=0.0, freq=100.0, radius=RADIUS,
           mass=1e-7, lanes=None, orientations=None, body_template=None, variables=None,
           outlet_x=OUTLET_X, seed=0, tipped=None, track=None):
    """Write the result file (module docstring); returns ``path``.

    ``speed``, ``mass``, ``radius``: scalars or one value per part; ``lanes``:
    each part's y [m] (default 0); ``orientations``: (parts, 4) quaternions
    (written only when given); ``tipped``: (parts, 4) orientations once past the
    edge, in the event and the falling frame (default: ``orientations``);
    ``track``: the track mesh (vertices, triangles), if any. The parts are
    shuffled at every frame.
    """
    rng = np.random.default_rng(seed)
    frame_times = np.asarray(frame_times, dtype=float)
    exit_times = np.asarray(exit_times, dtype=float)
    n = len(exit_times)
    speed, mass, radius = (np.broadcast_to(np.asarray(v, dtype=float), (n,)) for v in (speed, mass, radius))
    lanes = np.zeros(n) if lanes is None else np.asarray(lanes, dtype=float)
    w = 2 * np.pi * freq
    t_last = frame_times[-1]
    # The frame that reports each exit: the first at or after it.
    report = np.searchsorted(frame_times, exit_times, side="left")
    frames, counts = [], []
    for j, t in enumerate(frame_times):
        track_x = outlet_x - speed * (exit_times - t)
        on_track = (track_x >= 0) & (exit_times > t)
        inserted = (track_x >= 0) | (exit_times <= t)
        falling = report == j
        present = np.nonzero(on_track | falling)[0]
        present = rng.permutation(present)
        dt_fall = np.where(falling[present], t - exit_times[present], 0.0)
        # Falling parts fly off twice as fast as they were conveyed (a speed no
        # conveying-velocity measurement may pick up), without the track's motion.
        x = np.where(falling[present], outlet_x + 2 * speed[present] * dt_fall,
                     track_x[present] + amp * np.sin(w * t))
        z = np.where(falling[present], CATCH_Z - G / 2 * dt_fall ** 2 - 1e-6, radius[present])
        vx = np.where(falling[present], 2 * speed[present], speed[present] + amp * w * np.cos(w * t))
        vz = np.where(falling[present], -G * dt_fall, 0.0)
        m = len(present)
        parts = {"id": present + 1, "species": np.ones(m, int), "radius": radius[present],
                 "mass": mass[present], "position": np.column_stack([x, lanes[present], z]),
                 "velocity": np.column_stack([vx, np.zeros(m), vz]),
                 "angular_velocity": np.zeros((m, 3)), "force": np.zeros((m, 3))}
        if orientations is not None:
            q = np.asarray(orientations, dtype=float)[present]
            if tipped is not None:
                q = np.where(falling[present][:, None], np.asarray(tipped, dtype=float)[present], q)
            parts["orientation"] = q
        frames.append((j, float(t), parts))
        exited = int((exit_times <= t).sum())
        counts.append({"inserted": int(inserted.sum()), "on_track": int(on_track.sum()),
                       "exited": exited, "lost": 0})
    out = np.nonzero(exit_times <= t_last)[0]
    events = {"time": exit_times[out], "id": out + 1,
              "position": np.column_stack([np.full(len(out), outlet_x), lanes[out],
                                           np.full(len(out), CATCH_Z)]),
              "velocity": np.column_stack([speed[out], np.zeros(len(out)), np.full(len(out), -0.05)]),
              "orientation": (np.tile([1.0, 0, 0, 0], (len(out), 1)) if orientations is None
                              else np.asarray(orientations if tipped is None else tipped, dtype=float)[out])}
    surface = [([amp * np.sin(w * t), 0, 0], [amp * w * np.cos(w * t), 0, 0]) for t in frame_times]
    base = {"freq": (repr(float(freq)), "Hz", "vibration frequency", "100"),
            "track_length": (repr(outlet_x), "m", "track length", "0.02"),
            "part_size": (repr(2 * float(radius.mean())), "m", "part diameter", "3e-4")}
    base.update(variables or {})
    return write_bulk_result(path, frames, events=events, counts=counts, variables=base,
                             body_template=body_template, surface=surface, track=track,
                             outlet={"outlet_x": outlet_x, "catch_z": CATCH_Z, "method": "synthetic"})


def poisson_times(rate, t0, t1, rng):
    """Arrival times of a Poisson process of ``rate`` on (t0, t1]."""
    n = rng.poisson(rate * (t1 - t0) * 1.5 + 20)
    times = t0 + np.cumsum(rng.exponential(1 / rate, n))
    return times[times <= t1]
