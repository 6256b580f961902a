"""``vibrofeed sweep-report``: a sweep's settings, its best one, and the feed-rate maps."""

from __future__ import annotations

import json

DESCRIPTION = ("Summarise a sweep folder (the -o DIR of `vibrofeed sweep`, read while it runs or "
               "after): one line per setting with its feed rate and singulation (mean over the "
               "replicates, standard error), the best setting, the failed jobs; --plot draws a "
               "feed-rate heat map over two varied parameters and the feed rate against one, with "
               "the singulated fraction beside it.")


def add_arguments(p) -> None:
    from .options import add_output_arguments

    p.add_argument("folder", metavar="DIR", help="a sweep's output folder (holding summary.h5)")
    add_output_arguments(p)


def run(args) -> int:
    from ..sweep.report import report, text
    from .options import figures_written, plot_folder

    rep = report(args.folder, plot_folder(args.plot))
    figures_written(rep.get("figures", ()))
    print(json.dumps(rep, indent=2) if args.json else text(rep))
    return 0
