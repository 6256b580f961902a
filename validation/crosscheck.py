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
    batch-means errors (tolerance ``sigma``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import CaseError
from ..models import deck as dm
from ..models.constants import G
from . import micro_checks
from .cases import DERIVED_SWEEP_KEYS, Case
from .outcome import Outcome, Run, label, row


class CrossCheck:
    """Run one case: its DEM runs through the batch executor (``jobs`` at a
    time, each isolated), then the comparison of its kind. ``reuse`` keeps DEM
    results whose run id (deck, includes, parameters, version) matches."""

    def __init__(self, case: Case, out_dir, ranks: int = 1, jobs: int = 1, reuse: bool = False,
                 on_run: Callable[[str, str], None] | None = None):
        if case.kind not in KINDS:
            raise CaseError(f"case {case.name}: unknown kind {case.kind!r} ({', '.join(KINDS)})")
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
            params = resolve(deck, given)
            if self.case.kind == "vertical":
                check_vertical_case(params)
            output = self.dir / f"{point}.h5"
            request = RunRequest(deck, params, output, label=point, ranks=self.ranks,
                                 reuse=self.reuse)
            runs.append(Run(point, values, params, output, request))
        return runs

    def run(self) -> Outcome:
        from vibrofeed.engine.batch import run_many

        runs = self.plan()
        self.dir.mkdir(parents=True, exist_ok=True)
        outcomes = run_many([r.request for r in runs], jobs=self.jobs,
                            on_state=lambda request, state: self.on_run(request.label, state))
        for o in outcomes:
            if not o.ok:  # after the others finished
                raise o.error
        outcome = Outcome(self.case)
        KINDS[self.case.kind](self.case, runs, outcome, self.dir)
        return outcome


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
    from vibrofeed.postproc.transport import Transport
    from vibrofeed.results.reader import Result

    from .plots import plot_speed_curve

    transient = float(case.compare.get("transient_periods", 10))
    points = []
    for run in runs:
        p = dict(run.params)
        T = 1.0 / run.number("freq")
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
    figures = {}
    for run in runs:
        with Result(run.output) as r:
            figures[run.label] = FeedRate(r, model=False).run().summary()
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


KINDS = {"flights": _flights, "transport": _transport, "period": _period, "vertical": _vertical,
         "replay": _replay, "pulloff": _pulloff, "reference": _reference,
         **micro_checks.KINDS}
