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


def by_hand(tmp: Path, t_end: float, output_dt: float | None = None) -> tuple[float, float]:
    """(steps/s of the run loop, wall s of the whole command) of `liggghts -in` on the deck
    (no vibrofeed; a text dump every output_dt, the deck's default 1e-4 s if None)."""
    extra = [] if output_dt is None else ["-var", "output_dt", repr(output_dt)]
    t0 = time.monotonic()
    out = subprocess.run(["liggghts", "-in", str(DECK), "-var", "deck_dir", str(DECK.parent),
                          "-var", "t_end", str(t_end), "-var", "dump_file", str(tmp / "d.dump"),
                          *extra, "-log", str(tmp / "log"), "-nocite"], capture_output=True, text=True,
                         check=True).stdout
    wall = time.monotonic() - t0
    m = re.search(r"Loop time of ([0-9.e+-]+) on \d+ procs for (\d+) steps", out)
    return int(m[2]) / float(m[1]), wall


def engine_path(tmp: Path, t_end: float, output_dt: float) -> float:
    """Wall s of one run through the isolated runner as validation and sweeps use it
    (``runner.run_deck``: worker process, H5MD frames; no command line, no summary)."""
    from vibrofeed.decks import Deck
    from vibrofeed.engine.runner import run_deck

    t0 = time.monotonic()
    run_deck(Deck.find("single_part"), {"t_end": t_end, "output_dt": output_dt}, tmp / "e.h5")
    return time.monotonic() - t0


def overhead(tmp: Path, t_end: float, output_dt: float, repeats: int) -> dict:
    """Medians of `liggghts -in` (by hand), the runner (engine path) and `vibrofeed run` (the
    command, with its summary line) on the same deck writing the same frames, whole runs,
    alternated; and the two ratios to by hand (medians of the per-repeat ratios)."""
    hand, engine, command = [], [], []
    for _ in range(repeats):
        hand.append(by_hand(tmp, t_end, output_dt)[1])
        engine.append(engine_path(tmp, t_end, output_dt))
        command.append(through_vibrofeed(tmp, t_end, output_dt, 1)[1])

    def median(xs):
        return sorted(xs)[len(xs) // 2]
    return {"hand": median(hand), "engine": median(engine), "command": median(command),
            "engine_ratio": median([e / h for e, h in zip(engine, hand)]),
            "command_ratio": median([c / h for c, h in zip(command, hand)])}


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
              f"| {by_hand(tmp, t_end)[0] / 1e3:.0f}k steps/s |")
        for t_run in (0.6, t_end):
            o = overhead(tmp, t_run, 1e-3, 1 if args.quick else 5)
            print(f"| driver overhead, engine path (`runner.run_deck`, as validation and sweeps run) / "
                  f"`liggghts -in`, same frames (every 1e-3 s) | single_part, t_end={t_run} s, 1 rank "
                  f"| {o['engine_ratio']:.3f} ({o['engine']:.2f} s / {o['hand']:.2f} s, medians) |")
            print(f"| driver overhead, the command `vibrofeed run` (and its summary line) / "
                  f"`liggghts -in` | single_part, t_end={t_run} s, 1 rank "
                  f"| {o['command_ratio']:.3f} ({o['command']:.2f} s / {o['hand']:.2f} s, medians) |")
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
