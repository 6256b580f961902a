"""Does the feed rate depend on the softened Young's modulus? (issue 10)

Run ``python -m vibrofeed.validation.studies.stiffness [-o DIR] [-j JOBS]``:
the default bulk-feeder case at several Young's moduli (the track softened in
proportion, as the deck does), each through the batch executor; prints the
feed rate and the conveying speed with their batch-means errors, and whether
each lies within the combined uncertainty of the default (5e7 Pa). The
realised restitution moves with the stiffness (README, "Validation"), so the
answer has to be measured, not assumed.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

MODULI = (2e7, 5e7, 1e8, 2e8, 5e8, 1e9)  # Pa
DEFAULT = 5e7


def run_study(out_dir: Path, moduli=MODULI, jobs: int = 2, extra: dict | None = None,
              reuse: bool = True) -> list[dict]:
    from vibrofeed.decks import Deck
    from vibrofeed.engine.batch import RunRequest, run_many
    from vibrofeed.postproc.feedrate import FeedRate
    from vibrofeed.results.reader import Result

    deck = Deck.find("bulk_feeder")
    requests = [RunRequest(deck, {"youngs": repr(E), **(extra or {})}, out_dir / f"E{E:.0e}.h5",
                           label=f"youngs={E:g}", reuse=reuse) for E in moduli]
    outcomes = run_many(requests, jobs=jobs,
                        on_state=lambda r, state: print(f"  {r.label}: {state}", flush=True))
    rows = []
    for E, o in zip(moduli, outcomes):
        if not o.ok:
            rows.append({"youngs": E, "error": str(o.error)})
            continue
        with Result(o.request.output) as r:
            s = FeedRate(r).run().summary()
            derived = r.derived
        rows.append({"youngs": E, "parts_per_s": s["parts_per_s"], "err": s["parts_per_s_err"],
                     "velocity": s["mean_velocity"], "velocity_err": s["mean_velocity_err"],
                     "dt": derived.get("dt_used"), "wall": o.result.wall})
    return rows


def within(row: dict, ref: dict, key: str, err: str) -> bool:
    """|x - x_ref| <= 2 sqrt(err^2 + err_ref^2): the same within the two errors."""
    return abs(row[key] - ref[key]) <= 2 * math.hypot(row[err], ref[err])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", default="stiffness-study", help="folder for the runs")
    ap.add_argument("-j", "--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    rows = run_study(Path(a.output), jobs=a.jobs)
    ref = next(r for r in rows if r["youngs"] == DEFAULT)
    print("| youngs [Pa] | dt [s] | feed rate [parts/s] | same as 5e7? | speed [mm/s] | same? | wall [s] |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        if "error" in r:
            print(f"| {r['youngs']:.0e} | failed: {r['error']} |")
            continue
        print(f"| {r['youngs']:.0e} | {r['dt']:.3g} | {r['parts_per_s']:.1f} ± {r['err']:.1f} | "
              f"{'yes' if within(r, ref, 'parts_per_s', 'err') else 'NO'} | "
              f"{1e3 * r['velocity']:.2f} ± {1e3 * r['velocity_err']:.2f} | "
              f"{'yes' if within(r, ref, 'velocity', 'velocity_err') else 'NO'} | {r['wall']:.0f} |")


if __name__ == "__main__":
    main()
