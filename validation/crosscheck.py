"""Run a validation case: the DEM and the model on the same parameters.

``CrossCheck(case, out_dir).run()`` runs the deck once per sweep point through
``vibrofeed run`` (in parallel with ``jobs`` > 1), evaluates the model of
``vibrofeed.models.deck`` on the same parameters, and returns one :class:`Row` per
compared quantity plus the PNG figures it wrote. The comparison itself is the
case's ``kind``:

``flights``
    hopping part: lift-off phase, landing times and flight durations of the
    first flights from a common start (part resting on the plate at t = 0);
``transport``
    steady mean conveying speed along the track (any waveform, incline);
``period``
    period of the hopping attractor (1, 2, ...) after a transient;
``vertical``
    net climbing speed of a part squeezed against a vertical vibrating wall;
``replay``
    measured trials (``trials``) played on a vertical wall in LIGGGHTS and
    through the vertical-transport model with the same inputs;
``pulloff``
    the largest tension of a cohesive contact pulled apart slowly (deck
    ``pulloff``) against JKR's pull-off force 1.5 pi gamma R*;
``reference``
    DEM against DEM: the bulk feeder's feed rate and conveying velocity at
    each sweep point against those of the point ``[compare] reference`` names
    (e.g. the default stiffness), within a multiple of their combined
    batch-means errors (tolerance ``sigma``);
``line_transport``
    a feeder line (``sections=2``) carrying a few parts far apart: each
    section's whole-period speed against the single-part model of that
    section's own drive (``section_speed``);
``line_continuity``
    a feeder line fed steadily: in the steady window the outlet flux against
    the joint's (``joint_flux``), each section's line density times its speed
    against the flux through its end (``little_flux``, Little's law) and
    against the inlet's rate (``feed_flux``), and the density ratio against
    the speed ratio (``density_ratio``), DEM against DEM within a multiple of
    the combined errors.

The micro-scale kinds are ``micro_checks``'s, the box parts' rocking, free rocking and
tipping-or-sliding (``rocking_onset``, ``free_rocking``, ``tip_or_slide``) ``rocking_checks``'s.
"""

from __future__ import annotations

import contextlib
import math
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import CaseError, ParameterWarning, said
from ..feeders.feeder import Feeder
from ..models import deck as dm
from ..models.constants import G
from ..results import layout as L
from . import micro_checks, rocking_checks
from .cases import DERIVED_SWEEP_KEYS, Case
from .outcome import Outcome, Run, label, row


class CrossCheck:
    """Run one case: its DEM runs through the batch executor (``jobs`` at a
    time, each isolated), then the comparison of its kind. ``reuse`` keeps DEM
    results whose run id (deck, includes, parameters, version) matches."""

    def __init__(self, case: Case, out_dir, ranks: int = 1, jobs: int = 1, reuse: bool = False,
                 on_run: Callable[[str, str], None] | None = None):
        if case.kind not in KINDS:
            raise CaseError(f"case {case.name}: unknown kind {said(case.kind)} ({', '.join(KINDS)})")
        self.case, self.ranks, self.jobs, self.reuse = case, ranks, max(1, jobs), reuse
        self.dir = Path(out_dir) / case.name
        self.on_run = on_run or (lambda label, state: None)

    # -- runs ---------------------------------------------------------------------
    def plan(self) -> list[Run]:
        """The case's DEM runs (replay cases: one per measured trial)."""
        from vibrofeed.decks import Deck
        from vibrofeed.engine.batch import RunRequest
        from vibrofeed.parameters import resolve

        if self.case.kind == "replay":
            return _replay_runs(self.case, self.dir, self.ranks, self.reuse)
        deck = Deck.find(self.case.deck)
        runs = []
        for values in self.case.points():
            merged = {**self.case.parameters, **values}
            given = {}
            for key, value in merged.items():
                if key in DERIVED_SWEEP_KEYS:  # Gamma given: the deck wants an amplitude
                    freq = float(merged.get("freq", deck.variables["freq"].default))
                    given[DERIVED_SWEEP_KEYS[key]] = repr(float(dm.amp_from_gamma(float(value), freq)))
                else:
                    given[key] = str(value)
            point = label(values)
            with held_across_points():
                params = resolve(deck, given)
            if self.case.kind == "vertical":
                check_vertical_case(params)
            output = self.dir / f"{point}.h5"
            # (the run gets what the case gives; the deck's defaults are its own)
            request = RunRequest(deck, given, output, label=point, ranks=self.ranks,
                                 reuse=self.reuse)
            runs.append(Run(point, values, params, output, request))
        return runs

    def run(self) -> Outcome:
        from vibrofeed.engine.batch import run_many

        runs = self.plan()
        self.dir.mkdir(parents=True, exist_ok=True)
        with held_across_points():  # (each run resolves its parameters again)
            outcomes = run_many([r.request for r in runs], jobs=self.jobs,
                                on_state=lambda request, state: self.on_run(request.label, state))
        for o in outcomes:
            if not o.ok:  # after the others finished
                raise o.error
        outcome = Outcome(self.case)
        KINDS[self.case.kind](self.case, runs, outcome, self.dir)
        return outcome


@contextlib.contextmanager
def held_across_points():
    """A case holds its parameters across its points by design (vdw_sticking keeps its
    roughness at A = 0): a parameter idle at one point is no slip of the user's, and its
    warning is not shown."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r".* has no effect: ", category=ParameterWarning)
        yield


def _realised_restitution(case: Case, run: Run, result, out: Outcome) -> float:
    """The DEM's e: what its contact realises at the run's impacts (median
    over the faster half), recorded as a row against the nominal value."""
    from vibrofeed.postproc.flights import Flights

    e_dem = Flights(result).run().results.realised_restitution
    if e_dem != e_dem:
        raise CaseError(f"case {case.name} [{run.label}]: restitution = \"realised\" needs an "
                        "impact, and the part never lands")
    out.rows.append(row(case, "restitution", run.label, run.number("restitution"), e_dem))
    return e_dem


# ----------------------------------------------------------------- kind: flights
def model_flights(events, t_end: float) -> list[tuple[float, float, str]]:
    """(launch, landing, kind) of the model's flights: a flight starts at a
    lift-off ('launch') or at an impact the part rebounds from, ends at the
    next impact."""
    out, start = [], None
    for ev in events:
        if ev.t > t_end:
            break
        if ev.kind == "impact":
            if start is not None:
                out.append((start[0], ev.t, start[1]))
            start = (ev.t, "rebound") if ev.info.get("rebound") else None
        elif ev.kind == "launch":
            start = (ev.t, "lift-off")
        elif ev.kind == "rest":
            start = None
    return out


def _flights(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    from vibrofeed.postproc.flights import Flights
    from vibrofeed.results.reader import Result

    from ..models.part_on_surface import simulate
    from .plots import plot_flights

    n_compare = int(case.compare.get("flights", 3))
    min_flight = float(case.compare.get("min_flight", 0.05))  # [periods]
    realised = case.compare.get("restitution", "nominal") == "realised"
    panels = []
    for run in runs:
        p = dict(run.params)
        T = 1.0 / run.number("freq")
        with Result(run.output) as r:
            fl = Flights(r).run().results
            t_end = float(r.time[-1])
            dem_t, dem_gap = fl.time, fl.gap
        if realised:
            with Result(run.output) as r:
                p["restitution"] = repr(_realised_restitution(case, run, r, out))
        traj = simulate(dm.waveform(p), dm.part(p), n_periods=t_end / T,
                        incline=run.number("incline"), samples_per_period=400)
        model = [f for f in model_flights(traj.events, t_end) if f[1] - f[0] >= min_flight * T]
        dem = [(a, b, k) for (a, b), k in zip(fl.flights, fl.kinds) if b - a >= min_flight * T]
        if not model or not dem:
            raise CaseError(f"case {case.name} [{run.label}]: no flight longer than "
                            f"{min_flight} periods (model {len(model)}, DEM {len(dem)})")
        if "launch_phase" in case.tolerance and model[0][2] == "lift-off":
            out.rows.append(row(case, "launch_phase", run.label, model[0][0] / T, dem[0][0] / T, "T"))
        for k, (m, d) in enumerate(zip(model[:n_compare], dem[:n_compare]), start=1):
            out.rows.append(row(case, "landing_time", f"{run.label},#{k}", m[1] / T, d[1] / T, "T"))
            out.rows.append(row(case, "flight_duration", f"{run.label},#{k}",
                                 (m[1] - m[0]) / T, (d[1] - d[0]) / T, "T"))
        radius = run.number("radius")
        panels.append(dict(label=run.label, T=T, dem_t=dem_t, dem_gap=dem_gap,
                           model_t=traj.t, model_gap=traj.z - traj.zs, radius=radius,
                           surface_t=traj.t, surface_z=traj.zs))
    out.figures.append(plot_flights(case, panels, fig_dir / "trajectories.png"))


# --------------------------------------------------------------- kind: transport
def _transport(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    from vibrofeed.postproc.path import bowl_of
    from vibrofeed.postproc.transport import Transport
    from vibrofeed.results.reader import Result

    from .plots import plot_speed_curve

    transient = float(case.compare.get("transient_periods", 10))
    points = []
    for run in runs:
        p = dict(run.params)
        T = 1.0 / run.number("freq")
        if bowl_of(p) is not None:  # a bowl: along its helix, against the drive the helix sees
            model, dem = _bowl_rows(case, run, transient * T, out)
            out.rows.append(row(case, "mean_speed", run.label, model, dem, "m/s"))
            points.append((run, model, dem))
            continue
        with Result(run.output) as r:
            dem = Transport(r, start=transient * T).run().results.mean_velocity
            if case.compare.get("restitution", "nominal") == "realised":
                p["restitution"] = repr(_realised_restitution(case, run, r, out))
        model = dm.transport(p).velocity
        out.rows.append(row(case, "mean_speed", run.label, model, dem, "m/s"))
        points.append((run, model, dem))
    axis = case.compare.get("plot_axis") or (next(iter(case.sweep)) if case.sweep else None)
    if axis is not None:
        out.figures.append(plot_speed_curve(case, runs, points, axis, fig_dir / "speed.png"))


def _bowl_rows(case: Case, run: Run, t_from: float, out: Outcome) -> tuple[float, float]:
    """(model, DEM) mean speed up a bowl's helix (:func:`bowl_speeds`), the parts checked
    dilute, and the row of what the linear model leaves out: the torsion's centripetal pull
    at the parts, in g (model 0)."""
    from vibrofeed.results.reader import Result

    p = dict(run.params)
    with Result(run.output) as r:
        model, dem, centripetal = bowl_speeds(r, t_from)
        closest = min_distance(r)
    if closest < part_span(p):
        raise CaseError(f"case {case.name} [{run.label}]: not dilute: two parts came within "
                        f"{closest:.3g} m of each other (they can touch below {part_span(p):.3g} m)")
    out.rows.append(row(case, "centripetal", run.label, 0.0, centripetal / G, "g"))
    return model, dem


def _climb(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    """A bowl's climb threshold: up the helix or not, the model's sign against the DEM's."""
    from .plots import plot_speed_curve

    transient = float(case.compare.get("transient_periods", 10))
    points = []
    for run in runs:
        model, dem = _bowl_rows(case, run, transient / run.number("freq"), out)
        out.rows.append(row(case, "climbs", run.label, float(model > 0), float(dem > 0)))
        points.append((run, model, dem))
    axis = case.compare.get("plot_axis") or (next(iter(case.sweep)) if case.sweep else None)
    if axis is not None:
        out.figures.append(plot_speed_curve(case, runs, points, axis, fig_dir / "speed.png"))


def _whole_periods(result, t_from: float):
    """(times, path coordinates (frames, slots), ids) at the frames a whole number of periods
    apart from ``t_from`` on (vibrofeed.postproc.feedrate.period_lag, .path.along)."""
    from vibrofeed.postproc.feedrate import period_lag
    from vibrofeed.postproc.path import along

    frames = np.nonzero(result.time >= t_from - 1e-12)[0]
    m, _ = period_lag(result.time[frames], float(result.parameters["freq"]))
    chain = frames[::m]
    s, _ = along(result, chain)
    return result.time[chain], s, result.read("id", frames=chain), chain


def bowl_speeds(result, t_from: float) -> tuple[float, float, float]:
    """(model, DEM, centripetal) of the parts on a bowl's helix after ``t_from``: each part's
    speed along the helix over whole periods (its path coordinate, vibrofeed.postproc.path)
    until it reaches the chute, and the single-part model under the drive the helix sees at
    the part's own mean radius there (vibrofeed.bowl.track_drive: the torsion's amplitude
    grows with the radius); the means over the parts [m/s], and the largest peak centripetal
    acceleration the torsion adds at their radii [m/s^2], which the model leaves out.

    A part counts if it is on the helix for at least half the measured span. The chute is
    left out because the helix's drive is not its drive: along the chute's line the torsion
    also shakes parts across it, by x theta (docs/bowl.md), and they slow there."""
    from vibrofeed.bowl import bowl_from, track_drive

    p = result.parameters
    b = bowl_from(p)
    freq = float(p["freq"])
    time, s, ids, chain = _whole_periods(result, t_from)
    position = result.read("position", frames=chain)
    same = (ids == ids[0]).all(axis=0) & (ids[0] != L.ID_FILL)
    helix = np.isfinite(s) & (s <= b.length)
    # the frames up to each part's first one off the helix
    ends = np.where(helix.all(axis=0), len(chain), np.argmin(helix, axis=0)) - 1
    keep = same & (ends >= 1)
    keep &= time[np.maximum(ends, 0)] - time[0] >= 0.5 * (time[-1] - time[0])
    if not keep.any():
        raise CaseError("no part stayed on the bowl's helix for half the measurement")
    models, dems, centripetal = [], [], 0.0
    for j in np.nonzero(keep)[0]:
        k = ends[j]
        dems.append((s[k, j] - s[0, j]) / (time[k] - time[0]))
        r = float(np.hypot(position[:k + 1, j, 0], position[:k + 1, j, 1]).mean())
        d = track_drive(float(p["amp_t"]), float(p["amp_n"]), float(p["phase"]), freq,
                        float(p["helix_angle"]), b.r_mid, r)
        models.append(dm.transport({**p, "amp_t": d.amp_t, "amp_n": d.amp_n, "phase": d.phase,
                                    "incline": d.incline}).velocity)
        centripetal = max(centripetal, d.centripetal)
    return float(np.mean(models)), float(np.mean(dems)), centripetal


def chute_speeds(result, t_from: float, bin_width: float) -> list[tuple[float, float, int, float]]:
    """A bowl's parts on its chute after ``t_from``: their speed along it over each whole-period
    interval (path coordinate, vibrofeed.postproc.path) with both ends on the chute, binned by
    the interval's mid-point x along the chute from the slot in bins of ``bin_width`` [m], up
    to a part size short of the outlet edge (where a part tips over it). [(x_lo, x_hi,
    intervals, mean speed [m/s])] of the bins holding any."""
    from vibrofeed.bowl import bowl_from

    p = result.parameters
    b = bowl_from(p)
    time, s, ids, _ = _whole_periods(result, t_from)
    x = s - b.length  # along the chute (NaN off the track)
    end = b.chute_length - float(p["part_size"])
    on = (ids[:-1] == ids[1:]) & (ids[:-1] != L.ID_FILL) & (x[:-1] >= 0) & (x[1:] >= 0) \
        & (x[:-1] <= end) & (x[1:] <= end)
    mid = 0.5 * (x[:-1] + x[1:])[on]
    speed = ((s[1:] - s[:-1]) / (time[1:] - time[:-1])[:, None])[on]
    out = []
    for lo in np.arange(0.0, end, bin_width):
        sel = (mid >= lo) & (mid < min(lo + bin_width, end))
        if sel.any():
            out.append((float(lo), float(min(lo + bin_width, end)), int(sel.sum()), float(speed[sel].mean())))
    return out


def _chute(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    """A bowl's chute: the parts' speed along it in bins of x, against the sliding block
    between the chute's walls under the drive it sees there (vibrofeed.bowl.chute_speed),
    each bin with at least ``min_intervals`` whole-period intervals."""
    from vibrofeed.bowl import chute_speed
    from vibrofeed.postproc.feedrate import dilute_limit
    from vibrofeed.results.reader import Result

    from .plots import plot_chute

    transient = float(case.compare.get("transient_periods", 10))
    width = float(case.compare.get("bin_width", 1e-3))
    least = int(case.compare.get("min_intervals", 10))
    for run in runs:
        with Result(run.output) as r:
            p = dict(r.parameters)  # (as the analyses read them: numbers)
            bins = chute_speeds(r, transient / run.number("freq"), width)
        points = []
        for lo, hi, n, dem in bins:
            if n < least:
                continue
            x = 0.5 * (lo + hi)
            model = chute_speed(p, x).velocity
            label_x = f"x={x * 1e3:.1f}mm" + ("" if run.label == "base" else f",{run.label}")
            out.rows.append(row(case, "chute_speed", label_x, model, dem, "m/s"))
            points.append((x, n, model, dem))
        if not points:
            raise CaseError(f"case {case.name} [{run.label}]: no bin of the chute holds {least} "
                            "whole-period intervals of a part")
        helix, _ = dilute_limit(p)  # the helix's drive alone, at its centre line
        curve_x = np.linspace(0.0, points[-1][0] + width / 2, 13)
        curve = [chute_speed(p, float(c)).velocity for c in curve_x]
        out.figures.append(plot_chute(case, points, (curve_x, curve), helix,
                                      fig_dir / f"chute_{run.label}.png"))


def min_distance(result) -> float:
    """Smallest distance [m] between the centres of two parts at any frame; inf without two."""
    ids, x = result.read("id"), result.read("position")
    best = math.inf
    for k in range(len(ids)):
        here = x[k][ids[k] != L.ID_FILL]
        if len(here) >= 2:
            d = np.linalg.norm(here[:, None, :] - here[None, :, :], axis=-1)
            best = min(best, float(d[np.triu_indices(len(here), 1)].min()))
    return best


# ------------------------------------------------------------------ kind: period
def landing_period(landings: np.ndarray, T: float, t_from: float, max_period: int = 8,
                   tol: float = 0.005) -> int:
    """Smallest p such that every landing after ``t_from`` (but the last p
    periods) has a landing p periods later, to ``tol`` periods; 0 if none."""
    L = np.asarray(landings) / T
    L = L[L >= t_from / T]
    if len(L) < 2:
        return 0
    for p in range(1, max_period + 1):
        head = L[L <= L[-1] - p + tol]
        if len(head) < 2:
            break
        if all(np.min(np.abs(L - (x + p))) <= tol for x in head):
            return p
    return 0


def _period(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    from vibrofeed.postproc.flights import Flights
    from vibrofeed.results.reader import Result

    from ..models.hopping import bifurcation_diagram
    from ..models.part_on_surface import simulate
    from .plots import plot_bifurcation

    transient = float(case.compare.get("transient_periods", 20))
    min_flight = float(case.compare.get("min_flight", 0.05))
    tol = float(case.compare.get("repeat_tol", 0.005))
    realised = case.compare.get("restitution", "nominal") == "realised"
    dem_points, e_values = [], []
    for run in runs:
        p = dict(run.params)
        T = 1.0 / run.number("freq")
        gamma = dm.gamma_from_amp(run.number("amp_n"), run.number("freq"))
        with Result(run.output) as r:
            fl = Flights(r).run().results
            t_end = float(r.time[-1])
            if realised:
                p["restitution"] = repr(_realised_restitution(case, run, r, out))
        e_values.append(float(p["restitution"]))
        keep = fl.durations >= min_flight * T
        dem_landings = fl.flights[keep, 1]
        traj = simulate(dm.waveform(p), dm.part(p), n_periods=t_end / T, samples_per_period=50)
        model_landings = np.array([b for a, b, _ in model_flights(traj.events, t_end)
                                   if b - a >= min_flight * T])
        model_p = landing_period(model_landings, T, transient * T, tol=tol)
        dem_p = landing_period(dem_landings, T, transient * T, tol=tol)
        out.rows.append(row(case, "period", run.label, model_p, dem_p, "T"))
        late = fl.flights[keep & (fl.flights[:, 0] >= transient * T)]
        dem_points.append((gamma, (late[:, 1] - late[:, 0]) / T))
    gammas = case.compare.get("diagram_gammas")
    if gammas:
        grid = np.linspace(gammas[0], gammas[1], int(gammas[2]))
        e = float(np.mean(e_values))
        diagram = bifurcation_diagram(grid, e, min_jump=min_flight)
        out.figures.append(plot_bifurcation(case, grid, diagram, dem_points,
                                            fig_dir / "bifurcation.png"))


# ---------------------------------------------------------------- kind: vertical
def _vertical(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    from vibrofeed.postproc.transport import Transport
    from vibrofeed.results.reader import Result

    from ..models.vertical import periodic_transport, simulate
    from .plots import plot_vertical

    transient = float(case.compare.get("transient_periods", 5))
    panels = []
    for run in runs:
        p = run.params
        T = 1.0 / run.number("freq")
        surface = dm.waveform(p)
        contact = dm.vertical_contact(p)
        with Result(run.output) as r:
            dem = Transport(r, start=transient * T).run().results
            t, x = r.track(int(r.part_ids[0]))
            xs = r.surface_position[:, 0]
            t_end = float(r.time[-1])
        n = max(int(round(t_end / T)), 3)
        model = periodic_transport(surface, contact, n_periods=n, skip_periods=int(transient))
        out.rows.append(row(case, "net_speed", run.label, model.net_speed, dem.mean_velocity, "m/s"))
        traj = simulate(surface, contact, t_end=t_end, t_eval=np.linspace(0, t_end, 2000))
        panels.append(dict(label=run.label, T=T, dem_t=t, dem_x=x[:, 0] - x[0, 0], surface_x=xs,
                           model_t=traj.t, model_x=traj.z - traj.z[0]))
    out.figures.append(plot_vertical(case, panels, fig_dir / "trajectories.png"))


def check_vertical_case(params: dict) -> None:
    """Refuse a vertical-transport case the feasibility bounds rule out."""
    from ..models.vertical import check_feasible

    wf = dm.waveform(params)
    a_max = float(np.max(np.abs(wf.acceleration(np.linspace(0, wf.period, 4001))[0])))
    contact = dm.vertical_contact(params)
    try:
        check_feasible(contact.mass, contact.normal_force, contact.mu_s, a_max)
    except ValueError as exc:
        raise CaseError(f"infeasible vertical transport: {exc}") from None


# ------------------------------------------------------------------ kind: replay
def _trials(case: Case):
    from .replay.trials import load_trials, trials_dir

    directory = trials_dir()
    if directory is None:
        raise CaseError("the measured trials are not available: put them in "
                        "../shared/data/vertical-transport or set VIBROFEED_TRIALS_DIR")
    wanted = case.compare.get("trials")
    trials = [t for t in load_trials(directory) if wanted is None or t.name in wanted]
    if wanted and len(trials) != len(wanted):
        found = {t.name for t in trials}
        raise CaseError(f"case {case.name}: trials not found in {directory}: "
                        f"{', '.join(n for n in wanted if n not in found)}")
    return trials


def _replay_force(case: Case, trial) -> float:
    return float(case.compare["normal_force_mg"][trial.name]) * float(case.parameters["mass"]) * G


def _replay_runs(case: Case, out_dir: Path, ranks: int, reuse: bool) -> list[Run]:
    """One LIGGGHTS replay per measured trial; ``values`` holds the trial."""
    from .replay.dem import replay_request
    from .replay.fit import prepare

    mass, mu = float(case.parameters["mass"]), float(case.parameters["mu"])
    runs = []
    for trial in _trials(case):
        prep = prepare(trial)
        output = out_dir / f"{trial.name}.h5"
        request = replay_request(prep, mass, _replay_force(case, trial), mu, output, ranks=ranks,
                                 reuse=reuse)
        runs.append(Run(trial.name, {"trial": prep}, dict(request.params), output, request))
    return runs


def _replay(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    from .plots import plot_replay
    from .replay.dem import replay_result
    from .replay.fit import replay

    mass, mu = float(case.parameters["mass"]), float(case.parameters["mu"])
    dems = []
    for run in runs:
        prep = run.values["trial"]
        force = _replay_force(case, prep.trial)
        model = replay(prep, mass, force, mu, mu)
        dem = replay_result(prep, run.output, force, mu)
        dems.append(dem)
        n = min(len(model.predicted_mm), len(dem.predicted_mm))
        diff = float(np.mean(np.abs(model.predicted_mm[:n] - dem.predicted_mm[:n])))
        out.rows.append(row(case, "mean_difference_mm", run.label, 0.0, diff, "mm"))
        out.rows.append(row(case, "mean_abs_error_mm", run.label, model.mean_abs_error_mm,
                             dem.mean_abs_error_mm, "mm"))
        out.rows.append(row(case, "final_displacement_mm", run.label, model.final_predicted_mm,
                             dem.final_predicted_mm, "mm"))
    out.figures.append(plot_replay(dems, fig_dir / "dem_replays.png", engine="dem"))


# ------------------------------------------------------------------ kind: pulloff
def jkr_pulloff(surface_energy: float, part_size: float, pair: int) -> float:
    """JKR's pull-off force [N] 1.5 pi gamma R* of two spheres of diameter
    ``part_size`` (pair 0: R* = R/2) or of one on a flat (pair 1: R* = R)."""
    radius = part_size / 2
    r_star = radius / 2 if pair == 0 else radius
    return 1.5 * math.pi * surface_energy * r_star


def _pulloff(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    from vibrofeed.results.reader import Result

    from .plots import plot_pulloff

    panels = []
    for run in runs:
        with Result(run.output) as r:
            z = r.read("position", frames=-1)[:, 2]
            pulled = int(np.nanargmax(z))  # the slot of the sphere moving up
            fz = r.read("force", slots=[pulled])[:, 0, 2]
            t = r.time
        tension = -fz  # the contact pulls the pulled sphere back
        model = jkr_pulloff(run.number("surface_energy"), run.number("part_size"),
                            int(run.number("pair")))
        out.rows.append(row(case, "pulloff", run.label, model, float(tension.max()), "N"))
        panels.append({"label": run.label, "t": t, "tension": tension, "model": model})
    out.figures.append(plot_pulloff(case, panels, fig_dir / "pulloff.png"))


# ---------------------------------------------------------------- kind: reference
# Bulk-feeder figures a reference case compares, with the key of each one's error.
REFERENCE_QUANTITIES = {"parts_per_s": ("parts_per_s_err", "1/s"),
                        "mean_velocity": ("mean_velocity_err", "m/s")}


def _reference(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    from vibrofeed.postproc.feedrate import FeedRate
    from vibrofeed.results.reader import Result

    from .plots import plot_reference

    wanted = case.compare.get("reference")
    if not isinstance(wanted, dict) or not wanted:
        raise CaseError(f"case {case.name}: kind reference needs [compare] reference = {{ key = value }}")
    unknown = sorted(set(case.tolerance) - set(REFERENCE_QUANTITIES))
    if unknown:
        raise CaseError(f"case {case.name}: no reference quantity {', '.join(unknown)} "
                        f"(known: {', '.join(REFERENCE_QUANTITIES)})")
    ref = [run for run in runs
           if all(k in run.values and float(run.values[k]) == float(v) for k, v in wanted.items())]
    if len(ref) != 1:
        raise CaseError(f"case {case.name}: [compare] reference {wanted} matches {len(ref)} sweep "
                        "points, not one")
    ref = ref[0]
    # One window for all, the reference's: a pre-filled bed drains, its speed and rate move
    # with the window, and each run's own window would compare different moments.
    with Result(ref.output) as r:
        base = FeedRate(r, model=False).run().summary()
    window = {"start": base["steady_from"], "end": base["steady_to"]}
    figures = {}
    for run in runs:
        with Result(run.output) as r:
            figures[run.label] = FeedRate(r, model=False, **window).run().summary()
    base = figures[ref.label]
    for run in runs:
        if run is ref:
            continue
        s = figures[run.label]
        for quantity in case.tolerance:
            err, unit = REFERENCE_QUANTITIES[quantity]
            out.rows.append(row(case, quantity, run.label, base[quantity], s[quantity], unit,
                                 error=math.hypot(base[err], s[err])))
    out.figures.append(plot_reference(case, runs, figures, ref, REFERENCE_QUANTITIES,
                                      fig_dir / "reference.png"))


# ------------------------------------------------------------ kinds: feeder lines
def drive_freqs(p: dict, sections: int) -> list[float]:
    """The drive frequencies [Hz] of a line's sections: freq, s2_freq, ..."""
    return [float(p["freq"])] + [float(p[f"s{k}_freq"]) for k in range(2, sections + 1)]


def whole_period_stride(frame_dt: float, freqs, tol: float = 1e-4, max_stride: int = 1000) -> int:
    """Fewest frame spacings ``frame_dt`` spanning a whole number of periods of every drive
    (``freqs``, to ``tol`` of a period): a displacement over them cancels the oscillation of
    whichever section a part is on (frames every 10 ms, 100 and 150 Hz: 2 frames, 2 and 3
    periods)."""
    f = np.asarray(freqs, dtype=float)
    for k in range(1, max_stride + 1):
        cycles = k * frame_dt * f
        if np.all(np.abs(cycles - np.round(cycles)) <= tol) and np.all(np.round(cycles) >= 1):
            return k
    raise CaseError(f"no lag of up to {max_stride} frames of {frame_dt:g} s spans whole periods of "
                    f"{', '.join(f'{x:g}' for x in f)} Hz: choose output_dt accordingly")


def part_span(p: dict) -> float:
    """Diameter [m] of the sphere around a bulk-deck part: two parts whose centres are
    farther apart cannot touch (sphere, chip box, disc cylinder, box clump)."""
    shape, size = int(float(p.get("shape", 0))), float(p["part_size"])
    if shape == 0:
        return size * (1 + float(p.get("size_spread", 0.0)))
    if shape == 3:  # a box: its clump's circumscribed sphere about the centre of mass
        from vibrofeed.feeders.records import Part

        return 2 * Part.from_values(p).reach
    t = float(p["part_thickness"])
    return math.sqrt(2 * size ** 2 + t ** 2) if shape == 1 else math.hypot(size, t)


def closest_approach(result, edge: float) -> float:
    """Smallest distance [m] between the centres of two parts on the line (track x up to the
    outlet ``edge``) at any frame; inf when no frame holds two."""
    ids = result.read("id")
    x = result.read("position")
    track_x = x[..., 0] - result.read("surface_position")[:, 0][:, None]
    best = math.inf
    for k in range(len(ids)):
        here = x[k][(ids[k] != L.ID_FILL) & (track_x[k] <= edge)]
        if len(here) >= 2:
            d = np.linalg.norm(here[:, None, :] - here[None, :, :], axis=-1)
            best = min(best, float(d[np.triu_indices(len(here), 1)].min()))
    return best


def section_speeds(result, t_from: float, joint_margin: float, edge_margin: float):
    """[(speed, samples)] per section of a line: the mean whole-period speed [m/s] of the
    parts over it after ``t_from`` (section 1's start-up) and the number of (part, interval)
    samples. Section 1 counts up to ``edge_margin`` before the joint, section 2 from
    ``joint_margin`` past it (a part landing on it is still speeding up) to ``edge_margin``
    before the outlet edge. The intervals span whole periods of every section's drive."""
    from vibrofeed.postproc.feedrate import outlet_x, period_velocities
    from vibrofeed.postproc.line import section_bounds

    p = result.parameters
    edge = outlet_x(result)
    bounds = section_bounds(p, edge)
    time = result.time
    stride = whole_period_stride(float(np.median(np.diff(time))), drive_freqs(p, len(bounds)))
    frames = np.nonzero(time >= t_from - 1e-12)[0][::stride]
    out = []
    for k, (lo, hi) in enumerate(bounds):
        x_min = -math.inf if k == 0 else lo + joint_margin
        _, v, _, _ = period_velocities(result, frames, 0, hi - edge_margin, x_min)
        out.append((float(v.mean()) if len(v) else math.nan, len(v)))
    return out


def _line_transport(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    from vibrofeed.postproc.feedrate import outlet_x, period_velocities
    from vibrofeed.results.reader import Result

    from .plots import plot_line_speeds

    transient = float(case.compare.get("transient_periods", 10))
    joint_margin = float(case.compare["joint_margin"])
    panels = []
    for run in runs:
        p = dict(run.params)
        size = run.number("part_size")
        with Result(run.output) as r:
            edge = outlet_x(r)
            closest = closest_approach(r, edge)
            t_from = transient / run.number("freq")
            speeds = section_speeds(r, t_from, joint_margin, size)
            # every interval after the start-up, for the figure
            step = whole_period_stride(float(np.median(np.diff(r.time))), drive_freqs(p, 2))
            x_all, v_all, _, _ = period_velocities(r, np.nonzero(r.time >= t_from)[0][::step], 0, edge)
        if closest < part_span(p):  # they may have touched: not one part alone
            raise CaseError(f"case {case.name} [{run.label}]: not dilute: two parts came within "
                            f"{closest:.3g} m of each other (they can touch below {part_span(p):.3g} m)")
        models = []
        for k, (dem, n) in enumerate(speeds, start=1):
            if n == 0:
                raise CaseError(f"case {case.name} [{run.label}]: no part was measured on section "
                                f"{k} (lengthen t_end or move the pre-fill towards the joint)")
            models.append(dm.transport(Feeder.from_values(p).section_values(k)).velocity)
            out.rows.append(row(case, "section_speed", f"{run.label},s{k}", models[-1], dem, "m/s"))
        joint = run.number("track_length")
        panels.append(dict(label=run.label, x=x_all, v=v_all, model=models, dem=[s for s, _ in speeds],
                           bounds=[(0.0, joint), (joint, edge)],
                           stretches=[(0.0, joint - size), (joint + joint_margin, edge - size)]))
    out.figures.append(plot_line_speeds(case, panels, fig_dir / "section_speeds.png"))


def little_flows(result, fr, x_from: float, batches: int) -> list[dict]:
    """Per section of a line, over the feed rate's steady window (``fr``: FeedRate results):
    ``hold_up`` [parts] (mean over the window's frames) and ``speed`` [m/s] (mean whole-period
    speed), each with its batch-means error (``batches`` batches of whole periods, as FeedRate's),
    the line density ``rho`` [1/m] and ``flow`` = rho x speed [1/s] with its error (the two
    combined as independent). Section 1 is taken from ``x_from`` on: a part dropped by the inlet
    travels only from where it lands, so over the whole section rho v is the flux times
    (joint - landing x) / joint; Little's law holds on a stretch every part crosses entirely."""
    from vibrofeed.postproc.feedrate import outlet_x, period_velocities
    from vibrofeed.postproc.line import batch_cuts, batch_means, bed_pass, section_bounds

    p, time = result.parameters, result.time
    edge = outlet_x(result)
    joint = section_bounds(p, edge)[1][0]
    t_a, t_b = fr.steady_from, fr.steady_to
    window = np.nonzero((time >= t_a - 1e-12) & (time <= t_b + 1e-12))[0]
    gone = result.outlet, result.rejects
    _, counts = bed_pass(result, window, [x_from, joint], edge, np.r_[gone[0]["id"], gone[1]["id"]],
                         np.r_[gone[0]["time"], gone[1]["time"]])
    cuts = batch_cuts(t_a, t_b, float(p["freq"]), batches)
    out = []
    for k, (lo, hi) in enumerate([(x_from, joint), (joint, edge)]):
        x_max = float(np.nextafter(hi, -math.inf)) if k == 0 else hi  # the joint is section 2's
        _, v, interval, (m, _) = period_velocities(result, window, 0, x_max, lo)
        chain_t = time[window[::m]]
        mid_t = 0.5 * (chain_t[interval] + chain_t[interval + 1])
        n = counts[:, k + 1].astype(float)  # bed_pass's stretch 0 lies before x_from
        held, speed = float(n.mean()), float(v.mean()) if len(v) else math.nan
        err_n = batch_error(batch_means(time[window], n, cuts))
        err_v = batch_error(batch_means(mid_t, v, cuts))
        flow = held / (hi - lo) * speed
        rel = math.hypot(err_n / held, err_v / speed) if held > 0 and speed else math.nan
        out.append({"hold_up": held, "hold_up_error": err_n, "speed": speed, "speed_error": err_v,
                    "rho": held / (hi - lo), "flow": flow, "flow_error": abs(flow) * rel})
    return out


def inlet_flux(result, t_a: float, t_b: float) -> tuple[float, float]:
    """(rate, error) [1/s] of the parts the inlet inserted between the frames at the ends of
    the window [t_a, t_b] (the mass balance's ``inserted``). The inlet inserts ``inlet_batch``
    parts every so many steps, so the count is exact to one insertion at either end: error
    inlet_batch / window."""
    time = result.time
    k = np.nonzero((time >= t_a - 1e-12) & (time <= t_b + 1e-12))[0]
    inserted = result.mass_balance["inserted"]
    span = float(time[k[-1]] - time[k[0]])
    batch = float(result.parameters.get("inlet_batch", 1))
    return float(inserted[k[-1]] - inserted[k[0]]) / span, batch / span


def batch_error(series) -> float:
    """Standard error of the mean of batch values (NaN batches, which saw nothing, left
    out); NaN with fewer than two."""
    y = np.asarray(series, dtype=float)
    y = y[np.isfinite(y)]
    return float(y.std(ddof=1) / math.sqrt(len(y))) if len(y) >= 2 else math.nan


def _line_continuity(case: Case, runs: list[Run], out: Outcome, fig_dir: Path) -> None:
    from vibrofeed.postproc.feedrate import FeedRate
    from vibrofeed.results.reader import Result

    from .plots import plot_line_continuity

    x_from = float(case.compare["section1_from"])
    batches = int(case.compare.get("batches", 10))
    panels = []
    for run in runs:
        with Result(run.output) as r:
            fr = FeedRate(r, batches=batches, model=False).run().results
            if fr.reason:  # what follows holds in steady feeding only
                raise CaseError(f"case {case.name} [{run.label}]: no steady feeding to compare: "
                                f"{fr.reason}")
            flows = little_flows(r, fr, x_from, batches)
            feed, feed_error = inlet_flux(r, fr.steady_from, fr.steady_to)
        (j1, e1), (j2, e2) = [(s["joint_flux"], s["joint_flux_error"]) for s in fr.sections]
        # what crosses the joint leaves through the outlet or over section 2's sides
        r2, er2 = fr.sections[1]["reject_rate"], fr.sections[1]["reject_rate_error"]
        out.rows.append(row(case, "joint_flux", run.label, j1, j2 + r2, "1/s",
                            error=math.sqrt(e1 ** 2 + e2 ** 2 + er2 ** 2)))
        for k, (flux, err) in enumerate([(j1, e1), (j2, e2)]):
            f = flows[k]
            out.rows.append(row(case, "little_flux", f"{run.label},s{k + 1}", flux, f["flow"], "1/s",
                                error=math.hypot(err, f["flow_error"])))
            out.rows.append(row(case, "feed_flux", f"{run.label},s{k + 1}", feed, f["flow"], "1/s",
                                error=math.hypot(feed_error, f["flow_error"])))
        a, b = flows
        speed_ratio = b["speed"] / a["speed"]
        density_ratio = a["rho"] / b["rho"]
        error = math.hypot(speed_ratio * math.hypot(a["speed_error"] / a["speed"],
                                                    b["speed_error"] / b["speed"]),
                           density_ratio * math.hypot(a["hold_up_error"] / a["hold_up"],
                                                      b["hold_up_error"] / b["hold_up"]))
        out.rows.append(row(case, "density_ratio", run.label, speed_ratio, density_ratio, "",
                            error=error))
        panels.append(dict(label=run.label, feed=(feed, feed_error),
                           fluxes=[(j1, e1), (j2 + r2, math.hypot(e2, er2))],
                           flows=[(f["flow"], f["flow_error"]) for f in flows],
                           window=(fr.steady_from, fr.steady_to)))
    out.figures.append(plot_line_continuity(case, panels, fig_dir / "continuity.png"))


KINDS = {"flights": _flights, "transport": _transport, "climb": _climb, "chute": _chute, "period": _period,
         "vertical": _vertical, "replay": _replay, "pulloff": _pulloff, "reference": _reference,
         "line_transport": _line_transport, "line_continuity": _line_continuity,
         **micro_checks.KINDS, **rocking_checks.KINDS}
