"""Sweep bookkeeping and dispatch: what rank 0 spends per finished job, and the jobs/s
the dispatcher sustains with instant jobs (no LIGGGHTS).

    .venv/bin/python benchmarks/bench_dispatch.py [--jobs 1000 10000] [--workers 1 2 8]
        [--ranks 4 8 16 32] [--before-jobs 1000]

Every row is a bulk feeder's summary row (the sweep's columns, two parameters, the
feed-rate, singulation and model metrics: 39 columns). Three measurements, each in a
fresh folder under the system's temporary folder (the same disk as the work tree here):

1. Bookkeeping per finished job. Before: the whole summary rewritten
   (``summary.write`` of n rows: what the sweep did after every job; the median of
   3). After: ``summary.Ledger.add`` of n rows one after another, compactions
   included, total / n (and the slowest single add, a compaction).
2. Local: ``vibrofeed.engine.batch.run_local`` with ``-j`` workers, a job function
   that returns its row at once, the sweep's real ``Recorder``. ``--before-jobs``
   also runs that many jobs with the old recorder (a rewrite per job), for -j 2
   and under mpirun with the first of ``--ranks``.
3. MPI: ``mpirun --oversubscribe -np N`` of this script: rank 0 runs
   ``batch.dispatch`` with the real ``Recorder``, the others ``batch.serve``
   (``ranks_per_run`` = 1). The figure is rank 0's dispatch loop (after a barrier:
   every rank started), jobs / its wall time. Rank 0 runs jobs itself too, as in a
   sweep: with instant jobs its bookkeeping bounds the rate.

Prints Markdown tables for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_foundation import machine  # noqa: E402

from vibrofeed.engine import batch  # noqa: E402
from vibrofeed.sweep import summary as S  # noqa: E402
from vibrofeed.sweep.execute import Recorder  # noqa: E402
from vibrofeed.sweep.metrics import FEEDRATE, MODEL, SINGULATION  # noqa: E402

PARAMETERS = ["amp_n", "phase"]
METRICS = list(FEEDRATE) + ["feedrate_reason"] + list(SINGULATION) + ["singulation_reason"] + list(MODEL)


def row(job: int) -> dict:
    """A done job's summary row, its figures drawn at random (fixed by the job)."""
    rng = random.Random(job)
    out = {"job": job, "replicate": job % 3, "seed": 5000 + job, "amp_n": 5e-5 * (1 + job % 7),
           "phase": 30.0 * (job % 4), "status": S.DONE, "error": "", "file": f"jobs/job-{job:04d}.h5",
           "run_id": f"{rng.getrandbits(256):064x}", "wall_s": rng.uniform(20, 40)}
    for name in METRICS:
        out[name] = None if name.endswith("_reason") else rng.uniform(0, 500)
    for name in ("n_events", "inserted", "exited", "on_track", "lost", "n_arrivals"):
        out[name] = rng.randrange(1000)
    return out


def meta(n: int) -> dict:
    return {"fingerprint": "0" * 64, "deck": "bulk_feeder", "n_jobs": n, "replicates": 3,
            "varied": json.dumps(PARAMETERS)}


def instant(job: int):
    """The job function: its (row, computed) at once, as run_job returns them."""
    return row(job), True


class OldRecorder:
    """The recorder before the journal: the whole summary rewritten after every job."""

    def __init__(self, folder, rows, parameters, meta_):
        self.folder, self.parameters, self.meta = folder, parameters, meta_
        self.rows = {r["job"]: r for r in rows}
        S.write(folder, rows, parameters, meta_)

    def add(self, job, row_, computed) -> None:
        self.rows[row_["job"]] = row_
        S.write(self.folder, list(self.rows.values()), self.parameters, self.meta)

    def close(self) -> None:
        pass


def fresh(tmp: Path, name: str) -> Path:
    folder = tmp / name
    folder.mkdir()
    return folder


# ----------------------------------------------------------------- 1. bookkeeping per job
def rewrite_cost(tmp: Path, n: int) -> float:
    """Seconds of one whole rewrite of n rows (the old cost of each finished job)."""
    rows = [row(k) for k in range(n)]
    folder = fresh(tmp, f"rewrite{n}")
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        S.write(folder, rows, PARAMETERS, meta(n))
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def ledger_cost(tmp: Path, n: int) -> tuple[float, float, float, int]:
    """(median s per add, mean s per add, slowest add s, compactions) of n adds to a new
    ledger: the median is a journal line, the mean includes the compactions."""
    rows = [row(k) for k in range(n)]
    ledger = S.Ledger(fresh(tmp, f"ledger{n}"), PARAMETERS, meta(n))
    times = []
    for r in rows:
        t0 = time.perf_counter()
        ledger.add(r)
        times.append(time.perf_counter() - t0)
    compactions = ledger.compactions - 1  # those of the adds: not the one a new ledger starts with
    ledger.close()
    return statistics.median(times), sum(times) / n, max(times), compactions


def flush_cost(tmp: Path) -> float:
    """Median seconds of appending one journal line and flushing it (fdatasync) on this disk."""
    line = S._line(row(0))
    fd = os.open(tmp / "flush.jsonl", os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    times = []
    for _ in range(200):
        t0 = time.perf_counter()
        os.write(fd, line)
        os.fdatasync(fd)
        times.append(time.perf_counter() - t0)
    os.close(fd)
    return statistics.median(times)


# ----------------------------------------------------------------- 2. local workers
def local(tmp: Path, n: int, workers: int, old: bool = False) -> float:
    """Jobs/s of run_local with ``workers`` and the (old or real) recorder."""
    folder = fresh(tmp, f"local{n}j{workers}{'old' if old else ''}")
    recorder = (OldRecorder if old else Recorder)(folder, [], PARAMETERS, meta(n))
    t0 = time.perf_counter()
    batch.run_local(range(n), workers, instant, finished=lambda job, answer: recorder.add(job, *answer))
    recorder.close()
    wall = time.perf_counter() - t0
    assert len(S.read(folder)[0]) == n
    return n / wall


# ----------------------------------------------------------------- 3. under mpirun
def child(n: int, out: Path, old: bool) -> None:
    """One rank of ``mpirun -np N``: rank 0 dispatches n instant jobs, the others serve."""
    comm = batch.world()
    comm.Barrier()  # every rank started: the figure is the dispatch, not Python's start-up
    if comm.Get_rank() != 0:
        batch.serve(comm, lambda setup: instant)
        return
    recorder = (OldRecorder if old else Recorder)(out, [], PARAMETERS, meta(n))
    t0 = time.perf_counter()
    batch.dispatch(comm, range(n), {"ranks": 1}, instant,
                   finished=lambda job, answer: recorder.add(job, *answer))
    recorder.close()
    wall = time.perf_counter() - t0
    assert len(S.read(out)[0]) == n
    (out / "wall.json").write_text(json.dumps({"wall": wall}))


def under_mpirun(tmp: Path, n: int, ranks: int, old: bool = False) -> tuple[float, float]:
    """(jobs/s of rank 0's dispatch loop, whole mpirun wall s)."""
    folder = fresh(tmp, f"mpi{n}np{ranks}{'old' if old else ''}")
    env = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
    args = ["mpirun", "--oversubscribe", "-np", str(ranks), sys.executable, __file__, "--child",
            "--jobs", str(n), "--out", str(folder)] + (["--old"] if old else [])
    t0 = time.perf_counter()
    done = subprocess.run(args, capture_output=True, text=True, env=env)
    total = time.perf_counter() - t0
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} failed:\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    return n / json.loads((folder / "wall.json").read_text())["wall"], total


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, nargs="+", default=[1000, 10000])
    ap.add_argument("--workers", type=int, nargs="*", default=[1, 2, 8], help="none: no local runs")
    ap.add_argument("--ranks", type=int, nargs="*", default=[4, 8, 16, 32], help="none: no mpirun")
    ap.add_argument("--before-jobs", type=int, default=1000,
                    help="jobs run with the old rewrite-per-job recorder (locally with -j 2, and "
                         "under the first --ranks); 0: none")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--out", type=Path, help=argparse.SUPPRESS)
    ap.add_argument("--old", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(a.jobs[0], a.out, a.old)
        return
    say = lambda text: print(text, file=sys.stderr, flush=True)  # noqa: E731
    load = os.getloadavg()[0]  # the machine may be shared: the figures carry its load
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        print(f"machine: {machine()}; rows of {len(row(0))} columns "
              f"({len(S._line(row(0)))} bytes as a journal line); one line appended and flushed "
              f"(fdatasync) on this disk: {flush_cost(tmp) * 1e3:.2f} ms (median of 200)")
        print("\n| rows | before: whole rewrite per job [ms] | after: Ledger.add, median [ms] "
              "| after: mean, compactions included [ms] | after: slowest add [ms] | compactions |")
        print("|---|---|---|---|---|---|")
        for n in a.jobs:
            before = rewrite_cost(tmp, n)
            median, mean, slowest, compactions = ledger_cost(tmp, n)
            print(f"| {n} | {before * 1e3:.1f} | {median * 1e3:.2f} | {mean * 1e3:.2f} "
                  f"| {slowest * 1e3:.0f} | {compactions} |")
            say(f"  bookkeeping {n}: done")
        if a.workers:
            print("\n| jobs | local -j | jobs/s |")
            print("|---|---|---|")
        if a.workers and a.before_jobs:
            rate = local(tmp, a.before_jobs, 2, old=True)
            print(f"| {a.before_jobs} | 2 (before: rewrite per job) | {rate:.0f} |")
        for n in a.jobs:
            for w in a.workers:
                print(f"| {n} | {w} | {local(tmp, n, w):.0f} |")
                say(f"  local {n} -j {w}: done")
        if a.ranks:
            print("\n| jobs | mpirun -np | jobs/s (dispatch loop) | mpirun wall [s] |")
            print("|---|---|---|---|")
        if a.ranks and a.before_jobs:
            rate, total = under_mpirun(tmp, a.before_jobs, a.ranks[0], old=True)
            print(f"| {a.before_jobs} | {a.ranks[0]} (before: rewrite per job) | {rate:.0f} | {total:.1f} |")
        for n in a.jobs:
            for ranks in a.ranks:
                rate, total = under_mpirun(tmp, n, ranks)
                print(f"| {n} | {ranks} | {rate:.0f} | {total:.1f} |")
                say(f"  mpirun {n} -np {ranks}: done")
        print(f"\nload average (1 min) at the start {load:.1f}, at the end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
