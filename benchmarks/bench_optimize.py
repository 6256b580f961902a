"""The optimiser on a problem whose optimum the models know: how many DEM runs to it.

    .venv/bin/python benchmarks/bench_optimize.py [--study studies/single_part_phase.toml] [--runs 15]
                                                  [--seeds 0]

The study varies one drive setting of the single-part deck (the phase, in the shipped
study). The reference is the single-part model's optimum of the same drive, found by a
scan of the variable and a bounded refinement (scipy), and then run once in DEM: the DEM
conveying speed at the model's best setting. The study is then run with ``--runs`` DEM
runs of search (no confirmation or robustness: ``confirm = 0``), into a fresh folder; the
figure is the number of search runs until one reaches within 2 % of the reference speed,
and the best speed found against the reference. Prints a Markdown table for BENCHMARKS.md.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_foundation import machine  # noqa: E402

VIBROFEED = ROOT / ".venv" / "bin" / "vibrofeed"


def model_optimum(spec, deck) -> tuple[str, float, float]:
    """(variable, its value at the model's best, the model's speed there)."""
    import numpy as np
    from scipy.optimize import minimize_scalar

    from vibrofeed.models.deck import transport
    from vibrofeed.parameters import resolve
    from vibrofeed.sweep.plan import value_text

    (var,) = spec.variables  # one variable: the known-optimum problems are one-dimensional
    base = resolve(deck, {k: value_text(v) for k, v in spec.fixed.items()})

    def speed(x: float) -> float:
        p = {k: float(v) for k, v in base.items() if re.fullmatch(r"[-+0-9.eE]+", v)}
        return transport({**p, var.name: x}).velocity

    grid = np.linspace(var.low, var.high, 181)
    speeds = [speed(x) for x in grid]
    k = int(np.argmax(speeds))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    best = minimize_scalar(lambda x: -speed(x), bounds=(lo, hi), method="bounded",
                           options={"xatol": 1e-3 * (var.high - var.low)})
    return var.name, float(best.x), -float(best.fun)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", default=str(ROOT / "studies" / "single_part_phase.toml"))
    ap.add_argument("--runs", type=int, default=15)
    ap.add_argument("--seeds", type=int, default=None,
                    help="the screen's seeds (default: the study's; 0: the sampler alone)")
    a = ap.parse_args()
    from vibrofeed.optimize.spec import load
    from vibrofeed.sweep import summary as S
    from vibrofeed.sweep.plan import find_deck, value_text

    spec = load(a.study)
    deck = find_deck(spec)
    name, x_model, v_model = model_optimum(spec, deck)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        ref = tmp / "ref.h5"
        params = [w for k, v in {**spec.fixed, name: x_model}.items() for w in ("-p", f"{k}={value_text(v)}")]
        subprocess.run([str(VIBROFEED), "run", spec.deck, "-q", "-o", str(ref), *params], check=True,
                       capture_output=True)
        from vibrofeed.postproc import Transport
        from vibrofeed.results.reader import Result

        with Result(ref) as r:
            v_ref = float(Transport(r).run().results.mean_velocity)
        text = Path(a.study).read_text()
        text = re.sub(r"(?m)^confirm = \d+", "confirm = 0", text)
        text = re.sub(r"(?m)^\[robustness\][\s\S]*", "", text)
        if a.seeds is not None:
            text = re.sub(r"(?m)^seeds = \d+", f"seeds = {a.seeds}", text)
        study = tmp / "study.toml"
        study.write_text(text)
        t0 = time.monotonic()
        subprocess.run([str(VIBROFEED), "optimize", str(study), "-o", str(tmp / "out"), "-q",
                        "--budget", str(a.runs)], capture_output=True)
        wall = time.monotonic() - t0
        rows = sorted((r for r in S.read(tmp / "out", stem="study")[0] if r["stage"] == "search"),
                      key=lambda r: r["job"])
    speeds = [r["objective"] for r in rows]
    reached = next((i + 1 for i, v in enumerate(speeds) if v is not None and v >= 0.98 * v_ref), None)
    best = max((v for v in speeds if v is not None), default=float("nan"))
    seeds = "the study's" if a.seeds is None else a.seeds
    print(f"machine: {machine()}; study {Path(a.study).name}, {a.runs} search runs, seeds {seeds}")
    print("| measurement | result |\n|---|---|")
    print(f"| model optimum | {name} = {x_model:.4g}, model speed {v_model * 1e3:.3f} mm/s |")
    print(f"| DEM at the model optimum (the reference) | {v_ref * 1e3:.3f} mm/s |")
    print(f"| search runs to within 2 % of the reference | {reached if reached else 'not reached'} "
          f"of {len(rows)} |")
    print(f"| best found / reference | {best / v_ref:.4f} ({best * 1e3:.3f} mm/s) |")
    print(f"| study wall time | {wall:.0f} s |")


if __name__ == "__main__":
    main()
