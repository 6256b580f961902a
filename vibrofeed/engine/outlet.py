"""Parts leaving a bulk feeder's track: outlet events and the mass balance.

A part has left the track over its outlet edge when it is below the catch plane
(``z < catch_z``) with its centre beyond the edge less the part's reach, its radius (a
clump's: the sphere about its centre that encloses it): ``x > outlet_x - radius``. The
track is a sheet without thickness, so a part that tumbles over the edge can swing under it
and cross the plane with its centre still behind the edge, by up to its reach; every part
that leaves over the outlet is an exit, however it turns. The driver
looks at every frame; a part seen there for the first time is an *event*, and
the moment it crossed the catch plane is found exactly by following its free
flight backwards from the frame's state under the deck's gravity
(:func:`ballistic_crossing`): below the outlet edge nothing but gravity acts
on it. The orientation is the body's at the frame (a free body's rotation is
not reconstructed). FORMAT.md, "Bulk feeders", describes the result.
"""

from __future__ import annotations

import math

import numpy as np

METHOD = ("ballistic: crossing of z = catch_z reconstructed by free flight back from the first "
          "frame that sees the part below catch_z with its centre beyond outlet_x less its radius "
          "(a part tumbling over the edge swings under it); orientation at that frame")


def gravity_vector(g: float, incline_deg: float) -> np.ndarray:
    """Gravity in the simulation (track) frame: a track inclined by beta tilts it
    to g (-sin beta, 0, -cos beta), as the decks do (FORMAT.md, Frames)."""
    beta = math.radians(incline_deg)
    return g * np.array([-math.sin(beta), 0.0, -math.cos(beta)])


def ballistic_crossing(position: np.ndarray, velocity: np.ndarray, catch_z: float,
                       gravity: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """When (tau <= 0, relative to the frame), where and how fast parts crossed
    z = catch_z on the way down, following x(tau) = x + v tau + g tau^2 / 2 back.

    ``position``, ``velocity`` (E, 3) at the frame, below the plane. The
    descending root of z(tau) = catch_z is tau = 2 d / (sqrt(D) - v_z), with
    d = z - catch_z < 0 and D = v_z^2 - 2 g_z d (the form without
    cancellation). A part whose free flight never reaches the plane (D < 0,
    or rising with no gravity) gets tau = 0: the frame's own state.
    """
    position = np.asarray(position, dtype=float).reshape(-1, 3)
    velocity = np.asarray(velocity, dtype=float).reshape(-1, 3)
    gravity = np.asarray(gravity, dtype=float)
    d = position[:, 2] - catch_z
    vz = velocity[:, 2]
    disc = vz * vz - 2.0 * gravity[2] * d
    denom = np.sqrt(np.maximum(disc, 0.0)) - vz
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = np.where((disc >= 0) & (denom > 0), 2.0 * d / denom, 0.0)
    tau = np.minimum(tau, 0.0)
    crossing = position + velocity * tau[:, None] + 0.5 * gravity * tau[:, None] ** 2
    return tau, crossing, velocity + gravity * tau[:, None]


class Outlet:
    """Detects outlet events frame by frame and keeps the mass balance.

    ``step(time, parts, inserted)`` returns the new events (a table for
    ``ResultWriter.write_events``, None when there are none) and the counts of
    that frame (``inserted``, ``on_track``, ``exited``, ``lost``): exited = all
    events so far, on_track = present parts without an event, lost = inserted
    - on_track - exited, the parts that vanished without an event.
    """

    def __init__(self, outlet_x: float, catch_z: float, gravity):
        self.outlet_x = float(outlet_x)
        self.catch_z = float(catch_z)
        self.gravity = np.asarray(gravity, dtype=float)
        self.exited = np.empty(0, dtype=np.int64)  # ids with an event, sorted
        # events whose free flight back never reached the plane (timed at their
        # frame): something other than gravity acted below the edge
        self.not_ballistic = 0

    def attributes(self) -> dict:
        return {"outlet_x": self.outlet_x, "catch_z": self.catch_z, "method": METHOD}

    def _events(self, time: float, parts: dict, new: np.ndarray, extra: dict | None = None) -> dict | None:
        """The event table of the parts ``new`` marks, timed at their catch-plane crossing;
        ``extra``: further per-part columns (of all parts) to carry along."""
        if not new.any():
            return None
        ids = np.asarray(parts["id"], dtype=np.int64)[new]
        x = np.asarray(parts["position"], dtype=float).reshape(-1, 3)[new]
        v = np.asarray(parts["velocity"], dtype=float).reshape(-1, 3)[new]
        tau, pos, vel = ballistic_crossing(x, v, self.catch_z, self.gravity)
        self.not_ballistic += int(np.count_nonzero(tau == 0))
        order = np.argsort(tau, kind="stable")  # in the order they crossed
        q = parts.get("orientation")
        q = np.tile([1.0, 0.0, 0.0, 0.0], (len(ids), 1)) if q is None else np.asarray(q)[new]
        table = {"time": (time + tau)[order], "id": ids[order], "position": pos[order],
                 "velocity": vel[order], "orientation": q[order]}
        for name, column in (extra or {}).items():
            table[name] = np.asarray(column)[new][order]
        return table

    def _over_the_edge(self, parts: dict, x: np.ndarray) -> np.ndarray:
        """Whether each part's centre is beyond the outlet edge less its reach (its radius;
        0 where the parts give none): below the catch plane, it went over the edge."""
        radius = parts.get("radius")
        reach = np.zeros(len(x)) if radius is None else np.nan_to_num(np.asarray(radius, dtype=float))
        return x[:, 0] > self.outlet_x - reach

    def step(self, time: float, parts: dict, inserted: int) -> tuple[dict | None, dict]:
        ids = np.asarray(parts["id"], dtype=np.int64)
        x = np.asarray(parts["position"], dtype=float).reshape(-1, 3)
        reported = np.isin(ids, self.exited, assume_unique=True)
        new = self._over_the_edge(parts, x) & (x[:, 2] < self.catch_z) & ~reported
        events = self._events(time, parts, new)
        self.exited = np.union1d(self.exited, ids[new])
        on_track = int(len(ids) - reported.sum() - new.sum())
        exited = len(self.exited)
        counts = {"inserted": int(inserted), "on_track": on_track, "exited": exited,
                  "lost": int(inserted) - on_track - exited}
        return events, counts


class LineOutlet(Outlet):
    """A feeder line's outlet and rejects: a part below the catch plane that did not go over
    the outlet edge fell off a side (a side drop, swept off by a wiper, over a wall, or into
    a joint) and is a *reject* of the section it fell from (``section_x``: the sections'
    start x, ascending): the one it was on at the last frame that saw it above the plane,
    counted on a section once its centre is past the section's start by its reach (a part
    tumbling off at a joint, its centre swung under the next section's edge, fell from the
    section before; where no frame saw it above the plane, where it crossed the plane).
    A part below the plane past the edge but outside ``band`` (y from, to [m]:
    vibrofeed.feeders.Feeder.exit_band, the walls at the edge and a part either way; None:
    not judged) did not leave over the edge either: it was blown or fell off a side near the
    end and flew on past it, a reject too.

    ``step(time, parts, inserted)`` returns (outlet events, reject events with their
    ``section`` (1-based), counts with ``rejected``): inserted = on_track + exited +
    rejected + lost.
    """

    def __init__(self, outlet_x: float, catch_z: float, gravity, section_x, band=None):
        super().__init__(outlet_x, catch_z, gravity)
        self.section_x = np.asarray(section_x, dtype=float)
        self.band = None if band is None else (float(band[0]), float(band[1]))
        self.rejected = np.empty(0, dtype=np.int64)  # ids with a reject event, sorted
        self.reject_times = np.empty(0)  # their catch-plane crossings, for the returns
        # the parts present at the last frame (sorted ids) and where each was last seen above
        # the catch plane: its x less its reach (NaN: never seen there)
        self._seen_ids = np.empty(0, dtype=np.int64)
        self._seen_at = np.empty(0)

    def _last_on_track(self, ids: np.ndarray, at: np.ndarray, above: np.ndarray) -> np.ndarray:
        """``at`` (x less reach) of the parts above the plane now; for the others, theirs at
        the last frame that saw them above it (NaN if none did). Remembers the parts present."""
        before = np.full(len(ids), np.nan)
        if len(self._seen_ids):
            k = np.minimum(np.searchsorted(self._seen_ids, ids), len(self._seen_ids) - 1)
            known = self._seen_ids[k] == ids
            before[known] = self._seen_at[k[known]]
        last = np.where(above, at, before)
        order = np.argsort(ids)
        self._seen_ids, self._seen_at = ids[order], last[order]
        return last

    def step(self, time: float, parts: dict, inserted: int):
        ids = np.asarray(parts["id"], dtype=np.int64)
        x = np.asarray(parts["position"], dtype=float).reshape(-1, 3)
        radius = parts.get("radius")
        reach = np.zeros(len(ids)) if radius is None else np.nan_to_num(np.asarray(radius, dtype=float))
        last = self._last_on_track(ids, x[:, 0] - reach, x[:, 2] >= self.catch_z)
        reported = np.isin(ids, np.union1d(self.exited, self.rejected))
        below = (x[:, 2] < self.catch_z) & ~reported
        over = self._over_the_edge(parts, x)
        if self.band is not None:  # past the edge but across beyond the band: off a side
            over &= (x[:, 1] >= self.band[0]) & (x[:, 1] <= self.band[1])
        out, fell = below & over, below & ~over
        events = self._events(time, parts, out)
        rejects = self._events(time, parts, fell, {"last": last})
        if rejects is not None:  # the section it fell from (the class's docstring)
            at = rejects.pop("last")
            at = np.where(np.isfinite(at), at, rejects["position"][:, 0])
            rejects["section"] = np.searchsorted(self.section_x, at,
                                                 side="right").clip(1, len(self.section_x))
            self.reject_times = np.concatenate([self.reject_times, rejects["time"]])
        self.exited = np.union1d(self.exited, ids[out])
        self.rejected = np.union1d(self.rejected, ids[fell])
        on_track = int(len(ids) - reported.sum() - below.sum())
        exited, rejected = len(self.exited), len(self.rejected)
        counts = {"inserted": int(inserted), "on_track": on_track, "exited": exited,
                  "rejected": rejected, "lost": int(inserted) - on_track - exited - rejected}
        return events, rejects, counts
