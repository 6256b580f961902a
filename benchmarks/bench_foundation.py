"""Benchmarks of the foundation: engine throughput, driver overhead, writer speed.

    .venv/bin/python benchmarks/bench_foundation.py [--quick]

Prints a Markdown table with the machine it ran on; BENCHMARKS.md records
its output. Also registered in CTest under the label `slow`.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DECK = ROOT / "decks" / "single_part.liggghts"


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def by_hand(tmp: Path, t_end: float) -> float:
    """Steps/s of `liggghts -in` on the deck (no vibrofeed, text dump every output_dt)."""
    out = subprocess.run(["liggghts", "-in", str(DECK), "-var", "deck_dir", str(DECK.parent),
                          "-var", "t_end", str(t_end), "-var", "dump_file", str(tmp / "d.dump"),
                          "-log", str(tmp / "log"), "-nocite"], capture_output=True, text=True,
                         check=True).stdout
    m = re.search(r"Loop time of ([0-9.e+-]+) on \d+ procs for (\d+) steps", out)
    return int(m[2]) / float(m[1])


def through_vibrofeed(tmp: Path, t_end: float, output_dt: float, ranks: int) -> tuple[float, float]:
    """(steps/s, wall s) of `vibrofeed run` including frame extraction and H5MD writing."""
    out = tmp / "r.h5"
    t0 = time.monotonic()
    subprocess.run([sys.executable, "-m", "vibrofeed.cli", "run", "single_part", "-q", "-o", str(out),
                    "-n", str(ranks), "-p", f"t_end={t_end}", "-p", f"output_dt={output_dt}"],
                   check=True, capture_output=True)
    wall = time.monotonic() - t0
    from vibrofeed.results.reader import Result

    with Result(out) as r:
        steps = r.step[-1]
    return steps / wall, wall


def writer_rate(tmp: Path, n_parts: int, frames: int) -> float:
    """Frames/s of ResultWriter for n_parts particles (flush after every frame)."""
    from vibrofeed.results.writer import ResultWriter

    rng = np.random.default_rng(1)
    parts = {"id": np.arange(1, n_parts + 1), "species": np.ones(n_parts, int),
             "radius": np.full(n_parts, 5e-4), "mass": np.full(n_parts, 1e-6),
             "position": rng.random((n_parts, 3)), "velocity": rng.random((n_parts, 3)),
             "angular_velocity": rng.random((n_parts, 3)), "force": rng.random((n_parts, 3))}
    w = ResultWriter(tmp / f"w{n_parts}.h5", deck_name="b", deck_path="b", deck_text="b",
                     variables={}, derived={}, engine_version="LIGGGHTS", seed=1,
                     capacity_hint=n_parts)
    t0 = time.perf_counter()
    for k in range(frames):
        w.write_frame(k, k * 1e-4, parts, [0, 0, 0], [0, 0, 0])
    rate = frames / (time.perf_counter() - t0)
    w.finish()
    return rate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="shorter runs (for CI smoke)")
    args = ap.parse_args()
    t_end = 0.1 if args.quick else 1.0
    print(f"Machine: {machine()}\n")
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        print("| measurement | setting | result |\n|---|---|---|")
        print(f"| `liggghts -in` by hand (text dump every 1e-4 s) | single_part, t_end={t_end} s, 1 rank "
              f"| {by_hand(tmp, t_end) / 1e3:.0f}k steps/s |")
        for output_dt in (1e-3, 1e-4, 2e-5):
            for ranks in (1, 2):
                rate, wall = through_vibrofeed(tmp, t_end, output_dt, ranks)
                print(f"| `vibrofeed run` | single_part, t_end={t_end} s, output_dt={output_dt:g} s, "
                      f"{ranks} rank{'s' * (ranks > 1)} | {rate / 1e3:.0f}k steps/s ({wall:.1f} s) |")
        for n in (1, 1000, 10000):
            frames = 200 if n > 1000 else 1000
            print(f"| ResultWriter (batched, flushed within 0.25 s) | {n} particles, {frames} frames "
                  f"| {writer_rate(tmp, n, frames):.0f} frames/s |")


if __name__ == "__main__":
    main()
