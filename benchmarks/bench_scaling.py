"""Engine throughput of the bulk-feeder deck vs the number of parts and ranks.

    .venv/bin/python benchmarks/bench_scaling.py [--sizes 1000 4000 16000] [--ranks 1 2]
                                                 [--repeats 3] [-p NAME=VALUE ...]

For each size the track is made long enough to hold the parts as a single
layer on a 6 mm wide track (20 parts across at the default 300 um), so the
bed is the same vibrated monolayer at every size, only longer; LIGGGHTS then
runs it by hand (`vibrofeed prepare`, `liggghts -in`, no output but the
thermo lines) on 1 and 2 ranks. The figure is the vibration run's own loop:
particle-steps/s = atoms x steps / loop time, the median of ``--repeats``
runs. The fill settles for ``t_settle`` (short: the parts are inserted a few
diameters above the floor) and the vibration runs ``t_end`` (one period by
default), long enough for a stable rate and short enough to repeat.
Prints a Markdown table for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_foundation import machine  # noqa: E402

WIDTH = 6e-3          # [m] track width: 20 parts of 300 um across
PACKING = 0.8         # parts per (diameter^2) of the filled area in one layer, roughly
FILL = (0.05, 0.95)   # fractions of the track the pre-fill spans


def track_length(n: int, part_size: float = 3e-4) -> float:
    """Track length [m] whose filled span holds n parts in one layer."""
    per_row = WIDTH / part_size
    rows = n / (per_row * PACKING)
    return rows * part_size / (FILL[1] - FILL[0])


def loop(text: str) -> tuple[float, int, int]:
    """(seconds, steps, atoms) of the last `Loop time` line (the vibration run)."""
    found = re.findall(r"Loop time of ([0-9.e+-]+) on \d+ procs for (\d+) steps with (\d+) atoms", text)
    if not found:
        raise RuntimeError("no 'Loop time' line in the LIGGGHTS output")
    seconds, steps, atoms = found[-1]
    return float(seconds), int(steps), int(atoms)


def one_run(tmp: Path, n: int, ranks: int, extra: list[str], t_settle: float, t_end: float):
    params = {"n_parts": n, "track_length": f"{track_length(n):.6g}", "track_width": WIDTH,
              "fill_from": FILL[0], "fill_to": FILL[1], "t_settle": t_settle, "t_end": t_end,
              "output_dt": t_end}
    args = [w for k, v in params.items() for w in ("-p", f"{k}={v}")] + extra
    mesh = tmp / "mesh"
    line = subprocess.run([sys.executable, "-m", "vibrofeed.cli", "prepare", "bulk_feeder", "-o", str(mesh),
                           *args], check=True, capture_output=True, text=True).stdout.strip().splitlines()[-1]
    words = line.split() + ["-var", "dump_file", "/dev/null", "-log", "none", "-nocite"]
    if ranks > 1:
        words = ["mpirun", "-n", str(ranks), "--oversubscribe"] + words
    env = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
    done = subprocess.run(words, capture_output=True, text=True, cwd=tmp, env=env)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(words)} failed:\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    out = done.stdout
    seconds, steps, atoms = loop(out)
    return atoms * steps / seconds, atoms, steps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 4000, 16000])
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--t-settle", type=float, default=0.02, help="settling time [s]")
    ap.add_argument("--t-end", type=float, default=0.01, help="vibration time measured [s]")
    ap.add_argument("-p", "--param", action="append", default=[], metavar="NAME=VALUE")
    a = ap.parse_args()
    extra = [w for p in a.param for w in ("-p", p)]
    rows = []
    for n in a.sizes:
        for ranks in a.ranks:
            rates = []
            for _ in range(a.repeats):
                with tempfile.TemporaryDirectory() as d:
                    rate, atoms, steps = one_run(Path(d), n, ranks, extra, a.t_settle, a.t_end)
                rates.append(rate)
                print(f"  {n} parts, {ranks} rank(s): {rate / 1e6:.2f} M particle-steps/s", file=sys.stderr)
            rows.append((n, ranks, atoms, steps, statistics.median(rates), min(rates), max(rates)))
    print(f"machine: {machine()}; t_settle {a.t_settle} s, t_end {a.t_end} s, "
          f"medians of {a.repeats}; parameters: {' '.join(a.param) or 'defaults'}")
    print("| parts | track [mm] | ranks | atoms | steps | M particle-steps/s (median, min-max) | "
          "speed-up over 1 rank |")
    print("|---|---|---|---|---|---|---|")
    one = {n: rate for n, ranks, _, _, rate, _, _ in rows if ranks == 1}
    for n, ranks, atoms, steps, rate, lo, hi in rows:
        speedup = f"{rate / one[n]:.2f}" if n in one else "-"
        print(f"| {n} | {track_length(n) * 1e3:.0f} | {ranks} | {atoms} | {steps} | "
              f"{rate / 1e6:.2f} ({lo / 1e6:.2f}-{hi / 1e6:.2f}) | {speedup} |")


if __name__ == "__main__":
    main()
