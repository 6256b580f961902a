"""How to singulate: the feeder-line study (docs/studies.md, "How to singulate").

The figure of the sweep sweeps/line.toml,
``python -m vibrofeed.validation.studies.line_singulation LINE_DIR -o FIG.png``
(:func:`line_figure`): the singulated fraction, the feed rate and, for chips, the
orientation yield against the measured speed ratio v2/v1 of the line's two sections,
one line per single-file ledge width and part shape. The speed ratio is the DEM's (the
sections' whole-period conveying speeds in the sweep's summary), not the single-part
model's: rolling spheres do not follow the sliding block.
"""

from __future__ import annotations

import math
from pathlib import Path

from ...errors import CaseError

SHAPE_NAMES = {0: "spheres", 1: "chips", 2: "discs"}


def study_rows(folder) -> list[dict]:
    """The sweep's finished, measured jobs as dicts: shape, ledge width [m], speed ratio
    v2/v1 (with its error from the two speeds' batch-means errors where the summary has
    them), feed rate [parts/s] with its error, singulated fraction, orientation yield
    (None for spheres), doubles, rejects per second on section 2."""
    from vibrofeed.sweep import report

    rows, _ = report.load(Path(folder))
    out = []
    for r in rows:
        if r.get("status") != "done" or not _number(r.get("parts_per_s")):
            continue
        v1, v2 = _number(r.get("speed_1")), _number(r.get("speed_2"))
        if not v1 or v2 is None:
            continue
        out.append({"shape": int(float(r.get("shape", 0))), "ledge": float(r["s2_drop_width"]),
                    "stroke": float(r["s2_amp_t"]), "ratio": v2 / v1,
                    "rate": float(r["parts_per_s"]), "rate_err": _number(r.get("parts_per_s_err")),
                    "singulated": _number(r.get("singulated_fraction")),
                    "yield": _number(r.get("orientation_yield")),
                    "doubles": _number(r.get("doubles_rate")),
                    "rejects": _number(r.get("reject_rate_2")), "arrivals": _number(r.get("n_arrivals"))})
    if not out:
        raise CaseError(f"{folder}: no finished, measured job of a feeder line in the sweep's summary")
    return sorted(out, key=lambda row: (row["shape"], row["ledge"], row["ratio"]))


def _number(value) -> float | None:
    try:
        x = float(value)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def line_figure(folder, path) -> Path:
    """Singulated fraction (solid) and orientation yield (dotted, chips), and the feed
    rate, against the speed ratio, one colour per shape, one marker per ledge width."""
    from vibrofeed.pictures.plots import pyplot, save

    rows = study_rows(folder)
    plt = pyplot()
    fig, (ax_s, ax_r) = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = {0: "tab:blue", 1: "tab:orange", 2: "tab:green"}
    markers = {}
    for (shape, ledge) in sorted({(r["shape"], r["ledge"]) for r in rows}):
        mine = [r for r in rows if r["shape"] == shape and r["ledge"] == ledge]
        marker = markers.setdefault(ledge, "os^v"[len(markers) % 4])
        label = f"{SHAPE_NAMES.get(shape, shape)}, ledge {ledge * 1e3:g} mm"
        x = [r["ratio"] for r in mine]
        ax_s.plot(x, [100 * (r["singulated"] or 0) for r in mine], marker=marker, color=colours[shape],
                  label=label)
        if shape != 0:
            ax_s.plot(x, [100 * (r["yield"] or 0) for r in mine], marker=marker, color=colours[shape],
                      linestyle=":", label=f"{label}: flat and aligned")
        ax_r.errorbar(x, [r["rate"] for r in mine], yerr=[r["rate_err"] or 0 for r in mine],
                      marker=marker, color=colours[shape], capsize=3, label=label)
    ax_s.axhline(90, color="grey", linewidth=0.8, linestyle="--")
    ax_s.set_xlabel("speed ratio v2 / v1 (DEM)")
    ax_s.set_ylabel("parts delivered singulated [%]")
    ax_s.set_ylim(0, 102)
    ax_s.legend(fontsize=7)
    ax_r.set_xlabel("speed ratio v2 / v1 (DEM)")
    ax_r.set_ylabel("feed rate at the outlet [parts/s]")
    ax_r.legend(fontsize=7)
    fig.suptitle(f"feeder line, sweep {Path(folder).name}: 30 parts/s fed in clumps of three; "
                 "one run per point (fractions: ±5-10 %)", fontsize=9)
    fig.tight_layout()
    return save(fig, path)


def main(argv=None) -> int:
    import argparse

    parser = argparse.ArgumentParser(prog="python -m vibrofeed.validation.studies.line_singulation",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("folder", help="the output folder of `vibrofeed sweep sweeps/line.toml`")
    parser.add_argument("-o", "--output", default="line_singulation.png", help="the figure (PNG)")
    args = parser.parse_args(argv)
    for r in study_rows(args.folder):
        print(f"{SHAPE_NAMES.get(r['shape'], r['shape']):8s} ledge {r['ledge'] * 1e3:.2f} mm  "
              f"stroke {r['stroke'] * 1e6:4.0f} um  ratio {r['ratio']:.2f}  rate {r['rate']:.1f} "
              f"± {r['rate_err'] or math.nan:.2g} /s  singulated {100 * (r['singulated'] or math.nan):.1f} %"
              + (f"  flat and aligned {100 * r['yield']:.1f} %" if r["yield"] is not None else "")
              + f"  rejects {r['rejects'] or 0:.3g} /s  arrivals {r['arrivals'] or 0:.0f}")
    print(f"figure: {line_figure(args.folder, args.output)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
