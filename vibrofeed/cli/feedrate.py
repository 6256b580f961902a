"""``vibrofeed feedrate``: parts and mass per second at a bulk feeder's outlet,
the conveying speed along the track and its dilute-limit model."""

from __future__ import annotations

from ..values import fmt
from .numbers import real, whole
from .options import add_output_arguments, figures_written, plot_folder, print_figures, refuse, unmeasured

DESCRIPTION = ("Feed rate of a bulk-feeder result: parts/s and mass/s leaving the track over the "
               "detected steady window (batch-means error), the mean conveying velocity over whole "
               "vibration periods and its profile along the track, the mass balance, and the "
               "single-part model's speed for the same vibration (the dilute limit).")


def add_arguments(p) -> None:
    p.add_argument("result", metavar="RUN.h5", help="result of a bulk-feeder deck")
    p.add_argument("--start", type=real(), metavar="S", help="start of the steady window [s] "
                   "(default: detected)")
    p.add_argument("--end", type=real(), metavar="S", help="end of the steady window [s] "
                   "(default: detected)")
    p.add_argument("--batches", type=whole(2), default=10, metavar="N",
                   help="batches of the batch-means errors (default 10)")
    p.add_argument("--bins", type=whole(1), default=20, metavar="N",
                   help="bins of the velocity profile along the track (default 20)")
    p.add_argument("--no-model", action="store_true",
                   help="skip the single-part model comparison")
    add_output_arguments(p)


# The figures too few exits cannot measure: null in the JSON, "too few exits" in the table.
RATE_KEYS = ("parts_per_s", "parts_per_s_err", "mass_per_s", "mass_per_s_err")


def table(s: dict) -> str:
    """The figures as the command prints them."""
    rate = (f"{fmt(s['parts_per_s'])} ± {fmt(s['parts_per_s_err'], spec='.2g')} parts/s, "
            f"{fmt(s['mass_per_s'], 1e6)} ± {fmt(s['mass_per_s_err'], 1e6, '.2g')} mg/s")
    lines = [
        f"feed rate      {s['reason'] if s.get('reason') else rate}",
        f"steady window  {fmt(s['steady_from'])} .. {fmt(s['steady_to'])} s "
        f"({s['n_events']} exits in the run analysed)",
        f"conveying      {fmt(s['mean_velocity'], 1e3)} ± {fmt(s['mean_velocity_err'], 1e3, '.2g')} "
        f"mm/s (whole-period displacement, {s['velocity_lag']} frames per interval)",
    ]
    if "model_velocity" in s:
        if s["model_velocity"] is None:
            lines.append(f"single part    n/a ({s['model_note']})")
        else:
            lines.append(f"single part    {fmt(s['model_velocity'], 1e3)} mm/s (model, dilute limit); "
                         f"bulk / model = {fmt(s['velocity_ratio'], spec='.3f')}"
                         + (f"; {s['model_note']}" if s["model_note"] else ""))
    if s.get("inserted") is not None:
        rejected = f", rejected {s['rejected']}" if s.get("rejected") is not None else ""
        lines.append(f"mass balance   inserted {s['inserted']}, on track {s['on_track']}, exited "
                     f"{s['exited']}{rejected}, lost {s['lost']} (last frame)")
    return "\n".join(lines)


def run(args) -> int:
    from ..pictures.plots import feedrate_figures
    from ..postproc.feedrate import FeedRate
    from ..results.reader import Result

    folder = plot_folder(args.plot)
    with Result(args.result) as result:
        fr = FeedRate(result, start=args.start, end=args.end, batches=args.batches,
                      bins=args.bins, model=not args.no_model).run()
        summary = fr.summary()
        figures = figures_written(feedrate_figures(fr, folder)) if folder is not None else []
    reason = unmeasured(summary, RATE_KEYS)
    print_figures(summary, figures, args.json, table)
    return refuse(args.result, reason)
