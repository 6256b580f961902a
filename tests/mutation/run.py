"""Mutation testing of vibrofeed with cosmic-ray, in a scratch copy of the tree.

Usage (from the repository root, with the project's venv)::

    .venv/bin/python tests/mutation/run.py                      # every target
    .venv/bin/python tests/mutation/run.py parameters postproc  # some targets
    .venv/bin/python tests/mutation/run.py --retest-survivors   # after new tests
    .venv/bin/python tests/mutation/run.py --report             # figures only
    .venv/bin/python tests/mutation/run.py --plan               # mutants and time, nothing run
    .venv/bin/python tests/mutation/run.py --operators 'slips/.*' line  # some operators only

Each target of ``[tool.cosmic-ray.targets]`` in pyproject.toml (``modules`` to mutate,
``tests``: the fast unit tests that guard them; optional ``sample``, ``timeout``,
``exclude-operators`` added to the global ones, and ``functions``: module -> the functions or
classes, fnmatch patterns on the innermost enclosing definition, whose mutants are tested, the
others of that module skipped) runs in its own copy of the tree under ``--workdir`` (default
/tmp/vibrofeed-mutation), so the repository is never edited and targets can run side by side
(``--jobs``). cosmic-ray mutates one spot at a time in place and runs the target's tests; a
mutant is killed when they fail (or time out). The copy imports as ``vibrofeed`` through
PYTHONPATH: ``vibrofeed/postproc`` and ``vibrofeed/validation`` are symlinks to the top-level
folders, as setuptools' ``package-dir`` maps them.

Operators: cosmic-ray's core ones, one partner each (``exclude-operators``), and the provider
``slips`` of tests/mutation/slips.py for the slips they miss: ``slips/MeanMedian`` (np.mean <->
np.median, ``a.mean()`` -> ``np.median(a)``), ``slips/AxisNone`` (``axis=K`` -> ``axis=None``),
``slips/OffByOne`` (a slice or range() bound ``E`` -> ``E +/- 1``; ``a[:-1]`` -> ``a[:]``) and
``slips/LoosenTolerance`` (a tolerance-like name's value times 10); see that module. Nothing is
installed: run.py writes the module and a ``*.dist-info`` folder holding its entry point
(``cosmic_ray.operator_providers``) into ``WORKDIR/TARGET/plugin``, which it puts on PYTHONPATH,
checks that cosmic-ray loads the provider, and runs the operators' own examples first.
``slips = false`` in ``[tool.cosmic-ray]`` leaves them out.

A session is resumed while its modules, operators, sample, functions and ``--operators`` are
unchanged (an interrupted run goes on where it stopped). When only the operators, sample,
functions or ``--operators`` changed, a new session keeps the outcomes of the mutants both
share (same module, operator, occurrence and position): adding an operator or a larger sample
tests only the new mutants, and ``--operators 'slips/.*'`` followed by a plain run tests the rest.
When some of a target's modules changed, the new session keeps the outcomes of its unchanged
modules (compared with the copy of the sources the last session mutated) and tests the changed
ones' mutants afresh.
``--retest-survivors`` copies the current tests and runs the survivors again. Survivors listed
in tests/mutation/EQUIVALENT.md (same module, operator and source line) count as equivalent
mutants. The score is (killed + equivalent) / mutants tested, per target. A target with
``sample = f`` (or ``--sample f``) tests a fixed pseudo-random fraction f of its mutants, the
same ones every time: the score is then an estimate. ``--min-score`` makes the exit status 1
when any target is below it (CTest ``mutation``). ``--plan`` sets the sessions up and times each
target's tests once: the mutants to test and the most they take (one test run each).
Survivors with their diffs go to ``WORKDIR/survivors.md``, the figures to ``WORKDIR/summary.md``;
survivors.md also lists the rows of EQUIVALENT.md that only killed mutants match, to review
(a row whose claim the tests disprove, or one about a twin left out of the sample).
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
SLIPS = Path(__file__).with_name("slips.py")  # the provider `slips` of extra operators
PLUGIN = "vibrofeed_mutation_slips"  # its module and distribution name in the session's plugin/
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


def operators_fingerprint(cfg: dict, spec: dict) -> str:
    """What decides the set of operators: the exclusions and the slips provider's code."""
    h = hashlib.sha256(json.dumps([excluded(cfg, spec), cfg.get("slips", True)]).encode())
    if cfg.get("slips", True):
        h.update(SLIPS.read_bytes())
    return h.hexdigest()


def excluded(cfg: dict, spec: dict) -> list[str]:
    return list(cfg.get("exclude-operators", [])) + list(spec.get("exclude-operators", []))


def make_plugin(home: Path) -> Path:
    """The slips provider as an installed distribution would look, in ``home/plugin``: on
    PYTHONPATH, importlib.metadata (stevedore, hence cosmic-ray) finds its entry point
    ``cosmic_ray.operator_providers: slips``. Nothing is installed in the venv. Files are
    rewritten only when they change (stevedore caches entry points by path and mtime)."""
    plugin = home / "plugin"
    info = plugin / f"{PLUGIN}-1.0.dist-info"
    info.mkdir(parents=True, exist_ok=True)
    files = {
        plugin / f"{PLUGIN}.py": SLIPS.read_text(),
        info / "METADATA": f"Metadata-Version: 2.1\nName: {PLUGIN}\nVersion: 1.0\n",
        info / "entry_points.txt": f"[cosmic_ray.operator_providers]\nslips = {PLUGIN}:Provider\n",
    }
    for path, text in files.items():
        if not path.exists() or path.read_text() != text:
            path.write_text(text)
    return plugin


def check_slips() -> None:
    """The slips operators' own examples (tests/mutation/slips.py, ``check``)."""
    subprocess.run([sys.executable, str(SLIPS)], check=True, stdout=subprocess.DEVNULL)


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


def restrict(db: Path, functions: dict[str, list[str]], operators: str | None = None) -> None:
    """Only the mutants inside the named functions or classes (innermost enclosing definition,
    fnmatch patterns) of the modules listed, and only the operators matching the regular
    expression ``operators``; mark the others skipped."""
    def targeted(module, where, op):
        return ((module not in functions or any(fnmatch.fnmatchcase(where or "", f)
                                                for f in functions[module]))
                and (operators is None or re.fullmatch(operators, op) is not None))
    with sqlite3.connect(db) as c:
        rows = list(c.execute(
            "SELECT s.job_id, s.module_path, s.definition_name, s.operator_name FROM mutation_specs s "
            "LEFT JOIN work_results r ON r.job_id = s.job_id WHERE r.job_id IS NULL"))
        out = [("SKIPPED", "not targeted", None, None, job) for job, module, where, op in rows
               if not targeted(module, where, op)]
        c.executemany("INSERT INTO work_results (worker_outcome, output, test_outcome, diff, job_id) "
                      "VALUES (?, ?, ?, ?, ?)", out)


_KEY = "s.module_path, s.operator_name, s.occurrence, s.start_pos_row, s.start_pos_col"


def unchanged_modules(home: Path, modules) -> set[str]:
    """The target's module files whose source is byte for byte the one the last session mutated
    (its copy in ``home/sources``): their mutants are the same mutants."""
    out = set()
    for f in module_files(modules):
        rel = f.relative_to(REPO)
        before = home / "sources" / rel
        if before.exists() and before.read_bytes() == f.read_bytes():
            out.add(rel.as_posix())
    return out


def carry_results(old: Path, new: Path, modules: set[str] | None = None) -> int:
    """Copy the outcomes of mutants tested in the old session (same mutant: same module,
    operator, occurrence and position) into the new one, where it tests them too: a new operator,
    target option or sample adds mutants without testing the old ones again. ``modules``: carry
    only those modules' outcomes (the others changed: their positions moved, so they start over).
    A kept outcome was reached with the tests of its day; the tests only grow, and
    ``--retest-survivors`` runs the kept survivors again."""
    with sqlite3.connect(old) as c:
        done = {tuple(k): v for *k, v in (
            (*r[:5], r[5:]) for r in c.execute(
                f"SELECT {_KEY}, r.worker_outcome, r.output, r.test_outcome, r.diff "
                "FROM mutation_specs s JOIN work_results r ON r.job_id = s.job_id "
                "WHERE r.worker_outcome != 'SKIPPED'"))}
    with sqlite3.connect(new) as c:
        todo = list(c.execute(f"SELECT s.job_id, {_KEY} FROM mutation_specs s LEFT JOIN work_results r "
                              "ON r.job_id = s.job_id WHERE r.job_id IS NULL"))
        out = [(*done[tuple(key)], job) for job, *key in todo
               if tuple(key) in done and (modules is None or Path(key[0]).as_posix() in modules)]
        c.executemany("INSERT INTO work_results (worker_outcome, output, test_outcome, diff, job_id) "
                      "VALUES (?, ?, ?, ?, ?)", out)
    return len(out)


def run_target(name: str, spec: dict, cfg: dict, workdir: Path, retest: bool, fresh: bool,
               sample: float | None = None, survivors_only: bool = False,
               plan_only: bool = False, operators: str | None = None) -> dict | None:
    home = workdir / name
    tree, db, stamp = home / "tree", home / "session.sqlite", home / "fingerprint.json"
    log = home / "cosmic-ray.log"
    home.mkdir(parents=True, exist_ok=True)
    fraction = sample if sample is not None else spec.get("sample")
    functions = spec.get("functions", {})
    fp = fingerprint(spec["modules"])
    session = {"modules": fp, "operators": operators_fingerprint(cfg, spec), "sample": fraction,
               "functions": functions, "only_operators": operators}
    old = json.loads(stamp.read_text()) if stamp.exists() and db.exists() and not fresh else {}
    same = old == session
    # Same modules, other operators, sample or functions: a new session that keeps the outcomes.
    # Some modules changed: the unchanged ones keep theirs (a fix in one module of a target does
    # not send the others' hundreds of mutants round again).
    kept_modules = None if old.get("modules") == fp else unchanged_modules(home, spec["modules"])
    carry = bool(old) and not same and kept_modules != set()
    make_tree(tree)  # fresh sources every time: an interrupted run may have left a mutant in place
    if retest and not same:
        raise SystemExit(f"{name}: the mutated modules, operators, sample or functions changed "
                         "since the session began; run without --retest-survivors first")
    tests = " ".join(spec["tests"])
    python = sys.executable
    config = {
        "module-path": spec["modules"],
        "timeout": float(spec.get("timeout", cfg.get("timeout", 60.0))),
        "excluded-modules": [],
        "test-command": f"nice -n 10 {python} -m pytest -x -q -p no:cacheprovider {tests}",
        "distributor": {"name": "local"},
        "filters": {"operators-filter": {"exclude-operators": excluded(cfg, spec)}},
    }
    (home / "cosmic-ray.toml").write_text(_toml({"cosmic-ray": config}))
    path = [str(tree)] + ([str(make_plugin(home))] if cfg.get("slips", True) else [])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(path), VIBROFEED_MUTATION="1")
    env.pop("PYTHONSTARTUP", None)
    if not same:
        if cfg.get("slips", True):  # the provider must load, or its operators silently vanish
            subprocess.run([sys.executable, "-c", "import cosmic_ray.plugins as p, sys; "
                            "sys.exit('slips' not in p.OPERATOR_PROVIDERS)"], cwd=tree, env=env,
                           check=True)
        previous = home / "previous.sqlite"
        if carry:
            db.replace(previous)
        db.unlink(missing_ok=True)
        stamp.unlink(missing_ok=True)
        cosmic_ray("init", home / "cosmic-ray.toml", db, cwd=tree, env=env, log=log)
        subprocess.run([sys.executable, "-m", "cosmic_ray.tools.filters.operators_filter",
                        db, home / "cosmic-ray.toml"], cwd=tree, env=env, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        if functions or operators:
            restrict(db, functions, operators)
        if fraction is not None and fraction < 1:
            sample_out(db, float(fraction))
        if carry:
            kept = carry_results(previous, db, kept_modules)
            previous.unlink()
            where = "" if kept_modules is None else f" (unchanged: {', '.join(sorted(kept_modules))})"
            print(f"{name}: new session, {kept} outcomes kept from the last one{where}", flush=True)
        stamp.write_text(json.dumps(session))
        # The sources as mutated, for the report (the repository may move on meanwhile).
        shutil.rmtree(home / "sources", ignore_errors=True)
        for f in module_files(spec["modules"]):
            dest = home / "sources" / f.relative_to(REPO)
            dest.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(f, dest)
    # The unmutated copy must pass, or every mutant would count as killed.
    t_base = time.monotonic()
    base = subprocess.run(config["test-command"].split(), cwd=tree, env=env, capture_output=True,
                          text=True)
    if base.returncode != 0:
        raise SystemExit(f"{name}: the tests fail on the unmutated copy:\n{base.stdout[-3000:]}")
    if plan_only:
        return plan_figures(name, db, time.monotonic() - t_base)
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
    times["total_exec_s"] = times.get("total_exec_s", 0.0) * (same or retest or carry) + spent
    (home / "wall.json").write_text(json.dumps(times))
    return None


def plan_figures(name: str, db: Path, base_s: float) -> dict:
    """Mutants of a target (all, in the sample, still to test) and the time the rest takes at
    most: one run of the target's tests each (a killed mutant often stops earlier, at -x)."""
    with sqlite3.connect(db) as c:
        ops = {}
        for op, worker, output in c.execute(
                "SELECT s.operator_name, r.worker_outcome, r.output FROM mutation_specs s "
                "LEFT JOIN work_results r ON r.job_id = s.job_id"):
            filtered = worker == "SKIPPED" and output not in ("sampled out", "not targeted")
            if filtered:
                continue
            o = ops.setdefault(op.split("/")[0] if op.startswith("core/") else op, [0, 0, 0])
            o[0] += 1
            o[1] += worker != "SKIPPED"
            o[2] += worker is None
    total, tested, pending = (sum(v[i] for v in ops.values()) for i in range(3))
    slips = {k: v[1] for k, v in ops.items() if k.startswith("slips/")}
    print(f"{name}: {total} mutants, {tested} in the sample ({pending} to test; slips {slips}); "
          f"tests {base_s:.1f} s: at most {pending * base_s / 3600:.2f} h", flush=True)
    return dict(total=total, tested=tested, pending=pending, base_s=base_s)


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


def matching_rows(module: str, op: str, text: str, rows) -> list[tuple[str, str, str]]:
    """The rows of ``rows`` (see :func:`equivalents`) that name this mutant."""
    def match(pattern: str, value: str, glob: bool = False) -> bool:
        if pattern.startswith("re:"):
            return re.fullmatch(pattern[3:], value) is not None
        return fnmatch.fnmatchcase(value, pattern) if glob else pattern == value
    return [r for r in rows if match(r[0], module, glob=True) and match(r[1], op) and match(r[2], text)]


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
    # A row that names only killed mutants of this session is listed for review: its claim is
    # disproved, or gone stale, or (a sampled target) it is about a twin not in the sample.
    named_killed, named_survived = set(), set()
    sources: dict[str, list[str]] = {}  # each module's source, read once
    for _job, module, op, row, worker, outcome, diff, output in rows:
        worker, outcome = (worker or "").lower() or None, (outcome or "").lower()
        if worker == "skipped":
            counts["sampled_out"] += output == "sampled out"
            continue  # an operator left out by configuration, or a mutant not in the sample
        counts["mutants"] += 1
        if worker is None:
            counts["pending"] += 1
        else:
            if module not in sources:
                source = home / "sources" / module
                sources[module] = (source if source.exists() else REPO / module).read_text().splitlines()
            src = sources[module]
            text = src[row - 1].strip() if row - 1 < len(src) else ""
            rows_named = matching_rows(module, op, text, eq)
            if outcome != "survived":
                counts["killed"] += 1
                counts["timeout"] += output == "timeout"
                named_killed.update(rows_named)
            elif rows_named:
                counts["equivalent"] += 1
                named_survived.update(rows_named)
            else:
                counts["survived"] += 1
                survivors.append((module, row, op, text, diff))
    done = counts["mutants"] - counts["pending"]
    counts["score"] = (counts["killed"] + counts["equivalent"]) / done if done else float("nan")
    wall = home / "wall.json"
    counts["wall_s"] = json.loads(wall.read_text()).get("total_exec_s", 0.0) if wall.exists() else 0.0
    counts["survivors"] = survivors
    counts["rows_to_review"] = sorted(named_killed - named_survived)
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
    to_review = []
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
        to_review.extend(r["rows_to_review"])
    done = total["mutants"] - total["pending"]
    score = (total["killed"] + total["equivalent"]) / done if done else float("nan")
    lines.append(f"| **all** | {total['mutants']} | {total['killed']} ({total['timeout']}) "
                 f"| {total['equivalent']} | {total['survived']} | {total['pending']} "
                 f"| {100 * score:.1f} % | {total['wall_s'] / 60:.0f} min | |")
    text = "\n".join(lines) + "\n"
    if to_review:
        surv.append("# Rows of EQUIVALENT.md that only killed mutants match (review them)\n")
        surv.extend(f"- `{m}` `{o}` `{t}`" for m, o, t in sorted(set(to_review)))
        text += (f"\n{len(set(to_review))} row(s) of EQUIVALENT.md match only killed mutants: "
                 "listed in survivors.md\n")
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
    ap.add_argument("--operators", metavar="REGEX", default=None,
                    help="test only the mutants of the operators matching REGEX (whole name, e.g. "
                         "'slips/.*'); the others wait for a run without it, which keeps these outcomes")
    ap.add_argument("--plan", action="store_true",
                    help="set the sessions up and time the tests once: print each target's mutants "
                         "and the most its untested ones take; test no mutant")
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
        if cfg.get("slips", True):
            check_slips()
        with ThreadPoolExecutor(max(1, args.jobs)) as pool:
            futures = [pool.submit(run_target, n, targets[n], cfg, args.workdir,
                                   args.retest_survivors, args.fresh, args.sample,
                                   args.survivors_only, args.plan, args.operators) for n in names]
            plans = [f.result() for f in futures]
        if args.plan:
            pending = sum(p["pending"] * p["base_s"] for p in plans)
            print(f"all: {sum(p['tested'] for p in plans)} mutants in the samples, at most "
                  f"{pending / 3600:.1f} h on one core")
            return 0
    score = report(names, args.workdir, cfg)
    if args.min_score is not None and not score >= args.min_score:
        print(f"lowest target score {100 * score:.1f} % is below {100 * args.min_score:.0f} % "
              "(or a target was not run)")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
