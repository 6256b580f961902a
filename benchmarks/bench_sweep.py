"""Sweep throughput: jobs/hour of one fixed sweep on 1 and on N MPI ranks.

    .venv/bin/python benchmarks/bench_sweep.py [--ranks 1 2] [--jobs 8] [--t-end 0.3]

Writes a sweep of ``--jobs`` equal bulk-feeder jobs (the example sweep's
feeder: 40 spheres of 300 um on a 10 mm track two parts wide, Gamma_n = 2;
the jobs differ only in their seed), then runs it as users do on a cluster,
``mpirun -np N .venv/bin/vibrofeed sweep SWEEP.toml -o DIR`` with
``ranks_per_run = 1``, once for each N of ``--ranks``, each into a fresh
folder. The figure is the whole command's wall time (start-up, dispatch,
runs, analyses, summary writes): jobs/hour, and the parallel efficiency
(jobs/hour on N ranks) / (N x jobs/hour on 1 rank). Prints a Markdown table
for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_foundation import machine  # noqa: E402

VIBROFEED = ROOT / ".venv" / "bin" / "vibrofeed"

SWEEP = """\
deck = "bulk_feeder"
ranks_per_run = 1
replicates = {jobs}
description = "benchmark: {jobs} equal jobs (seeds)"

[fixed]
n_parts = 40
track_length = 0.01
track_width = 6e-4
fill_from = 0.2
fill_to = 0.95
amp_n = 5e-5
t_end = {t_end}
output_dt = 0.005
"""


def run_sweep(sweep: Path, out: Path, ranks: int) -> float:
    """Wall seconds of ``mpirun -np ranks vibrofeed sweep`` (every job must finish)."""
    env = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
    args = ["mpirun", "-np", str(ranks), "--oversubscribe", str(VIBROFEED), "sweep", str(sweep),
            "-o", str(out), "-q"]
    t0 = time.monotonic()
    done = subprocess.run(args, capture_output=True, text=True, env=env)
    wall = time.monotonic() - t0
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} failed:\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    with open(out / "summary.csv", newline="") as fh:
        status = [row["status"] for row in csv.DictReader(fh)]
    if status.count("done") != len(status):
        raise RuntimeError(f"{out}: not every job finished: {status}")
    return wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--jobs", type=int, default=8, help="jobs in the sweep (a multiple of every rank count)")
    ap.add_argument("--t-end", type=float, default=0.3, help="simulated time of each job [s]")
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as d:
        sweep = Path(d) / "bench.toml"
        sweep.write_text(SWEEP.format(jobs=a.jobs, t_end=a.t_end))
        for ranks in a.ranks:
            wall = run_sweep(sweep, Path(d) / f"np{ranks}", ranks)
            rows.append((ranks, wall, a.jobs / wall * 3600))
            print(f"  {ranks} rank(s): {wall:.1f} s", file=sys.stderr)
    print(f"machine: {machine()}; {a.jobs} jobs of t_end {a.t_end} s (40 spheres, ranks_per_run 1)")
    print("| ranks | wall [s] | jobs/hour | parallel efficiency |")
    print("|---|---|---|---|")
    base = {r: jph for r, _, jph in rows}.get(1)
    for ranks, wall, jph in rows:
        eff = f"{jph / (ranks * base):.2f}" if base else "-"
        print(f"| {ranks} | {wall:.1f} | {jph:.0f} | {eff} |")


if __name__ == "__main__":
    main()
