"""`vibrofeed sweep` with LIGGGHTS: rows true of their jobs, a failing job, resume, SIGKILL, mpirun.

Tiny runs: 30 spheres near the outlet of a 6 mm track for 0.04 s (bulk feeder, ~2 s
each), or one part for 0.1 s (single part, ~1.5 s each). One job fails inside
LIGGGHTS: a copy of the bulk deck issues an unknown fix style when restitution_pp
< 0.2, a value the parameter checks accept."""

from __future__ import annotations

import csv
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pytest

from helpers import DECKS, stamp, vibrofeed
from vibrofeed.postproc import Transport
from vibrofeed.postproc.feedrate import FeedRate
from vibrofeed.results.reader import Result
from vibrofeed.sweep import summary as S
from vibrofeed.sweep.plan import plan
from vibrofeed.sweep.spec import load

BULK_FIXED = """[fixed]
n_parts = 30
track_length = 0.006
fill_from = 0.5
fill_to = 0.95
t_settle = 0.01
t_end = 0.1
output_dt = 0.005
"""
FAILING = 'if "${restitution_pp} < 0.2" then "fix broken all no_such_style"'


def failing_deck(tmp_path: Path) -> Path:
    decks = tmp_path / "decks"
    shutil.copytree(DECKS, decks)
    deck = decks / "bulk_feeder.liggghts"
    text = deck.read_text()
    at = text.index("\ntimestep")
    deck.write_text(text[:at] + "\n" + FAILING + text[at:])
    return deck


def mtimes(folder: Path) -> dict:
    return {p.name: p.stat().st_mtime_ns for p in (folder / "jobs").glob("*.h5")}


def assert_rows_true(folder: Path, spec_path: Path) -> list[dict]:
    """Every row of the summary is true of its job: a done row's file is the job's
    complete result and its metrics are what the analyses give on it."""
    rows, meta = S.read(folder)
    jobs = {j.index: j for j in plan(load(spec_path))}
    with open(folder / S.CSV_NAME, newline="") as f:  # a snapshot: maybe older than the journal
        table = list(csv.DictReader(f))
    by_job = {r["job"]: r for r in rows}
    assert {int(r["job"]) for r in table} <= set(by_job)
    for line in table:
        job = jobs[int(line["job"])]
        assert line["run_id"] == job.run_id and line["status"] in (S.DONE, S.FAILED)
        if line["status"] == S.DONE:
            assert line["file"] == job.file and line["error"] == ""
            with Result(folder / job.file) as r:
                assert r.run_id == job.run_id
        if job.index in by_job:
            assert line["status"] == by_job[job.index]["status"]
    for row in rows:
        job = jobs[row["job"]]
        assert row["run_id"] == job.run_id and row["seed"] == job.seed
        if row["status"] == S.DONE:
            assert row["error"] is None and row["file"] == job.file
            with Result(folder / row["file"]) as r:  # refuses an incomplete file
                assert r.run_id == job.run_id
                if r.outlet_plane is not None:
                    fr = FeedRate(r).run().results
                    if fr.reason:  # measured nothing: the row says so, it holds no number
                        assert row["parts_per_s"] is None and row["feedrate_reason"] == fr.reason
                    else:
                        assert row["parts_per_s"] == pytest.approx(fr.parts_per_s, rel=1e-12, abs=1e-12)
                    assert row["n_events"] == fr.n_events
                    assert row["lost"] == 0 and row["exited"] + row["on_track"] == row["inserted"]
                else:
                    v = Transport(r).run().results.mean_velocity
                    assert row["mean_velocity"] == pytest.approx(float(v), rel=1e-12)
        else:
            assert row["status"] == S.FAILED and row["error"]
    return rows


def test_a_sweep_records_done_and_failed_jobs_and_a_rerun_skips_what_is_finished(tmp_path):
    failing_deck(tmp_path)
    spec = tmp_path / "s.toml"
    spec.write_text('deck = "decks/bulk_feeder.liggghts"\n' + BULK_FIXED
                    + "[[point]]\namp_n = 5e-5\n[[point]]\namp_n = 7e-5\n[[point]]\nrestitution_pp = 0.1\n")
    out = tmp_path / "out"
    proc = vibrofeed("sweep", spec, "-o", out, "-j", "2")
    assert proc.returncode == 1, proc.stderr
    assert "1 of 3 jobs failed" in proc.stderr and "--retry-failed" in proc.stderr
    rows = assert_rows_true(out, spec)
    assert [r["status"] for r in rows] == [S.DONE, S.DONE, S.FAILED]
    assert [r["amp_n"] for r in rows] == [5e-5, 7e-5, 5e-5] and rows[2]["restitution_pp"] == 0.1
    failed = rows[2]
    assert "Invalid fix style" in failed["error"] and "bulk_feeder.liggghts:" in failed["error"]
    assert failed["file"] is None and not (out / "jobs" / "job-0002.h5").exists()
    assert all((r["parts_per_s"] is not None or r["feedrate_reason"]) and r["wall_s"] > 0 for r in rows[:2])
    done = mtimes(out)
    assert sorted(done) == ["job-0000.h5", "job-0001.h5"]

    # The same command again: nothing to run (failed jobs are kept), nothing rewritten.
    proc = vibrofeed("sweep", spec, "-o", out, "--dry-run")
    assert proc.returncode == 0 and "2 done, 1 failed kept, 0 to run" in proc.stdout
    assert [line.split()[-1] for line in proc.stdout.splitlines()[2:]] == ["done", "done", "failed"]
    proc = vibrofeed("sweep", spec, "-o", out)
    assert proc.returncode == 1 and "0 to run" in proc.stderr
    assert mtimes(out) == done

    # --retry-failed runs the failed job again (and it fails again); the others stay.
    proc = vibrofeed("sweep", spec, "-o", out, "--retry-failed")
    assert proc.returncode == 1 and "1 to run" in proc.stderr and "job 2" in proc.stderr
    assert "FAILED: LIGGGHTS error: Invalid fix style" in proc.stderr
    assert mtimes(out) == done

    # A result that is gone or does not check is run again; its row disappears until it is done.
    (out / "jobs" / "job-0000.h5").unlink()
    (out / "jobs" / "job-0001.h5").write_bytes(b"garbage")
    proc = vibrofeed("sweep", spec, "-o", out)
    assert proc.returncode == 1 and "0 done, 1 failed kept, 2 to run" in proc.stderr
    rows = assert_rows_true(out, spec)
    assert [r["status"] for r in rows] == [S.DONE, S.DONE, S.FAILED]

    # Another design into the same folder is refused before anything runs.
    spec.write_text(spec.read_text().replace("amp_n = 7e-5", "amp_n = 8e-5"))
    proc = vibrofeed("sweep", spec, "-o", out)
    assert proc.returncode == 2 and "holds another sweep" in proc.stderr and "point" in proc.stderr

    # The report: every setting, the failure, the best among the done ones, the plots.
    import json

    proc = vibrofeed("sweep-report", out, "--json", "--plot", tmp_path / "plots", check=True)
    rep = json.loads(proc.stdout)
    assert len(rep["settings"]) == 3 and [f["job"] for f in rep["failed"]] == [2]
    assert rep["best"]["jobs"] in ([0], [1]) and rep["merit"] == "parts_per_s"
    assert rep["figures"] and all(Path(p).is_file() for p in rep["figures"])


def _children(pid: int) -> list[int]:
    out = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            out += [int(c) for c in (task / "children").read_text().split()]
        except OSError:
            pass
    return out


def _gone(pids, timeout=15.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end and any(Path(f"/proc/{p}").exists() for p in pids):
        time.sleep(0.05)


def _rows_now(folder: Path) -> int:
    try:
        return len(S.read(folder)[0])
    except (OSError, KeyError):
        return 0


def test_sigkill_at_any_moment_leaves_a_true_summary_and_nothing_is_run_twice(tmp_path):
    shutil.copytree(DECKS, tmp_path / "decks")  # run ids hash the deck: keep it still meanwhile
    spec = tmp_path / "k.toml"
    spec.write_text('deck = "decks/single_part.liggghts"\n[fixed]\nt_end = 0.1\noutput_dt = 1e-3\n'
                    "[grid]\nphase = [0, 30, 60, 90, 120]\n")
    out = tmp_path / "out"
    rng = random.Random(7)
    first_seen: dict[str, tuple] = {}
    # Kill early (start-up or the first job), then each time once the summary holds
    # 1, 2, 3 rows, a random fraction of a job later (wherever that lands: in a run,
    # its analysis, a summary write); then let it finish.
    kills = [(0, rng.uniform(0.2, 1.5))] + [(n, rng.uniform(0.0, 1.5)) for n in (1, 2, 3)] + [None]
    killed_midway = 0
    for kill in kills:
        proc = subprocess.Popen([sys.executable, "-m", "vibrofeed.cli", "sweep", str(spec), "-o", str(out),
                                 "-q"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        if kill is None:
            proc.wait(timeout=300)
        else:
            rows_needed, extra = kill
            end = time.monotonic() + 120
            while _rows_now(out) < rows_needed and proc.poll() is None and time.monotonic() < end:
                time.sleep(0.05)
            time.sleep(extra)
            if proc.poll() is None:
                workers = _children(proc.pid)
                os.kill(proc.pid, signal.SIGKILL)
                proc.wait()
                _gone(workers)  # they get SIGTERM as their parent dies
        if (out / S.H5_NAME).exists():
            rows = assert_rows_true(out, spec)
            killed_midway += proc.returncode == -signal.SIGKILL and 0 < len(rows) < 5
            for row in rows:  # a done job's result is the one first made: never run again
                if row["status"] == S.DONE:
                    now = stamp(out / row["file"])
                    assert first_seen.setdefault(row["file"], now) == now
    assert proc.returncode == 0, proc.stderr.read().decode()
    assert killed_midway >= 2  # the kills did land between the jobs' ends
    rows = assert_rows_true(out, spec)
    assert [r["status"] for r in rows] == [S.DONE] * 5 and [r["phase"] for r in rows] == [0, 30, 60, 90, 120]
    # what the kills left (half-written summaries, scratch folders, partial runs) is gone
    assert not list(out.glob(".*.tmp")) and not list((out / "jobs").glob(".vibrofeed-*"))
    assert not list((out / "jobs").glob("*.part"))


def test_under_mpirun_two_groups_share_the_jobs(tmp_path):
    mpirun = shutil.which("mpirun")
    assert mpirun, "mpirun is part of the project's setup (bootstrap.sh)"
    shutil.copytree(DECKS, tmp_path / "decks")
    spec = tmp_path / "m.toml"
    spec.write_text('deck = "decks/bulk_feeder.liggghts"\n' + BULK_FIXED + "[grid]\namp_n = [5e-5, 7e-5]\n")
    out = tmp_path / "out"
    cmd = [mpirun, "-np", "2", "--oversubscribe"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    env = {k: v for k, v in os.environ.items() if k != "VIBROFEED_DEBUG"}
    proc = subprocess.run(cmd + [sys.executable, "-m", "vibrofeed.cli", "sweep", str(spec), "-o", str(out)],
                          capture_output=True, text=True, timeout=300, env=env)
    assert proc.returncode == 0, proc.stderr
    assert "(2 MPI ranks, 1 rank per run)" in proc.stderr
    rows = assert_rows_true(out, spec)
    assert [r["status"] for r in rows] == [S.DONE, S.DONE]
    # dispatched at once to the two groups: each started before the other finished
    spans = []
    for row in rows:
        with h5py.File(out / row["file"], "r") as f:
            a = f["parameters/run"].attrs
            spans.append((str(a["started"]), str(a["finished"])))
    assert max(s for s, _ in spans) <= min(e for _, e in spans)
