"""Feed rate of a bulk feeder: parts and mass per second at the outlet, conveying speed.

What is measured
----------------
* **Feed rate** from the outlet's event table (``observables/outlet``): every
  part that left the track has one row with the exact time its centre
  crossed the catch plane, so the rate does not depend on the frame spacing.
  Mass per second weighs each event with the part's recorded mass.
* **Conveying velocity** from the frames: the displacement along the track
  of each part present at both ends of a frame interval that spans a whole
  number of vibration periods, divided by its duration. Over whole periods the
  part's oscillation with the track cancels; over other intervals it would
  alias into the speed (frames every 0.7 periods sample the cycle at drifting
  phases). Parts beyond the outlet edge are falling, not conveyed, and are
  left out. The profile along the track bins these speeds by the interval's
  mid-point along x in the track's frame.

Steady window
-------------
A feeder starts empty at its outlet (the front must travel to the edge) and a
pre-filled track runs out at the end, so the rate is measured over a window
detected from the data. The events are counted in bins of whole vibration
periods (feeding is phase-locked to the vibration: bins of fractional periods
would add a beat to the counts), ~10 events per bin on average so that a
transient stands out of a bin's Poisson noise (the reason MSER-5 averages
batches of 5 observations). The window is the Marginal Standard Error Rule's
(MSER; White, 1997, "An effective truncation heuristic for bias reduction in
simulation output"): the cuts d at the start and e at the end minimising the
variance of the kept bins divided by their number squared, i.e. the squared
standard error of their mean, which falls as bins are kept and rises as
transient bins are. Both ends are searched together (the run-out of the fill
is a transient too, and a transient left at one end hides the other from a
one-sided search), keeping at least half the bins as MSER prescribes. A run
fed by an inlet does not run out: its end is kept, only its start is cut.
``start``/``end`` replace the detection.

Uncertainty
-----------
Batch means: the window is split into ``batches`` contiguous batches of whole
periods (lengths differing by at most one period), each gives a rate, and the
error (1 sigma) is their standard deviation over sqrt(batches). Arrivals of
touching parts are correlated over a few parts; batches of many periods are
nearly independent, so the error includes that correlation, which a Poisson
sqrt(N)/T would not. The conveying velocity's error is the batch means of its
whole-period intervals, the same way.

Sections and joints (feeder lines)
----------------------------------
A line's sections (:mod:`.line`: section 1 up to the joint x = track_length,
section 2 from it to the outlet edge, along x in the track's frame) each get:
the flux through their downstream end (the joint: parts crossing it from
x < joint to x >= joint between two frames and staying beyond it, each once,
at the linearly interpolated time; the outlet: the feed rate) in the steady
window with its batch-means error; the rejects fallen from them per second;
the conveying speed of the parts over them (whole periods, both ends of an
interval over the section); the hold-up (mean parts over them at the window's
frames, parts with an outlet or reject event left out) and the line density
(hold-up per metre). In steady feeding a joint's flux is the next section's
out-flux plus its rejects. The rejects are also sorted by the tooling where
they fell (side drop, wiper, jet, slot, other: :func:`.line.tooling`; jet and slot only
for a line that has one).

Steadiness of the bed
---------------------
Steady exits do not make a steady bed: a bed still speeding up, or a section
still filling, can hand the outlet a steady stream for a while. Over the
window, in batches of whole periods (``batches``, at least 6), every section's
conveying speed and every fed section's hold-up (a section past a joint, or
section 1 with an inlet) are followed; one drifts when the means of the last
and first thirds of its batches differ by more than 3 standard errors of that
difference (the batch scatter about a straight line, :func:`.line.drift`).
A store without inflow (the first element of a pre-filled bed without inlet:
a line's section 1, a bowl's helix and chute) drains at its out-flux however
steadily it feeds, so its hold-up is not judged. A
drift makes ``unsteady`` (and ``reason``) say which, and how much: the rate is
then not a steady one. A single track is section 1. When the window is found
(no ``start`` given), it starts no earlier than every fed section is full (the
MSER start of its hold-up in bins of five periods), and if the bed still drifts
over it, its start moves later by sixths of it, at most three times, while it
keeps enough exits: a line still filling is waited for, not reported.

Dilute limit
------------
The conveying velocity is compared with that of one part alone on the track
under the same vibration: the rigid-part model of Khan & Sarma, §2.3.2
(hopping and sliding), driven by the deck's parameters as the single-part
validation cases drive it (:func:`vibrofeed.models.deck.transport`).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError, ParameterError
from ..results import layout as L
from .base import AnalysisBase
from .line import (
    BOWL_SECTIONS,
    DRIFT_MIN_BATCHES,
    TOOLING,
    batch_cuts,
    batch_means,
    bed_pass,
    fired_at,
    section_bounds,
    tooling,
    trend,
    unsteady,
)
from .path import (  # noqa: F401  (outlet_x: imported from here)
    BLOCK_VALUES,
    along,
    bowl_of,
    falls,
    feeder_of,
    outlet_x,
    path_end,
)

_BLOCK_VALUES = BLOCK_VALUES  # (this module's name for it)
# The count series: bins of ~10 events, so that a transient stands out of one
# bin's Poisson noise (the reason MSER-5 averages batches of 5 observations);
# within 10 .. 200 bins (MSER's resolution, its cost).
_BIN_EVENTS, _MIN_BINS, _MAX_BINS = 10, 10, 200
# A frame lag is "whole periods" when it is within this fraction of a period of one.
_PERIOD_TOLERANCE = 1e-4
# Longest frame lag searched for a whole number of periods.
_MAX_LAG = 1000
# Keys of the command's summary (JSON and table), in order.
SUMMARY_KEYS = ("parts_per_s", "parts_per_s_err", "mass_per_s", "mass_per_s_err", "mean_velocity",
                "mean_velocity_err", "steady_from", "steady_to", "unsteady", "bed_trends", "n_events",
                "inserted", "exited", "rejected", "returned", "on_track", "lost", "sections",
                "rejects_by_tooling", "bin_width", "velocity_lag", "profile_x", "profile_velocity",
                "profile_count", "fell", "fell_per_s", "fell_per_s_err", "model_velocity", "model_note",
                "velocity_ratio", "shape", "reason")
# Summary keys of feeder lines only (returned: of one that recirculates its rejects).
LINE_KEYS = ("rejected", "returned", "sections", "rejects_by_tooling")
# Summary keys of bowls, not of a single track (sections: also a line's).
BOWL_KEYS = ("sections", "rejects_by_tooling", "fell", "fell_per_s", "fell_per_s_err")

# Parameters the single-part model needs from the deck (the rest have defaults).
MODEL_NEEDS = ("freq", "mu", "restitution")


# ----------------------------------------------------------------- the event table
def require_outlet(result) -> None:
    """Refuse a result without an outlet event table (e.g. a single-part run)."""
    if result.outlet_plane is None:
        raise InputError(f"{result.path}: no outlet data (/{L.OUTLET}): deck "
                         f"{result.deck_name or '?'!r} is not a feeder; feed rate and singulation "
                         "need a bulk_feeder result")


def outlet_events(result, t_lo: float = -math.inf, t_hi: float = math.inf) -> dict[str, np.ndarray]:
    """The outlet events with t_lo < time <= t_hi, sorted by time (stable)."""
    require_outlet(result)
    ev = result.outlet
    keep = (ev["time"] > t_lo) & (ev["time"] <= t_hi)
    order = np.argsort(ev["time"][keep], kind="stable")
    return {name: np.asarray(values)[keep][order] for name, values in ev.items()}


def values_at(result, frames, ids, names) -> dict[str, np.ndarray]:
    """Per-part fields ``names`` of parts ``ids`` (E,) at ``frames`` (E,).

    Rows where the part is not present at that frame hold NaN (and ``found``
    says which). Each distinct frame is read once, in blocks of bounded size.
    """
    frames = np.asarray(frames, dtype=np.int64)
    ids = np.asarray(ids, dtype=np.int64)
    out = {}
    for name in names:
        shape = result.read(name, frames=slice(0, 0)).shape[2:]  # per-part components
        out[name] = np.full((len(ids), *shape), np.nan)
    found = np.zeros(len(ids), dtype=bool)
    if len(ids) == 0:
        out["found"] = found
        return out
    unique, inverse = np.unique(frames, return_inverse=True)
    per_block = max(1, _BLOCK_VALUES // max(3 * result.n_slots, 1))
    for a in range(0, len(unique), per_block):
        block = unique[a:a + per_block]
        row_ids = result.read("id", frames=block)
        values = {name: result.read(name, frames=block) for name in names}
        for k in range(len(block)):
            wanted = np.nonzero(inverse == a + k)[0]
            sorter = np.argsort(row_ids[k], kind="stable")
            pos = np.searchsorted(row_ids[k], ids[wanted], sorter=sorter)
            slot = sorter[np.minimum(pos, len(sorter) - 1)]
            hit = row_ids[k][slot] == ids[wanted]
            found[wanted[hit]] = True
            for name in names:
                out[name][wanted[hit]] = values[name][k][slot[hit]]
    out["found"] = found
    return out


# ----------------------------------------------------------------- steady window
def mser(series, cut_start: bool = True, cut_end: bool = True) -> tuple[int, int]:
    """(d, e): the MSER cut of a series at its start and at its end.

    Minimises SSD(y[d:n-e]) / (n - d - e)^2 (the variance of the mean of the
    kept values, as a function of what is cut) over d + e <= n/2: at least
    half the series is kept, MSER's rule against "truncating" noise at the
    far end. Both cuts are searched jointly, since a transient left at one end
    hides the other from a one-sided search.
    """
    y = np.asarray(series, dtype=float)
    n = len(y)
    if n < 3:
        return 0, 0
    yc = y - y.mean()  # the variance is shift-free; centring keeps the sums accurate
    c1 = np.r_[0.0, np.cumsum(yc)]
    c2 = np.r_[0.0, np.cumsum(yc ** 2)]
    d = np.arange(n // 2 + 1)[:, None] if cut_start else np.zeros((1, 1), dtype=int)
    e = np.arange(n // 2 + 1)[None, :] if cut_end else np.zeros((1, 1), dtype=int)
    m = n - d - e
    valid = (d + e) <= n // 2
    hi = n - e
    s1 = c1[hi] - c1[d]
    s2 = c2[hi] - c2[d]
    stat = np.where(valid, (s2 - s1 ** 2 / np.maximum(m, 1)) / np.maximum(m, 1) ** 2, np.inf)
    k = np.unravel_index(int(np.argmin(stat)), stat.shape)  # first minimum: the smallest cuts
    return int(d[k[0], 0]), int(e[0, k[1]])


def bin_width(t_lo: float, t_hi: float, freq: float, n_events: int = 0) -> float:
    """Width [s] of the count bins: whole periods, holding ~``_BIN_EVENTS``
    events on average (at most ``_MAX_BINS`` bins, at least ``_MIN_BINS``)."""
    span = t_hi - t_lo
    n_bins = int(np.clip(n_events // _BIN_EVENTS, _MIN_BINS, _MAX_BINS))
    if freq > 0:
        periods = math.floor(span * freq + 1e-9)
        return max(1, round(periods / n_bins)) / freq if periods >= 1 else span
    return span / n_bins


# Fewer exits than this in the window measure no rate: their Poisson noise alone is
# 1/sqrt(N), above 30 %, and a batch-means error needs exits in every batch.
MIN_EXITS = 10
# How often the window's start may move later for a drifting bed (by a sixth each time).
SETTLE_STEPS = 3


def store_sections(parameters) -> int:
    """How many sections along the path, from the first, are the store a pre-fill without
    inlet drains: the first element's (a line's section 1; a bowl's helix and chute)."""
    feeder = feeder_of(parameters)
    return len(feeder.elements[0].bounds) if feeder is not None else 1


def is_fed(parameters) -> bool:
    """Whether an inlet feeds the run: it does not drain, its hold-up must hold, its end is kept."""
    return float(parameters.get("inlet_rate", 0.0)) > 0


def too_few_exits(n: int, need: int = MIN_EXITS) -> str | None:
    """Why ``n`` exits in the window measure nothing; None when they do."""
    return None if n >= need else f"too few exits to measure ({n} in the window; need ≥ {need})"


def check_window(start: float | None, end: float | None, t_lo: float, t_hi: float) -> None:
    """Refuse a window that is not a time of the run [t_lo, t_hi]: past its end it
    would dilute the rate with time in which nothing could exit."""
    slack = 1e-9 * max(t_hi - t_lo, 1e-12)
    for name, t in (("start", start), ("end", end)):
        if t is None:
            continue
        if not math.isfinite(t):
            raise InputError(f"window {name} {t} is not a time")
        if not t_lo - slack <= t <= t_hi + slack:
            raise InputError(f"window {name} {t:g} s is outside the run ({t_lo:g} .. {t_hi:g} s)")


def steady_window(times, t_lo: float, t_hi: float, freq: float, start: float | None = None,
                  end: float | None = None, fed: bool = False) -> tuple[float, float, float, np.ndarray]:
    """(t_a, t_b, width, counts) of the steady feeding window (module docstring).

    ``counts`` are the events per bin over the whole span, bins of ``width``
    from ``t_lo``; t_a and t_b fall on bin edges unless ``start``/``end`` are given
    (within the span: see :func:`check_window`). A ``fed`` run (an inlet) has no
    draining end to cut: it is cut at its start only.
    """
    check_window(start, end, t_lo, t_hi)
    times = np.asarray(times, dtype=float)
    width = bin_width(t_lo, t_hi, freq, len(times))
    n = max(1, int(math.floor((t_hi - t_lo) / width + 1e-9)))
    edges = t_lo + width * np.arange(n + 1)
    counts = np.histogram(times, bins=edges)[0]
    # Bins cut at the start (d) and at the end (e): detected unless given.
    lo = 0 if start is None else int(np.clip(np.searchsorted(edges, start - 1e-12), 0, n))
    hi = n if end is None else int(np.clip(np.searchsorted(edges, end + 1e-12) - 1, lo, n))
    d, e = mser(counts[lo:hi], start is None, end is None and not fed)
    d, e = lo + d, n - hi + e
    t_a = edges[d] if start is None else float(start)
    t_b = edges[n - e] if end is None else float(end)
    if t_b <= t_a:
        raise InputError(f"no steady window: start {t_a:g} s is not before end {t_b:g} s")
    return float(t_a), float(t_b), float(width), counts


def batch_rate(times, weights, t_a: float, t_b: float, freq: float, batches: int):
    """(rate, error) of weighted events in [t_a, t_b) per second, error by batch means.

    The window is split into ``batches`` contiguous batches of whole periods
    (lengths differing by at most one period; 1/200 of the window without a
    frequency); the error is the standard deviation of their rates over
    sqrt(batches); NaN when the window holds fewer than two periods.
    """
    times = np.asarray(times, dtype=float)
    weights = np.asarray(weights, dtype=float)
    inside = (times >= t_a) & (times < t_b)
    rate = float(weights[inside].sum() / (t_b - t_a))
    cuts = batch_cuts(t_a, t_b, freq, batches)  # periods per batch, +-1
    b = len(cuts) - 1
    if b < 2:
        return rate, math.nan
    sums = np.histogram(times[inside], bins=cuts, weights=weights[inside])[0]
    rates = sums / np.diff(cuts)
    return rate, float(rates.std(ddof=1) / math.sqrt(b))


# ----------------------------------------------------------------- dilute limit
def dilute_limit(parameters) -> tuple[float | None, str]:
    """(speed [m/s], note) of one part alone on the track under the same
    vibration (module docstring); (None, why) when the deck lacks a parameter
    or the model does not apply. The note also says when the model did not
    converge."""
    from ..models.deck import transport  # scipy: loaded when a model is wanted

    missing = [name for name in MODEL_NEEDS if name not in parameters]
    if missing:
        return None, f"the result lacks {', '.join(missing)}"
    b = bowl_of(parameters)
    if b is not None:  # the bowl's drive as the helix's centre line sees it
        from ..bowl import track_drive

        drive = track_drive(float(parameters["amp_t"]), float(parameters["amp_n"]),
                            float(parameters["phase"]), float(parameters["freq"]),
                            float(parameters["helix_angle"]), b.r_mid)
        parameters = {**parameters, "amp_t": drive.amp_t, "amp_n": drive.amp_n,
                      "phase": drive.phase, "incline": drive.incline}
    try:
        state = transport(parameters)
    except (KeyError, ValueError) as exc:
        return None, f"model not applicable ({exc})"
    note = "" if state.converged else "model not converged (chaotic hopping?): mean of its last blocks"
    return float(state.velocity), note


def chute_model(parameters) -> tuple[float | None, str]:
    """(speed [m/s], note) of a lone part crossing a bowl's chute by its model
    (:func:`vibrofeed.bowl.chute_mean_speed`: the torsion also shakes the chute across, and
    its walls brake the part); (None, why) without the parameters it needs."""
    from ..bowl import chute_mean_speed

    missing = [name for name in MODEL_NEEDS + ("amp_t", "amp_n", "phase", "part_size")
               if name not in parameters]
    if missing:
        return None, f"the result lacks {', '.join(missing)}"
    return chute_mean_speed(parameters)


def velocity_ratio(measured: float | None, model: float | None) -> float | None:
    """Measured conveying velocity over the model's; None without both (or with a model of 0)."""
    return measured / model if model and measured is not None else None


# ----------------------------------------------------------------- conveying speed
def period_lag(times, freq: float) -> tuple[int, float]:
    """(m, alias) of the shortest frame lag m spanning a whole number of periods.

    ``alias`` is the lag's distance from whole periods (fraction of a period,
    0 when one within ``_PERIOD_TOLERANCE`` exists). Without one up to
    ``_MAX_LAG`` frames, the lag with the smallest alias per period spanned.
    Uniform frame spacing is assumed (the driver writes every output_every steps).
    """
    times = np.asarray(times, dtype=float)
    if len(times) < 2:
        return 1, math.nan
    if not freq > 0:
        return 1, 0.0
    dt = float(np.median(np.diff(times)))
    lags = np.arange(1, min(_MAX_LAG, len(times) - 1) + 1)
    cycles = lags * dt * freq
    off = np.abs(cycles - np.round(cycles))
    whole = np.nonzero((off <= _PERIOD_TOLERANCE) & (np.round(cycles) >= 1))[0]
    if len(whole):
        return int(lags[whole[0]]), 0.0
    k = int(np.argmin(off / np.maximum(cycles, 1e-300)))
    return int(lags[k]), float(off[k])


def period_velocities(result, frames, axis: int = 0, x_max: float = math.inf,
                      x_min: float = -math.inf):
    """Whole-period speeds of the parts: (x_mid, velocity, interval) arrays.

    ``frames`` are frame indices in increasing order; the intervals chain
    frames[0], frames[m], frames[2m], ... with m from :func:`period_lag`. One
    row per part present at both ends of an interval and on the track, or on
    the stretch asked for (x_min <= x <= x_max in the track's frame), at both:
    the mid-point along ``axis`` in the track's frame [m], the speed [m/s], and
    the interval's number. An interval longer or shorter than m frames of the
    usual spacing (an uneven last frame) is left out: it would not span whole
    periods. Returns also (m, alias).
    """
    frames = np.asarray(frames, dtype=np.int64)
    freq = float(result.parameters.get("freq", 0.0))
    times = result.time[frames]
    m, alias = period_lag(times, freq)
    chain = frames[::m]
    # The chain's intervals as long as m usual frame spacings (within the whole-period tolerance).
    spacing = m * float(np.median(np.diff(times))) if len(times) > 1 else 0.0
    even = np.abs(np.diff(result.time[chain]) - spacing) * max(freq, 0.0) <= _PERIOD_TOLERANCE
    xs, vs, ks = [], [], []
    if len(chain) < 2:
        return np.empty(0), np.empty(0), np.empty(0, dtype=np.int64), (m, alias)
    per_block = max(2, _BLOCK_VALUES // max(4 * result.n_slots, 1))
    for a in range(0, len(chain) - 1, per_block - 1):
        block = chain[a:a + per_block]
        ids = result.read("id", frames=block)
        track_x, x = along(result, block, axis)
        t = result.time[block]
        same = (ids[:-1] == ids[1:]) & (ids[:-1] != L.ID_FILL) & even[a:a + len(block) - 1, None]
        same &= (track_x[:-1] <= x_max) & (track_x[1:] <= x_max)
        same &= (track_x[:-1] >= x_min) & (track_x[1:] >= x_min)
        k, slot = np.nonzero(same)
        xs.append(0.5 * (track_x[k, slot] + track_x[k + 1, slot]))
        vs.append((x[k + 1, slot] - x[k, slot]) / (t[k + 1] - t[k]))
        ks.append(a + k)
    return np.concatenate(xs), np.concatenate(vs), np.concatenate(ks), (m, alias)


def _batch_starts(groups, batches: int) -> np.ndarray:
    """The first interval number of each of at most ``batches`` contiguous batches of
    the distinct interval numbers ``groups`` (non-decreasing), lengths differing by at most one."""
    uniq = np.unique(groups)
    b = min(int(batches), len(uniq))
    return np.array([part[0] for part in np.array_split(uniq, max(b, 1))])


def profile_error(which, values, groups, bins: int, batches: int) -> np.ndarray:
    """(bins,) batch-means error of each bin's mean speed: the batches of
    :func:`_batch_starts`, each giving the mean of its values in the bin; the standard
    deviation of those means over sqrt(their number). NaN where fewer than two
    batches have values in the bin."""
    out = np.full(bins, np.nan)
    if len(values) == 0:
        return out
    batch = np.searchsorted(_batch_starts(groups, batches), groups, side="right") - 1
    nb = int(batch.max()) + 1
    key = which * nb + batch
    count = np.bincount(key, minlength=bins * nb).reshape(bins, nb)
    total = np.bincount(key, weights=values, minlength=bins * nb).reshape(bins, nb)
    for k in range(bins):
        seen = count[k] > 0
        if seen.sum() >= 2:
            means = total[k, seen] / count[k, seen]
            out[k] = means.std(ddof=1) / math.sqrt(seen.sum())
    return out


def _mean_and_batch_error(values, groups, batches: int) -> tuple[float, float]:
    """Mean of ``values`` and its batch-means error over contiguous groups
    (``groups``: the interval number of each value, non-decreasing)."""
    if len(values) == 0:
        return math.nan, math.nan
    mean = float(values.mean())
    first = _batch_starts(groups, batches)
    if len(first) < 2:
        return mean, math.nan
    b = len(first)
    cuts = np.r_[np.searchsorted(groups, first), len(groups)]
    means = np.add.reduceat(values, cuts[:-1]) / np.diff(cuts)
    return mean, float(means.std(ddof=1) / math.sqrt(b))


class FeedRate(AnalysisBase):
    """Parts and mass per second leaving the track, and the conveying speed.

    See the module's docstring for what is measured, the steady window and the
    uncertainty. Frames (``run(start, stop, step)``) bound the time span: events
    after the first analysed frame and up to the last count.

    Parameters
    ----------
    result:
        A bulk-feeder :class:`~vibrofeed.results.reader.Result` (with an outlet).
    start, end:
        The steady window [s]; default: detected (MSER, module docstring).
    batches:
        Number of batches of the batch-means errors (default 10).
    bins:
        Number of bins of the velocity profile along the track (default 20),
        from x = 0 to the outlet edge.
    axis:
        Component along the track (0: x).
    model:
        Compare the conveying velocity with the single-part model (the dilute
        limit, module docstring); default True.

    Results: ``parts_per_s``, ``parts_per_s_err``, ``mass_per_s``,
    ``mass_per_s_err`` (1 sigma, batch means); ``steady_from``, ``steady_to``
    [s], ``bin_width`` [s] and ``counts`` (events per bin from the first
    frame); ``event_times`` (sorted) and ``n_events``; ``mean_velocity``,
    ``mean_velocity_err`` [m/s] over the steady window, ``velocity_lag``
    (frames per whole-period interval) and ``velocity_alias`` (its distance
    from whole periods, in periods); ``profile_edges``, ``profile_x``,
    ``profile_velocity``, ``profile_velocity_err`` (batch means per bin, NaN in a bin
    seen by fewer than two batches), ``profile_count``, ``profile_height`` (a bowl: the track
    centre line's floor height at each bin [m], the profile in height; else None); a bowl's
    ``fell_times`` (every fall off its track back into the bowl, :func:`.path.falls`), ``fell``
    (those in the steady window), ``fell_per_s`` and ``fell_per_s_err`` (their rate and its
    counting error sqrt(n) / window); the mass balance at the last frame
    analysed: ``inserted``, ``on_track``, ``exited``, ``lost`` (None without one),
    ``rejected`` for a feeder line and ``returned`` (rejects put back at the inlet, part of
    ``inserted``) for one that recirculates;
    with ``model``: ``model_velocity`` [m/s] (None when the model does not
    apply), ``model_note`` (why not, or that it did not converge; else empty)
    and ``velocity_ratio`` (mean_velocity / model_velocity).

    The bed (module docstring): ``unsteady`` (why the bed is not steady over
    the window, else None; also the ``reason`` when there are enough exits),
    ``bed_trends`` (per section and quantity judged: ``section`` (and a bowl's ``name``), ``quantity``
    "conveying speed" [m/s] or "hold-up" [parts], ``first``, ``last`` (means of
    the first and last thirds), ``error``, ``drifts``), ``bed`` (``batch_edges``,
    ``speed`` and ``hold_up`` per section and batch, ``joint_crossings``: per
    joint, (times, ids) of the parts counted). A feeder line also gets
    ``sections``: per section a dict of ``section`` (1-based), ``x_from``,
    ``x_to`` [m], ``joint_flux``, ``joint_flux_error`` [1/s] (through its
    downstream end: the joint, or the outlet for the last section),
    ``reject_rate``, ``reject_rate_error`` [1/s], ``rejects_in_window``,
    ``speed``, ``speed_error`` [m/s], ``hold_up``, ``hold_up_error`` [parts],
    ``line_density`` [1/m], ``along`` ("x": ``x_from`` and ``x_to`` are the deck's x; "path":
    path coordinates, a bowl's or a mesh element's); and ``rejects_by_tooling``: for ``side_drop``,
    ``wiper``, ``jet`` (only a line with a jet), ``slot`` (only a line with a slot trap),
    ``other``, ``per_s``, ``per_s_error`` (in the window), ``in_window``, ``total`` (in the
    run analysed), or None for a tool the line does not have.

    >>> fr = FeedRate(result).run()
    >>> fr.results.parts_per_s, fr.results.parts_per_s_err, fr.results.steady_from
    """

    def __init__(self, result, start: float | None = None, end: float | None = None,
                 batches: int = 10, bins: int = 20, axis: int = 0, model: bool = True):
        super().__init__(result)
        require_outlet(result)
        if batches < 2:
            raise InputError(f"batches must be at least 2, not {batches}")
        if bins < 1:
            raise InputError(f"bins must be at least 1, not {bins}")
        self.start, self.end, self.batches, self.bins, self.axis = start, end, batches, bins, axis
        self.model = model

    def _compute(self, frames: np.ndarray) -> None:
        if len(frames) < 2:
            raise InputError("feed rate: at least two frames are needed")
        r = self.results
        result = self.result
        t_lo, t_hi = float(self.times[0]), float(self.times[-1])
        freq = float(result.parameters.get("freq", 0.0))
        ev = outlet_events(result, t_lo, t_hi)
        times = ev["time"]
        r.event_times, r.n_events = times, len(times)
        bowl = bowl_of(result.parameters)
        if bowl is not None:  # parts the track lost back into the bowl (the bed's rejects)
            r.fell_times, _, r.fell_where = falls(result, frames)
        fed = is_fed(result.parameters)
        t_a, t_b, width, counts = steady_window(times, t_lo, t_hi, freq, self.start, self.end, fed)
        r.parts_per_s = r.parts_per_s_err = math.nan  # the bed's figures before the rate is measured
        if self.start is None:
            t_a = self._settled_start(frames, times, t_a, t_b, freq)
        r.steady_from, r.steady_to, r.bin_width, r.counts = t_a, t_b, width, counts
        r.parts_per_s, r.parts_per_s_err = batch_rate(times, np.ones(len(times)), t_a, t_b, freq,
                                                      self.batches)
        r.reason = too_few_exits(int(((times >= t_a) & (times < t_b)).sum()),
                                 max(MIN_EXITS, self.batches))
        # Each event's mass: the part at the first frame at or after its crossing
        # (the frame that reported it), else the frame before.
        after = np.minimum(np.searchsorted(result.time, times, side="left"), result.n_frames - 1)
        mass = values_at(result, after, ev["id"], ["mass"])
        missing = ~mass["found"]
        if missing.any():
            before = values_at(result, np.maximum(after[missing] - 1, 0), ev["id"][missing], ["mass"])
            mass["mass"][missing] = before["mass"]
        r.event_mass = mass["mass"]
        if np.isnan(r.event_mass).any():
            r.mass_per_s, r.mass_per_s_err = math.nan, math.nan
        else:
            r.mass_per_s, r.mass_per_s_err = batch_rate(times, r.event_mass, t_a, t_b, freq,
                                                        self.batches)
        self._velocities(frames, t_a, t_b)
        if bowl is not None:  # the falls in the window
            fell_times = r.fell_times
            n, span = int(((fell_times >= t_a) & (fell_times < t_b)).sum()), t_b - t_a
            r.fell = n
            r.fell_per_s = n / span if span > 0 else math.nan
            r.fell_per_s_err = math.sqrt(n) / span if span > 0 else math.nan  # counts: Poisson
        self._mass_balance(frames)
        self._bed(frames, t_a, t_b, freq)
        r.reason = r.reason or r.unsteady  # a drifting bed measures no steady rate either
        if self.model:
            r.shape = int(float(result.parameters.get("shape", 0)))  # what the model is compared with
            r.model_velocity, r.model_note = dilute_limit(result.parameters)
            r.velocity_ratio = velocity_ratio(r.mean_velocity, r.model_velocity)
            for k, sec in enumerate(r.get("sections") or (), 1):  # each section's own drive
                if bowl is not None and k <= 2:  # the helix's dilute limit; the chute's own model
                    sec["model_speed"], sec["model_note"] = ((r.model_velocity, r.model_note) if k == 1
                                                             else chute_model(result.parameters))
                else:
                    try:
                        feeder = feeder_of(result.parameters)
                        drive = feeder.section_values(k)
                    except ParameterError as exc:
                        sec["model_speed"], sec["model_note"] = None, f"the result lacks {exc}"
                    else:
                        none = ("undriven (a chute)" if feeder.element_of(k).kind == "chute"
                                else "none for a track from CAD (its path turns)")
                        sec["model_speed"], sec["model_note"] = (
                            dilute_limit(drive) if drive is not None else (None, none))
                sec["speed_ratio"] = velocity_ratio(sec["speed"], sec["model_speed"])

    def _bed_pass(self, frames):
        """:func:`.line.bed_pass` over ``frames``, read once per run of the analysis: the
        window's search (:meth:`_filled`, :meth:`_settled_start`) and the final figures all
        ask for the same pass over every frame."""
        key = np.asarray(frames, dtype=np.int64).tobytes()
        if getattr(self, "_pass_key", None) != key:
            result = self.result
            edge = path_end(result)
            bounds = section_bounds(result.parameters, edge)
            out, rejects = result.outlet, result.rejects
            self._pass = bed_pass(result, frames, [lo for lo, _ in bounds[1:]], edge,
                                  np.r_[out["id"], rejects["id"]], np.r_[out["time"], rejects["time"]],
                                  self.axis)
            self._pass_key = key
        return self._pass

    def _filled(self, frames, freq: float) -> float:
        """When every fed section is full: the latest MSER start (no end cut) of their
        hold-ups, averaged over bins of 5 periods (MSER-5; 5 frames without a frequency)
        from the first frame; the first frame's time for a store that only drains (a
        pre-fill without inlet)."""
        result = self.result
        t0 = float(self.times[0])
        frame_dt = float(np.median(np.diff(self.times))) if len(self.times) > 1 else 1.0
        width = max(5 / freq if freq > 0 else 0.0, 5 * frame_dt)
        _, counts = self._bed_pass(frames)
        judged = 0 if is_fed(result.parameters) else store_sections(result.parameters)
        which = np.floor((self.times - t0) / width + 1e-9).astype(np.int64)
        n_bins = int(which.max()) + 1
        start = t0
        for k in range(judged, counts.shape[1]):
            total = np.bincount(which, weights=counts[:, k], minlength=n_bins)
            held = total / np.maximum(np.bincount(which, minlength=n_bins), 1)
            start = max(start, t0 + width * mser(held, cut_end=False)[0])
        return start

    def _settled_start(self, frames, times, t_a: float, t_b: float, freq: float) -> float:
        """The window's start: not before every fed section is full (:meth:`_filled`), then
        moved later by sixths of the window (at most three) while the bed drifts over it
        and enough exits remain (module docstring)."""
        filled = self._filled(frames, freq)
        if filled > t_a and ((times >= filled) & (times < t_b)).sum() >= max(MIN_EXITS, self.batches):
            t_a = filled
        step = (t_b - t_a) / 6
        for _ in range(SETTLE_STEPS):
            self._bed(frames, t_a, t_b, freq)
            later = t_a + step
            if self.results.unsteady is None or ((times >= later) & (times < t_b)).sum() < \
                    max(MIN_EXITS, self.batches):
                break
            t_a = later
        return t_a

    def _velocities(self, frames: np.ndarray, t_a: float, t_b: float) -> None:
        r = self.results
        edge = path_end(self.result)
        window = frames[(self.times >= t_a - 1e-12) & (self.times <= t_b + 1e-12)]
        x_mid, v, interval, (m, alias) = period_velocities(self.result, window, self.axis,
                                                           edge if math.isfinite(edge) else math.inf)
        r.velocity_lag, r.velocity_alias = m, alias
        r.mean_velocity, r.mean_velocity_err = _mean_and_batch_error(v, interval, self.batches)
        hi = edge if math.isfinite(edge) else (float(x_mid.max()) if len(x_mid) else 1.0)
        lo = min(0.0, float(x_mid.min())) if len(x_mid) else 0.0
        edges = np.linspace(lo, hi, self.bins + 1)
        which = np.clip(np.searchsorted(edges, x_mid, side="right") - 1, 0, self.bins - 1)
        count = np.bincount(which, minlength=self.bins)
        total = np.bincount(which, weights=v, minlength=self.bins)
        with np.errstate(invalid="ignore", divide="ignore"):
            r.profile_velocity = np.where(count > 0, total / np.maximum(count, 1), np.nan)
        r.profile_edges, r.profile_x, r.profile_count = edges, 0.5 * (edges[1:] + edges[:-1]), count
        r.profile_velocity_err = profile_error(which, v, interval, self.bins, self.batches)
        # a bowl's profile is also one in height: each bin's centre-line floor height
        feeder = feeder_of(self.result.parameters)
        r.profile_height = feeder.height_at(r.profile_x) if feeder is not None else None

    def _mass_balance(self, frames: np.ndarray) -> None:
        balance = self.result.mass_balance
        last = int(frames[-1])
        for name in L.MASS_BALANCE_COUNTS:
            value = None if balance is None or name not in balance else int(balance[name][last])
            self.results[name] = value
        for name in ("rejected", "returned"):  # a feeder line's; returned if it recirculates
            if balance is not None and name in balance:
                self.results[name] = int(balance[name][last])

    def _bed(self, frames: np.ndarray, t_a: float, t_b: float, freq: float) -> None:
        """The bed section by section (module docstring, "Sections and joints"): ``sections``
        and ``rejects_by_tooling`` for a line; for any result its drift over the window
        (``bed``, ``bed_trends``, ``unsteady``)."""
        r, result = self.results, self.result
        edge = path_end(result)
        bounds = section_bounds(result.parameters, edge)
        feeder = feeder_of(result.parameters)
        bowl = feeder is not None and feeder.bowl is not None
        rejects = self._rejects(feeder)
        crossings, counts = self._bed_pass(frames)
        inside = (self.times >= t_a - 1e-12) & (self.times <= t_b + 1e-12)
        window, window_t = frames[inside], self.times[inside]
        span = (t_a, t_b, freq)
        cuts = batch_cuts(t_a, t_b, freq, max(self.batches, DRIFT_MIN_BATCHES))
        # A store without inflow (the first element of a pre-filled bed, no inlet: a line's
        # section 1, a bowl's helix and chute) drains at its out-flux however steadily it
        # feeds: only a fed section's hold-up must hold.
        fed = is_fed(result.parameters)
        store = store_sections(result.parameters)
        sections, speeds, held, trends = [], [], [], []
        # a bowl's sections are named: the helix, the chute, then its exit line's elements (s<k>)
        names = BOWL_SECTIONS + tuple(f"s{e.number}" for e in feeder.elements[1:]) if bowl else ()
        for k, (lo, hi) in enumerate(bounds):
            name = names[k] if k < len(names) else None
            last = k == len(bounds) - 1
            # Section 1 takes everything upstream of the joint, the last one up to the edge.
            x_min = -math.inf if k == 0 else lo
            x_max = edge if last else float(np.nextafter(hi, -math.inf))
            _, v, interval, (m, _) = period_velocities(result, window, self.axis,
                                                       x_max if math.isfinite(x_max) else math.inf, x_min)
            chain_t = result.time[window[::m]]
            mid_t = 0.5 * (chain_t[interval] + chain_t[interval + 1]) if len(v) else np.empty(0)
            n = counts[inside, k].astype(float)
            flux = (r.parts_per_s, r.parts_per_s_err) if last else \
                batch_rate(crossings[k][0], np.ones(len(crossings[k][0])), *span, self.batches)
            sections.append(self._section(k, lo, hi, v, interval, window_t, n, flux, rejects, span))
            speeds.append(batch_means(mid_t, v, cuts))
            held.append(batch_means(window_t, n, cuts))
            trends += trend(k + 1, "conveying speed", speeds[-1], name)
            if k >= store or fed:
                trends += trend(k + 1, "hold-up", held[-1], name)
        r.bed = {"batch_edges": cuts, "speed": np.array(speeds), "hold_up": np.array(held),
                 "joint_crossings": crossings}
        r.bed_trends = trends
        r.unsteady = unsteady(trends)
        along = "x" if feeder is None or feeder.path_is_x else "path"
        for sec in sections:
            sec["along"] = along
        for sec, name in zip(sections, names):
            sec["name"] = name
        if feeder is not None and feeder.several_sections:  # (a line; a bowl's helix and chute)
            r.sections = sections
            r.rejects_by_tooling = self._rejects_by_tooling(rejects, span)

    def _rejects(self, feeder) -> dict:
        """Every reject: ``time``, ``section`` (1-based, along the path), ``where`` (its path
        coordinate [m]) and ``id`` (-1 for a bowl's fall): a bowl's falls back into it, where
        they left its track, and the parts a line (or a bowl's exit line) lost over a side,
        where they crossed the catch plane (empty for a single track)."""
        r, line = self.results, self.result.rejects
        time = [np.asarray(line["time"], dtype=float)]
        section = [np.asarray(line["section"], dtype=np.int64)]
        x = np.asarray(line["position"][:, self.axis], dtype=float)
        where = [feeder.path_at_x(x) if feeder is not None else x]
        ids = [np.asarray(line["id"], dtype=np.int64)]
        if feeder is not None and feeder.bowl is not None:
            fell = np.asarray(r.fell_where, dtype=float)
            time.append(np.asarray(r.fell_times, dtype=float))
            section.append((feeder.section_at(fell) + 1).astype(np.int64))
            where.append(fell)
            ids.append(np.full(len(fell), -1, dtype=np.int64))
        time, section, where = np.concatenate(time), np.concatenate(section), np.concatenate(where)
        ids = np.concatenate(ids)
        order = np.argsort(time, kind="stable")
        return {"time": time[order], "section": section[order], "where": where[order], "id": ids[order]}

    def _section(self, k: int, lo: float, hi: float, v, interval, window_t, n, flux: tuple,
                 rejects: dict, span: tuple) -> dict:
        """Section ``k``'s figures (0-based; ``sections`` in the class docstring): whole-period
        speeds ``v`` (their ``interval`` numbers), parts over it ``n`` at the window's frames
        (times ``window_t``), the (rate, error) through its downstream end."""
        t_a, t_b, freq = span
        speed, speed_err = _mean_and_batch_error(v, interval, self.batches)
        hold_up = float(n.mean()) if len(n) else math.nan
        per_batch = batch_means(window_t, n, batch_cuts(t_a, t_b, freq, self.batches))
        per_batch = per_batch[np.isfinite(per_batch)]
        hold_err = (float(per_batch.std(ddof=1) / math.sqrt(len(per_batch))) if len(per_batch) >= 2
                    else math.nan)
        mine = rejects["section"] == k + 1
        rate, rate_err = batch_rate(rejects["time"][mine], np.ones(int(mine.sum())), t_a, t_b, freq,
                                    self.batches)
        length = hi - lo
        return {"section": k + 1, "x_from": lo, "x_to": hi,
                "joint_flux": flux[0], "joint_flux_error": flux[1],
                "reject_rate": rate, "reject_rate_error": rate_err,
                "rejects_in_window": int((mine & (rejects["time"] >= t_a) & (rejects["time"] < t_b)).sum()),
                "speed": speed, "speed_error": speed_err,
                "line_density": hold_up / length if length > 0 else math.nan,
                "hold_up": hold_up, "hold_up_error": hold_err}

    def _rejects_by_tooling(self, rejects: dict, span: tuple) -> dict:
        """Per tool (:data:`.line.TOOLING`): rejects per second in the window with their
        batch-means error, the number in the window and in the run analysed; None for a
        tool the line does not have (a jet: no entry, unless the line has one)."""
        result, (t_a, t_b, freq) = self.result, span
        size = float(result.parameters.get("part_size", 0.0))
        t_lo, t_hi = float(self.times[0]), float(self.times[-1])
        run = (rejects["time"] > t_lo) & (rejects["time"] <= t_hi)
        stations = feeder_of(result.parameters).stations
        which = tooling(rejects["where"], rejects["section"], stations, size)
        has = {kind: any(st.kind == kind for st in stations)
               for kind in ("side_drop", "wiper", "jet", "slot")}
        if has["jet"]:  # a part a jet fired at is the jet's reject, wherever it fell
            blown = fired_at(rejects["id"], rejects["time"], rejects["section"], result.jet_firings)
            which = np.where(blown, TOOLING.index("jet"), which)
        out = {}
        for k, name in enumerate(TOOLING):
            if name in ("jet", "slot") and not has[name]:
                continue  # (a line without one: the figures lines have always had)
            if not has.get(name, True):
                out[name] = None
                continue
            mine = which == k
            rate, err = batch_rate(rejects["time"][mine], np.ones(int(mine.sum())), t_a, t_b, freq,
                                   self.batches)
            inside = mine & (rejects["time"] >= t_a) & (rejects["time"] < t_b)
            out[name] = {"per_s": rate, "per_s_error": err, "in_window": int(inside.sum()),
                         "total": int((mine & run).sum())}
        return out

    # -- views ----------------------------------------------------------------------
    def summary(self) -> dict:
        """The command's figures (JSON-ready)."""
        return self.as_dict([k for k in SUMMARY_KEYS if k in self.results])
