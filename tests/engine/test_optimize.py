"""`vibrofeed optimize` with LIGGGHTS: a study of the single part's phase (one sphere, 0.1 s,
~1.5 s a run). A copy of the deck fails inside LIGGGHTS for |phase| > 60 deg (a value the
checks accept), so some evaluations fail and the study must go on; the screen's seeds are
spread over the phase, so the second one lies beyond 60 deg. Every row of study.csv is true
of its run (its objective is what the analysis gives on its file), a killed study resumes
without running a finished run again, and under mpirun two groups share the runs.

Two objectives: a bulk feeder (80 spheres settled up to the outlet edge of a 6 mm track,
0.1 s, ~4 s a run) maximising the feed rate and minimising the arrivals' irregularity
(cv_interarrival). The study's Pareto front is the
non-dominated set of its search runs, its members confirmed with fresh seeds, the report
gives the front and draws it."""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from helpers import DECKS, stamp, vibrofeed
from vibrofeed.postproc import Transport
from vibrofeed.postproc.feedrate import MIN_EXITS, FeedRate
from vibrofeed.results.reader import Result
from vibrofeed.sweep import summary as S

FAILING = 'if "(${phase} > 60) || (${phase} < -60)" then "fix broken all no_such_style"'
STUDY = """deck = "decks/single_part.liggghts"
seed = 7

[fixed]
freq = 50
amp_t = 1e-4
amp_n = 1.5e-4
t_end = 0.1
output_dt = 1e-3

[variables]
phase = { low = -90, high = 90 }

[constraints]
min_model_speed = 1e-3

[objective]
maximize = "mean_velocity"

[budget]
runs = RUNS
seeds = 2
screen = 16
confirm = 1
replicates = 2

[robustness]
mu = [0.4]
"""


def study(tmp_path: Path, runs: int = 5) -> Path:
    decks = tmp_path / "decks"
    if not decks.exists():
        shutil.copytree(DECKS, decks)
        deck = decks / "single_part.liggghts"
        text = deck.read_text()
        at = text.index("\ntimestep")
        deck.write_text(text[:at] + "\n" + FAILING + text[at:])
    path = tmp_path / "study.toml"
    path.write_text(STUDY.replace("RUNS", str(runs)))
    return path


def rows_true(out: Path) -> list[dict]:
    """Every row is true of its run: a done row's objective is the Transport analysis of its
    file (to float rounding), a failed one carries LIGGGHTS' error."""
    rows, _ = S.read(out, stem="study")
    for row in rows:
        if row["status"] == S.DONE:
            with Result(out / row["file"]) as r:
                assert r.run_id == row["run_id"]
                v = float(Transport(r).run().results.mean_velocity)
            assert row["objective"] == pytest.approx(v, rel=1e-12, abs=1e-15)
            assert abs(row["phase"]) <= 60
        else:
            assert "no_such_style" in row["error"] or "Invalid fix style" in row["error"]
            assert abs(row["phase"]) > 60
    return rows


def test_a_study_screens_searches_confirms_and_goes_on_past_failures(tmp_path):
    spec, out = study(tmp_path), tmp_path / "out"
    proc = vibrofeed("optimize", spec, "-o", out)
    assert proc.returncode == 0, proc.stderr
    rows = rows_true(out)
    stages = [r["stage"] for r in rows]
    assert stages.count("search") == 5 and stages.count("confirm") == 2 and stages.count("robust") == 1
    search = [r for r in rows if r["stage"] == "search"]
    assert any(r["status"] == S.FAILED for r in search)  # beyond 60 deg: LIGGGHTS refuses it
    doc = json.loads((out / "study.json").read_text())
    assert doc["screen"]["screened"] == 16 and 0 < doc["screen"]["feasible"] <= 16
    # the confirmed best is the best searched setting's mean over two fresh seeds
    best = doc["confirmed"][0]
    done = [r for r in search if r["status"] == S.DONE]
    top = max(done, key=lambda r: r["objective"])
    assert best["setting"]["phase"] == pytest.approx(top["phase"], abs=1e-12)
    confirm = [r for r in rows if r["stage"] == "confirm"]
    assert {r["seed"] for r in confirm} & {r["seed"] for r in search} == set()  # fresh seeds
    mean = sum(r["objective"] for r in confirm) / 2
    assert best["mean_velocity"][0] == pytest.approx(mean, rel=1e-12)
    # robustness: the best at mu = 0.4, its spread with the confirmed value
    robust = [r for r in rows if r["stage"] == "robust"]
    assert robust[0]["mu"] == 0.4 and doc["robustness"]["table"][0]["value"] == 0.4
    assert "best design: phase=" in proc.stdout and "robustness:" in proc.stdout
    # the report reads the folder and draws
    rep = vibrofeed("optimize-report", out, "--json", "--plot", tmp_path / "plots", check=True)
    got = json.loads(rep.stdout)
    assert got["runs"] == 8 and got["confirmed"][0]["setting"]["phase"] == best["setting"]["phase"]
    assert (tmp_path / "plots" / "convergence.png").is_file()
    # the same folder: refused without --resume; a changed study file refused even with it
    again = vibrofeed("optimize", spec, "-o", out)
    assert again.returncode == 2 and "--resume continues it" in again.stderr
    spec.write_text(spec.read_text().replace("seed = 7", "seed = 8"))
    changed = vibrofeed("optimize", spec, "-o", out, "--resume")
    assert changed.returncode == 2 and "holds another study" in changed.stderr and "seed" in changed.stderr


def _search_rows(out: Path) -> int:
    try:
        return sum(r["stage"] == "search" for r in S.read(out, stem="study")[0])
    except (OSError, KeyError, ValueError):
        return 0


def test_sigkill_then_resume_finishes_without_running_a_finished_run_again(tmp_path):
    spec, out = study(tmp_path, runs=6), tmp_path / "out"
    seen: dict[str, tuple] = {}
    killed = 0
    for attempt, rows_needed in enumerate((2, 4, None)):
        args = [sys.executable, "-m", "vibrofeed.cli", "optimize", str(spec), "-o", str(out), "-q"]
        proc = subprocess.Popen(args + (["--resume"] if attempt else []), stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE)
        if rows_needed is None:
            stdout, stderr = proc.communicate(timeout=600)
            assert proc.returncode == 0, stderr.decode()
            break
        end = time.monotonic() + 300
        while _search_rows(out) < rows_needed and proc.poll() is None and time.monotonic() < end:
            time.sleep(0.05)
        time.sleep(0.7)  # somewhere in the next run
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait()
            killed += 1
            time.sleep(1.0)  # its worker gets SIGTERM as its parent dies
        for row in S.read(out, stem="study")[0]:
            if row["status"] == S.DONE:
                assert seen.setdefault(row["file"], stamp(out / row["file"])) == stamp(out / row["file"])
    assert killed == 2
    rows = rows_true(out)
    assert sum(r["stage"] == "search" for r in rows) == 6
    for row in rows:  # a result first seen is never made again
        if row["status"] == S.DONE and row["file"] in seen:
            assert seen[row["file"]] == stamp(out / row["file"])
    assert not list((out / "runs").glob(".vibrofeed-*")) and not list((out / "runs").glob("*.part"))


def test_retry_failed_runs_the_failed_runs_again_and_keeps_the_others(tmp_path):
    """A study whose runs failed for a cause since mended (here the deck's failing line removed)
    runs them again with --retry-failed: their settings are asked again first, the finished
    runs are kept as they are (their files untouched), and the budget is met by done runs."""
    spec, out = study(tmp_path, runs=3), tmp_path / "out"
    first = vibrofeed("optimize", spec, "-o", out, "-q")
    assert first.returncode == 0, first.stderr
    before = [r for r in S.read(out, stem="study")[0] if r["stage"] == "search"]
    failed = [r["phase"] for r in before if r["status"] == S.FAILED]
    kept = {r["file"]: stamp(out / r["file"]) for r in before if r["status"] == S.DONE}
    assert failed and kept  # the seeded run beyond 60 deg failed, another did not
    deck = tmp_path / "decks" / "single_part.liggghts"
    deck.write_text(deck.read_text().replace(FAILING + "\n", ""))
    again = vibrofeed("optimize", spec, "-o", out, "--retry-failed")
    assert again.returncode == 0, again.stderr
    assert f"retry: {len(failed)} failed run(s) again" in again.stderr
    rows = S.read(out, stem="study")[0]
    search = [r for r in rows if r["stage"] == "search"]
    assert len(search) == 3 and all(r["status"] == S.DONE for r in rows)
    assert sorted(failed) == sorted(r["phase"] for r in search if r["file"] not in kept)
    for file, mark in kept.items():  # a finished run is not run again
        assert stamp(out / file) == mark
    for row in search:  # and each row is its file's analysis
        with Result(out / row["file"]) as r:
            assert r.run_id == row["run_id"]
            assert row["objective"] == pytest.approx(float(Transport(r).run().results.mean_velocity),
                                                     rel=1e-12, abs=1e-15)


def test_under_mpirun_two_groups_share_the_runs(tmp_path):
    mpirun = shutil.which("mpirun")
    assert mpirun, "mpirun is part of the project's setup (bootstrap.sh)"
    spec, out = study(tmp_path, runs=4), tmp_path / "out"
    cmd = [mpirun, "-np", "2", "--oversubscribe"] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
    env = {k: v for k, v in os.environ.items() if k != "VIBROFEED_DEBUG"}
    args = [sys.executable, "-m", "vibrofeed.cli", "optimize", str(spec), "-o", str(out)]
    proc = subprocess.run(cmd + args, capture_output=True, text=True, timeout=600, env=env)
    assert proc.returncode == 0, proc.stderr
    rows = rows_true(out)
    assert sum(r["stage"] == "search" for r in rows) == 4 and "best design" in proc.stdout


# The bed reaches the edge (exits from the start: no empty stretch for the steady window to
# pick) and the drives are fast (the model's speed 25-45 mm/s): the window holds ten exits or
# more, which the feed rate needs to be measured (slower ones feed too few in 0.1 s).
BULK = """deck = "bulk_feeder"
seed = 11

[fixed]
n_parts = 80
track_length = 0.006
fill_from = 0.2
fill_to = 1.0
youngs = 2e7
t_settle = 0.01
t_end = 0.1
output_dt = 0.005

[variables]
amp_t = { low = 6.5e-5, high = 8.5e-5 }
phase = { low = -20, high = 0 }

[objective]
maximize = ["parts_per_s", "cv_interarrival"]

[budget]
runs = 4
seeds = 2
screen = 16
confirm = 2
replicates = 2
"""
TWO = ("objective", "objective_err", "objective_2", "objective_2_err")


def _value(text: str):
    return None if text == "" else float(text)


def _outlet_figures(path: Path) -> dict:
    """A bulk result's objectives: parts/s and the cv of the inter-arrival times, counted here
    from the outlet's event times in the window the feed-rate analysis finds, and the rate's
    batch-means error; None where nothing is measured (the rate: the analysis gives a reason;
    the cv: fewer than MIN_EXITS arrivals in the window)."""
    with Result(path) as r:
        fr = FeedRate(r).run().results
        t_a, t_b = fr.steady_from, fr.steady_to
        times = np.sort(np.asarray(r.outlet["time"], dtype=float))
    inside = times[(times >= t_a) & (times < t_b)]
    dt = np.diff(inside)
    err = float(fr.parts_per_s_err)
    return {"objective": None if fr.reason else len(inside) / (t_b - t_a),
            "objective_err": None if fr.reason or not math.isfinite(err) else err,
            "objective_2": None if len(inside) < MIN_EXITS else float(np.std(dt, ddof=1) / np.mean(dt)),
            "objective_2_err": None}  # a cv has no error of its own


def _dominates(q: dict, p: dict) -> bool:
    """More parts/s and a lower cv (at least as good on both, not the same point)."""
    a, b = (q["objective"], q["objective_2"]), (p["objective"], p["objective_2"])
    return a != b and a[0] >= b[0] and a[1] <= b[1]


def test_two_objectives_give_a_pareto_front_confirmed_with_fresh_seeds(tmp_path):
    spec, out = tmp_path / "bulk.toml", tmp_path / "out"
    spec.write_text(BULK)
    proc = vibrofeed("optimize", spec, "-o", out)
    assert proc.returncode == 0, proc.stderr
    with open(out / "study.csv", newline="") as f:
        table = list(csv.DictReader(f))
    assert set(TWO) <= set(table[0])
    rows = [{**r, "job": int(r["job"]), "seed": int(r["seed"]), **{k: _value(r[k]) for k in TWO},
             "amp_t": float(r["amp_t"]), "phase": float(r["phase"])} for r in table]
    h5 = {r["job"]: r for r in S.read(out, stem="study")[0]}  # study.h5 holds the same rows
    assert sorted(h5) == [r["job"] for r in rows]
    for row in rows:
        assert all(h5[row["job"]][k] == row[k] for k in TWO)
        if row["status"] != S.DONE:
            assert all(row[k] is None for k in TWO)
            continue
        # each run's two objectives are what its outlet events give
        for key, want in _outlet_figures(out / row["file"]).items():
            assert (row[key] is None) == (want is None), (row["job"], key, row[key], want)
            if want is not None:  # parts/s ~ 500, cv ~ 1
                assert np.isclose(row[key], want, rtol=1e-12, atol=1e-12), (row["job"], key, row[key], want)
    search = [r for r in rows if r["stage"] == "search"]
    assert len(search) == 4

    # the front: the runs that measured both, none dominated by another, best first by the rate
    # one standard error towards worse (the order confirmation takes them in)
    doc = json.loads((out / "study.json").read_text())
    counted = [r for r in search if r["objective"] is not None and r["objective_2"] is not None]
    front = [p for p in counted if not any(_dominates(q, p) for q in counted)]
    front.sort(key=lambda r: r["objective"] - (r["objective_err"] or 0.0), reverse=True)  # no error: 0
    assert front, f"no search run measured both objectives: {proc.stderr}"
    assert [f["job"] for f in doc["front"]] == [r["job"] for r in front]
    for f, r in zip(doc["front"], front):
        assert f["seed"] == r["seed"] and f["parts_per_s"] == [r["objective"], r["objective_err"]]
        assert f["cv_interarrival"] == [r["objective_2"], None]
        assert f["setting"] == {"amp_t": r["amp_t"], "phase": r["phase"]}
    best = doc["best"]
    assert best == [{"amp_t": r["amp_t"], "phase": r["phase"]} for r in front[:2]]  # confirm = 2

    # confirmation: two runs of each of those with fresh seeds; a confirmed value is the mean of
    # those runs alone (the ones that measured it), best first by the rate's mean one error
    # towards worse (the error: the larger of the scatter's and the runs' own)
    confirm = [r for r in rows if r["stage"] == "confirm"]
    assert len(confirm) == 2 * len(best) and all(r["status"] == S.DONE for r in confirm)
    seeds = [r["seed"] for r in confirm]
    assert len(set(seeds)) == len(seeds) and not set(seeds) & {r["seed"] for r in search}
    ranked = []
    for i, setting in enumerate(best):
        reps = [r for r in confirm if 10_000 + 100 * i <= r["job"] < 10_000 + 100 * (i + 1)]
        assert len(reps) == 2 and all({"amp_t": r["amp_t"], "phase": r["phase"]} == setting for r in reps)
        entries = [c for c in doc["confirmed"] if c["setting"] == setting]
        rated = [r for r in reps if r["objective"] is not None]
        if not rated:  # its fresh runs measured no rate: not a confirmed design
            assert not entries
            continue
        (entry,) = entries
        assert entry["runs"] == 2
        for key, metric in (("objective", "parts_per_s"), ("objective_2", "cv_interarrival")):
            values = [r[key] for r in reps if r[key] is not None]
            assert entry[f"{metric}_measured"] == len(values)
            if values:  # parts/s ~ 500, cv ~ 1
                assert np.isclose(entry[metric][0], sum(values) / len(values), rtol=1e-12, atol=1e-12)
        rates, errs = [r["objective"] for r in rated], [r["objective_err"] for r in rated]
        known = [abs(rates[0] - rates[1]) / 2] if len(rates) == 2 else []  # sd of two / sqrt(2)
        if None not in errs:
            known.append(math.sqrt(sum(e * e for e in errs)) / len(errs))
        error = max(known) if known else None
        if error is None:
            assert entry["parts_per_s"][1] is None
        else:  # parts/s
            assert np.isclose(entry["parts_per_s"][1], error, rtol=1e-9, atol=1e-9)
        ranked.append((sum(rates) / len(rates) - (error or 0.0), setting))
    ranked.sort(key=lambda t: t[0], reverse=True)
    assert ranked and [c["setting"] for c in doc["confirmed"]] == [s for _, s in ranked]
    assert "best design: amp_t=" in proc.stdout and f"Pareto front of the search: {len(front)}" in proc.stdout

    # the report gives the front and draws it
    rep = vibrofeed("optimize-report", out, "--json", "--plot", out / "report", check=True)
    got = json.loads(rep.stdout)
    assert [f["job"] for f in got["front"]] == [r["job"] for r in front]
    assert [f["setting"] for f in got["front"]] == [f["setting"] for f in doc["front"]]
    png = out / "report" / "pareto.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 1000
