"""``vibrofeed optimize-report``: a study's answer, convergence, Pareto front and importances."""

from __future__ import annotations

import json

DESCRIPTION = ("Summarise a study folder (the -o DIR of `vibrofeed optimize`, read while it runs or "
               "after): the best design with its confirmed value (fresh seeds) and robustness, the "
               "screen's counts and the DEM it saved, the design variables' importance; --plot "
               "draws the convergence (best against DEM runs), the Pareto front of two objectives "
               "and the importances.")


def add_arguments(p) -> None:
    from .options import add_output_arguments

    p.add_argument("folder", metavar="DIR", help="a study's output folder (holding study.json)")
    add_output_arguments(p)


def run(args) -> int:
    from ..optimize.report import report, text
    from ..values import to_json
    from .options import figures_written, plot_folder

    rep = report(args.folder, plot_folder(args.plot))
    figures_written(rep.get("figures", ()))
    if args.json:
        print(json.dumps(to_json({k: v for k, v in rep.items() if k != "figures"}), indent=2))
    else:
        print(text(rep))
    return 0
