"""Mutation testing of vibrofeed with cosmic-ray, in a scratch copy of the tree.

Usage (from the repository root, with the project's venv)::

    .venv/bin/python tests/mutation/run.py                      # every target
    .venv/bin/python tests/mutation/run.py parameters postproc  # some targets
    .venv/bin/python tests/mutation/run.py --retest-survivors   # after new tests
    .venv/bin/python tests/mutation/run.py --report             # figures only

Each target of ``[tool.cosmic-ray.targets]`` in pyproject.toml (modules to
mutate, the fast unit tests that guard them) runs in its own copy of the tree
under ``--workdir`` (default /tmp/vibrofeed-mutation), so the repository is
never edited and targets can run side by side (``--jobs``). cosmic-ray mutates
one spot at a time in place and runs the target's tests; a mutant is killed
when they fail (or time out). The copy imports as ``vibrofeed`` through
PYTHONPATH: ``vibrofeed/postproc`` and ``vibrofeed/validation`` are symlinks
to the top-level folders, as setuptools' ``package-dir`` maps them.

A session is resumed while the mutated modules are unchanged (an interrupted
run goes on where it stopped); ``--retest-survivors`` copies the current tests
and runs the survivors again. Survivors listed in tests/mutation/EQUIVALENT.md
(same module, operator and source line) count as equivalent mutants. The score
is (killed + equivalent) / mutants tested, per target. A target with ``sample = f`` (or
``--sample f``) tests a fixed pseudo-random fraction f of its mutants, the same
ones every time: the score is then an estimate. ``--min-score`` makes the exit status 1
when any target is below it (CTest ``mutation``). Survivors with their diffs go to
``WORKDIR/survivors.md``, the figures to ``WORKDIR/summary.md``.
"""

from __future__ import annotations

import argparse
import fnmatch
import hashlib
import json
import os
import re
import shutil
import sqlite3
import subprocess
import sys
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
EQUIVALENT = Path(__file__).with_name("EQUIVALENT.md")
# What the copy needs to import and test the package (no build tree, no venv).
COPIED = ("vibrofeed", "postproc", "validation", "decks", "tests", "pyproject.toml", "README.md",
          "FORMAT.md")
MAPPED = {"postproc": "postproc", "validation": "validation"}  # vibrofeed.<key> -> <folder>


def load_config() -> dict:
    with open(REPO / "pyproject.toml", "rb") as f:
        return tomllib.load(f)["tool"]["cosmic-ray"]


# -- the copy ------------------------------------------------------------------------------
def _ignore(_dir, names):
    return [n for n in names if n in ("__pycache__", ".hypothesis", ".pytest_cache")]


def make_tree(tree: Path) -> None:
    """A fresh copy of the sources and tests, importable as ``vibrofeed`` via PYTHONPATH."""
    if tree.exists():
        shutil.rmtree(tree)
    tree.mkdir(parents=True)
    for name in COPIED:
        src = REPO / name
        if src.is_dir():
            shutil.copytree(src, tree / name, ignore=_ignore)
        else:
            shutil.copy2(src, tree / name)
    for sub, folder in MAPPED.items():
        (tree / "vibrofeed" / sub).symlink_to(Path("..") / folder)


def refresh_tests(tree: Path) -> None:
    shutil.rmtree(tree / "tests")
    shutil.copytree(REPO / "tests", tree / "tests", ignore=_ignore)


def module_files(modules) -> list[Path]:
    out = []
    for m in modules:
        p = REPO / m
        out += sorted(p.rglob("*.py")) if p.is_dir() else [p]
    return out


def fingerprint(modules) -> str:
    h = hashlib.sha256()
    for p in module_files(modules):
        h.update(str(p.relative_to(REPO)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()


# -- one target ----------------------------------------------------------------------------
def cosmic_ray(*args, cwd, env, log):
    cmd = [sys.executable, "-m", "cosmic_ray.cli", *map(str, args)]
    with open(log, "a") as out:
        subprocess.run(cmd, cwd=cwd, env=env, check=True, stdout=out, stderr=subprocess.STDOUT)


def sample_out(db: Path, fraction: float) -> None:
    """Keep a fixed pseudo-random ``fraction`` of the mutants (the same ones on every run: the
    choice hashes each mutant's module, operator and position); mark the rest skipped."""
    with sqlite3.connect(db) as c:
        rows = list(c.execute(
            "SELECT s.job_id, s.module_path, s.operator_name, s.occurrence, s.start_pos_row, "
            "s.start_pos_col FROM mutation_specs s LEFT JOIN work_results r ON r.job_id = s.job_id "
            "WHERE r.job_id IS NULL"))
        out = []
        for job, *key in rows:
            h = int(hashlib.sha256(repr(key).encode()).hexdigest()[:8], 16) / 16 ** 8
            if h >= fraction:
                out.append(("SKIPPED", "sampled out", None, None, job))
        c.executemany("INSERT INTO work_results (worker_outcome, output, test_outcome, diff, job_id) "
                      "VALUES (?, ?, ?, ?, ?)", out)


def run_target(name: str, spec: dict, cfg: dict, workdir: Path, retest: bool, fresh: bool,
               sample: float | None = None, survivors_only: bool = False) -> None:
    home = workdir / name
    tree, db, stamp = home / "tree", home / "session.sqlite", home / "fingerprint.json"
    log = home / "cosmic-ray.log"
    home.mkdir(parents=True, exist_ok=True)
    fp = fingerprint(spec["modules"])
    same = (stamp.exists() and json.loads(stamp.read_text()).get("modules") == fp
            and db.exists() and not fresh)
    make_tree(tree)  # fresh sources every time: an interrupted run may have left a mutant in place
    if retest and not same:
        raise SystemExit(f"{name}: the mutated modules changed since the session began; "
                         "run without --retest-survivors for a new session")
    tests = " ".join(spec["tests"])
    python = sys.executable
    config = {
        "module-path": spec["modules"],
        "timeout": float(spec.get("timeout", cfg.get("timeout", 60.0))),
        "excluded-modules": [],
        "test-command": f"nice -n 10 {python} -m pytest -x -q -p no:cacheprovider {tests}",
        "distributor": {"name": "local"},
        "filters": {"operators-filter": {"exclude-operators": cfg.get("exclude-operators", [])}},
    }
    (home / "cosmic-ray.toml").write_text(_toml({"cosmic-ray": config}))
    env = dict(os.environ, PYTHONPATH=str(tree), VIBROFEED_MUTATION="1")
    env.pop("PYTHONSTARTUP", None)
    if not same:
        db.unlink(missing_ok=True)
        cosmic_ray("init", home / "cosmic-ray.toml", db, cwd=tree, env=env, log=log)
        subprocess.run([sys.executable, "-m", "cosmic_ray.tools.filters.operators_filter",
                        db, home / "cosmic-ray.toml"], cwd=tree, env=env, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        fraction = sample if sample is not None else spec.get("sample")
        if fraction is not None and fraction < 1:
            sample_out(db, float(fraction))
        stamp.write_text(json.dumps({"modules": fp, "sample": fraction}))
        # The sources as mutated, for the report (the repository may move on meanwhile).
        shutil.rmtree(home / "sources", ignore_errors=True)
        for f in module_files(spec["modules"]):
            dest = home / "sources" / f.relative_to(REPO)
            dest.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(f, dest)
    # The unmutated copy must pass, or every mutant would count as killed.
    base = subprocess.run(config["test-command"].split(), cwd=tree, env=env, capture_output=True,
                          text=True)
    if base.returncode != 0:
        raise SystemExit(f"{name}: the tests fail on the unmutated copy:\n{base.stdout[-3000:]}")
    deferred = []
    if retest:
        with sqlite3.connect(db) as c:
            if survivors_only:  # keep the untested mutants for a later run
                deferred = [r[0] for r in c.execute(
                    "SELECT w.job_id FROM work_items w LEFT JOIN work_results r "
                    "ON r.job_id = w.job_id WHERE r.job_id IS NULL")]
                c.executemany("INSERT INTO work_results (worker_outcome, output, job_id) "
                              "VALUES ('SKIPPED', 'deferred', ?)", [(j,) for j in deferred])
            c.execute("DELETE FROM work_results WHERE lower(test_outcome) = 'survived'")
    t0 = time.monotonic()
    try:
        cosmic_ray("exec", home / "cosmic-ray.toml", db, cwd=tree, env=env, log=log)
    finally:
        if deferred:
            with sqlite3.connect(db) as c:
                c.execute("DELETE FROM work_results WHERE output = 'deferred'")
    spent = time.monotonic() - t0
    times = json.loads((home / "wall.json").read_text()) if (home / "wall.json").exists() else {}
    times["last_exec_s"] = spent
    times["total_exec_s"] = times.get("total_exec_s", 0.0) * (same or retest) + spent
    (home / "wall.json").write_text(json.dumps(times))


def _toml(d: dict, prefix: str = "") -> str:
    """Just enough TOML for cosmic-ray's configuration."""
    lines, tables = [], []
    for k, v in d.items():
        if isinstance(v, dict):
            tables.append((k, v))
        else:
            lines.append(f"{k} = {json.dumps(v)}")
    out = "\n".join(lines) + ("\n" if lines else "")
    for k, v in tables:
        name = f"{prefix}.{k}" if prefix else k
        out += f"\n[{name}]\n" + _toml(v, name)
    return out


# -- figures -------------------------------------------------------------------------------
def equivalents() -> list[tuple[str, str, str]]:
    """(module, operator, source line) of every documented equivalent mutant.

    A cell may be a pattern: module ``*`` or a glob, operator and line ``re:...``
    (a regular expression matching the whole stripped text).
    """
    out = []
    for line in EQUIVALENT.read_text().splitlines():
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line.strip().strip("|"))]
        if len(cells) >= 4 and (cells[0].strip("`").endswith(".py") or cells[0].strip("`") == "*"):
            cells = [c.strip("`") for c in cells[:3]]
            out.append(tuple(c if c.startswith("re:") else c.replace("\\|", "|") for c in cells))
    return out


def is_equivalent(module: str, op: str, text: str, rows) -> bool:
    def match(pattern: str, value: str, glob: bool = False) -> bool:
        if pattern.startswith("re:"):
            return re.fullmatch(pattern[3:], value) is not None
        return fnmatch.fnmatchcase(value, pattern) if glob else pattern == value
    return any(match(m, module, glob=True) and match(o, op) and match(t, text) for m, o, t in rows)


def results(name: str, workdir: Path) -> dict:
    home = workdir / name
    db = home / "session.sqlite"
    rows = []
    with sqlite3.connect(db) as c:
        q = ("SELECT s.job_id, s.module_path, s.operator_name, s.start_pos_row, r.worker_outcome, "
             "r.test_outcome, r.diff, r.output FROM mutation_specs s "
             "LEFT JOIN work_results r ON r.job_id = s.job_id")
        rows = list(c.execute(q))
    eq = equivalents()
    counts = dict(mutants=0, killed=0, timeout=0, equivalent=0, survived=0, pending=0, sampled_out=0)
    survivors = []
    for _job, module, op, row, worker, outcome, diff, output in rows:
        worker, outcome = (worker or "").lower() or None, (outcome or "").lower()
        if worker == "skipped":
            counts["sampled_out"] += output == "sampled out"
            continue  # an operator left out by configuration, or a mutant not in the sample
        counts["mutants"] += 1
        if worker is None:
            counts["pending"] += 1
        elif outcome == "survived":
            source = home / "sources" / module
            src = (source if source.exists() else REPO / module).read_text().splitlines()
            text = src[row - 1].strip() if row - 1 < len(src) else ""
            if is_equivalent(module, op, text, eq):
                counts["equivalent"] += 1
            else:
                counts["survived"] += 1
                survivors.append((module, row, op, text, diff))
        else:
            counts["killed"] += 1
            counts["timeout"] += output == "timeout"
    done = counts["mutants"] - counts["pending"]
    counts["score"] = (counts["killed"] + counts["equivalent"]) / done if done else float("nan")
    wall = home / "wall.json"
    counts["wall_s"] = json.loads(wall.read_text()).get("total_exec_s", 0.0) if wall.exists() else 0.0
    counts["survivors"] = survivors
    return counts


def report(names, workdir: Path, cfg: dict) -> float:
    """Print and store the figures; returns the lowest score of the targets run (each must
    reach the bar on its own: a good target cannot hide a weak one in the total)."""
    head = ("| target | mutants | killed (timeouts) | equivalent | survived | pending | score "
            "| exec time | not sampled |")
    lines = [head, "|---|---|---|---|---|---|---|---|---|"]
    total = dict(mutants=0, killed=0, timeout=0, equivalent=0, survived=0, pending=0, wall_s=0.0)
    surv = ["# Surviving mutants\n"]
    scores = []
    for name in names:
        if not (workdir / name / "session.sqlite").exists():
            lines.append(f"| {name} | not run | | | | | | | |")
            scores.append(float("nan"))
            continue
        r = results(name, workdir)
        scores.append(r["score"])
        for k in total:
            total[k] += r[k]
        lines.append(f"| {name} | {r['mutants']} | {r['killed']} ({r['timeout']}) | {r['equivalent']} "
                     f"| {r['survived']} | {r['pending']} | {100 * r['score']:.1f} % "
                     f"| {r['wall_s'] / 60:.0f} min | {r['sampled_out'] or ''} |")
        for module, row, op, text, diff in r["survivors"]:
            surv.append(f"## {module}:{row} `{op}`\n\n`{text}`\n\n```diff\n{diff}\n```\n")
    done = total["mutants"] - total["pending"]
    score = (total["killed"] + total["equivalent"]) / done if done else float("nan")
    lines.append(f"| **all** | {total['mutants']} | {total['killed']} ({total['timeout']}) "
                 f"| {total['equivalent']} | {total['survived']} | {total['pending']} "
                 f"| {100 * score:.1f} % | {total['wall_s'] / 60:.0f} min | |")
    text = "\n".join(lines) + "\n"
    (workdir / "summary.md").write_text(text)
    (workdir / "survivors.md").write_text("\n".join(surv))
    print(text + f"\nsurvivors: {workdir / 'survivors.md'}")
    return min(scores, key=lambda x: -1.0 if x != x else x) if scores else score  # NaN: not run


def main(argv=None) -> int:
    cfg = load_config()
    targets = cfg["targets"]
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("targets", nargs="*", help=f"targets (default: all of {', '.join(targets)})")
    ap.add_argument("--workdir", type=Path, default=Path(os.environ.get(
        "VIBROFEED_MUTATION_DIR", "/tmp/vibrofeed-mutation")))
    ap.add_argument("--jobs", type=int, default=1, help="targets run side by side")
    ap.add_argument("--retest-survivors", action="store_true",
                    help="copy the current tests and test the survivors again (and the pending)")
    ap.add_argument("--survivors-only", action="store_true",
                    help="with --retest-survivors: leave the untested mutants for later")
    ap.add_argument("--fresh", action="store_true", help="start new sessions")
    ap.add_argument("--report", action="store_true", help="only print the figures")
    ap.add_argument("--min-score", type=float, default=None,
                    help="exit 1 when a target scores below this (0-1)")
    ap.add_argument("--sample", type=float, default=None,
                    help="test only this fraction of a new session's mutants (the same ones each "
                         "time); default: a target's `sample` in pyproject.toml, else all")
    args = ap.parse_args(argv)
    args.workdir = args.workdir.resolve()  # cosmic-ray runs in the copy: a relative path would move
    names = args.targets or list(targets)
    unknown = [n for n in names if n not in targets]
    if unknown:
        ap.error(f"unknown target(s) {', '.join(unknown)}; known: {', '.join(targets)}")
    args.workdir.mkdir(parents=True, exist_ok=True)
    if not args.report:
        with ThreadPoolExecutor(max(1, args.jobs)) as pool:
            futures = [pool.submit(run_target, n, targets[n], cfg, args.workdir,
                                   args.retest_survivors, args.fresh, args.sample,
                                   args.survivors_only) for n in names]
            for f in futures:
                f.result()
    score = report(names, args.workdir, cfg)
    if args.min_score is not None and not score >= args.min_score:
        print(f"lowest target score {100 * score:.1f} % is below {100 * args.min_score:.0f} % "
              "(or a target was not run)")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
