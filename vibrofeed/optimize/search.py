"""Running a study: the model screen, the search, the confirmation and the robustness runs.

Optuna does the search (its TPE sampler: one objective or two, constraints, a parallel
batch with the constant liar; the study kept in a journal file, ``DIR/optuna.journal``,
that a kill leaves valid). Optuna, because it is well kept and has in one library what a
DEM study needs: constraints that the sampler learns from, a Pareto front, ask/tell for a
dispatcher of our own, and a study that survives SIGKILL; scikit-optimize is no longer
maintained, and Ax brings PyTorch for a budget of tens of runs.

1. **Screen** (no DEM): ``budget.screen`` settings spread over the design space (a scrambled
   Sobol sequence) go through the parameter checks of ``vibrofeed run`` and the models
   (:mod:`.screen`); the feasible ones are ranked by the models' conveying speed of the
   slowest section and ``budget.seeds`` of them, spread out (greedy max-min distance), are the
   search's first DEM runs. The screen's counts are kept in ``DIR/study.json``.
2. **Search**: each setting the sampler proposes is screened first; one the models rule out
   is told to the sampler as infeasible without a DEM run (counted: the DEM it saved). The
   others are DEM runs of the sweep's executor (:func:`vibrofeed.sweep.execute.run_job`:
   the isolated runner, its own folder ``runs/``, named by run id, so a killed study's
   rerun reuses a result that completed), ``-j`` at a time or across the groups of an
   ``mpirun``; a failed run is recorded and told as failed, and the study goes on.
3. **Confirm**: the ``budget.confirm`` best settings (ranked one standard error towards
   worse, so a lucky noisy run does not win; with two objectives, the first of the Pareto
   front, :func:`pareto_front`) are run ``budget.replicates`` times with fresh seeds; the
   confirmed value is the mean of those runs alone (the search's run was selected for being
   high) with its standard error.
4. **Robustness**: the confirmed best at each value ``[robustness]`` lists, one parameter
   at a time; the spread of the objective says how much the design depends on them.

Every DEM run is a row of ``DIR/study.csv`` / ``DIR/study.h5`` (the sweep's ledger, stem
"study"): ``job`` (search: the trial's number; confirm: 10000 + 100 x rank + replicate;
robustness: 20000 + k), ``stage``, the parameters, status, metrics, ``objective`` (and
``objective_2``) with errors. ``DIR/study.json`` holds the study file, the screen and, at
the end, the answer (:func:`answer_text`; with two objectives ``front``, the search's Pareto
front).
"""

from __future__ import annotations

import json
import math
import os
import shlex
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..engine import batch
from ..engine.runner import check_at_once
from ..errors import ParameterError, RunError, UsageError
from ..parameters import resolve, speaker
from ..sweep import folder as F
from ..sweep import summary as S
from ..sweep.execute import run_job
from ..sweep.plan import Job, cost, find_deck, value_text
from . import objective as O
from .screen import screen
from .spec import ORIENTED, StudySpec, load

STUDY_JSON, JOURNAL, STEM = "study.json", "optuna.journal", "study"
CONFIRM_BASE, ROBUST_BASE = 10_000, 20_000
SEED_OFFSET = {"search": 0, "confirm": 1_000_003, "robust": 2_000_003}
# Proposals the models may rule out in a row before the study says the space is too tight.
MAX_RULED_OUT = 2000


@dataclass
class Evaluation:
    """A DEM run of the study: the sweep's job, its stage and (search) its Optuna trial."""

    job: Job
    stage: str
    trial: int | None = None
    label: str = ""


# ------------------------------------------------------------------ the space
def distributions(spec: StudySpec) -> dict:
    import optuna.distributions as D

    out = {}
    for v in spec.variables:
        if v.kind == "choice":
            out[v.name] = D.CategoricalDistribution(v.choices)
        elif v.kind == "int":
            out[v.name] = D.IntDistribution(int(v.low), int(v.high), log=v.log)
        else:
            out[v.name] = D.FloatDistribution(v.low, v.high, log=v.log)
    return out


def from_unit(spec: StudySpec, u: np.ndarray) -> dict:
    """A setting from a point of the unit cube (one coordinate per variable)."""
    out = {}
    for v, x in zip(spec.variables, u):
        if v.kind == "choice":
            out[v.name] = v.choices[min(int(x * len(v.choices)), len(v.choices) - 1)]
            continue
        if v.log:
            value = math.exp(math.log(v.low) + x * (math.log(v.high) - math.log(v.low)))
        else:
            value = v.low + x * (v.high - v.low)
        out[v.name] = int(round(value)) if v.kind == "int" else float(value)
    return out


def to_unit(spec: StudySpec, setting: dict) -> np.ndarray:
    u = []
    for v in spec.variables:
        x = setting[v.name]
        if v.kind == "choice":
            u.append((v.choices.index(x) + 0.5) / len(v.choices))
        elif v.log:
            u.append((math.log(x) - math.log(v.low)) / (math.log(v.high) - math.log(v.low)))
        else:
            u.append((x - v.low) / (v.high - v.low))
    return np.array(u)


# ------------------------------------------------------------------ one setting
def deck_params(spec: StudySpec, setting: dict) -> dict:
    """A setting with the study's fixed values, as ``vibrofeed run -p`` takes them."""
    return {name: value_text(v) for name, v in {**spec.fixed, **setting}.items()}


class Setting:
    """A design setting made into deck values, checked and screened."""

    def __init__(self, spec: StudySpec, deck, setting: dict):
        self.setting = setting
        self.params = deck_params(spec, setting)
        self.values, self.refused, self.screened = None, "", None
        try:
            self.values = resolve(deck, self.params)
        except ParameterError as exc:
            self.refused = str(exc)
            return
        self.screened = screen(spec, self.values)

    @property
    def feasible(self) -> bool:
        return self.values is not None and self.screened.feasible

    @property
    def why_not(self) -> str:
        return self.refused or "; ".join(self.screened.broken)

    @property
    def slowest(self) -> float:
        """The models' speed of the slowest section (-inf unknown): the screen's ranking."""
        speeds = [d.speed for d in self.screened.drives] if self.screened else []
        return min((s for s in speeds if s is not None), default=-math.inf)


def _kind(refusal: str) -> str:
    """A parameter check's refusal without its numbers (what the screen's counts group by)."""
    import re

    words = re.sub(r"(?<![\w.])[-+]?\d[\d.]*(e[-+]?\d+)?", "#", refusal)
    return "parameter check: " + words.split(";")[0][:80]


def screen_space(spec: StudySpec, deck) -> tuple[list[dict], dict]:
    """(the seeds: settings for the first DEM runs, the screen's counts) (module docstring, 1)."""
    from scipy.stats import qmc

    n = spec.budget["screen"]
    points = qmc.Sobol(len(spec.variables), scramble=True, seed=spec.seed).random(n)
    tried = [Setting(spec, deck, from_unit(spec, u)) for u in points]
    ok = [s for s in tried if s.feasible]
    counts = {"screened": n, "feasible": len(ok), "refused_by_checks": sum(bool(s.refused) for s in tried),
              "ruled_out_by_models": sum(s.values is not None and not s.screened.feasible for s in tried)}
    reasons: dict[str, int] = {}
    for s in tried:  # a refusal's kind: its words before the first number or quote
        for name in ([_kind(s.refused)] if s.refused else s.screened.broken):
            reasons[name] = reasons.get(name, 0) + 1
    counts["reasons"] = reasons
    # the fastest feasible setting first, then each next one as far as possible from those chosen
    ok.sort(key=lambda s: -s.slowest)
    chosen: list[Setting] = []
    picked: list[np.ndarray] = []
    units = [to_unit(spec, s.setting) for s in ok]
    while ok and len(chosen) < spec.budget["seeds"]:
        k = 0 if not picked else int(np.argmax([np.min(np.linalg.norm(np.array(picked) - u, axis=1))
                                                for u in units]))
        chosen.append(ok.pop(k))
        picked.append(units.pop(k))
    return [c.setting for c in chosen], counts


# ------------------------------------------------------------------ the study
def objective_keys(spec: StudySpec) -> list[str]:
    """The ledger's objective columns: ``objective`` (and ``objective_2``), each with ``_err``."""
    return ["objective" if i == 0 else f"objective_{i + 1}" for i in range(len(spec.maximize))]


def objective_row(spec: StudySpec, row: dict) -> dict:
    """The objective columns of a finished run's row (None where it measured nothing)."""
    out = {}
    for key, name in zip(objective_keys(spec), spec.maximize):
        value, err = O.value_and_error(row, name) if row.get("status") == S.DONE else (None, None)
        out[key], out[f"{key}_err"] = value, err
    return out


def target_margins(spec: StudySpec, row: dict) -> list[float]:
    """How far a run falls short of each ``at_least`` target, relative (<= 0: reached)."""
    out = []
    for name, target in spec.at_least.items():
        value, _ = O.value_and_error(row, name)
        scale = abs(target) or 1.0
        out.append(1.0 if value is None else (target - value) / scale)
    return out


def setting_index(setting: dict) -> int:
    """A seed offset from the setting itself (0 .. 999 999)."""
    import hashlib

    text = json.dumps({k: value_text(v) for k, v in sorted(setting.items())})
    return int(hashlib.sha256(text.encode()).hexdigest()[:8], 16) % 1_000_000


def _counts(spec: StudySpec, row: dict, keys: list[str]) -> bool:
    """Whether a search run counts for the answer: it measured ``keys`` and reaches every
    target (the trials the sampler is told as feasible)."""
    return (row.get("stage") == "search" and all(row.get(k) is not None for k in keys)
            and all(m <= 0 for m in target_margins(spec, row)))


def _ranked(spec: StudySpec, rows: list[dict]) -> list[dict]:
    """Rows best first by the first objective one standard error towards worse."""
    name = spec.maximize[0]
    return sorted(rows, key=lambda r: O.cautious(r["objective"], r.get("objective_err"), name),
                  reverse=O.direction(name) == "maximize")


def non_dominated(points: list[tuple], names: list[str]) -> list[bool]:
    """Which points (one value per metric of ``names``) no other point dominates: another
    dominates a point when it is at least as good on every metric (each in its own
    direction) and differs from it; equal points are both kept."""
    sign = [1.0 if O.direction(n) == "maximize" else -1.0 for n in names]
    return [not any(q != p and all(s * a >= s * b for s, a, b in zip(sign, q, p)) for q in points)
            for p in points]


def pareto_front(spec: StudySpec, rows: list[dict]) -> list[dict]:
    """Two objectives: the search runs on the Pareto front, best first as confirmation takes
    them. A run takes part when it measured both objectives and reaches every ``at_least``
    target (as the sampler is told: the others are infeasible); it is on the front when no
    such run dominates it on the values as measured (each metric's own direction). The
    front is then ordered by the first objective one standard error towards worse."""
    keys = objective_keys(spec)
    rows = [r for r in rows if _counts(spec, r, keys)]
    keep = non_dominated([tuple(float(r[k]) for k in keys) for r in rows], spec.maximize)
    return _ranked(spec, [r for r, k in zip(rows, keep) if k])


def front_entries(spec: StudySpec, rows: list[dict]) -> list[dict]:
    """The Pareto front as study.json and optimize-report give it: each member's setting,
    its search run (job, seed) and its values with their errors (as measured by that run)."""
    out = []
    for r in pareto_front(spec, rows):
        entry = {"setting": {n: r[n] for n in spec.names}, "job": r["job"], "seed": r.get("seed")}
        for key, metric in zip(objective_keys(spec), spec.maximize):
            entry[metric] = (r[key], r.get(f"{key}_err"))
        out.append(entry)
    return out


def _placeholder(spec: StudySpec) -> list[float]:
    """The values told for a setting with nothing measured: the worst, so that even a
    sampler that ignores constraints learns to avoid it."""
    return [1e30 if O.direction(n) == "minimize" else -1e30 for n in spec.maximize]


class Study:
    """One study in its folder: the Optuna study, the ledger, the progress lines."""

    def __init__(self, spec: StudySpec, deck, folder: Path, runs: int, quiet: bool, command: str):
        import optuna

        optuna.logging.set_verbosity(optuna.logging.WARNING)
        self.spec, self.deck, self.folder, self.runs, self.quiet = spec, deck, folder, runs, quiet
        self.command = command
        from optuna.storages import JournalStorage
        from optuna.storages.journal import JournalFileBackend

        storage = JournalStorage(JournalFileBackend(str(folder / JOURNAL)))
        sampler = optuna.samplers.TPESampler(
            seed=spec.seed, multivariate=True, constant_liar=True,
            n_startup_trials=max(spec.budget["seeds"], 1))
        self.study = optuna.create_study(
            study_name="vibrofeed", storage=storage, sampler=sampler, load_if_exists=True,
            directions=[O.direction(n) for n in spec.maximize])
        self.dists = distributions(spec)
        self.ruled_out = 0
        self.searched = 0  # search runs finished (in the ledger)
        self.in_flight = 0  # search runs started and not finished
        self.live: dict = {}  # trial number -> the Trial asked in this session, until told
        self.walls: list[float] = []

    # -- trials
    def job(self, index: int, setting: dict, stage: str, replicate: int, seed_index: int,
            extra: dict | None = None) -> Job:
        params = deck_params(self.spec, {**setting, **(extra or {})})
        seed = None
        if "seed" in self.deck.tunables:
            seed = self.spec.seed + SEED_OFFSET[stage] + seed_index
            params["seed"] = str(seed)
        values = resolve(self.deck, params)
        from ..engine.runner import run_id

        target = self.spec.target_error
        rid = run_id(self.deck, values, target_error=target)
        return Job(index=index, replicate=replicate, seed=seed, setting={**setting, **(extra or {})},
                   params=params, values=values, run_id=rid, cost=cost(values),
                   file=f"runs/run-{rid[:16]}.h5", target_error=target)

    def search_job(self, number: int, setting: dict) -> Evaluation:
        # the seed follows the setting, not the trial: a setting asked again after a kill is the
        # same run (its result reused when it completed)
        return Evaluation(self.job(number, setting, "search", 0, setting_index(setting)), "search", number)

    def search_items(self, ledger):
        """The search's evaluations, asked one at a time as a slot frees (batch's lazy items).

        After a kill: a trial told but not yet in the ledger is analysed again (its result
        reused); a trial left running is told failed and its setting asked again."""
        import optuna

        self.searched = sum(r.get("stage") == "search" for r in ledger.rows.values())
        for t in self.study.trials:
            setting = {n: t.params[n] for n in self.spec.names if n in t.params}
            if t.state == optuna.trial.TrialState.RUNNING:
                self.study.tell(t.number, state=optuna.trial.TrialState.FAIL)
                self.study.enqueue_trial(setting, user_attrs={"again": t.number})
            elif (t.state == optuna.trial.TrialState.COMPLETE and t.user_attrs.get("dem")
                  and t.number not in ledger.rows):
                self.in_flight += 1
                yield self.search_job(t.number, setting)
        in_a_row = 0
        while self.searched + self.in_flight < self.runs:
            trial = self.study.ask(self.dists)
            setting = {n: trial.params[n] for n in self.spec.names}
            s = Setting(self.spec, self.deck, setting)
            if not s.feasible:
                self.ruled_out += 1
                in_a_row += 1
                trial.set_user_attr("ruled_out", s.why_not)
                self._constrain(trial, measured=False, row=None)
                self.study.tell(trial, _placeholder(self.spec))
                if in_a_row >= MAX_RULED_OUT:
                    raise UsageError(f"the models rule out {MAX_RULED_OUT} proposals in a row (the "
                                     f"last: {s.why_not}): the constraints leave (almost) no design "
                                     "space; widen the bounds or loosen [constraints]")
                continue
            in_a_row = 0
            trial.set_user_attr("dem", True)
            self.live[trial.number] = trial
            self.in_flight += 1
            yield self.search_job(trial.number, setting)

    def _constrain(self, trial, measured: bool, row: dict | None) -> None:
        """The trial's constraints, before it is told (the sampler reads them then): a setting
        the models rule out, or a run that fed nothing measurable, breaks ``measured``; each
        target's shortfall, relative, its own."""
        trial.set_constraint("measured", 0.0 if measured else 1.0)
        margins = target_margins(self.spec, row) if row is not None else [0.0] * len(self.spec.at_least)
        for name, margin in zip(self.spec.at_least, margins):
            trial.set_constraint(f"at_least {name}", margin)

    def tell(self, number: int, row: dict) -> None:
        """Tell the sampler what a search run measured: a run that failed (the engine, the
        analysis) as failed; one that fed nothing measurable (no steady feed) as infeasible.
        A trial told before a kill (re-analysed on resume) is not told again."""
        import optuna

        trial = self.live.pop(number, None)
        if trial is None:
            return
        values = [objective_row(self.spec, row)[key] for key in objective_keys(self.spec)]
        if row.get("status") != S.DONE:
            self.study.tell(trial, state=optuna.trial.TrialState.FAIL)
            return
        measured = all(v is not None for v in values)
        self._constrain(trial, measured, row)
        self.study.tell(trial, values if measured else _placeholder(self.spec))

    # -- ranking
    def best_settings(self, ledger_rows: list[dict], k: int) -> list[dict]:
        """The k best searched settings by the cautious value (one objective: value minus one
        error), reaching every target; two objectives: the first k of the Pareto front
        (:func:`pareto_front`), in the same order."""
        if self.spec.multi:
            rows = pareto_front(self.spec, ledger_rows)
        else:
            rows = _ranked(self.spec, [r for r in ledger_rows if _counts(self.spec, r, ["objective"])])
        return [{n: r[n] for n in self.spec.names} for r in rows[:k]]

    # -- progress
    def say(self, text: str) -> None:
        if not self.quiet:
            print(f"optimize: {text}", file=sys.stderr, flush=True)


def _label(spec: StudySpec, setting: dict) -> str:
    """A setting as people read it (4 significant digits; the runs use the exact values)."""
    def short(v):
        return f"{v:.4g}" if isinstance(v, float) else str(v)

    return " ".join(f"{n}={short(setting[n])}" for n in spec.names if n in setting)


def _mean_and_error(values: list[float], errors: list[float | None]) -> tuple[float, float | None]:
    """Mean of replicate runs and its standard error: the larger of their scatter's
    (s / sqrt(n)) and their own errors' (sqrt(sum e^2) / n)."""
    n = len(values)
    mean = float(np.mean(values))
    scatter = float(np.std(values, ddof=1) / math.sqrt(n)) if n > 1 else None
    own = math.sqrt(sum(e * e for e in errors)) / n if all(e is not None for e in errors) else None
    known = [e for e in (scatter, own) if e is not None]
    return mean, (max(known) if known else None)


# ------------------------------------------------------------------ the command
def optimize(spec_path, output=None, workers: int = 1, budget: int | None = None, resume: bool = False,
             quiet: bool = False, comm=None, out=None, retry_failed: bool = False) -> int:
    """``vibrofeed optimize``: the exit status (or a VibrofeedError). ``retry_failed``: resume
    the study and run its failed runs again (:func:`_retry`)."""
    resume = resume or retry_failed
    out = out or sys.stdout
    spec = load(spec_path)
    deck = find_deck(spec)
    spec = own_names(spec, deck)
    for names, key in ((spec.parameters, ("variables",)), (list(spec.robustness), ("robustness",)),
                       ([n for q in spec.inequalities for n in q.names], ("constraints", "require"))):
        unknown = sorted({n for n in names if n not in deck.tunables})
        if unknown:
            raise ParameterError(f"{spec.where(*key)}: unknown parameter(s) {', '.join(unknown)} for "
                                 f"deck {deck.name} (vibrofeed params {deck.name} lists them)")
    check_values(spec, deck)
    if spec.target_error is not None:
        from ..engine.runner import check_target_error

        try:
            check_target_error(spec.target_error, deck)
        except UsageError as exc:
            raise UsageError(f"{spec.where('target_error')}: {exc}") from None
    runs = budget if budget is not None else spec.budget["runs"]
    if runs < 1 or runs >= CONFIRM_BASE:  # (named as the user gave it: the option or the file's key)
        given = f"--budget {runs}" if budget is not None else f"{spec.where('budget', 'runs')}: runs = {runs}"
        raise UsageError(f"{given}: give 1 to {CONFIRM_BASE - 1} DEM runs")
    folder = Path(output if output is not None else Path("results") / Path(spec_path).stem).absolute()
    _check_folder(folder, spec, resume)
    if comm is not None and workers > 1:
        raise UsageError("-j: under mpirun the groups of ranks_per_run ranks are the workers; drop -j")
    if comm is None:
        check_at_once(workers, spec.ranks_per_run)
    groups = 1 if comm is None else comm.Get_size() // spec.ranks_per_run
    if comm is not None and groups < 1:
        raise UsageError(f"ranks_per_run = {spec.ranks_per_run} needs at least that many ranks; "
                         f"mpirun started {comm.Get_size()}")
    fresh, made = not (folder / STUDY_JSON).is_file(), not folder.exists()
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "runs").mkdir(exist_ok=True)
    lock = F.lock(folder, "study")
    try:
        F.clear_leftovers(folder, "runs")
        done = _run(spec, deck, folder, runs, workers, quiet, comm, out, spec_path, retry_failed)
        if comm is None:  # again at the end: a worker whose parent was killed may have ended
            F.clear_leftovers(folder, "runs")  # after the start (under mpirun a group may still run)
        return done
    except UsageError as exc:
        if fresh and getattr(exc, "before_any_run", False):  # (still locked) nothing left behind:
            _forget(folder, made)                             # the file corrected is not "another study"
        raise
    finally:
        os.close(lock)


def own_names(spec: StudySpec, deck) -> StudySpec:
    """The study with the deck's own names for a feeder description's dotted ones
    (``element.2.drive.amp_t`` -> ``s2_amp_t``, as ``-p`` and resolve read them; the study
    file records the renaming for optimize-report); a parameter fixed or varied under both
    names is refused naming both."""
    names = {n: deck.aliases[n] for n in [*spec.parameters, *spec.robustness] if n in deck.aliases}
    seen: dict[str, str] = {}
    for table, name in [("fixed", n) for n in spec.fixed] + [("variables", v.name) for v in spec.variables]:
        own = names.get(name, name)
        if own in seen:
            raise ParameterError(f"{spec.where(table, name)}: parameter {own} is set twice, as "
                                 f"{seen[own]} and as {name}; a parameter is fixed or a design "
                                 "variable, not both")
        seen[own] = name
    varied = {names.get(v.name, v.name) for v in spec.variables}
    for name in spec.robustness:
        if names.get(name, name) in varied:
            raise ParameterError(f"{spec.where('robustness', name)}: {name} is a design variable; "
                                 "robustness varies what the design does not fix")
    return spec.renamed(names)


def check_values(spec: StudySpec, deck) -> None:
    """What the study's file asks that no run could give, before any run: a value of
    ``[fixed]``, a variable's choice or a ``[robustness]`` value that ``vibrofeed run``
    refuses on its own (``mu = -1``: the robustness runs come after the search and the
    confirmation), and an objective or target the deck's runs never measure (a deck without
    an outlet measures ``mean_velocity`` only; spheres no orientation)."""
    from ..parameters import checked_value
    from ..results import layout as L

    given = [(("fixed", name), name, value) for name, value in spec.fixed.items()]
    given += [(("variables", v.name), v.name, c) for v in spec.variables for c in v.choices]
    given += [(("robustness", name), name, value) for name, values in spec.robustness.items()
              for value in values]
    written = {own: name for name, own in spec.renames.items()}  # as the file names it
    speak = speaker({}, written)
    for key, name, value in given:
        try:
            checked_value(deck, name, value_text(value))
        except ParameterError as exc:
            shown = written.get(name, name)
            what = {"fixed": "", "variables": f"variable {shown}: a choice: ",
                    "robustness": f"robustness {shown}: "}[key[0]]
            raise ParameterError(f"{spec.where(*key)}: {what}{speak(str(exc))}") from None
    outlet = any(name in deck.formulas for name in L.BULK_CONTRACT)
    shapes = ({value_text(c) for v in spec.variables if v.name == "shape" for c in v.choices}
              or {value_text(spec.fixed.get("shape", deck.tunables["shape"].default
                                            if "shape" in deck.tunables else 0))})
    spheres = {str(int(checked_value(deck, "shape", s))) for s in shapes} == {"0"} \
        if "shape" in deck.tunables else True
    for table, names in (("fixed", spec.fixed), ("variables", [v.name for v in spec.variables])):
        if "correct" in names and spheres:
            raise ParameterError(f"{spec.where(table, 'correct')}: the study's parts are spheres, "
                                 "which have no orientation; correct is for chips, discs, boxes and "
                                 "stl parts")
    named = [(("objective", "maximize"), m) for m in spec.maximize]
    named += [(("objective", "at_least"), m) for m in spec.at_least]
    for key, metric in named:
        if not outlet and metric != "mean_velocity":
            raise UsageError(f"{spec.where(*key)}: {metric}: deck {deck.name} has no outlet (it is "
                             "not a bulk feeder), so its runs measure mean_velocity only")
        if outlet and metric in ORIENTED and spheres:
            raise UsageError(f"{spec.where(*key)}: {metric}: the study's parts are spheres, which "
                             "have no orientation; it is measured on chips and discs (shape = 1 or 2)")


def _forget(folder: Path, made: bool) -> None:
    """Remove what a new study wrote into ``folder`` (empty before it, or made by it)."""
    import shutil

    if made:
        shutil.rmtree(folder, ignore_errors=True)
        return
    for entry in folder.iterdir():
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)
        else:
            entry.unlink(missing_ok=True)


def _check_folder(folder: Path, spec: StudySpec, resume: bool) -> None:
    from ..sweep.spec import describe_change

    if folder.exists() and not folder.is_dir():
        raise UsageError(f"-o {folder}: not a folder")
    path = folder / STUDY_JSON
    if not path.is_file():
        if folder.is_dir() and any(folder.iterdir()):
            raise UsageError(f"{folder} is not empty and holds no {STUDY_JSON}: give another -o DIR")
        return
    try:
        old = json.loads(path.read_text())
    except (OSError, ValueError):
        raise UsageError(f"{path} is not readable: not a study folder vibrofeed wrote") from None
    if old.get("fingerprint") != spec.fingerprint:
        raise UsageError(f"{folder} holds another study ({spec.source} differs in "
                         f"{describe_change(old.get('spec', {}), spec.data)}); give another -o DIR, "
                         f"or remove {folder} to start over")
    if not resume:
        raise UsageError(f"{folder} holds this study already: --resume continues it "
                         "(finished runs are not repeated)")


def _write_json(folder: Path, doc: dict) -> None:
    text = json.dumps(doc, indent=1, default=str)
    S.replace_atomically(folder / STUDY_JSON, lambda tmp: tmp.write_text(text))


def _retry(st: Study, spec: StudySpec, kept: list[dict]) -> list[dict]:
    """The rows to keep when a study's failed runs run again: all but the failed. A failed
    search run's setting is asked again first (the same setting is the same seed and run id:
    a run whose DEM finished before its analysis failed is analysed again, not rerun); the
    confirmation and robustness runs are asked anew by their stages."""
    failed = [r for r in kept if r.get("status") == S.FAILED]
    for row in failed:
        if row.get("stage") == "search":
            st.study.enqueue_trial({n: row[n] for n in spec.names}, user_attrs={"again": row["trial"]})
    if failed:
        st.say(f"retry: {len(failed)} failed run(s) again (a run whose DEM finished is analysed again)")
    return [r for r in kept if r.get("status") != S.FAILED]


def _run(spec, deck, folder, runs, workers, quiet, comm, out, spec_path, retry_failed=False) -> int:
    command = shlex.join(["vibrofeed", "optimize", str(spec_path), "-o", str(folder)])
    st = Study(spec, deck, folder, runs, quiet, command)
    doc = json.loads((folder / STUDY_JSON).read_text()) if (folder / STUDY_JSON).is_file() else {}
    doc.update({"format": "vibrofeed-study", "fingerprint": spec.fingerprint, "source": str(spec.source),
                "deck": str(deck.path), "spec": spec.data, "spec_text": spec.text,
                "renames": spec.renames, "budget_runs": runs})
    units = {n: deck.tunables[n].unit for n in spec.parameters}
    meta = {"fingerprint": spec.fingerprint, "deck": deck.name, "source": str(spec.source),
            "objectives": json.dumps(spec.maximize), "units": json.dumps(units), "spec": spec.text}
    parameters = [p for p in spec.parameters if p != "seed"] + list(spec.robustness)
    kept = S.read(folder, stem=STEM)[0] if (folder / STUDY_JSON).is_file() else []
    if retry_failed:
        kept = _retry(st, spec, kept)
    ledger = S.Ledger(folder, parameters, meta, rows=kept, stem=STEM)
    if not st.study.trials:  # a new study: the screen seeds it
        seeds, counts = screen_space(spec, deck)
        for setting in seeds:
            st.study.enqueue_trial(setting, user_attrs={"seeded": True})
        doc["screen"] = counts
        st.say(f"screen: {counts['feasible']} of {counts['screened']} settings pass the checks and "
               f"models; {len(seeds)} seed the search")
        if not counts["feasible"]:
            why = ", ".join(f"{name} rules out {n}" for name, n in counts["reasons"].items())
            refused = UsageError(f"no setting of the design space passes the checks and the models "
                                 f"({why}); widen the bounds or loosen [constraints]")
            refused.before_any_run = True  # (a new study: optimize() removes what it wrote)
            raise refused
    _write_json(folder, doc)
    ruled_before = doc.get("ruled_out", 0)

    def run_one(ev: Evaluation):
        return run_job(ev.job, folder, deck, spec.ranks_per_run, parameters, st.command)

    def completed(ev: Evaluation, answer) -> dict:
        """A finished run's row with its stage, trial and objective columns."""
        row, computed = answer
        row.update({"stage": ev.stage, "trial": ev.trial})
        row.update(objective_row(spec, row))
        if computed and row.get("wall_s"):
            st.walls.append(float(row["wall_s"]))
        return row

    def execute(items, finished):
        if comm is None:
            batch.run_local(items, workers, run_one, finished=finished)
        else:  # the sweep's group leaders run the jobs: they get the Job, not the Evaluation
            evs: dict[int, Evaluation] = {}

            def jobs():
                for ev in items:
                    if ev is batch.WAIT:
                        yield ev
                        continue
                    evs[ev.job.index] = ev
                    yield ev.job

            setup = {"deck": str(deck.path), "folder": str(folder), "ranks": spec.ranks_per_run,
                     "parameters": parameters, "command": st.command}
            batch.dispatch(comm, jobs(), setup, lambda job: run_one(evs[job.index]),
                           finished=lambda job, answer: finished(evs[job.index], answer))

    # 2. the search
    def searched(ev, answer):
        row = completed(ev, answer)
        st.in_flight -= 1
        st.tell(ev.trial, row)  # then the ledger: a kill between is mended on resume (search_items)
        ledger.add(row)
        st.searched += 1
        done = st.searched
        eta = _eta(st, runs - done, max(workers, groups(comm, spec)))
        st.say(f"run {done}/{runs} [{_label(spec, ev.job.setting)}]: {_summary(spec, row)}; "
               f"{_best_so_far(spec, ledger.rows.values())}; models ruled out "
               f"{ruled_before + st.ruled_out} proposal(s){eta}")

    pending = {"n": 0}  # confirmation and robustness runs started and not finished

    def finished(ev, answer):
        if ev.stage == "search":
            return searched(ev, answer)
        pending["n"] -= 1
        row = completed(ev, answer)
        ledger.add(row)
        st.say(f"{ev.label}: {_summary(spec, row)}")

    def later(evs):
        for ev in evs:
            pending["n"] += 1
            yield ev
        while pending["n"]:  # the next stage needs every run of this one
            yield batch.WAIT

    def stages():
        """The whole study as one stream of runs (one dispatch: under mpirun the other ranks
        serve until it ends), each stage waiting for the runs the next one is chosen from."""
        before = sum(r.get("stage") == "search" for r in ledger.rows.values())
        st.say(f"search: {runs} DEM runs ({before} finished before) -> {folder}")
        yield from st.search_items(ledger)
        while st.in_flight:
            yield batch.WAIT
        doc["ruled_out"] = ruled_before + st.ruled_out
        _write_json(folder, doc)
        if spec.multi:
            doc["front"] = front_entries(spec, list(ledger.rows.values()))
        best = st.best_settings(list(ledger.rows.values()), spec.budget["confirm"])
        doc["best"] = best
        if best:
            st.say(f"confirm: {len(best)} setting(s) x {spec.budget['replicates']} fresh seeds")
        yield from later(Evaluation(st.job(CONFIRM_BASE + 100 * i + r, b, "confirm", r, 100 * i + r),
                                    "confirm", label=f"confirm {i + 1}.{r + 1}")
                         for i, b in enumerate(best) for r in range(spec.budget["replicates"]))
        doc["confirmed"] = _confirmed(spec, best, list(ledger.rows.values()))
        if doc["confirmed"] and spec.robustness:
            top = doc["confirmed"][0]["setting"]
            st.say(f"robustness: the confirmed best at {len(robust_points(spec))} material setting(s)")
            yield from later(Evaluation(st.job(ROBUST_BASE + k, top, "robust", 0, 0, {name: value}),
                                        "robust", label=f"robustness {name}={value}")
                             for k, (name, value) in enumerate(robust_points(spec)))
            doc["robustness"] = _robustness(spec, list(ledger.rows.values()), doc["confirmed"][0])

    execute(stages(), finished)
    confirmed = doc.get("confirmed") or []
    ledger.close()
    _write_json(folder, doc)
    rows = list(ledger.rows.values())
    failed = sum(r.get("status") != S.DONE for r in rows)
    print(answer_text(spec, doc, rows), file=out)
    if not confirmed:
        raise RunError(f"no searched setting measured {spec.maximize[0]}"
                       + (" and reached the targets" if spec.at_least else "")
                       + f" ({failed} of {len(rows)} runs failed; see {folder / (STEM + '.csv')})")
    return 0


def groups(comm, spec) -> int:
    return 1 if comm is None else max(comm.Get_size() // spec.ranks_per_run, 1)


def _confirmed(spec: StudySpec, best: list[dict], rows: list[dict]) -> list[dict]:
    """Each confirmed setting: its replicates' mean and error, best first."""
    out = []
    name = spec.maximize[0]
    for i, setting in enumerate(best):
        reps = [r for r in rows if r.get("stage") == "confirm" and CONFIRM_BASE + 100 * i <= r["job"]
                < CONFIRM_BASE + 100 * (i + 1)]
        entry = {"setting": setting, "runs": len(reps)}
        for key, metric in zip(objective_keys(spec), spec.maximize):
            got = [(r[key], r.get(f"{key}_err")) for r in reps if r.get(key) is not None]
            entry[metric] = _mean_and_error([v for v, _ in got], [e for _, e in got]) if got else (None, None)
            entry[f"{metric}_measured"] = len(got)
        for target in spec.at_least:
            vals = [O.value_and_error(r, target)[0] for r in reps]
            vals = [v for v in vals if v is not None]
            entry[target] = _mean_and_error(vals, [None] * len(vals)) if vals else (None, None)
        out.append(entry)
    measured = [e for e in out if e[name][0] is not None]
    measured.sort(key=lambda e: O.cautious(e[name][0], e[name][1], name),
                  reverse=O.direction(name) == "maximize")
    return measured


def robust_points(spec: StudySpec) -> list[tuple[str, object]]:
    """(parameter, value) of each robustness run, in order: run k is job ROBUST_BASE + k."""
    return [(name, value) for name, values in spec.robustness.items() for value in values]


def _robustness(spec: StudySpec, rows: list[dict], best: dict) -> dict:
    """The confirmed best's objective at each robustness point, and the spread of all of them
    with the confirmed value, relative to it."""
    name = spec.maximize[0]
    by_job = {r["job"]: r for r in rows if r.get("stage") == "robust"}
    table = []
    for k, (param, value) in enumerate(robust_points(spec)):
        r = by_job.get(ROBUST_BASE + k, {})
        table.append({"parameter": param, "value": value, "objective": r.get("objective"),
                      "objective_err": r.get("objective_err"), "status": r.get("status")})
    centre = best[name][0]
    values = [t["objective"] for t in table if t["objective"] is not None] + [centre]
    low, high = min(values), max(values)
    return {"table": table, "low": low, "high": high,
            "spread": (high - low) / abs(centre) if centre else None}


# ------------------------------------------------------------------ what it prints
def _fmt(x, err=None) -> str:
    if x is None:
        return "n/a"
    return f"{x:.4g}" + (f" ± {err:.2g}" if err is not None else "")


def _summary(spec: StudySpec, row: dict) -> str:
    if row.get("status") != S.DONE:
        return f"FAILED: {row.get('error')}"
    bits = []
    for key, name in zip(objective_keys(spec), spec.maximize):
        bits.append(f"{name} {_fmt(row.get(key), row.get(f'{key}_err'))}")
    reason = row.get("feedrate_reason") or row.get("singulation_reason")
    return ", ".join(bits) + (f" ({reason})" if reason and row.get("objective") is None else "")


def _best_so_far(spec: StudySpec, rows) -> str:
    name = spec.maximize[0]
    done = [r for r in rows if r.get("stage") == "search" and r.get("objective") is not None
            and all(m <= 0 for m in target_margins(spec, r))]
    if not done:
        return "no best yet"
    best = max(done, key=lambda r: r["objective"] if O.direction(name) == "maximize" else -r["objective"])
    return f"best so far {_fmt(best['objective'], best.get('objective_err'))} (run of trial {best['trial']})"


def _eta(st: Study, left: int, slots: int) -> str:
    if not st.walls or left <= 0:
        return ""
    from ..values import duration

    return f"; ETA {duration(np.mean(st.walls) * left / max(slots, 1))}"


def answer_text(spec: StudySpec, doc: dict, rows: list[dict]) -> str:
    """The study's answer as ``vibrofeed optimize`` prints it (and optimize-report)."""
    name = spec.maximize[0]
    dem = [r for r in rows if r.get("stage") == "search"]
    lines = [f"study {spec.source}: {len(dem)} search runs, {doc.get('ruled_out', 0)} proposals ruled "
             f"out by the models without a DEM run"]
    screen_ = doc.get("screen")
    if screen_:
        lines.append(f"screen: {screen_['feasible']} of {screen_['screened']} settings feasible "
                     f"({screen_['refused_by_checks']} refused by the parameter checks, "
                     f"{screen_['ruled_out_by_models']} ruled out by the models)")
    if spec.multi:
        front = front_entries(spec, rows)
        lines.append(f"Pareto front of the search: {len(front)} setting(s) (confirmation takes the "
                     f"first {min(len(front), spec.budget['confirm'])})")
        for f in front:
            lines.append(f"  {_label(spec, f['setting'])}: "
                         + ", ".join(f"{m} {_fmt(*f[m])}" for m in spec.maximize))
    confirmed = doc.get("confirmed") or []
    if not confirmed:
        lines.append("no confirmed design")
        return "\n".join(lines)
    top = confirmed[0]
    lines.append("best design: " + _label(spec, top["setting"]))
    for metric in spec.maximize:
        v, e = top[metric]
        lines.append(f"  {metric} {_fmt(v, e)} (confirmed: mean of {top[metric + '_measured']} runs with "
                     "fresh seeds)")
    for target, bound in spec.at_least.items():
        v, e = top.get(target, (None, None))
        lines.append(f"  {target} {_fmt(v, e)} (target >= {bound:g})")
    rob = doc.get("robustness")
    if rob:
        spread = rob["spread"]
        lines.append(f"robustness: {name} from {_fmt(rob['low'])} to {_fmt(rob['high'])}"
                     + (f" ({spread:.0%} of the confirmed value)" if spread is not None else ""))
        for t in rob["table"]:
            lines.append(f"  {t['parameter']} = {t['value']}: {_fmt(t['objective'], t['objective_err'])}")
    for other in confirmed[1:]:
        v, e = other[name]
        lines.append(f"also confirmed: {_label(spec, other['setting'])}: {name} {_fmt(v, e)}")
    return "\n".join(lines)
