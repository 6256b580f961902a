"""``vibrofeed feedrate``: parts and mass per second at a bulk feeder's outlet,
the conveying speed along the track and its dilute-limit model."""

from __future__ import annotations

import json
import math
from pathlib import Path

from ..errors import UsageError

DESCRIPTION = ("Feed rate of a bulk-feeder result: parts/s and mass/s leaving the track over the "
               "detected steady window (batch-means error), the mean conveying velocity over whole "
               "vibration periods and its profile along the track, the mass balance, and the "
               "single-part model's speed for the same vibration (the dilute limit).")


def add_arguments(p) -> None:
    p.add_argument("result", metavar="RUN.h5", help="result of a bulk-feeder deck")
    p.add_argument("--start", type=float, metavar="S", help="start of the steady window [s] "
                   "(default: detected)")
    p.add_argument("--end", type=float, metavar="S", help="end of the steady window [s] "
                   "(default: detected)")
    p.add_argument("--batches", type=int, default=10, metavar="N",
                   help="batches of the batch-means errors (default 10)")
    p.add_argument("--bins", type=int, default=20, metavar="N",
                   help="bins of the velocity profile along the track (default 20)")
    p.add_argument("--no-model", action="store_true",
                   help="skip the single-part model comparison")
    add_output_arguments(p)


def add_output_arguments(p) -> None:
    """--json and --plot DIR, shared by the analysis commands."""
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--plot", metavar="DIR",
                   help="write the figures (PNG) into DIR (created if missing; its parent must exist)")


def plot_folder(path: str | None) -> Path | None:
    """The figures' folder, checked before any work: created if missing, but a
    mistyped parent is refused rather than created silently."""
    if path is None:
        return None
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"--plot {path}: not a folder")
    if not folder.exists():
        if not folder.absolute().parent.is_dir():
            raise UsageError(f"--plot {path}: folder {folder.absolute().parent} does not exist")
        folder.mkdir()
    return folder


# Parameters the single-part model needs from the deck (the rest have defaults).
MODEL_NEEDS = ("freq", "mu", "restitution")


def dilute_limit(parameters: dict) -> tuple[float | None, str]:
    """(speed [m/s], note) of one part alone on the track under the same
    vibration: the rigid-part model of Khan & Sarma, §2.3.2 (hopping and
    sliding), driven through ``vibrofeed.validation.deck_models`` like the
    single-part validation cases; (None, why) when the deck lacks a parameter."""
    missing = [name for name in MODEL_NEEDS if name not in parameters]
    if missing:
        return None, f"the result lacks {', '.join(missing)}"
    from ..validation import deck_models as dm
    from ..validation.models.part_on_surface import PartParams, mean_velocity

    mu = float(parameters["mu"])
    part = PartParams(mu_s=mu, mu_k=mu, e=min(float(parameters["restitution"]), 0.999))
    try:
        state = mean_velocity(dm.waveform(parameters), part,
                              incline=float(parameters.get("incline", 0.0)))
    except (KeyError, ValueError) as exc:
        return None, f"model not applicable ({exc})"
    note = "" if state.converged else "model not converged (chaotic hopping?): mean of its last blocks"
    return float(state.velocity), note


def add_dilute_limit(summary: dict, parameters: dict) -> dict:
    """``summary`` with ``model_velocity``, ``model_note`` and ``velocity_ratio``
    (measured mean conveying velocity / model) added (see :func:`dilute_limit`)."""
    model, note = dilute_limit(parameters)
    measured = summary.get("mean_velocity")
    summary["model_velocity"], summary["model_note"] = model, note
    summary["velocity_ratio"] = measured / model if model and measured is not None else None
    return summary


def _fmt(value, scale: float = 1.0, spec: str = ".4g") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return format(value * scale, spec)


def table(s: dict) -> str:
    """The figures as the command prints them."""
    lines = [
        f"feed rate      {_fmt(s['parts_per_s'])} ± {_fmt(s['parts_per_s_err'], spec='.2g')} parts/s, "
        f"{_fmt(s['mass_per_s'], 1e6)} ± {_fmt(s['mass_per_s_err'], 1e6, '.2g')} mg/s",
        f"steady window  {_fmt(s['steady_from'])} .. {_fmt(s['steady_to'])} s "
        f"({s['n_events']} exits in the run analysed)",
        f"conveying      {_fmt(s['mean_velocity'], 1e3)} ± {_fmt(s['mean_velocity_err'], 1e3, '.2g')} "
        f"mm/s (whole-period displacement, {s['velocity_lag']} frames per interval)",
    ]
    if "model_velocity" in s:
        if s["model_velocity"] is None:
            lines.append(f"single part    n/a ({s['model_note']})")
        else:
            lines.append(f"single part    {_fmt(s['model_velocity'], 1e3)} mm/s (model, dilute limit); "
                         f"bulk / model = {_fmt(s['velocity_ratio'], spec='.3f')}"
                         + (f"; {s['model_note']}" if s["model_note"] else ""))
    if s.get("inserted") is not None:
        rejected = f", rejected {s['rejected']}" if s.get("rejected") is not None else ""
        lines.append(f"mass balance   inserted {s['inserted']}, on track {s['on_track']}, exited "
                     f"{s['exited']}{rejected}, lost {s['lost']} (last frame)")
    return "\n".join(lines)


def run(args) -> int:
    from ..postproc.feedrate import FeedRate
    from ..results.reader import Result

    folder = plot_folder(args.plot)
    with Result(args.result) as result:
        fr = FeedRate(result, start=args.start, end=args.end, batches=args.batches,
                      bins=args.bins).run()
        summary = fr.summary()
        if not args.no_model:
            add_dilute_limit(summary, result.parameters)
        figures = fr.plot(folder) if folder is not None else []
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(table(summary))
        for path in figures:
            print(f"figure: {path}")
    return 0
