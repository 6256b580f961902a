"""Sections and joints of a feeder line: the pieces :class:`.feedrate.FeedRate` puts together.

A line (docs/feeder-lines.md) is section 1 from x = 0 to the joint x = ``track_length``,
then section 2 from the joint to the outlet edge; a single track is one section. Where a
part is along the line is its x in the track's frame (x minus section 1's recorded
displacement, the frame of FeedRate's profile): section 2's own motion is not recorded
yet, and either drive's amplitude is far below a section's length.

* :func:`section_bounds`: where each section lies; a part is over section 1 when x <
  the joint (the inlet wall keeps it at x > 0), over section 2 when the joint <= x <= the
  outlet edge (beyond it, it falls). A bowl has two sections too, along its path: the
  helix, and the chute from the helix's end (its drive is not the helix's: the torsion
  also shakes it across, docs/bowl.md);
* :func:`bed_pass`: one pass over the frames giving each joint's crossings and the parts
  over each section at each frame (the hold-up);
* :func:`tooling`: the rejects sorted by the tool that threw them off (a side drop, a
  wiper, a slot trap; a bowl's falls too);
* :func:`batch_cuts`, :func:`batch_means`: a quantity in batches of whole periods over
  the window; :func:`drift`, :func:`trend`, :func:`unsteady`: whether it drifts, and
  the words that say so.

This module reads frames and parameters only; it imports nothing of the other analyses
(FeedRate imports it).
"""

from __future__ import annotations

import math

import numpy as np

from ..feeders.feeder import section_index
from ..results import layout as L
from .path import BLOCK_VALUES, along, feeder_of

_BLOCK_VALUES = BLOCK_VALUES  # (a name of this module's: tests set it to read in small blocks)
# Rejects: the tools, in the order they are tried (a part falls sideways only where the
# side drop leaves no wall, so its stretch is tried first; through the floor only where the
# slot opens it: a section's slot and side drop do not overlap, nor a slot and the wiper's bar).
TOOLING = ("side_drop", "wiper", "jet", "other", "slot")
# A part the wiper sweeps back falls within this many part sizes upstream of its face.
WIPER_REACH = 3.0
# A part a jet blows off crosses the catch plane within this many part sizes downstream of
# the jet's block (it flies on along the path as it falls), or one upstream.
JET_REACH = 5.0
# A part a jet fired at that falls off its section within this time of its window's end fell
# because of the jet, wherever it crossed the catch plane (over a side drop, too) [s].
JET_FALL = 0.2
# A drift counts when the last third's mean differs from the first third's by more than
# this many combined standard errors.
DRIFT_SIGMAS = 3.0
# Fewest batches a drift is judged from: two per third.
DRIFT_MIN_BATCHES = 6


def section_bounds(parameters, edge: float) -> list[tuple[float, float]]:
    """[(from, to)] of each section along the path [m], the last one ending at the outlet
    ``edge``: the feeder's (:attr:`vibrofeed.feeders.Feeder.bounds`; a line's sections in
    the track's frame, a bowl's helix then its chute along its path, :mod:`.path`)."""
    feeder = feeder_of(parameters)
    bounds = feeder.bounds if feeder is not None else [(0.0, edge)]
    return bounds[:-1] + [(bounds[-1][0], edge)]


def _left_at(ids, gone_ids, gone_times) -> np.ndarray:
    """When each part of ``ids`` (any shape) left the track: its event's time (outlet or
    reject, ``gone_ids`` at ``gone_times``), inf for a part without one."""
    ids = np.asarray(ids)
    if len(gone_ids) == 0:
        return np.full(ids.shape, np.inf)
    order = np.argsort(gone_ids, kind="stable")
    gid, gt = gone_ids[order], gone_times[order]
    pos = np.minimum(np.searchsorted(gid, ids), len(gid) - 1)
    return np.where(gid[pos] == ids, gt[pos], np.inf)


def bed_pass(result, frames, joints, edge: float, gone_ids=(), gone_times=(), axis: int = 0):
    """One pass over ``frames`` (increasing frame indices): (crossings, counts).

    ``crossings[j]`` = (times, ids) of the parts that crossed joint ``j``: a part counts
    once, at its last crossing from x < joint to x >= joint between two consecutive frames
    (the time interpolated linearly between them), provided it never comes back below
    the joint in a later frame; a part first seen beyond the joint, or gone between the
    frames that would show its crossing, or fallen below the catch plane before it, does
    not count. ``counts`` (frames, sections): the parts over each section at each frame,
    those with an event (``gone_ids`` left at ``gone_times``, outlet or reject) at or
    before it left out.
    """
    frames = np.asarray(frames, dtype=np.int64)
    joints = np.asarray(joints, dtype=float)
    gone_ids = np.asarray(gone_ids, dtype=np.int64)
    gone_times = np.asarray(gone_times, dtype=float)
    counts = np.zeros((len(frames), len(joints) + 1), dtype=np.int64)
    seen = [[] for _ in joints]  # per joint: (frame position, time, id, +1 up / -1 down) blocks
    per_block = max(2, _BLOCK_VALUES // max(4 * result.n_slots, 1))
    # Blocks overlap by one frame, so every consecutive pair is seen once.
    for a in range(0, max(len(frames) - 1, 1), per_block - 1):
        block = frames[a:a + per_block]
        ids = result.read("id", frames=block)
        x = along(result, block, axis)[0]
        t = result.time[block]
        which = section_index(x, joints, edge)
        # A part below the catch plane, still falling, is no longer on a section.
        left = _left_at(ids, gone_ids, gone_times)
        which[(ids == L.ID_FILL) | (left <= t[:, None])] = -1
        for s in range(len(joints) + 1):
            counts[a:a + len(block), s] = (which == s).sum(axis=1)
        same = (ids[:-1] == ids[1:]) & (ids[:-1] != L.ID_FILL)
        x0, x1 = x[:-1], x[1:]
        for j, joint in enumerate(joints):
            up = same & (x0 < joint) & (x1 >= joint)
            k, slot = np.nonzero(up | (same & (x0 >= joint) & (x1 < joint)))
            frac = (joint - x0[k, slot]) / (x1[k, slot] - x0[k, slot])
            when = t[k] + frac * (t[k + 1] - t[k])
            # A part that had already fallen below the catch plane crosses nothing.
            live = when < left[k + 1, slot]
            seen[j].append(((a + k)[live], when[live], ids[k, slot][live],
                            np.where(up[k, slot], 1, -1)[live]))
    crossings = []
    for blocks in seen:
        pos, when, who, sign = (np.concatenate(c) for c in zip(*blocks)) if blocks else \
            (np.empty(0, np.int64), np.empty(0), np.empty(0, np.int64), np.empty(0, np.int64))
        order = np.lexsort((pos, who))       # by part, then in time
        who, when, sign = who[order], when[order], sign[order]
        last = np.r_[who[1:] != who[:-1], True] if len(who) else np.empty(0, dtype=bool)
        keep = last & (sign == 1)            # its last crossing was forward: it stayed
        times = when[keep]
        order = np.argsort(times, kind="stable")
        crossings.append((times[order], who[keep][order]))
    return crossings, counts


def tooling(where, section, stations, size: float) -> np.ndarray:
    """Index into :data:`TOOLING` of each reject at path coordinate ``where`` [m] (a line's:
    its crossing of the catch plane; a bowl's fall: the last on the track) fallen from
    ``section`` (1-based), among the feeder's tooling ``stations``
    (:attr:`vibrofeed.feeders.Feeder.stations`), parts ``size`` across: a side drop's
    stretch on its section widened by a part size either way, or a slot's the same way; else a
    jet's block widened by a part size upstream and :data:`JET_REACH` downstream; else from
    :data:`WIPER_REACH` part sizes upstream of a wiper's face to its bar's downstream end;
    else other. (The feed rate then gives a jet the parts it fired at: :func:`fired_at`.)"""
    s = np.asarray(where, dtype=float)
    section = np.broadcast_to(np.asarray(section), s.shape)
    out = np.full(len(s), TOOLING.index("other"))
    reach = (("wiper", WIPER_REACH, 0.0), ("jet", 1.0, JET_REACH), ("side_drop", 1.0, 1.0),
             ("slot", 1.0, 1.0))
    for kind, before, after in reach:
        for st in (st for st in stations if st.kind == kind):  # (a side drop is decided last)
            hit = (section == st.section) & (s >= st.start - before * size) & (s <= st.end + after * size)
            out[hit] = TOOLING.index(kind)
    return out


def fired_at(ids, times, sections, firings) -> np.ndarray:
    """Which rejects (``ids``, ``times`` [s], ``sections``, one per reject) fell because a jet
    fired at them: a firing of the same part on the same section (``firings``: the result's
    :attr:`~vibrofeed.results.reader.Result.jet_firings`) whose window started before the
    fall and ended at most :data:`JET_FALL` before it. (E,) bool."""
    ids = np.asarray(ids, dtype=np.int64)
    out = np.zeros(len(ids), dtype=bool)
    f_id = np.asarray(firings.get("id", []), dtype=np.int64)
    if not len(f_id) or not len(ids):
        return out
    f_sec = np.asarray(firings["section"], dtype=np.int64)
    start, end = np.asarray(firings["start"], dtype=float), np.asarray(firings["end"], dtype=float)
    times, sections = np.asarray(times, dtype=float), np.asarray(sections, dtype=np.int64)
    # Sorted lookups, not a loop over rejects (O((R + F) log F)): the firings by (part,
    # section) and start; per reject the last firing of its pair that started by then, and the
    # latest end of its pair's firings up to that one (a running maximum within each pair).
    m = int(max(f_sec.max(), sections.max())) + 1  # (sections count from 1)
    codes, f_pair = np.unique(f_id * m + f_sec, return_inverse=True)
    n = len(start)
    starts = np.sort(start)
    f_rank = np.searchsorted(starts, start, side="right")  # starts <= each start, 1..n
    order = np.lexsort((f_rank, f_pair))
    f_pair, f_rank, end = f_pair[order], f_rank[order], end[order]
    key = f_pair * (n + 1) + f_rank  # ascending: by pair, then start
    by_end = np.argsort(end, kind="stable")
    end_rank = np.empty(n, dtype=np.int64)
    end_rank[by_end] = np.arange(n)
    latest = end[by_end][np.maximum.accumulate(end_rank + f_pair * n) - f_pair * n]
    r_code = ids * m + sections
    r_pair = np.minimum(np.searchsorted(codes, r_code), len(codes) - 1)
    at = np.searchsorted(key, r_pair * (n + 1) + np.searchsorted(starts, times, side="right"),
                         side="right") - 1
    ok = (codes[r_pair] == r_code) & (at >= 0)
    ok[ok] &= f_pair[at[ok]] == r_pair[ok]
    out[ok] = times[ok] <= latest[at[ok]] + JET_FALL
    return out


def batch_cuts(t_a: float, t_b: float, freq: float, batches: int) -> np.ndarray:
    """Edges of ``batches`` contiguous batches of whole periods over [t_a, t_b] (lengths
    differing by at most a period; 200 units without a frequency); fewer when the window
    holds fewer periods; a single batch when it holds less than two."""
    units = max(1, int(round((t_b - t_a) * freq))) if freq > 0 else 200
    b = max(1, min(int(batches), units))
    sizes = [len(c) for c in np.array_split(np.arange(units), b)]
    return t_a + (t_b - t_a) * np.r_[0, np.cumsum(sizes)] / units


def batch_means(times, values, cuts) -> np.ndarray:
    """Mean of the ``values`` whose ``times`` fall in each batch [cuts[i], cuts[i+1]) (the
    last one closed); NaN for a batch holding none."""
    times, values = np.asarray(times, dtype=float), np.asarray(values, dtype=float)
    b = len(cuts) - 1
    which = np.searchsorted(cuts, times, side="right") - 1
    which[times == cuts[-1]] = b - 1
    ok = (which >= 0) & (which < b)
    n = np.bincount(which[ok], minlength=b)
    total = np.bincount(which[ok], weights=values[ok], minlength=b)
    return np.where(n > 0, total / np.maximum(n, 1), np.nan)


def drift(series) -> tuple[float, float, float] | None:
    """(first, last, error) of a series of batch values: the means of its first and last
    thirds and the standard error of their difference; None with fewer than
    :data:`DRIFT_MIN_BATCHES` values (NaN batches are left out).

    A batch's noise is the scatter about a straight line through the series, not about
    its mean, so a trend does not inflate the error it is judged by.
    """
    y = np.asarray(series, dtype=float)
    at = np.nonzero(np.isfinite(y))[0]
    y = y[at]
    n = len(y)
    if n < DRIFT_MIN_BATCHES:
        return None
    third = n // 3
    residual = y - np.polyval(np.polyfit(at, y, 1), at)
    scatter = math.sqrt(float(residual @ residual) / (n - 2))
    return float(y[:third].mean()), float(y[-third:].mean()), scatter * math.sqrt(2.0 / third)


def drifts(first: float, last: float, error: float) -> bool:
    """Whether the change first -> last exceeds :data:`DRIFT_SIGMAS` errors (and round-off:
    a series of equal values does not drift)."""
    change = abs(last - first)
    return change > DRIFT_SIGMAS * error and change > 1e-9 * max(abs(first), abs(last))


# A bowl's two sections along its path (the feed-rate summary's ``sections``, each with a
# ``name``; its exit line's elements after them are named s<k>).
BOWL_SECTIONS = ("helix", "chute")


def trend(section: int, quantity: str, series, name: str | None = None) -> list[dict]:
    """[{section, quantity, first, last, error, drifts}] of a bed's batch series (SI units),
    as :func:`drift` finds it, and the section's ``name`` where it has one (a bowl's helix and
    chute, its exit line's s<k>: as the feed-rate table names them); [] when there are too few
    batches to judge."""
    found = drift(series)
    if found is None:
        return []
    first, last, error = found
    named = {"name": name} if name else {}
    return [{"section": section, **named, "quantity": quantity, "first": first, "last": last,
             "error": error, "drifts": drifts(first, last, error)}]


# How a drift is told: scale from SI and unit of each quantity.
_SAID = {"conveying speed": ("the bed's conveying speed", 1e3, "mm/s"),
         "hold-up": ("the hold-up", 1.0, "parts")}


def unsteady(trends) -> str | None:
    """Why the bed is not steady over the window ("not steady: the bed's conveying speed
    on section 1 rises 12.0 -> 20.1 mm/s over the window ..."); None when nothing drifts."""
    said = []
    for t in trends:
        if not t["drifts"]:
            continue
        name, scale, unit = _SAID[t["quantity"]]
        way = "rises" if t["last"] > t["first"] else "falls"
        limit = DRIFT_SIGMAS * t["error"] * scale
        where = (f"the {t['name']}" if t["name"] in BOWL_SECTIONS else t["name"]) if t.get("name") \
            else f"section {t['section']}"
        said.append(f"{name} on {where} {way} {t['first'] * scale:.1f} -> "
                    f"{t['last'] * scale:.1f} {unit} over the window (more than {DRIFT_SIGMAS:g} "
                    f"standard errors: {limit:.2g} {unit})")
    return "not steady: " + "; ".join(said) if said else None
