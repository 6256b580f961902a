"""The optimiser against a full grid of the same design space: DEM runs and wall time to the best.

    .venv/bin/python benchmarks/bench_optimize_grid.py [--study studies/line_singulated_rate.toml]
        [--levels 6 4 4] [--runs 8] [--seeds 3] [--study-seeds 5489 ...] [-j 2] [--work DIR]

The grid is ``--levels`` values of each variable of the study (evenly spaced over its bounds,
geometric on a log scale), with the study's fixed values. A grid setting that breaks the
study's constraints (actuator, hopping, the inequalities, the parameter checks) cannot be
the answer, so only the settings within them are run, as one ``vibrofeed sweep`` with one
seed: that is the grid's DEM runs (the whole grid's size is printed beside it). The grid's
best is the best setting whose run meets the study's ``at_least`` targets; as the study
confirms its own best, the grid's best is then re-run with fresh seeds (``replicates`` of
the study), and both confirmed values are means of fresh runs only.

The study runs with ``--runs`` search runs, ``--seeds`` of them placed by the model screen,
one setting confirmed (no robustness). Its DEM runs are the search runs plus the
confirmation's. It passes when its confirmed value is within one combined standard error of
the grid's confirmed best (or above it) in at most one fifth of the grid's runs. A study is
one draw of a noisy search (its sampler's and its runs' seeds), so ``--study-seeds`` runs
it once per seed (each its own folder ``study-SEED``) and the benchmark passes when every
one of them does; the table gives each.

``--work DIR`` keeps the sweep and the study there (rerun: a killed benchmark continues;
finished runs are not made again). Prints a Markdown table for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_foundation import machine  # noqa: E402

VIBROFEED = ROOT / ".venv" / "bin" / "vibrofeed"
GRID_SEED_OFFSET = 7000  # the grid's seeds: apart from the study's search and confirmation seeds


def axis(var, n: int) -> list:
    if var.kind == "choice":
        return list(var.choices)
    if var.kind == "int":
        return sorted({int(round(x)) for x in np.linspace(var.low, var.high, n)})
    if var.log:
        return [float(x) for x in np.geomspace(var.low, var.high, n)]
    return [float(x) for x in np.linspace(var.low, var.high, n)]


def toml_value(v) -> str:
    return json.dumps(v) if isinstance(v, str) else repr(v)


def sweep_text(spec, points: list[dict], seed: int, replicates: int) -> str:
    lines = [f'deck = "{spec.deck}"', "ranks_per_run = 1", f"replicates = {replicates}", "", "[fixed]"]
    lines += [f"{k} = {toml_value(v)}" for k, v in {**spec.fixed, "seed": seed}.items()]
    for p in points:
        lines += ["", "[[point]]"] + [f"{k} = {toml_value(v)}" for k, v in p.items()]
    if spec.target_error is not None:
        lines.insert(0, f"target_error = {spec.target_error}")
    return "\n".join(lines) + "\n"


def timed(cmd: list[str]) -> float:
    t0 = time.monotonic()
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({done.returncode}):\n{done.stderr[-2000:]}")
    return time.monotonic() - t0


def complete(path: Path) -> bool:
    from vibrofeed.results.reader import Result

    if not path.is_file():
        return False
    try:
        with Result(path) as r:
            return r.status == "complete"
    except Exception:  # noqa: BLE001 - a file we cannot read is one to run again
        return False


def wall_of(path: Path) -> float:
    import h5py

    with h5py.File(path, "r") as f:
        return float(f["parameters/run"].attrs.get("wall_seconds", 0.0))


def started_of(path: Path) -> float:
    import datetime

    import h5py

    with h5py.File(path, "r") as f:
        text = f["parameters/run"].attrs["started"]
    return datetime.datetime.fromisoformat(str(text)).timestamp()


def rows_of(folder: Path, stem: str) -> list[dict]:
    from vibrofeed.sweep import summary as S

    return S.read(folder, stem=stem)[0]


def scored(spec, row: dict) -> tuple[float | None, float | None]:
    """The objective and its error, None when the run failed or missed an at_least target."""
    from vibrofeed.optimize import objective as O

    for name, bound in spec.at_least.items():
        v, _ = O.value_and_error(row, name)
        if v is None or v < bound:
            return None, None
    return O.value_and_error(row, spec.maximize[0])


def mean_and_error(rows: list[dict], spec) -> tuple[float, float]:
    from vibrofeed.optimize import objective as O

    got = [O.value_and_error(r, spec.maximize[0]) for r in rows]
    vals = np.array([v for v, _ in got if v is not None])
    errs = [e for v, e in got if v is not None and e is not None]
    scatter = vals.std(ddof=1) / math.sqrt(len(vals)) if len(vals) > 1 else math.inf
    own = math.sqrt(sum(e * e for e in errs)) / len(errs) if errs else math.inf
    return float(vals.mean()), float(max(scatter, own) if len(vals) > 1 else own)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default=str(ROOT / "studies" / "line_singulated_rate.toml"))
    ap.add_argument("--levels", type=int, nargs="+", default=[6, 4, 4])
    ap.add_argument("--runs", type=int, default=8, help="the study's search runs")
    ap.add_argument("--seeds", type=int, default=3, help="of which the model screen places")
    ap.add_argument("--study-seeds", type=int, nargs="+", default=[5489],
                    help="one study per seed (the study file's seed replaced)")
    ap.add_argument("-j", "--jobs", type=int, default=2)
    ap.add_argument("--work", default="bench_optimize_grid", help="folder kept between reruns")
    a = ap.parse_args()
    from vibrofeed.optimize.search import Setting
    from vibrofeed.optimize.spec import load
    from vibrofeed.sweep.plan import find_deck

    spec = load(a.study)
    from vibrofeed.optimize import objective as O

    if spec.multi or O.direction(spec.maximize[0]) != "maximize":
        sys.exit("a study with one objective to maximise only")
    deck = find_deck(spec)
    if len(a.levels) != len(spec.variables):
        sys.exit(f"--levels: one count per variable ({len(spec.variables)})")
    work = Path(a.work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    reps = spec.budget["replicates"]

    # the grid, within the constraints: one result file per setting (the sweep's jobs/); a
    # setting without a complete file (a first run, or one a killed or superseded sweep lost) is
    # run now, as a sweep of its own into grid_fill/
    axes = [axis(v, n) for v, n in zip(spec.variables, a.levels)]
    every = [dict(zip(spec.names, p)) for p in itertools.product(*axes)]
    within = [p for p in every if Setting(spec, deck, p).feasible]
    files = [work / "grid" / "jobs" / f"job-{k:04d}.h5" for k in range(len(within))]
    missing = [k for k, f in enumerate(files) if not complete(f)]
    grid_wall = 0.0
    if missing:
        fill = work / ("grid" if len(missing) == len(within) else "grid_fill")
        sweep_file = work / f"{fill.name}.toml"
        points = [within[k] for k in missing]
        text = sweep_text(spec, points, spec.seed + GRID_SEED_OFFSET, 1)
        # the same fill as last time continues (the sweep reuses its finished runs); another
        # one (other settings missing) starts afresh
        if fill.name == "grid_fill" and fill.exists() and not (sweep_file.is_file()
                                                               and sweep_file.read_text() == text):
            import shutil

            shutil.rmtree(fill)
        sweep_file.write_text(text)
        grid_wall += timed([str(VIBROFEED), "sweep", str(sweep_file), "-o", str(fill), "-q",
                            "-j", str(a.jobs)])
        if fill.name == "grid_fill":
            for j, k in enumerate(missing):
                files[k] = fill / "jobs" / f"job-{j:04d}.h5"
    from vibrofeed.sweep.metrics import metrics

    grid_rows = [{**within[k], **metrics(f), "wall_s": wall_of(f), "started": started_of(f)}
                 for k, f in enumerate(files)]
    scores = [(scored(spec, r)[0], r) for r in grid_rows]
    ok = [(s, r) for s, r in scores if s is not None]
    if not ok:
        sys.exit("no grid run met the study's targets")
    best_raw, best_row = max(ok, key=lambda t: t[0])
    best_setting = {n: best_row[n] for n in spec.names}
    conf_file = work / "grid_best.toml"
    conf_file.write_text(sweep_text(spec, [best_setting], spec.seed + GRID_SEED_OFFSET + 100, reps))
    grid_wall += timed([str(VIBROFEED), "sweep", str(conf_file), "-o", str(work / "grid_best"), "-q",
                        "-j", str(a.jobs)])
    conf_rows = rows_of(work / "grid_best", "summary")
    g_mean, g_err = mean_and_error(conf_rows, spec)
    grid_runs = len(grid_rows) + reps
    grid_cpu = sum(r["wall_s"] for r in grid_rows) + sum(float(r.get("wall_s") or 0) for r in conf_rows)
    # the grid's wall time as it ran: from its first run's start to its last file
    first = min(r["started"] for r in grid_rows)
    span = max(f.stat().st_mtime for f in files) - first

    # the studies, same space: a few search runs, one setting confirmed, no robustness
    studies = [run_study(a, work, seed) for seed in a.study_seeds]
    name = spec.maximize[0]

    def fmt(setting: dict) -> str:
        return ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in setting.items())

    print(f"machine: {machine()}; study {Path(a.study).name}; grid levels {a.levels}; -j {a.jobs}")
    print(f"| | grid ({len(every)} settings, {len(within)} within the constraints) | "
          + " | ".join(f"study, seed {s['seed']}" for s in studies) + " |")
    print("|---" * (1 + len(studies) + 1) + "|")
    print(f"| DEM runs | {grid_runs} ({len(grid_rows)} + {reps} confirming its best) | "
          + " | ".join(f"{s['runs']} ({a.runs} search, {a.seeds} screen seeds)" for s in studies) + " |")
    print(f"| wall time | {span / 60:.1f} min (first run's start to last file; this call "
          f"{grid_wall / 60:.1f} min) | " + " | ".join(f"{s['wall'] / 60:.1f} min" for s in studies) + " |")
    print(f"| run time summed over runs | {grid_cpu / 60:.1f} min | "
          + " | ".join(f"{s['cpu'] / 60:.1f} min" for s in studies) + " |")
    print(f"| best setting | {fmt(best_setting)} | " + " | ".join(fmt(s["setting"]) for s in studies) + " |")
    print(f"| {name}: its single run | {best_raw:.3f} | "
          + " | ".join(f"{s['raw']:.3f}" for s in studies) + " |")
    print(f"| {name}: confirmed ({reps} fresh seeds) | {g_mean:.3f} ± {g_err:.3f} | "
          + " | ".join(f"{s['mean']:.3f} ± {s['err']:.3f}" for s in studies) + " |")
    passed = []
    for s in studies:
        combined = math.hypot(g_err, s["err"])
        reached = s["mean"] >= g_mean - combined
        fifth = s["runs"] <= grid_runs / 5
        passed.append(reached and fifth)
        print(f"\nstudy seed {s['seed']}: study - grid = {s['mean'] - g_mean:+.3f}, combined error "
              f"{combined:.3f}: {'within' if reached else 'NOT within'} one combined error; runs "
              f"{s['runs']}/{grid_runs} = {s['runs'] / grid_runs:.2f} ({'<=' if fifth else '>'} 1/5)")
    print(f"\n{sum(passed)} of {len(passed)} studies reached the grid's confirmed best "
          "in at most a fifth of its runs")
    sys.exit(0 if all(passed) else 1)


def same(a, b) -> bool:
    """A setting's value as the ledger read it back and as study.json holds it."""
    if isinstance(a, float) or isinstance(b, float):
        return a is not None and b is not None and math.isclose(float(a), float(b), rel_tol=1e-9)
    return a == b


def run_study(a, work: Path, seed: int) -> dict:
    """One study of the benchmark's design (its seed replaced): its runs, times and answer."""
    from vibrofeed.optimize.spec import load

    text = Path(a.study).read_text()
    text = re.sub(r"(?m)^seed = \d+", f"seed = {seed}", text)
    text = re.sub(r"(?m)^confirm = \d+", "confirm = 1", text)
    text = re.sub(r"(?m)^seeds = \d+", f"seeds = {a.seeds}", text)
    text = re.sub(r"(?m)^\[robustness\][\s\S]*", "", text)
    study = work / f"study-{seed}.toml"
    study.write_text(text)
    spec = load(study)
    out = work / f"study-{seed}"
    cmd = [str(VIBROFEED), "optimize", str(study), "-o", str(out), "-q", "--budget", str(a.runs),
           "-j", str(a.jobs)]
    if (out / "study.json").exists():
        cmd.append("--resume")
    wall = timed(cmd)
    srows = rows_of(out, "study")
    doc = json.loads((out / "study.json").read_text())
    conf = [r for r in srows if r["stage"] == "confirm"]
    mean, err = mean_and_error(conf, spec)
    setting = doc["confirmed"][0]["setting"] if doc.get("confirmed") else {}
    searched = [scored(spec, r)[0] for r in srows if r["stage"] == "search"
                and all(same(r.get(n), setting.get(n)) for n in spec.names)]
    return {"seed": seed, "runs": len(srows), "wall": wall, "mean": mean, "err": err, "setting": setting,
            "cpu": sum(float(r.get("wall_s") or 0) for r in srows),
            "raw": next((v for v in searched if v is not None), float("nan"))}



if __name__ == "__main__":
    main()
