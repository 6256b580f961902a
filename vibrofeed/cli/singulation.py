"""``vibrofeed singulation``: how well separated a bulk feeder delivers its parts."""

from __future__ import annotations

from ..values import fmt
from .numbers import real, whole
from .options import (
    add_output_arguments,
    figures_written,
    plot_folder,
    print_figures,
    refuse,
    slips,
    unmeasured,
)

DESCRIPTION = ("Singulation of a bulk-feeder result over the steady window: inter-arrival times at "
               "the outlet (coefficient of variation), doubles (parts closer than a gap, or touching), "
               "gaps between consecutive parts, cluster sizes on the track (contact graph), and for "
               "chips the face-up fraction, the alignment with the track and the orientation yield "
               "(face up and aligned) at the outlet.")


def add_arguments(p) -> None:
    p.add_argument("result", metavar="RUN.h5", help="result of a bulk-feeder deck")
    p.add_argument("--gap", type=real(above=0), metavar="S",
                   help="doubles: arrivals less than S seconds apart")
    p.add_argument("--gap-distance", type=real(at_least=0), metavar="M",
                   help="doubles: less than M metres of clear track between consecutive parts "
                        "(default 0, i.e. abreast or overlapping along the track, unless --gap "
                        "is given)")
    p.add_argument("--tolerance", type=real(at_least=0), metavar="M",
                   help="touching: centre distance <= r_i + r_j + M (default 1%% of a diameter)")
    p.add_argument("--start", type=real(), metavar="S", help="start of the window [s] (default: "
                   "the detected steady window)")
    p.add_argument("--end", type=real(), metavar="S", help="end of the window [s]")
    p.add_argument("--cluster-frames", type=whole(1), default=20, metavar="N",
                   help="frames sampled for the cluster sizes (default 20)")
    add_output_arguments(p)


# The statistics of the arrivals, which too few exits cannot give.
ARRIVAL_KEYS = ("mean_interarrival", "cv_interarrival", "mean_gap", "doubles_rate", "doubles_per_s",
                "singulated_fraction")


def table(s: dict) -> str:
    """The figures as the command prints them."""
    if s["gap"] is not None:
        rule = f"closer than {fmt(s['gap'], 1e3)} ms"
        if s["gap_distance"] is not None:
            rule += f" or {fmt(s['gap_distance'], 1e6)} um"
    elif s["gap_distance"]:
        rule = f"closer than {fmt(s['gap_distance'], 1e6)} um of clear track"
    else:
        rule = "abreast or overlapping along the track"
    shown = list(s["cluster_sizes"].items())
    sizes = ", ".join(f"{k}: {v:.3g}" for k, v in shown[:8]) or "none"
    if len(shown) > 8:
        sizes += f", ... up to {shown[-1][0]}"
    lines = [
        f"window         {fmt(s['steady_from'])} .. {fmt(s['steady_to'])} s, "
        f"{s['n_arrivals']} arrivals" + (f"; {s['reason']}" if s.get("reason") else ""),
        f"inter-arrival  mean {fmt(s['mean_interarrival'], 1e3)} ms, "
        f"CV {fmt(s['cv_interarrival'], spec='.3f')} (1: random, 0: periodic)",
        f"doubles        {fmt(s['doubles_rate'], 100, '.1f')} % of consecutive pairs "
        f"({s['n_doubles']}, {fmt(s['doubles_per_s'])} /s; {rule}, or touching)",
        f"singulated     {fmt(s['singulated_fraction'], 100, '.1f')} % of the parts at the outlet; "
        f"mean clear gap {fmt(s['mean_gap'], 1e6)} um "
        f"(edge speed {fmt(s['edge_velocity'], 1e3)} mm/s)",
        f"clusters       per frame on the track, size: number = {sizes}; alone "
        f"{fmt(s['track_singulated_fraction'], 100, '.1f')} %",
    ]
    if s.get("face_up_fraction") is not None:
        lines.append(f"orientation    face up {fmt(s['face_up_fraction'], 100, '.1f')} %, face down "
                     f"{fmt(s['face_down_fraction'], 100, '.1f')} %, on edge "
                     f"{fmt(s['on_edge_fraction'], 100, '.1f')} %; aligned with the track "
                     f"{fmt(s['aligned_fraction'], 100, '.1f')} %")
        if s.get("orientation_yield") is not None:
            lines.append(f"yield          {fmt(s['orientation_yield'], 100, '.1f')} % of the parts "
                         "delivered face up and aligned with the track (each part both)")
    return "\n".join(lines)


def run(args) -> int:
    from ..pictures.plots import singulation_figures
    from ..postproc.singulation import Singulation
    from ..results.reader import Result

    slips(("--gap", args.gap, "s"), ("--gap-distance", args.gap_distance, "m"),
          ("--tolerance", args.tolerance, "m"))
    folder = plot_folder(args.plot)
    with Result(args.result) as result:
        sg = Singulation(result, gap=args.gap, gap_distance=args.gap_distance,
                         tolerance=args.tolerance, start=args.start, end=args.end,
                         cluster_frames=args.cluster_frames).run()
        summary = sg.summary()
        figures = figures_written(singulation_figures(sg, folder)) if folder is not None else []
    reason = unmeasured(summary, ARRIVAL_KEYS)
    print_figures(summary, figures, args.json, table)
    return refuse(args.result, reason)
