"""``vibrofeed optimize-report``: a study's answer, its convergence, its Pareto front and which
design variables mattered, read from its folder (while it runs, or after).

With two objectives the report gives the search's Pareto front (``front``: each member's
setting, search run and values; :func:`vibrofeed.optimize.search.pareto_front`, the front the
study confirms from).

Figures (with ``--plot DIR``): ``convergence.png`` (each search run's objective with its
error, the best so far, and the confirmed best with its error band), ``pareto.png`` (two
objectives: every run that measured both, those missing an ``at_least`` target hollow, and
the study's front), ``importance.png`` (Optuna's importance of each design variable for the
first objective, over the search's finished runs: PED-ANOVA by default; needs a few runs).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from ..errors import UsageError
from ..sweep import summary as S
from . import objective as O
from .search import (
    JOURNAL,
    STEM,
    STUDY_JSON,
    answer_text,
    front_entries,
    non_dominated,
    pareto_front,
    target_margins,
)
from .spec import parse


def read(folder) -> tuple[dict, list[dict], object]:
    folder = Path(folder)
    path = folder / STUDY_JSON
    if not path.is_file():
        raise UsageError(f"{folder}: no {STUDY_JSON}; not a study folder (the -o DIR of vibrofeed optimize)")
    try:
        doc = json.loads(path.read_text())
    except ValueError as exc:  # (not JSON, or not text)
        where = f" at line {exc.lineno}" if isinstance(exc, json.JSONDecodeError) else ""
        raise UsageError(f"{path}: not readable{where}: damaged, or not a file vibrofeed optimize "
                         "wrote") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("spec_text"), str):
        raise UsageError(f"{path}: holds no study (its spec_text): damaged, or not a file vibrofeed "
                         "optimize wrote")
    rows, _ = S.read(folder, stem=STEM)
    spec = parse(doc["spec_text"], str(doc.get("source", "study.toml")))  # as it ran, not as edited since
    renames = doc.get("renames")  # a description's dotted names, run by the deck's own
    return doc, rows, spec.renamed(renames if isinstance(renames, dict) else {})


def importances(folder, spec) -> dict:
    """Each design variable's importance for the first objective over the search runs that
    measured it (not the placeholders told for a setting the models ruled out or a run that
    measured nothing). The importance evaluator ranks trials by a target it takes as lower
    is better (PED-ANOVA looks at the lowest quantile), so a maximised metric is negated:
    what matters is what reaches its best values, not its worst."""
    import warnings

    import optuna
    from optuna.storages import JournalStorage
    from optuna.storages.journal import JournalFileBackend

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    storage = JournalStorage(JournalFileBackend(str(Path(folder) / JOURNAL)))
    try:
        study = optuna.load_study(study_name="vibrofeed", storage=storage)
    except KeyError:  # an empty journal (a study stopped before its search began): nothing to rank
        return {}
    done = [t for t in study.trials if t.state == optuna.trial.TrialState.COMPLETE
            and "ruled_out" not in t.user_attrs and t.constraints.get("measured", 0.0) <= 0]
    if len(done) < 4 or len(spec.variables) < 2:
        return {}
    sign = -1.0 if O.direction(spec.maximize[0]) == "maximize" else 1.0
    measured = optuna.create_study(directions=study.directions)
    measured.add_trials(done)
    try:
        with warnings.catch_warnings():  # "computes the importances ... to achieve low target values"
            warnings.filterwarnings("ignore", message=".*low `target` values")
            return optuna.importance.get_param_importances(
                measured, target=lambda t: sign * t.values[0],
                params=[v.name for v in spec.variables])
    except (RuntimeError, ValueError):
        return {}


def report(folder, plot: Path | None = None) -> dict:
    doc, rows, spec = read(folder)
    rep = {"text": answer_text(spec, doc, rows), "confirmed": doc.get("confirmed"),
           "robustness": doc.get("robustness"), "screen": doc.get("screen"),
           "ruled_out": doc.get("ruled_out", 0), "runs": len(rows),
           "importance": importances(folder, spec),
           "front": front_entries(spec, rows) if spec.multi else None}
    if plot is not None:
        rep["figures"] = figures(spec, doc, rows, rep["importance"], Path(plot))
    return rep


def text(rep: dict) -> str:
    lines = [rep["text"]]
    if rep["importance"]:
        lines.append("importance (first objective): " + ", ".join(
            f"{k} {v:.2f}" for k, v in rep["importance"].items()))
    return "\n".join(lines)


def figures(spec, doc, rows, importance, folder: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = []
    name = spec.maximize[0]
    search = sorted((r for r in rows if r.get("stage") == "search"), key=lambda r: r["job"])
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    xs = list(range(1, len(search) + 1))
    ys = [r.get("objective") for r in search]
    es = [r.get("objective_err") or 0.0 for r in search]
    ok = [(x, y, e) for x, y, e in zip(xs, ys, es) if y is not None]
    if ok:
        ax.errorbar([p[0] for p in ok], [p[1] for p in ok], yerr=[p[2] for p in ok], fmt="o", ms=4,
                    color="0.5", label="search run (± 1σ)")
    best, line = None, []
    for y in ys:
        if y is not None and (best is None or O.better(y, best, name)):
            best = y
        line.append(best if best is not None else math.nan)
    ax.step(xs, line, where="post", color="C0", label="best so far")
    confirmed = doc.get("confirmed") or []
    if confirmed and confirmed[0][name][0] is not None:
        v, e = confirmed[0][name]
        ax.axhline(v, color="C3", label="confirmed best (fresh seeds)")
        if e:
            ax.axhspan(v - e, v + e, color="C3", alpha=0.15)
    ax.set_xlabel("DEM runs of the search")
    ax.set_ylabel(name)
    ax.set_title(f"{spec.source.name}: convergence")
    ax.legend(fontsize=8)
    fig.tight_layout()
    out.append(_save(fig, folder / "convergence.png"))
    if spec.multi:
        fig, ax = plt.subplots(figsize=(5.2, 4.4))
        measured = [r for r in search if r.get("objective") is not None and r.get("objective_2") is not None]
        short = [r for r in measured if any(m > 0 for m in target_margins(spec, r))]
        pts = [(r["objective"], r["objective_2"]) for r in measured if r not in short]
        if pts:
            ax.scatter(*zip(*pts), s=14, color="0.5", label="search runs")
        if short:
            ax.scatter([r["objective"] for r in short], [r["objective_2"] for r in short], s=14,
                       facecolors="none", edgecolors="0.5", label="missing a target")
        front = sorted((r["objective"], r["objective_2"]) for r in pareto_front(spec, rows))
        if front:  # the study's front: runs that count (the targets reached), as it confirms them
            ax.plot(*zip(*front), "o-", color="C3", label="Pareto front")
        ax.set_xlabel(spec.maximize[0])
        ax.set_ylabel(spec.maximize[1])
        ax.legend(fontsize=8)
        fig.tight_layout()
        out.append(_save(fig, folder / "pareto.png"))
    if importance:
        fig, ax = plt.subplots(figsize=(5.2, 0.5 + 0.4 * len(importance)))
        names = list(importance)[::-1]
        ax.barh(names, [importance[n] for n in names], color="C0")
        ax.set_xlabel(f"importance for {name}")
        fig.tight_layout()
        out.append(_save(fig, folder / "importance.png"))
    plt.close("all")
    return out


def _front(points, spec):
    """The non-dominated points, sorted along the first objective."""
    return sorted(set(p for p, keep in zip(points, non_dominated(points, spec.maximize)) if keep))


def _save(fig, path: Path) -> Path:
    from ..pictures.plots import save

    return save(fig, path)
