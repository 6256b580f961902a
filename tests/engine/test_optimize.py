"""`vibrofeed optimize` with LIGGGHTS: a study of the single part's phase (one sphere, 0.1 s,
~1.5 s a run). A copy of the deck fails inside LIGGGHTS for |phase| > 60 deg (a value the
checks accept), so some evaluations fail and the study must go on; the screen's seeds are
spread over the phase, so the second one lies beyond 60 deg. Every row of study.csv is true
of its run (its objective is what the analysis gives on its file), a killed study resumes
without running a finished run again, and under mpirun two groups share the runs."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from helpers import DECKS, stamp, vibrofeed
from vibrofeed.postproc import Transport
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
