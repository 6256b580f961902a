"""Where a part is along the conveying path: the coordinate the bed's analyses bin by.

A linear track (and a feeder line): x along the track in the track's frame, the part's x
minus the surface's recorded displacement, from the back wall to the outlet edge
(:func:`outlet_x`). A bowl (decks/bowl_feeder.liggghts; its parameters name a
``bowl_diameter``): the arc length along the helical track's centre line from its start,
then along the chute (:func:`vibrofeed.bowl.path_coordinate`), of the part's centre in the
bowl's frame (the recorded lift and rotation undone); NaN for a part that is not on the
track (in the pile on the bottom, falling). The outlet edge is then the path's end, the
helix's length plus the chute's.

:func:`along` gives both the coordinate and what a speed is measured on: a linear track's
raw x (over whole periods the surface's displacement cancels), a bowl's path coordinate.
"""

from __future__ import annotations

import math

import numpy as np


def is_bowl(parameters) -> bool:
    return "bowl_diameter" in parameters


def bowl_of(parameters):
    from ..bowl import bowl_from

    return bowl_from({k: float(v) for k, v in parameters.items() if isinstance(v, int | float)})


def outlet_x(result) -> float:
    """x of the outlet edge [m]: the table's attribute, else the deck's track_length."""
    plane = result.outlet_plane or {}
    x = plane.get("outlet_x", math.nan)
    if not math.isfinite(x):
        x = float(result.parameters.get("track_length", math.nan))
    return x


def path_end(result) -> float:
    """The outlet edge's coordinate along the path [m] (a linear track: :func:`outlet_x`)."""
    if is_bowl(result.parameters):
        b = bowl_of(result.parameters)
        return b.length + b.chute_length
    return outlet_x(result)


def along(result, frames, axis: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(coordinate, moved) of every slot at ``frames`` (frames, slots) [m]: where each part is
    along the path in the track's frame, and the coordinate whose change over whole periods
    is its conveying (module docstring). NaN where no part is (or, in a bowl, off the track)."""
    position = result.read("position", frames=frames)
    if not is_bowl(result.parameters):
        x = position[..., axis]
        return x - result.read("surface_position", frames=frames)[:, axis][:, None], x
    from ..bowl import path_coordinate

    lift = result.read("surface_position", frames=frames)
    angle = result.read("surface_angle", frames=frames)[:, 2]
    c, s = np.cos(-angle)[:, None], np.sin(-angle)[:, None]
    rest = np.stack([c * position[..., 0] - s * position[..., 1],
                     s * position[..., 0] + c * position[..., 1],
                     position[..., 2] - lift[:, 2][:, None]], axis=-1)
    coordinate = path_coordinate(bowl_of(result.parameters), rest)
    return coordinate, coordinate
