"""``vibrofeed feedrate``: parts and mass per second at a bulk feeder's outlet,
the conveying speed along the track and its dilute-limit model."""

from __future__ import annotations

from ..values import fmt
from .numbers import real, whole
from .options import add_output_arguments, figures_written, plot_folder, print_figures, refuse, unmeasured

DESCRIPTION = ("Feed rate of a bulk-feeder result: parts/s and mass/s leaving the track over the "
               "detected steady window (batch-means error), the mean conveying velocity over whole "
               "vibration periods and its profile along the track, the mass balance, and the "
               "single-part model's speed for the same vibration (the dilute limit). A bed whose "
               "conveying speed or hold-up still drifts over the window measures no steady rate. "
               "A feeder line also gets, per section, the flux through its downstream end, its "
               "speed, line density, hold-up and rejects, and its rejects by tooling.")


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


# The figures too few exits (or a drifting bed) cannot measure: null in the JSON, the
# reason in the table.
RATE_KEYS = ("parts_per_s", "parts_per_s_err", "mass_per_s", "mass_per_s_err")
# A line's per-section figures that are rates over the window, unmeasured with the rest.
SECTION_RATE_KEYS = ("joint_flux", "joint_flux_error", "reject_rate", "reject_rate_error")
TOOLING_NAMES = {"side_drop": "side drop", "wiper": "wiper", "jet": "jet", "other": "other",
                 "slot": "slot"}


def unmeasured_sections(summary: dict) -> None:
    """A line's per-section and per-tooling rates set to None when the summary gives a
    reason for measuring nothing (as :func:`~.options.unmeasured` does for the rate)."""
    if not summary.get("reason"):
        return
    for section in summary.get("sections") or []:
        section.update(dict.fromkeys(SECTION_RATE_KEYS))
    for tool in (summary.get("rejects_by_tooling") or {}).values():
        if tool is not None:
            tool.update(per_s=None, per_s_error=None)


def _pm(value, error, scale: float = 1.0) -> str:
    return f"{fmt(value, scale)} ± {fmt(error, scale, '.2g')}"


def _columns(cells, widths) -> str:
    """Cells padded to their column's width, and at least one space after each: a cell as
    wide as its column (sections at 12.5 .. 30.4 mm) never runs into the next."""
    return "".join(c.ljust(w - 1) + " " for c, w in zip(cells, widths))


def section_name(section: dict) -> str:
    """A section's name in the tables: its number, or a bowl's helix and chute."""
    return str(section.get("name", section["section"]))


def section_table(s: dict) -> list[str]:
    """A line's lines of the table: one row per section, its rejects by tooling and the
    continuity at each joint; nothing for a single track. Rates read n/a when the summary
    gives a reason for measuring none."""
    sections = s.get("sections")
    if not sections:
        return []
    measured = not s.get("reason")
    bowl = "name" in sections[0]  # a bowl's helix and chute, along its path
    # a bowl alone: its rejects fall back into it; with an exit line, some are the line's
    returns = bowl and len(sections) == 2
    widths = (22, 22, 22, 20, 15) if bowl else (15, 22, 22, 20, 15)
    head = (f"{sections[0].get('along', 'x')} [mm]", "out [parts/s]", "speed [mm/s]", "hold-up [parts]",
            "density [/mm]")
    rejects_head = "fell back [/s]" if returns else "rejects [/s]"
    lines = ["sections       " + _columns(head, widths) + rejects_head]
    for k, sec in enumerate(sections):
        out = "outlet" if k == len(sections) - 1 else "joint"
        cells = (f"{section_name(sec)}: {fmt(sec['x_from'], 1e3, '.3g')} .. {fmt(sec['x_to'], 1e3, '.3g')}",
                 f"{out} " + (_pm(sec["joint_flux"], sec["joint_flux_error"]) if measured else "n/a"),
                 _pm(sec["speed"], sec["speed_error"], 1e3),
                 _pm(sec["hold_up"], sec["hold_up_error"]),
                 fmt(sec["line_density"], 1e-3))
        rejects = _pm(sec["reject_rate"], sec["reject_rate_error"]) if measured else "n/a"
        lines.append("  " + " " * 13 + _columns(cells, widths) + rejects)
    told = []
    for name, tool in (s.get("rejects_by_tooling") or {}).items():
        label = TOOLING_NAMES.get(name, name)
        if tool is None:
            told.append(f"{label}: none on the {'bowl' if returns else 'feeder' if bowl else 'line'}")
            continue
        rate = _pm(tool["per_s"], tool["per_s_error"]) + " /s" if measured else "n/a"
        told.append(f"{label} {rate} ({tool['in_window']} in the window, {tool['total']} in all)")
    if told:
        lines.append(("fell back by   " if returns else "rejects        ") + "; ".join(told))
    for k in range(len(sections) - 1 if measured else 0):
        into, nxt = sections[k], sections[k + 1]
        flows = (into["joint_flux"], nxt["joint_flux"], nxt["reject_rate"])
        errors = (into["joint_flux_error"], nxt["joint_flux_error"], nxt["reject_rate_error"])
        gap = flows[0] - flows[1] - flows[2] if None not in flows else None
        spread = sum(e * e for e in errors) ** 0.5 if None not in errors else None
        where = "the outlet" if k + 2 == len(sections) else f"joint {k + 2}"
        lines.append(f"continuity     joint {k + 1}: {fmt(flows[0])} /s in = {fmt(flows[1])} through "
                     f"{where} + {fmt(flows[2])} rejected /s (in - out {_pm(gap, spread)})")
    return lines


# What the single-part model is, said where a sphere is compared with it.
SLIDING_BLOCK = "a sliding block's speed: spheres roll, so for them a reference, not a prediction"


def single_part(s: dict) -> str:
    """The dilute-limit line: the single-part model's speed (each section's for a line)
    and the measured speed over it, with what the comparison means for spheres."""
    sphere = s.get("shape", 0) == 0
    sections = [sec for sec in s.get("sections") or () if "model_speed" in sec]
    if sections:
        told = [f"{section_name(sec)}: {fmt(sec['model_speed'], 1e3)} mm/s (DEM / model "
                f"{fmt(sec['speed_ratio'], spec='.3f')})" if sec["model_speed"] is not None
                else f"{section_name(sec)}: n/a ({sec['model_note']})" for sec in sections]
        return ("single part    model, dilute limit, each section's drive: " + ", ".join(told)
                + (f"; {SLIDING_BLOCK}" if sphere else ""))
    if s["model_velocity"] is None:
        return f"single part    n/a ({s['model_note']})"
    return (f"single part    {fmt(s['model_velocity'], 1e3)} mm/s (model, dilute limit); "
            f"bulk / model = {fmt(s['velocity_ratio'], spec='.3f')}"
            + (f"; {s['model_note']}" if s["model_note"] else "")
            + (f"; {SLIDING_BLOCK}" if sphere else ""))


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
        *section_table(s),
    ]
    if s.get("fell") is not None:  # a bowl
        lines.append(f"fell back      {s['fell']} in the window, {fmt(s['fell_per_s'])} ± "
                     f"{fmt(s['fell_per_s_err'], spec='.2g')} /s (off the track back into the bowl)")
    if "model_velocity" in s:
        lines.append(single_part(s))
    if s.get("inserted") is not None:
        rejected = f", rejected {s['rejected']}" if s.get("rejected") is not None else ""
        if s.get("returned") is not None:
            rejected += f" (returned to the inlet {s['returned']}, counted in inserted)"
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
    unmeasured_sections(summary)
    print_figures(summary, figures, args.json, table)
    return refuse(args.result, reason)
