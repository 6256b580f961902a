"""Benchmark of the main job: the bulk feeder through vibrofeed vs LIGGGHTS by hand.

    .venv/bin/python benchmarks/bench_bulk.py [--deck bulk_feeder] [-p NAME=VALUE ...] [--ranks N]

Runs the deck (bulk_feeder, or bowl_feeder; its defaults, or the given parameters) twice
with the same frames: by hand (`vibrofeed prepare`, then `liggghts -in` writing a text
dump every output_dt) and through `vibrofeed run` (H5MD frames, bodies, outlet
events, mass balance); then times the feed-rate and singulation analyses of
the result. Prints a Markdown table for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_foundation import machine  # noqa: E402


def _loop(text: str) -> tuple[float, int]:
    """(seconds, steps) of the last `Loop time` line of a LIGGGHTS output (the vibration run)."""
    found = re.findall(r"Loop time of ([0-9.e+-]+) on \d+ procs for (\d+) steps", text)
    return float(found[-1][0]), int(found[-1][1])


def by_hand(tmp: Path, deck: str, params: list[str], ranks: int) -> tuple[float, float, int]:
    """(wall s, vibration-run s, steps) of liggghts -in on the prepared geometry."""
    mesh = tmp / "mesh"
    line = subprocess.run([sys.executable, "-m", "vibrofeed.cli", "prepare", deck,
                           "-o", str(mesh), *params], check=True, capture_output=True,
                          text=True).stdout.strip().splitlines()[-1]
    words = line.split() + ["-var", "dump_file", str(tmp / "d.dump"), "-log", str(tmp / "log"),
                            "-nocite"]
    if ranks > 1:
        words = ["mpirun", "-n", str(ranks), "--oversubscribe"] + words
    t0 = time.monotonic()
    out = subprocess.run(words, check=True, capture_output=True, text=True, cwd=tmp).stdout
    wall = time.monotonic() - t0
    seconds, steps = _loop(out)
    return wall, seconds, steps


def through_vibrofeed(tmp: Path, deck: str, params: list[str], ranks: int) -> tuple[float, Path]:
    out = tmp / f"{deck}.h5"
    args = [sys.executable, "-m", "vibrofeed.cli", "run", deck, "-q", "-o", str(out),
            "-n", str(ranks)]
    for p in params[1::2]:
        args += ["-p", p]
    t0 = time.monotonic()
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(args)} failed ({done.returncode}):\n{done.stderr[-3000:]}")
    return time.monotonic() - t0, out


def analyses(path: Path) -> float:
    from vibrofeed.errors import InputError
    from vibrofeed.postproc.feedrate import FeedRate
    from vibrofeed.postproc.singulation import Singulation
    from vibrofeed.results.reader import Result

    t0 = time.perf_counter()
    with Result(path) as r:
        fr = FeedRate(r).run().summary()
        try:
            Singulation(r, start=fr["steady_from"], end=fr["steady_to"]).run().summary()  # as the demo
        except InputError:  # a run too short to have a window: the feed rate's time alone
            pass
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--deck", default="bulk_feeder", help="bulk_feeder (default) or bowl_feeder")
    ap.add_argument("-p", "--param", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=3, help="runs of each; medians are reported")
    a = ap.parse_args()
    params = [w for p in a.param for w in ("-p", p)]
    hand, driven, ratios, t_an = [], [], [], []
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for k in range(a.repeats):  # alternated, so that a slow spell of the machine hits both
            (tmp / f"hand{k}").mkdir()
            hand.append(by_hand(tmp / f"hand{k}", a.deck, params, a.ranks))
            wall_vf, out = through_vibrofeed(tmp, a.deck, params, a.ranks)
            driven.append(wall_vf)
            ratios.append(wall_vf / hand[-1][0])
            t_an.append(analyses(out))
        from vibrofeed.results.reader import Result

        with Result(out) as r:
            parts = int(r.mass_balance["inserted"][-1])
            present = float(r.mass_balance["on_track"][:].mean())  # a fed line holds few at a time
            frames = r.n_frames
            sim = float(r.time[-1] - r.time[0])
    med = statistics.median
    wall_hand, loop_hand = med(h[0] for h in hand), med(h[1] for h in hand)
    steps = hand[0][2]
    print(f"machine: {machine()}; deck {a.deck}; ranks {a.ranks}; "
          f"parameters: {' '.join(a.param) or 'defaults'}; "
          f"medians of {a.repeats}")
    print("| measurement | result |\n|---|---|")
    print(f"| parts fed, simulated time, frames | {parts}, {sim:g} s, {frames} |")
    print(f"| `liggghts -in` by hand, whole run (settle + vibration, text dump) | {wall_hand:.1f} s |")
    print(f"| by hand, vibration run only | {loop_hand:.1f} s, {steps / loop_hand:.0f} steps/s, "
          f"{present * steps / loop_hand / 1e6:.3f} M particle-steps/s ({present:.1f} parts on the "
          "track on average) |")
    print(f"| `vibrofeed run`, whole run | {med(driven):.1f} s (ratio to by hand {med(ratios):.3f}; "
          f"each run {', '.join(f'{x:.3f}' for x in ratios)}) |")
    share = med(t_an) / med(driven)
    print(f"| feed-rate + singulation analyses | {med(t_an):.2f} s ({share:.2%} of the run) |")


if __name__ == "__main__":
    main()
