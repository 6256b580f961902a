"""Orientation of the parts a feeder delivers, station by station and along its path.

A part's state (:mod:`vibrofeed.orientation`: which face is up, grouped as ``up``, ``down``,
``side`` and ``end``; which end leads; its long axis's angle to the path) is read from its
quaternion and the result's body template alone: the template's principal axes are its body
frame (:func:`vibrofeed.orientation.body_axes`: x along its longest spread, z through its
thinnest, +z the body's own +z side where the template is laid out along the body axes),
whatever the deck called its shape; the air jets classify the same way as they run. What
counts as correct is a :class:`vibrofeed.orientation.Correct`, given in words
(``"up, lengthwise"``); by default the run's own, its parameter ``correct`` (a result recorded
before it: ``"up, lengthwise"``: :func:`vibrofeed.orientation.run_correct`). The path's
direction where a part is (``tangent``) and the floor's normal (``up``) come from the feeder
(:func:`path_directions`): +x and +z along a line; up the helix of a bowl (its slope, the
bowl's tiny turn under the drive neglected), along its chute, along a track from CAD's path;
``up`` is vertical with the tangent's slope taken out (a floor's cross tilt, a few degrees, is
far inside the 45 degrees between states).

What is measured (over the steady window of :mod:`.feedrate`, detected the same way unless
``start``/``end`` are given)
------------------------------------------------------------------------------------------
* **At the outlet**: each delivered part's state at the last frame its centre was over the
  track (:func:`.singulation.delivered_orientation`, as singulation reads a chip's face),
  with the outlet's direction (:attr:`vibrofeed.feeders.Feeder.exit_direction`): the fraction
  in each state, the lengthwise fraction, the ``correct_fraction``; ``correct_rate`` (correct
  parts per second) and ``oriented_rate``, correct **single** parts per second (a part
  counts when it is correct and singulated, :class:`.singulation.Singulation` at its
  defaults), both with batch-means errors as the feed rate's (:func:`.feedrate.batch_rate`).
* **Recirculation load**: the parts per second sent back to be fed again: when the run
  recirculates its rejects (``recirculate = 1``), the mass balance's ``returned`` count over
  the window; otherwise the rejects a return would send back, the reject table's (a line's
  parts over a side) and a bowl's falls back into it. ``recirculation_source`` says which.
* **Per station** (:attr:`vibrofeed.feeders.Feeder.stations`: gates, side drops, wipers, air
  jets): the parts crossing in (at ``x_in``, a part size before the tool) and out (at ``x_out``,
  a part size past it) in the window, each by its state where it crossed: the first frame
  pair between which its path coordinate passes the station's, the time interpolated
  linearly, the state read at the later frame. A station whose ``x_out`` is at or past the
  outlet edge counts out the parts delivered (the outlet's census). A part that appears past a
  station's crossing (inserted there: the inlet's block may reach past it) passes it at its
  first frame; one already past a station's way in at the run's first frame (pre-filled there)
  counts at neither. Its **orienting
  efficiency** is the correct fraction out over the correct fraction in; the share of the
  flow it takes off, (in - out) / in (steady flows: the two counts are over the same window);
  and the rejects per second the feed rate's reject table attributes to its kind of tool
  (:func:`.line.tooling`; shared by stations of one kind, None for a gate or a jet).
* **Along the path**: at every frame of the window, the parts on the track (a finite path
  coordinate up to the outlet edge, none that has left), classified and binned by their path
  coordinate: each bin's state fractions and correct fraction (``census_*``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import InputError
from ..orientation import (
    STATES,
    Correct,
    axes_quaternion,
    parse_correct,
    run_correct,
    turned_states,
)
from ..results import layout as L
from .base import AnalysisBase
from .feedrate import FeedRate, batch_rate, require_outlet, too_few_exits
from .line import _left_at
from .path import BLOCK_VALUES, along, feeder_of, path_end
from .singulation import Singulation

SUMMARY_KEYS = ("correct", "correct_source", "run_correct", "within", "n_delivered", "state_fractions",
                "lengthwise_fraction",
                "correct_fraction", "correct_rate", "correct_rate_err", "oriented_rate",
                "oriented_rate_err", "singulated_fraction", "parts_per_s", "parts_per_s_err",
                "recirculation_per_s", "recirculation_per_s_err", "recirculation_source",
                "stations", "census_x", "census_fractions", "census_correct", "census_count",
                "steady_from", "steady_to", "reason")
def up_of(tangent) -> np.ndarray:
    """The floor's normal under a path running along ``tangent`` (N, 3): vertical with the
    tangent's slope taken out (module docstring)."""
    t = np.asarray(tangent, dtype=float).reshape(-1, 3)
    z = np.zeros_like(t)
    z[:, 2] = 1.0
    up = z - t * t[:, 2:3]
    return up / np.linalg.norm(up, axis=1, keepdims=True)


def path_directions(feeder, s) -> tuple[np.ndarray, np.ndarray]:
    """(tangent, up), each (N, 3), of the path at path coordinates ``s`` (N,) [m] of
    ``feeder`` (None: a single track along +x): up a bowl's helix and along its chute, along
    a track from CAD's path, +x elsewhere (module docstring); +x where ``s`` is NaN."""
    s = np.asarray(s, dtype=float).reshape(-1)
    t = np.zeros((len(s), 3))
    t[:, 0] = 1.0
    if feeder is None:
        return t, up_of(t)
    b = feeder.bowl
    if b is not None:
        a = math.radians(b.helix_angle)
        helix = s < b.length
        theta = b.theta_at(s[helix])
        t[helix] = np.column_stack([-np.sin(theta) * math.cos(a), np.cos(theta) * math.cos(a),
                                    np.full(len(theta), math.sin(a))])
        chute = (s >= b.length) & (s <= b.length + b.chute_length)
        t[chute] = feeder.elements[0].exit_direction
    for i, (e, shift) in enumerate(zip(feeder.elements[1:], feeder.offsets[1:]), start=1):
        if not hasattr(e, "points"):  # straight elements run along +x
            continue
        p = e.points + np.asarray(feeder.line_origin)
        d = np.diff(p, axis=0)
        arc = np.r_[0.0, np.cumsum(np.linalg.norm(d, axis=1))]
        end = e.x0 + shift + arc[-1] if i < len(feeder.elements) - 1 else np.inf  # (the last: beyond)
        on = (s >= e.x0 + shift) & (s < end) & np.isfinite(s)
        seg = np.clip(np.searchsorted(arc, s[on] - e.x0 - shift, side="right") - 1, 0, len(d) - 1)
        t[on] = d[seg] / np.linalg.norm(d[seg], axis=1, keepdims=True)
    return t, up_of(t)


class Orientation(AnalysisBase):
    """The orientation of the parts a feeder delivers, per station and along its path
    (module docstring).

    Parameters
    ----------
    result:
        A bulk-feeder :class:`~vibrofeed.results.reader.Result` of bodies (clumps: its body
        template); spheres have no orientation (InputError).
    correct:
        What counts as correctly oriented, in words (``"up, lengthwise"``, ``"up|down"``,
        ``"up, lengthwise, lead +x"``: :func:`vibrofeed.orientation.parse_correct`; a state
        that does not exist is a ParameterError naming ``correct_name``) or a
        :class:`~vibrofeed.orientation.Correct`. Default (None): the run's own, its parameter
        ``correct`` (``"up, lengthwise"`` for a result that records none).
    within:
        Lengthwise: the long axis within this many degrees of the path (0 < within <= 90).
    start, end:
        The window [s]; default: the steady window of the feed rate.
    bins:
        Bins of the census along the path (from 0 to the outlet edge).
    batches:
        Batches of the rates' batch-means errors (as the feed rate's).
    correct_name:
        The option or parameter ``correct`` came from, for its errors.
    feedrate, singulation:
        The ``results`` of a :class:`.feedrate.FeedRate` and a :class:`.singulation.Singulation`
        already run on this result over the same frames and window (a sweep's metrics), reused
        instead of run again; their window is then the window.

    Results: ``correct`` (the rule, in words), ``correct_source`` (``"run"``: the run's own;
    ``"given"``: ``correct`` was given), ``run_correct`` (the run's own rule, in words),
    ``within`` [deg], ``steady_from``, ``steady_to``
    [s]; at the outlet: ``n_delivered``, ``delivered_times`` and ``delivered_states`` (per part:
    state name), ``state_fractions`` ({state: fraction}), ``lengthwise_fraction``,
    ``correct_fraction``, ``correct_rate``, ``correct_rate_err``, ``oriented_rate``,
    ``oriented_rate_err`` [parts/s, 1 sigma], ``singulated_fraction``, ``parts_per_s``,
    ``parts_per_s_err`` (the feed rate over the window); ``recirculation_per_s``,
    ``recirculation_per_s_err`` [parts/s], ``recirculation_source`` (``returned``,
    ``rejected`` or ``fell``: module docstring); ``stations``: per station a dict of ``name``,
    ``kind``, ``element``, ``section``, ``x_in``, ``x_out`` [m], ``n_in``, ``n_out``,
    ``in_states``, ``out_states`` ({state: count}), ``correct_in``, ``correct_out``
    (fractions), ``efficiency`` (correct_out / correct_in), ``rejected_share`` ((n_in -
    n_out) / n_in), ``out_at`` (``"x_out"`` or ``"outlet"``), ``rejects_per_s``,
    ``rejects_per_s_err`` (the reject table's for its kind of tool, None for a gate or a jet);
    the census along the path: ``census_edges``, ``census_x`` [m], ``census_count``
    (part-frames per bin), ``census_fractions`` ({state: (bins,) fractions}, NaN in an
    empty bin), ``census_correct`` (bins,); ``reason`` (too few exits, else None).

    >>> o = Orientation(result).run()     # the run's correct; correct="up|down" for another
    >>> o.results.oriented_rate, o.results.state_fractions, o.results.stations
    """

    def __init__(self, result, correct: str | Correct | None = None, within: float = 20.0,
                 start: float | None = None, end: float | None = None, bins: int = 20,
                 batches: int = 10, axis: int = 0, correct_name: str = "correct", feedrate=None,
                 singulation=None):
        super().__init__(result)
        require_outlet(result)
        if result.body_template is None:
            raise InputError(f"{result.path}: spheres have no orientation (the result has no "
                             "body template: its parts are not clumps)")
        if not (isinstance(within, int | float) and 0 < within <= 90):
            raise InputError(f"within must be an angle in (0, 90] degrees, not {within}")
        if bins < 1:
            raise InputError(f"bins must be at least 1, not {bins}")
        if batches < 2:
            raise InputError(f"batches must be at least 2, not {batches}")
        self.run_correct = run_correct(result.parameters, float(within))
        if correct is None:
            self.correct, self.correct_source = self.run_correct, "run"
        else:
            self.correct = (dataclasses.replace(correct, within=float(within))
                            if isinstance(correct, Correct) else parse_correct(correct, correct_name,
                                                                               float(within)))
            self.correct_source = "given"
        self.within, self.start, self.end = float(within), start, end
        self.bins, self.batches, self.axis = bins, batches, axis
        self._axes_q = axes_quaternion(result.body_template)
        self._feedrate, self._singulation = feedrate, singulation

    def _compute(self, frames: np.ndarray) -> None:
        if len(frames) < 2:
            raise InputError("orientation: at least two frames are needed")
        r, result = self.results, self.result
        freq = float(result.parameters.get("freq", 0.0))
        fr = self._feedrate
        if fr is None:
            fr = FeedRate(result, start=self.start, end=self.end, batches=self.batches, model=False)
            fr = fr.run(frames=frames).results
        t_a, t_b = fr.steady_from, fr.steady_to
        r.steady_from, r.steady_to = t_a, t_b
        r.correct, r.within = str(self.correct), self.within
        r.correct_source, r.run_correct = self.correct_source, str(self.run_correct)
        r.parts_per_s, r.parts_per_s_err = fr.parts_per_s, fr.parts_per_s_err
        sg = self._singulation
        if sg is None:
            sg = Singulation(result, start=t_a, end=t_b, cluster_frames=1, axis=self.axis)
            sg = sg.run(frames=frames).results
        self._outlet(sg, (t_a, t_b, freq))
        self._recirculation(fr, (t_a, t_b, freq))
        self._stations_and_census(frames, fr, (t_a, t_b, freq))
        r.reason = too_few_exits(r.n_delivered)

    # -- the outlet -------------------------------------------------------------------
    def _outlet(self, sg, span) -> None:
        r, result = self.results, self.result
        times = np.asarray(sg.arrival_times, dtype=float)
        feeder = feeder_of(result.parameters)
        direction = np.zeros(3)
        direction[self.axis] = 1.0
        if feeder is not None and self.axis == 0:
            direction = feeder.exit_direction
        n = len(times)
        tangent = np.broadcast_to(direction, (n, 3))
        q = sg.delivered if n else np.empty((0, 4))
        states = turned_states(q, self._axes_q, tangent, up_of(tangent)) if n else None
        correct = self.correct.of(states) if n else np.zeros(0, dtype=bool)
        single = np.asarray(sg.singulated, dtype=bool)
        r.n_delivered, r.delivered_times = n, times
        r.delivered_states = states.names() if n else []
        r.delivered_correct, r.delivered_singulated = correct, single
        r.state_fractions = {name: float((states.state == k).mean()) if n else math.nan
                             for k, name in enumerate(STATES)}
        r.lengthwise_fraction = float(states.lengthwise(self.within).mean()) if n else math.nan
        r.correct_fraction = float(correct.mean()) if n else math.nan
        r.singulated_fraction = float(single.mean()) if n else math.nan
        r.correct_rate, r.correct_rate_err = batch_rate(times, correct.astype(float), *span, self.batches)
        r.oriented_rate, r.oriented_rate_err = batch_rate(times, (correct & single).astype(float), *span,
                                                          self.batches)
        self._outlet_census = (states, correct)

    # -- what is sent back ------------------------------------------------------------
    def _recirculation(self, fr, span) -> None:
        r, result = self.results, self.result
        balance = result.mass_balance
        if balance is not None and "returned" in balance:
            returned = np.asarray(balance["returned"], dtype=float)
            r.recirculation_source = "returned"
            r.recirculation_per_s, r.recirculation_per_s_err = batch_rate(
                result.time[1:], np.diff(returned), *span, self.batches)
            return
        times = [np.asarray(result.rejects["time"], dtype=float)]
        fell = fr.get("fell_times")
        if fell is not None:
            times.append(np.asarray(fell, dtype=float))
        times = np.concatenate(times)
        r.recirculation_source = "fell" if fell is not None else "rejected"
        r.recirculation_per_s, r.recirculation_per_s_err = batch_rate(times, np.ones(len(times)), *span,
                                                                      self.batches)

    # -- stations and the census along the path ---------------------------------------
    def _stations_and_census(self, frames, fr, span) -> None:
        r, result = self.results, self.result
        t_a, t_b, _ = span
        feeder = feeder_of(result.parameters)
        stations = feeder.stations if feeder is not None else []
        edge = path_end(result)
        # the window's frames, with the one before it (a crossing just after t_a)
        inside = np.nonzero((self.times >= t_a - 1e-12) & (self.times <= t_b + 1e-12))[0]
        first = max(int(inside[0]) - 1, 0) if len(inside) else 0
        window = frames[first:int(inside[-1]) + 1] if len(inside) else frames[:0]
        coords = np.array([c for st in stations for c in (st.x_in, st.x_out)], dtype=float)
        hi = edge if math.isfinite(edge) else 1.0
        edges = np.linspace(0.0, hi, self.bins + 1)
        counts = np.zeros((self.bins, len(STATES)))
        right = np.zeros(self.bins)
        gone_ids = np.r_[result.outlet["id"], result.rejects["id"]].astype(np.int64)
        gone_times = np.r_[result.outlet["time"], result.rejects["time"]].astype(float)
        seen = [([], [], []) for _ in coords]  # per coordinate: times, ids, state index / correct
        per_block = max(2, BLOCK_VALUES // max(8 * result.n_slots, 1))
        for a in range(0, max(len(window) - 1, 1), per_block - 1):
            block = window[a:a + per_block]
            if len(block) == 0:
                break
            ids = result.read("id", frames=block)
            position = result.read("position", frames=block)
            quats = result.read("orientation", frames=block)
            s = along(result, block, self.axis, position)[0]
            t = result.time[block]
            live = (ids != L.ID_FILL) & np.isfinite(s) & (_left_at(ids, gone_ids, gone_times) > t[:, None])
            # the census: each frame of the window once (blocks overlap by a frame)
            counted = (t >= t_a - 1e-12) & (t <= t_b + 1e-12)
            if a > 0:
                counted[0] = False
            on = live & counted[:, None] & (s <= edge if math.isfinite(edge) else True) & (s >= 0)
            k, slot = np.nonzero(on)
            if len(k):
                tangent, up = path_directions(feeder, s[k, slot])
                st = turned_states(quats[k, slot], self._axes_q, tangent, up)
                which = np.clip(np.searchsorted(edges, s[k, slot], side="right") - 1, 0, self.bins - 1)
                np.add.at(counts, (which, st.state), 1)
                np.add.at(right, which, self.correct.of(st).astype(float))
            # the stations' crossings, and the parts that appear past one (the inlet's block
            # may reach past a station's way in): their first frame is their passage
            same = (ids[:-1] == ids[1:]) & live[:-1] & live[1:]
            appear = live[1:] & ~((ids[:-1] == ids[1:]) & live[:-1])  # not there a frame before
            s0, s1 = s[:-1], s[1:]
            for j, c in enumerate(coords):
                passed = same & (s0 < c) & (s1 >= c)
                k, slot = np.nonzero(passed | (appear & (s1 >= c)))
                if not len(k):
                    continue
                new = ~passed[k, slot]
                step = np.where(new, 1.0, s1[k, slot] - s0[k, slot])
                frac = np.where(new, 1.0, (c - s0[k, slot]) / step)
                tangent, up = path_directions(feeder, s1[k, slot])
                st = turned_states(quats[k + 1, slot], self._axes_q, tangent, up)
                seen[j][0].append(t[k] + frac * (t[k + 1] - t[k]))
                seen[j][1].append(ids[k + 1, slot])  # (an appearing part: the later frame's)
                seen[j][2].append(np.c_[st.state, self.correct.of(st)])
        total = counts.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            r.census_fractions = {name: np.where(total > 0, counts[:, k] / total, np.nan)
                                  for k, name in enumerate(STATES)}
            r.census_correct = np.where(total > 0, right / total, np.nan)
        r.census_edges, r.census_x = edges, 0.5 * (edges[1:] + edges[:-1])
        r.census_count = total.astype(np.int64)
        # A part that starts past a station's way in (pre-filled there) never crosses it: counted
        # neither in nor out, or the station would seem to add parts to the flow.
        start_ids, start_s = self._at_start()
        past = [start_ids[start_s >= st.x_in] for st in stations]
        first_crossings = [self._first(times, who, what, t_a, t_b, past[j // 2])
                           for j, (times, who, what) in enumerate(seen)]
        tooling = fr.get("rejects_by_tooling") or {}
        r.stations = [self._station(st, first_crossings[2 * k], first_crossings[2 * k + 1], edge, tooling)
                      for k, st in enumerate(stations)]

    def _at_start(self) -> tuple[np.ndarray, np.ndarray]:
        """The ids and path coordinates of the parts on the track at the run's first frame
        (the file's, whatever frames the analysis reads)."""
        result = self.result
        block = np.zeros(1, dtype=np.int64)
        ids = result.read("id", frames=block)[0]
        s = along(result, block, self.axis, result.read("position", frames=block))[0][0]
        here = (ids != L.ID_FILL) & np.isfinite(s)
        return ids[here].astype(np.int64), s[here]

    @staticmethod
    def _first(times, who, what, t_a: float, t_b: float, skip=()) -> np.ndarray:
        """(state, correct) rows of each part's first crossing, kept when it falls in the window
        and the part is not one of ``skip``."""
        if not times:
            return np.empty((0, 2), dtype=np.int64)
        times, who, what = np.concatenate(times), np.concatenate(who), np.concatenate(what)
        order = np.lexsort((times, who))
        times, who, what = times[order], who[order], what[order]
        first = np.r_[True, who[1:] != who[:-1]]
        keep = first & (times >= t_a) & (times < t_b) & ~np.isin(who, np.asarray(skip, dtype=np.int64))
        return what[keep].astype(np.int64)

    def _station(self, st, rows_in, rows_out, edge: float, tooling: dict) -> dict:
        out_at = "x_out"
        if math.isfinite(edge) and st.x_out >= edge:  # past the edge: the parts delivered
            states, correct = self._outlet_census
            rows_out = (np.c_[states.state, correct] if states is not None
                        else np.empty((0, 2), dtype=np.int64))
            out_at = "outlet"
        n_in, n_out = len(rows_in), len(rows_out)
        correct_in = float(rows_in[:, 1].mean()) if n_in else math.nan
        correct_out = float(rows_out[:, 1].mean()) if n_out else math.nan
        rejects = tooling.get(st.kind)
        return {"name": st.name, "kind": st.kind, "element": st.element, "section": st.section,
                "x_in": st.x_in, "x_out": st.x_out, "n_in": n_in, "n_out": n_out,
                "in_states": {name: int((rows_in[:, 0] == k).sum()) for k, name in enumerate(STATES)},
                "out_states": {name: int((rows_out[:, 0] == k).sum()) for k, name in enumerate(STATES)},
                "correct_in": correct_in, "correct_out": correct_out,
                "efficiency": correct_out / correct_in if correct_in > 0 else math.nan,
                "rejected_share": (n_in - n_out) / n_in if n_in else math.nan, "out_at": out_at,
                "rejects_per_s": rejects["per_s"] if rejects else None,
                "rejects_per_s_err": rejects["per_s_error"] if rejects else None}

    # -- views ----------------------------------------------------------------------
    def summary(self) -> dict:
        """The command's figures (JSON-ready)."""
        return self.as_dict([k for k in SUMMARY_KEYS if k in self.results])
