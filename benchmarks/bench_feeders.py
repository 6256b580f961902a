"""Benchmark of feeder descriptions: their generated deck against today's deck, and
`vibrofeed run` against plain `liggghts -in` of the generated deck, side by side.

    .venv/bin/python benchmarks/bench_feeders.py
        [--feeder demo-line|bowl-line|orient-ledge|orient-line] [--pairs 5] [--t-end 0.3] [--without-jet]

The feeder is the demo line (feeders/demo_line.toml, the parameters of `vibrofeed demo`),
the bowl with its exit line (feeders/bowl_line.toml, `vibrofeed demo --case bowl-line`), the
orientation demo's line (feeders/orient_ledge.toml, `vibrofeed demo --case orient`) or the gated
orientation line (feeders/orient_line.toml). By hand an orientation line's jet never fires and
its rejects are not returned (`-var recirculate 0`); --without-jet: both runs with the jet's
force 0 and no returns, `s2_jet_force=0` and `recirculate=0`, the same physics (the driver
still senses every part and places and removes the jet's fix as it would fire),
run for --t-end seconds of vibration on one rank. Each comparison runs its two commands in
turn, A B A B ..., after one warm-up pair, as whole processes; it prints each command's
median wall time and the median of the pairs' ratios A/B (a ratio pair by pair holds when
the machine's speed drifts), as a Markdown table for BENCHMARKS.md:

* described vs deck (the demo line: a project deck runs the same feeder): `vibrofeed run
  feeders/demo_line.toml` against `vibrofeed run bulk_feeder` with the demo's parameters
  (the same commands and values: the description costs its reading and the deck's
  generation);
* vibrofeed vs by hand: `vibrofeed run` of the generated deck against `liggghts -in` of it
  on the geometry `vibrofeed prepare` wrote (a text dump every output_dt).
"""

from __future__ import annotations

import argparse
import os
import resource
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_foundation import machine  # noqa: E402

VIBROFEED = [sys.executable, "-m", "vibrofeed.cli"]


def timed(command: list[str], cwd: Path) -> tuple[float, float]:
    """(wall s, CPU s: user + system of the process and every child it waited for)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
    seconds = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        sys.exit(f"{shlex.join(command)} failed ({done.returncode}):\n{done.stderr[-3000:]}")
    return seconds, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def paired(a: list[str], b: list[str], pairs: int, cwd: Path) -> dict:
    """Medians of A's and B's wall and CPU seconds and of the pairs' ratios A/B (with their
    least and most) over ``pairs`` alternated pairs after a warm-up pair."""
    timed(a, cwd), timed(b, cwd)
    ta, tb = [], []
    for _ in range(pairs):
        ta.append(timed(a, cwd))
        tb.append(timed(b, cwd))
    out = {}
    for i, what in enumerate(("wall", "cpu")):
        ratios = [x[i] / y[i] for x, y in zip(ta, tb)]
        out[what] = (statistics.median(x[i] for x in ta), statistics.median(y[i] for y in tb),
                     statistics.median(ratios), min(ratios), max(ratios))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--t-end", type=float, default=0.3)
    ap.add_argument("--feeder", choices=("demo-line", "bowl-line", "orient-ledge", "orient-line"),
                    default="demo-line")
    ap.add_argument("--without-jet", action="store_true",
                    help="the orientation line without its jet and returns in both runs: the same physics")
    args = ap.parse_args()
    toml = ROOT / "feeders" / f"{args.feeder.replace('-', '_')}.toml"
    sys.path.insert(0, str(ROOT))
    from vibrofeed.cli.demo import CASES

    os.environ.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    os.environ.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    _, deck, given = CASES["line"]
    t_end = f"t_end={args.t_end:g}"
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        os.environ["XDG_CACHE_HOME"] = str(tmp / "cache")
        rows = []
        if args.feeder == "demo-line":
            described = VIBROFEED + ["run", str(toml), "-q", "-o", "a.h5", "-p", t_end]
            by_deck = VIBROFEED + ["run", deck, "-q", "-o", "b.h5", "-p", t_end]
            for name, value in given.items():
                if name != "t_end":
                    by_deck += ["-p", f"{name}={value}"]
            rows.append(("`vibrofeed run feeders/demo_line.toml` / `vibrofeed run bulk_feeder -p ...`",
                         paired(described, by_deck, args.pairs, tmp)))
        same = ["-p", "s2_jet_force=0", "-p", "recirculate=0"] if args.without_jet else []
        line = subprocess.run(VIBROFEED + ["prepare", str(toml), "-o",
                                           str(tmp / "prep"), "-p", t_end, *same],
                              check=True, capture_output=True, text=True).stdout.strip().splitlines()[-1]
        generated = shlex.split(line)[2]
        hand = shlex.split(line) + ["-log", "none", "-nocite", "-var", "dump_file",
                                    str(tmp / "d.dump")]
        if args.feeder.startswith("orient"):  # (the deck refuses recirculate=1 by hand)
            hand += ["-var", "recirculate", "0"]
        driver = VIBROFEED + ["run", generated, "-q", "-o", "c.h5", "-p", t_end, *same]
        rows.append(("`vibrofeed run` / `liggghts -in` of the generated deck",
                     paired(driver, hand, args.pairs, tmp / "prep")))
    print(f"Machine: {machine()}; {toml.name}{' without its jet' if args.without_jet else ''}, "
          f"{args.t_end:g} s of vibration, 1 rank, "
          f"{args.pairs} alternated pairs after a warm-up pair\n")
    print("| A / B | time | A (median) | B (median) | A/B median (min .. max) |")
    print("|---|---|---|---|---|")
    for what, figures in rows:
        for kind, (a, b, r, lo, hi) in figures.items():
            print(f"| {what} | {kind} | {a:.2f} s | {b:.2f} s | {r:.3f} ({lo:.3f} .. {hi:.3f}) |")


if __name__ == "__main__":
    main()
