"""Singulation of a bulk feeder: how well separated the parts leave the track.

What is measured (over the steady window of :mod:`.feedrate`, detected the
same way unless ``start``/``end`` are given)
----------------------------------------------------------------------------
* **Inter-arrival times** of consecutive outlet events, their distribution
  and coefficient of variation (CV = standard deviation / mean: 1 for random,
  Poisson arrivals, 0 for perfectly periodic ones).
* **Gaps** between consecutive parts at the outlet, as clear distance along
  the track [m]: inter-arrival time x the conveying speed at the edge minus
  how far the first reaches back and the second forward along the track
  (a sphere: its radius; a clump: exactly, from its spheres turned as it lies at
  the last frame its centre was over the track, :func:`.clusters.along_extents`:
  a square chip square to the track reaches half its edge, not its corner's
  circumscribed radius). The edge speed is the whole-period speed
  (:func:`.feedrate.period_velocities`) of the parts within ``edge_length``
  of the outlet edge; both parts fall the same way from the edge, so their
  time apart at the catch plane is their time apart at the edge.
* **Doubles**: consecutive parts arriving closer than the gap you set —
  ``gap`` in time [s] or ``gap_distance`` in clear distance [m]; by default no
  clear track at all between them (abreast on a wide track, or overlapping
  along it) — or touching (contact graph, below) at the last frame before the
  first of them crosses the catch plane.
  ``doubles_rate`` is the fraction of consecutive pairs that are doubles;
  ``singulated_fraction`` the fraction of parts in no double, neither with the
  part before nor with the part after.
* **Clusters on the track**: at ``cluster_frames`` frames spread over the
  window, the connected components of the contact graph of the parts on the
  track (:mod:`.clusters`: a k-d tree, never all pairs; clumps by their
  spheres). ``cluster_sizes`` is the mean number of clusters of each size per
  frame, ``track_singulated_fraction`` the fraction of parts alone.
* **Chips and discs** (results with a body template): the fraction leaving
  face up (the body's thin axis, rotated by the part's quaternion, within 45°
  of +z), face down or on edge, and the orientation along the track: the
  in-plane angle between the body's x axis and the track, folded by the
  part's symmetry (90° for a square chip) into (-45°, 45°]. Both as the track
  delivers the part: at the last frame at which its centre was still over the
  track, before it tips over the outlet edge. The **orientation yield** is the
  fraction of the parts delivered that are both face up and aligned: what an
  orienting feeder passes on to a pick-and-place.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..results import layout as L
from .base import AnalysisBase
from .clusters import along_extents, clump_labels, cluster_labels, pairs_touch, quaternion_matrices
from .feedrate import (
    FeedRate,
    outlet_events,
    period_velocities,
    require_outlet,
    steady_window,
    too_few_exits,
    values_at,
)
from .path import along, feeder_of, outlet_x, path_end

SUMMARY_KEYS = ("cv_interarrival", "doubles_rate", "singulated_fraction", "mean_gap", "cluster_sizes",
                "n_arrivals", "n_doubles", "doubles_per_s", "mean_interarrival", "edge_velocity",
                "track_singulated_fraction", "steady_from", "steady_to", "gap", "gap_distance",
                "tolerance", "face_up_fraction", "face_down_fraction", "on_edge_fraction",
                "aligned_fraction", "orientation_yield", "reason")
# Faces: up/down when the thin axis is within this angle of +z/-z, else on edge.
FACE_ANGLE = 45.0
# In-plane alignment with the track counted within this angle [deg].
ALIGNED_ANGLE = 10.0


def thin_axis(template) -> np.ndarray:
    """The body axis along which a clump template is thinnest (its face normal),
    as a unit vector with its largest component positive. The spread is the spheres
    of the template's most common radius (a box's lattice, not its bump); when two
    spreads tie (a box as wide as thick), the axis nearest body z (a box's marked
    face's normal, vibrofeed.parts)."""
    rows = np.asarray(template, dtype=float)
    radii, counts = np.unique(rows[:, 3], return_counts=True)
    xyz = rows[rows[:, 3] == radii[np.argmax(counts)], :3]
    xyz = xyz - xyz.mean(axis=0)
    values, vectors = np.linalg.eigh(xyz.T @ xyz)
    axis = vectors[:, 0]  # the smallest spread
    if values[1] - values[0] <= 1e-9 * values[2]:
        z = vectors[:, :2] @ vectors[2, :2]  # body z projected into the tied plane
        if np.linalg.norm(z) > 0:
            axis = z / np.linalg.norm(z)
    return axis * np.sign(axis[np.argmax(np.abs(axis))])


def face_orientation(quaternions, template) -> tuple[np.ndarray, np.ndarray]:
    """(cos_tilt, yaw_deg) of parts: the z component of their rotated thin axis
    (+1 face up, -1 face down) and the in-plane angle of the rotated body axis
    perpendicular to it (the first of x, y not along it) from +x, folded
    into (-45°, 45°] (a square chip looks the same every 90°)."""
    rot = quaternion_matrices(quaternions)
    normal = thin_axis(template)
    cos_tilt = rot @ normal
    # An in-plane body axis: x, unless the template is thin along x.
    ref = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    ref = ref - normal * (ref @ normal)
    ref /= np.linalg.norm(ref)
    edge = rot @ ref
    yaw = np.degrees(np.arctan2(edge[:, 1], edge[:, 0]))
    yaw = -((-yaw + 45.0) % 90.0 - 45.0)  # fold into (-45, 45]
    return cos_tilt[:, 2], yaw


def delivered_orientation(result, ev: dict, before: np.ndarray, axis: int = 0) -> np.ndarray:
    """Each leaving part's orientation (E, 4) at the last frame at which its centre was still
    over the track (not past the outlet edge), where a chip still lies as the track delivers
    it: ``ev`` the outlet events (``id``, ``orientation``), ``before`` the frame before each
    crossed the catch plane, searched back from there; the event's own orientation (at the
    catch plane, after it tipped over the edge) only for a part never seen over the track
    (frames 0..before)."""
    edge = outlet_x(result)
    orientation = np.array(ev["orientation"], dtype=float)
    if not math.isfinite(edge):
        return orientation
    frames = np.asarray(before, dtype=np.int64).copy()
    pending = np.ones(len(frames), dtype=bool)
    while pending.any():
        k = np.nonzero(pending)[0]
        state = values_at(result, frames[k], ev["id"][k], ["position", "orientation"])
        surface_x = result.read("surface_position", frames=frames[k])[:, axis]
        over = state["found"] & (state["position"][:, axis] - surface_x <= edge)
        orientation[k[over]] = state["orientation"][over]
        pending[k[over]] = False
        pending &= frames > 0
        frames[pending] -= 1
    return orientation


class Singulation(AnalysisBase):
    """Inter-arrival times, doubles, gaps and clusters of a bulk feeder (module docstring).

    Parameters
    ----------
    result:
        A bulk-feeder :class:`~vibrofeed.results.reader.Result` (with an outlet).
    gap:
        Doubles: consecutive arrivals less than ``gap`` seconds apart.
    gap_distance:
        Doubles: consecutive parts with less than ``gap_distance`` metres of
        clear track between them; default (when ``gap`` is not given) 0: parts
        abreast or overlapping along the track. An escapement that needs room
        between parts sets its own.
    tolerance:
        Touching: centre distance <= r_i + r_j + tolerance [m]; default 1 % of
        the mean part diameter (parts resting side by side are separated by
        round-off and elastic overlaps far below that).
    start, end:
        The window [s]; default: the steady window of the feed rate.
    cluster_frames:
        Frames sampled for the cluster sizes (spread evenly over the window).
    edge_length:
        Length [m] before the outlet edge over which the edge speed is taken;
        default 5 mean part diameters.

    Results: the ``SUMMARY_KEYS`` and ``interarrival`` [s], ``gaps`` [m],
    ``doubles`` and ``touching`` (per consecutive pair), ``arrival_times``, ``arrival_ids``,
    ``cluster_size_counts`` (sizes of every cluster sampled), ``singulated`` (per arrival:
    in no double, neither with the part before nor with the part after), ``delivered`` (per
    arrival: a clump's orientation as the track delivered it, :func:`delivered_orientation`;
    None for spheres), ``yaw_deg`` and
    ``cos_tilt`` of the chips at the outlet (None for spheres); ``orientation_yield``
    (chips: the fraction face up and aligned, per part; None for spheres).

    >>> sg = Singulation(result, gap=2e-3).run()
    >>> sg.results.doubles_rate, sg.results.cv_interarrival, sg.results.cluster_sizes
    """

    def __init__(self, result, gap: float | None = None, gap_distance: float | None = None,
                 tolerance: float | None = None, start: float | None = None, end: float | None = None,
                 cluster_frames: int = 20, edge_length: float | None = None, axis: int = 0):
        super().__init__(result)
        require_outlet(result)
        for name, value in (("gap", gap), ("edge_length", edge_length)):
            if value is not None and not value > 0:
                raise InputError(f"{name} must be > 0, not {value}")
        if gap_distance is not None and not gap_distance >= 0:
            raise InputError(f"gap_distance must be >= 0, not {gap_distance}")
        if cluster_frames < 1:
            raise InputError(f"cluster_frames must be at least 1, not {cluster_frames}")
        self.gap, self.gap_distance, self.tolerance = gap, gap_distance, tolerance
        self.start, self.end, self.cluster_frames = start, end, cluster_frames
        self.edge_length, self.axis = edge_length, axis

    def _compute(self, frames: np.ndarray) -> None:
        if len(frames) < 2:
            raise InputError("singulation: at least two frames are needed")
        result, r = self.result, self.results
        t_lo, t_hi = float(self.times[0]), float(self.times[-1])
        freq = float(result.parameters.get("freq", 0.0))
        ev = outlet_events(result, t_lo, t_hi)
        if self.start is None:  # feed rate's window, moved past a bed still filling
            fr = FeedRate(result, end=self.end, model=False).run(frames=frames)
            t_a, t_b = fr.results.steady_from, fr.results.steady_to
        else:
            t_a, t_b, _, _ = steady_window(ev["time"], t_lo, t_hi, freq, self.start, self.end)
        r.steady_from, r.steady_to = t_a, t_b
        inside = (ev["time"] >= t_a) & (ev["time"] < t_b)
        ev = {name: values[inside] for name, values in ev.items()}
        times = ev["time"]
        r.arrival_times, r.arrival_ids, r.n_arrivals = times, ev["id"], len(times)

        # State of each part at the last frame before its crossing.
        before = np.maximum(np.searchsorted(result.time, times, side="left") - 1, 0)
        names = ["position", "radius"] + (["orientation"] if result.body_template is not None else [])
        state = values_at(result, before, ev["id"], names)
        diameter = 2.0 * self._mean_radius(state["radius"], frames)
        default_tol = 0.01 * diameter if math.isfinite(diameter) else 0.0  # NaN: no part at all
        tol = default_tol if self.tolerance is None else float(self.tolerance)
        r.tolerance = tol
        r.gap = self.gap
        r.gap_distance = 0.0 if self.gap is None and self.gap_distance is None else self.gap_distance

        dt = np.diff(times)
        r.interarrival = dt
        r.mean_interarrival = float(dt.mean()) if len(dt) else math.nan
        r.cv_interarrival = float(dt.std(ddof=1) / dt.mean()) if len(dt) > 1 and dt.mean() > 0 \
            else math.nan

        r.edge_velocity = self._edge_velocity(frames, t_a, t_b, diameter)
        delivered = (self._on_track_orientation(ev, before) if result.body_template is not None
                     else None)
        r.delivered = delivered
        front, back = self._reach(state["radius"], delivered)
        r.gaps = dt * r.edge_velocity - (back[:-1] + front[1:])
        r.mean_gap = float(np.nanmean(r.gaps)) if np.isfinite(r.gaps).any() else math.nan
        r.touching = self._touching(state, before, ev["id"], names, tol)
        doubles = r.touching.copy()
        if r.gap is not None:
            doubles |= dt < r.gap
        if r.gap_distance is not None:
            doubles |= r.gaps < r.gap_distance  # NaN (no edge speed) compares False
        r.doubles = doubles
        r.n_doubles = int(doubles.sum())
        r.doubles_rate = float(doubles.mean()) if len(doubles) else math.nan
        r.doubles_per_s = r.n_doubles / (t_b - t_a)
        alone = np.ones(len(times), dtype=bool)
        alone[:-1] &= ~doubles
        alone[1:] &= ~doubles
        r.singulated = alone
        r.singulated_fraction = float(alone.mean()) if len(times) else math.nan

        r.reason = too_few_exits(len(times))  # the arrivals' statistics are noise (see the command)
        self._clusters(frames, t_a, t_b, tol)
        self._faces(ev, delivered)

    # -- pieces -----------------------------------------------------------------------
    def _reach(self, radius: np.ndarray, orientation) -> tuple[np.ndarray, np.ndarray]:
        """(front, back) of each arriving part along the track at its exit [m]: a sphere's
        radius; a clump's reach turned as it was delivered (``orientation``), along the
        track's direction there (a bowl's chute rises at the helix angle)."""
        if orientation is None:
            return radius, radius
        direction = np.zeros(3)
        direction[self.axis] = 1.0
        feeder = feeder_of(self.result.parameters)
        if feeder is not None and self.axis == 0:  # the last element's own direction
            direction = feeder.exit_direction
        return along_extents(orientation, self.result.body_template, direction)

    def _mean_radius(self, event_radii: np.ndarray, frames: np.ndarray) -> float:
        """Mean part radius [m]: of the arriving parts, else of the parts at the first frame."""
        if np.isfinite(event_radii).any():
            return float(np.nanmean(event_radii))
        ids = self.result.read("id", frames=int(frames[0]))
        radii = self.result.read("radius", frames=int(frames[0]))[ids != L.ID_FILL]
        return float(radii.mean()) if len(radii) else math.nan

    def _edge_velocity(self, frames, t_a: float, t_b: float, diameter: float) -> float:
        """Mean whole-period speed [m/s] of the parts within edge_length of the outlet edge
        (along the path: a bowl's chute end is its helix's and chute's length from the start)."""
        edge = path_end(self.result)
        window = frames[(self.times >= t_a - 1e-12) & (self.times <= t_b + 1e-12)]
        if not math.isfinite(edge):
            return math.nan
        x_mid, v, _, _ = period_velocities(self.result, window, self.axis, edge)
        length = 5 * diameter if self.edge_length is None else self.edge_length
        near = x_mid >= edge - length
        if near.any():
            return float(v[near].mean())
        return float(v.mean()) if len(v) else math.nan

    def _touching(self, state: dict, before: np.ndarray, ids: np.ndarray, names: list,
                  tol: float) -> np.ndarray:
        """Per consecutive pair: both present and touching at the frame before the first crossed."""
        if len(ids) < 2:
            return np.zeros(0, dtype=bool)
        # The second part's state at the first one's frame (it has not crossed yet).
        second = values_at(self.result, before[:-1], ids[1:], names)
        both = state["found"][:-1] & second["found"]
        k = np.nonzero(both)[0]
        clumps = self.result.body_template is not None
        touching = np.zeros(len(ids) - 1, dtype=bool)
        touching[k] = pairs_touch(
            state["position"][k], second["position"][k], state["radius"][k], second["radius"][k],
            state["orientation"][k] if clumps else None, second["orientation"][k] if clumps else None,
            self.result.body_template, tol)
        return touching

    def _clusters(self, frames, t_a: float, t_b: float, tol: float) -> None:
        r, result = self.results, self.result
        edge = path_end(result)
        window = frames[(self.times >= t_a - 1e-12) & (self.times <= t_b + 1e-12)]
        if len(window) == 0:
            window = frames
        pick = np.unique(np.linspace(0, len(window) - 1, min(self.cluster_frames, len(window)))
                         .round().astype(int))
        fields = ("position", "radius") + (("orientation",) if result.body_template is not None else ())
        sizes_seen: list[np.ndarray] = []
        for frame in result.iter_frames(window[pick], fields):
            # on the track: up to the outlet edge along the path (in a bowl, not the pile on its
            # bottom nor a part falling: their coordinate is NaN)
            coordinate = along(result, [frame.index], self.axis, frame["position"][None])[0][0]
            on = coordinate <= edge if math.isfinite(edge) else np.ones(len(frame), dtype=bool)
            if result.body_template is None:
                labels = cluster_labels(frame["position"][on], frame["radius"][on], tol)
            else:
                labels = clump_labels(frame["position"][on], frame["orientation"][on],
                                      result.body_template, tol)
            sizes_seen.append(np.bincount(labels) if len(labels) else np.empty(0, dtype=np.int64))
        all_sizes = np.concatenate(sizes_seen) if sizes_seen else np.empty(0, dtype=np.int64)
        r.cluster_frames = len(sizes_seen)
        r.cluster_size_counts = all_sizes
        sizes, counts = np.unique(all_sizes[all_sizes > 0], return_counts=True)
        r.cluster_sizes = {int(s): float(n) / max(len(sizes_seen), 1) for s, n in zip(sizes, counts)}
        parts = all_sizes.sum()
        r.track_singulated_fraction = float((all_sizes == 1).sum() / parts) if parts else math.nan

    def _faces(self, ev: dict, delivered) -> None:
        """Faces and alignment of the parts as delivered (``delivered``: their orientations
        at the last frame over the track, :meth:`_on_track_orientation`; None for spheres)."""
        r, template = self.results, self.result.body_template
        keys = ("face_up_fraction", "face_down_fraction", "on_edge_fraction", "aligned_fraction",
                "orientation_yield")
        if template is None or len(ev["time"]) == 0:
            r.cos_tilt, r.yaw_deg = None, None
            for key in keys:
                r[key] = None
            return
        r.cos_tilt, r.yaw_deg = face_orientation(delivered, template)
        c = math.cos(math.radians(FACE_ANGLE))
        r.face_up_fraction = float((r.cos_tilt >= c).mean())
        r.face_down_fraction = float((r.cos_tilt <= -c).mean())
        r.on_edge_fraction = 1.0 - r.face_up_fraction - r.face_down_fraction
        aligned = np.abs(r.yaw_deg) <= ALIGNED_ANGLE
        r.aligned_fraction = float(aligned.mean())
        # Per part: face up and aligned together (not the product of the two fractions,
        # which would take them as independent).
        r.orientation_yield = float(((r.cos_tilt >= c) & aligned).mean())

    def _on_track_orientation(self, ev: dict, before: np.ndarray) -> np.ndarray:
        """:func:`delivered_orientation` of the leaving parts."""
        return delivered_orientation(self.result, ev, before, self.axis)

    # -- views ----------------------------------------------------------------------
    def summary(self) -> dict:
        """The command's figures (JSON-ready)."""
        return self.as_dict([k for k in SUMMARY_KEYS if k in self.results])
