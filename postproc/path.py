"""Where a part is along the conveying path: the coordinate the bed's analyses bin by.

A linear track (and a feeder line): x along the track in the track's frame, the part's x
minus the surface's recorded displacement, from the back wall to the outlet edge
(:func:`outlet_x`). A feeder that starts with a bowl (vibrofeed.feeders.Feeder.bowl): the
arc length along the helical track's centre line from its start, then along the chute
(:func:`vibrofeed.bowl.path_coordinate`), of the part's centre in the bowl's frame (the
recorded lift and rotation undone), then on along its exit line, if it has one
(:meth:`vibrofeed.feeders.Feeder.line_coordinate`); NaN for a part that is not on the
track (in the pile on the bottom, falling). The outlet edge is then the path's end. Over a
line's first mesh element (a track from CAD) on: the arc length along its path (the same
method), NaN off it, then on along the elements after it (their x plus how much longer the
mesh's path is than its run along x); the last element's end is the outlet edge.

:func:`along` gives both the coordinate and what a speed is measured on: a linear track's
raw x (over whole periods the surface's displacement cancels), a bowl's path coordinate.
"""

from __future__ import annotations

import math

import numpy as np

# Frames read at once by the bed's analyses: blocks of at most this many slot values.
BLOCK_VALUES = 1 << 22


def feeder_of(parameters):
    """The feeder a result's parameters describe (vibrofeed.feeders.Feeder), or None for a
    deck of one's own without the feeders' vocabulary (a single track to the outlet)."""
    from ..errors import ParameterError
    from ..feeders.feeder import Feeder

    try:
        return Feeder.from_values(parameters)
    except ParameterError:
        return None


def bowl_of(parameters):
    """The bowl (vibrofeed.bowl.Bowl) a result's feeder starts with, or None."""
    feeder = feeder_of(parameters)
    return feeder.bowl if feeder is not None else None


def outlet_x(result) -> float:
    """x of the outlet edge [m]: the table's attribute, else the deck's track_length."""
    plane = result.outlet_plane or {}
    x = plane.get("outlet_x", math.nan)
    if not math.isfinite(x):
        x = float(result.parameters.get("track_length", math.nan))
    return x


def path_end(result) -> float:
    """The outlet edge's coordinate along the path [m] (a linear track: :func:`outlet_x`)."""
    feeder = feeder_of(result.parameters)
    if feeder is not None and (feeder.bowl is not None or math.isfinite(feeder.mesh_start)):
        return feeder.path_end
    return outlet_x(result)


def along(result, frames, axis: int = 0, position=None) -> tuple[np.ndarray, np.ndarray]:
    """(coordinate, moved) of every slot at ``frames`` (frames, slots) [m]: where each part is
    along the path in the track's frame, and the coordinate whose change over whole periods
    is its conveying (module docstring). NaN where no part is (or, in a bowl, off the track).
    ``position`` (frames, n, 3): positions already read at those frames (any n parts, e.g. a
    Frame's present ones), instead of every slot's read again."""
    if position is None:
        position = result.read("position", frames=frames)
    feeder = feeder_of(result.parameters)
    b = feeder.bowl if feeder is not None else None
    if b is None:
        x = position[..., axis]
        coordinate = x - result.read("surface_position", frames=frames)[:, axis][:, None]
        if feeder is None or not math.isfinite(feeder.mesh_start):
            return coordinate, x
        # over a mesh element at rest (its strokes are far below a part): along its path
        on, curved = position[..., 0] >= feeder.mesh_start, feeder.line_coordinate(position)
        return np.where(on, curved, coordinate), np.where(on, curved, x)
    from ..bowl import path_coordinate

    lift = result.read("surface_position", frames=frames)
    angle = result.read("surface_angle", frames=frames)[:, 2]
    c, s = np.cos(-angle)[:, None], np.sin(-angle)[:, None]
    rest = np.stack([c * position[..., 0] - s * position[..., 1],
                     s * position[..., 0] + c * position[..., 1],
                     position[..., 2] - lift[:, 2][:, None]], axis=-1)
    coordinate = path_coordinate(b, rest)
    if feeder.further_elements:  # its exit line, in its own frame at rest (its strokes are far below a part)
        coordinate = np.where(np.isnan(coordinate), feeder.line_coordinate(position), coordinate)
    return coordinate, coordinate


def falls(result, frames) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A bowl's parts that fell off its track back into the bowl: (times, ids, where), one row
    per fall, in frame order; ``where`` is the part's path coordinate at the earlier frame,
    the last on the track [m]. A fall: a part on the track at one frame (a finite path coordinate)
    and off it at the next (NaN: below the floor, or inside the track's inner edge) while still
    inside the bowl's wall (not leaving over the chute's end); its time is the later frame's.
    A part picked up again and falling again counts again. Empty for a linear track."""
    frames = np.asarray(frames, dtype=np.int64)
    b = bowl_of(result.parameters)
    if b is None or len(frames) < 2:
        return np.empty(0), np.empty(0, dtype=np.int64), np.empty(0)
    from ..results import layout as L

    radius = b.radius
    times, ids_out, where = [], [], []
    # (blocks overlap by one frame, so each consecutive pair is seen once)
    per_block = max(2, BLOCK_VALUES // max(4 * result.n_slots, 1))
    for a in range(0, len(frames) - 1, per_block - 1):
        block = frames[a:a + per_block]
        ids = result.read("id", frames=block)
        position = result.read("position", frames=block)
        s = along(result, block, position=position)[0]
        inside = np.hypot(position[..., 0], position[..., 1]) <= radius
        same = (ids[:-1] == ids[1:]) & (ids[:-1] != L.ID_FILL)
        fell = same & np.isfinite(s[:-1]) & np.isnan(s[1:]) & inside[1:]
        k, slot = np.nonzero(fell)
        times.append(result.time[block][k + 1])
        ids_out.append(ids[k + 1, slot])
        where.append(s[k, slot])
    order = np.argsort(np.concatenate(times), kind="stable")
    return (np.concatenate(times)[order], np.concatenate(ids_out)[order].astype(np.int64),
            np.concatenate(where)[order])
