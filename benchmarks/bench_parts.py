"""Benchmark of a part's shape: what a chip component (a box clump) costs against a sphere,
per part and per step, on the same track.

    .venv/bin/python benchmarks/bench_parts.py [--n-parts 60] [--t-end 0.1] [--repeats 3]

Each shape runs the bulk_feeder deck by hand (`vibrofeed prepare`, then `liggghts -in`, one
dump at the end: the engine alone), its track pre-filled with --n-parts parts settled before the
vibration, for --t-end seconds of vibration on one rank. The figure is the vibration run's
loop time (LIGGGHTS' `Loop time`) over its steps and parts, the median of --repeats runs
taken in turn (box, sphere, 1 x 0.5 mm chip, box, ...). Shapes:

* ``box``: 1.0 x 0.5 x 0.35 mm, clump_spacing 1 (36 spheres of 0.175 mm);
* ``box-fine``: the same box at the default clump_spacing 0.75 (84 spheres);
* ``sphere``: a 0.5 mm sphere;
* ``chip``: a 1.0 mm square die 0.35 mm thick (the project's chip clump).

All at youngs 2e7 Pa (the bulk feeder's validated stiffness floor), so that the time step
the deck derives is each shape's own (the smallest sphere's contact time); the figure per
part-step removes the step count, the per-second figure keeps it (what a designer waits for).
Prints a Markdown table for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_foundation import machine  # noqa: E402

SHAPES = {
    "box": ["shape=box", "part_size=1e-3", "part_width=5e-4", "part_thickness=3.5e-4", "clump_spacing=1"],
    "box-fine": ["shape=box", "part_size=1e-3", "part_width=5e-4", "part_thickness=3.5e-4"],
    "sphere": ["shape=0", "part_size=5e-4"],
    "chip": ["shape=1", "part_size=1e-3", "part_thickness=3.5e-4"],
}
COMMON = ["track_length=8e-3", "track_width=3e-3", "wall_height=2e-3", "youngs=2e7", "inlet_rate=0"]


def loop(text: str) -> tuple[float, int, int]:
    """(seconds, steps, atoms) of the last `Loop time` line of a LIGGGHTS output."""
    found = re.findall(r"Loop time of ([0-9.e+-]+) on \d+ procs for (\d+) steps with (\d+) atoms", text)
    return float(found[-1][0]), int(found[-1][1]), int(found[-1][2])


def run(tmp: Path, shape: str, n_parts: int, t_end: float) -> tuple[float, int, int]:
    params = [*COMMON, *SHAPES[shape], f"n_parts={n_parts}", f"t_end={t_end:g}", f"output_dt={t_end:g}"]
    args = [sys.executable, "-m", "vibrofeed.cli", "prepare", "bulk_feeder", "-o", str(tmp / shape)]
    for p in params:
        args += ["-p", p]
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{shape}: {done.stderr.strip()}")
    line = done.stdout.strip().splitlines()[-1]
    words = line.split() + ["-var", "dump_file", str(tmp / f"{shape}.dump"), "-log", "none", "-nocite"]
    out = subprocess.run(words, check=True, capture_output=True, text=True, cwd=tmp).stdout
    return loop(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-parts", type=int, default=60)
    ap.add_argument("--t-end", type=float, default=0.1)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--shapes", nargs="+", default=list(SHAPES), choices=list(SHAPES))
    args = ap.parse_args()
    figures: dict[str, list[tuple[float, int, int]]] = {s: [] for s in args.shapes}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.repeats):
            for shape in args.shapes:
                figures[shape].append(run(Path(tmp), shape, args.n_parts, args.t_end))
                print(f"{shape}: {figures[shape][-1]}", file=sys.stderr, flush=True)
    print(f"Machine: {machine()}; bulk_feeder pre-filled with {args.n_parts} parts, {args.t_end:g} s of "
          f"vibration, 1 rank, liggghts -in without a dump, median of {args.repeats}\n")
    print("| shape | spheres | steps | loop time | µs per part-step | part-steps per s | vs sphere |")
    print("|---|---|---|---|---|---|---|")
    per = {s: statistics.median(t / (n * args.n_parts) for t, n, _ in f) for s, f in figures.items()}
    for shape, f in figures.items():
        t = statistics.median(x[0] for x in f)
        _, steps, atoms = f[0]
        ref = per.get("sphere")
        against = f"{per[shape] / ref:.2f}x" if ref else "-"
        print(f"| {shape} | {atoms // args.n_parts} | {steps} | {t:.2f} s | {per[shape] * 1e6:.2f} | "
              f"{1 / per[shape]:.3g} | {against} |")


if __name__ == "__main__":
    main()
