"""Engine settings of the bulk feeder: neighbour skin, bin size and output interval
against throughput, with the feed rate checked to stay inside its uncertainty.

    .venv/bin/python benchmarks/bench_settings.py [--skins 0.2 0.4 0.8 1.6] [--bins 0.5 1 2]
                                                  [--output-dts 0.002 0.005 0.01 0.02 0.05]
                                                  [--repeats 1] [-p NAME=VALUE ...]

Every setting is one `vibrofeed run` of the bulk_feeder deck (the main job's
defaults unless -p: 300 spheres, 1 s), timed whole, and its result analysed
with `FeedRate`. The neighbour skin (deck: `neighbor $(0.4*v_r_min) bin`) and
the bin size (LIGGGHTS' default: half the largest cut-off; here a multiple of
the largest cut-off, 2 r_max + skin, through `neigh_modify binsize`) are not
user parameters: each variant is a copy of decks/ with that line changed.
The output interval is the deck's `output_dt`. A setting passes when its feed
rate and conveying speed are within 2 combined batch-means errors of the
reference (the deck as it is). Prints a Markdown table for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import math
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_foundation import machine  # noqa: E402

NEIGHBOR = re.compile(r"(?m)^neighbor\s+\$\(0\.4\*v_r_min\) bin\nneigh_modify\s+delay 0\n")


def variant(tmp: Path, skin: float | None, binsize: float | None) -> Path:
    """A copy of decks/ whose bulk_feeder has skin x r_min and a bin of binsize x the cut-off."""
    decks = tmp / "decks"
    if decks.exists():
        shutil.rmtree(decks)
    shutil.copytree(ROOT / "decks", decks)
    deck = decks / "bulk_feeder.liggghts"
    text = deck.read_text()
    if not NEIGHBOR.search(text):
        raise RuntimeError("the deck's neighbor lines changed: update bench_settings.NEIGHBOR")
    skin_text = f"$({skin if skin is not None else 0.4}*v_r_min)"
    modify = "neigh_modify    delay 0"
    if binsize is not None:
        # the largest cut-off: the largest sphere's diameter plus the skin
        modify += f" binsize $({binsize}*(2*v_r_sph*(1+v_size_spread)+{skin or 0.4}*v_r_min))"
    deck.write_text(NEIGHBOR.sub(f"neighbor        {skin_text} bin\n{modify}\n", text))
    return deck


def one(deck: Path, out: Path, params: list[str]) -> dict:
    from vibrofeed.postproc.feedrate import FeedRate
    from vibrofeed.results.reader import Result

    args = [sys.executable, "-m", "vibrofeed.cli", "run", str(deck), "-q", "-o", str(out), *params]
    t0 = time.monotonic()
    done = subprocess.run(args, capture_output=True, text=True)
    wall = time.monotonic() - t0
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} failed:\n{done.stderr[-2000:]}")
    with Result(out) as r:
        fr = FeedRate(r).run().results
        steps = int(r.derived["n_steps"])
    return {"wall": wall, "steps": steps, "rate": fr.parts_per_s, "rate_err": fr.parts_per_s_err,
            "v": fr.mean_velocity, "v_err": fr.mean_velocity_err}


def consistent(a: dict, ref: dict) -> bool:
    """Within 2 combined errors of the reference, feed rate and conveying speed."""
    ok = True
    for k in ("rate", "v"):
        err = math.hypot(a[k + "_err"], ref[k + "_err"])
        ok &= abs(a[k] - ref[k]) <= 2 * err
    return bool(ok)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--skins", type=float, nargs="*", default=[0.2, 0.8, 1.6],
                    help="skins to try, in units of the smallest radius (the deck: 0.4)")
    ap.add_argument("--bins", type=float, nargs="*", default=[0.5, 1.0, 2.0],
                    help="bin sizes to try, in units of the largest cut-off (LIGGGHTS' default: 0.5)")
    ap.add_argument("--output-dts", type=float, nargs="*", default=[0.002, 0.005, 0.02, 0.05],
                    help="output intervals to try [s] (the deck: 0.01)")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("-p", "--param", action="append", default=[], metavar="NAME=VALUE")
    a = ap.parse_args()
    params = [w for p in a.param for w in ("-p", p)]
    settings = [("reference (the deck)", None, None, [])]
    settings += [(f"skin {s:g} r_min", s, None, []) for s in a.skins]
    settings += [(f"bin {b:g} x cut-off", None, b, []) for b in a.bins]
    settings += [(f"output_dt {o:g} s", None, None, ["-p", f"output_dt={o:g}"]) for o in a.output_dts]
    rows = []
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for label, skin, binsize, extra in settings:
            deck = variant(tmp, skin, binsize)
            runs = [one(deck, tmp / f"r{i}.h5", params + extra) for i in range(a.repeats)]
            row = dict(runs[0], wall=statistics.median(r["wall"] for r in runs), label=label)
            rows.append(row)
            print(f"  {label}: {row['wall']:.1f} s, {row['rate']:.1f} +- {row['rate_err']:.1f} parts/s",
                  file=sys.stderr)
    ref = rows[0]
    print(f"machine: {machine()}; 1 rank; parameters: {' '.join(a.param) or 'defaults'}; "
          f"median wall of {a.repeats}")
    print("| setting | wall [s] | vs the deck | feed rate [parts/s] | conveying [mm/s] | within 2 sigma |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['label']} | {r['wall']:.1f} | {r['wall'] / ref['wall']:.3f} | "
              f"{r['rate']:.1f} ± {r['rate_err']:.1f} | {1e3 * r['v']:.2f} ± {1e3 * r['v_err']:.2f} | "
              f"{'yes' if consistent(r, ref) else 'NO'} |")


if __name__ == "__main__":
    main()
