"""``vibrofeed demo``: the main job — a bulk feeder, its feed rate and its singulation.

Runs the ``bulk_feeder`` deck at its defaults (hundreds of parts pre-filled
on a vibrating track, so feeding is steady at once), then prints the
feed-rate and singulation reports and writes the result, a picture of the
last frame of the steady feeding window and the plots into one folder.
"""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

DESCRIPTION = ("Run the default bulk-feeder case (hundreds of micro-parts on a vibrating track), then "
               "print its feed rate and singulation and write DIR/bulk_feeder.h5, a picture of the "
               "last frame of the steady feeding window (DIR/bulk_feeder.png) and the plots (DIR/plots/).")
DECK = "bulk_feeder"


def add_arguments(p) -> None:
    from .options import ranks

    p.add_argument("-o", "--output", default="results", metavar="DIR",
                   help="folder for the result, the picture and the plots (default: results)")
    p.add_argument("-p", "--param", action="append", metavar="NAME=VALUE",
                   help="change a parameter of the default case (see `vibrofeed params bulk_feeder`)")
    p.add_argument("-n", "--ranks", type=ranks, default=1, metavar="RANKS",
                   help="MPI ranks for LIGGGHTS (default 1)")
    p.add_argument("--reuse", action="store_true",
                   help="keep DIR/bulk_feeder.h5 if it is a complete run of the same case")
    p.add_argument("--no-pictures", action="store_true", help="skip the picture and the plots")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def run(args) -> int:
    from ..decks import Deck
    from ..engine.runner import run_deck
    from ..parameters import parse_assignments
    from ..run_progress import RunProgress
    from ..run_summary import run_summary
    from .outputs import folder_destination, written

    folder = folder_destination("-o", args.output, create=False, parents=True)
    deck = Deck.find(DECK)
    params = parse_assignments(args.param)
    output = folder / f"{DECK}.h5"
    progress = RunProgress(DECK, enabled=False if args.quiet else None)
    try:
        result = run_deck(deck, params, output, ranks=args.ranks, on_event=progress,
                          reuse=args.reuse, command=shlex.join(["vibrofeed"] + sys.argv[1:]))
    finally:
        progress.close()
    written(result.output)
    print(run_summary(result))
    from .options import refuse

    text, reason = report(output, None if args.no_pictures else folder)
    print(text)
    return refuse(output, reason)


def report(path, folder: Path | None = None) -> tuple[str, str | None]:
    """The feed-rate and singulation reports of a bulk result, and why they measure
    nothing (too few exits; None when they measure); with ``folder``, also its
    picture (folder/<name>.png) and plots (folder/plots/)."""
    from ..postproc.feedrate import FeedRate
    from ..postproc.singulation import Singulation
    from ..results.reader import Result
    from . import feedrate as F
    from . import singulation as S
    from .options import figures_written, unmeasured
    from .outputs import written

    lines, figures = [], []
    with Result(path) as result:
        fr = FeedRate(result).run()
        summary = fr.summary()
        reason = unmeasured(summary, F.RATE_KEYS)
        sg = Singulation(result).run()
        singulation = sg.summary()
        reason = reason or unmeasured(singulation, S.ARRIVAL_KEYS)
        lines += ["", "Feed rate", F.table(summary), "", "Singulation", S.table(singulation)]
        if folder is not None:
            from ..pictures.plots import feedrate_figures, singulation_figures
            from ..pictures.render import render

            plots = folder / "plots"
            plots.mkdir(parents=True, exist_ok=True)
            figures += figures_written(feedrate_figures(fr, plots) + singulation_figures(sg, plots))
            picture = folder / f"{Path(path).stem}.png"
            frame = picture_frame(result.time, summary["steady_to"])
            figures.append(written(render(result, picture, frame=frame).path))
    lines += [f"figure: {f}" for f in figures]
    return "\n".join(lines), reason


def picture_frame(times, steady_to: float) -> int:
    """The frame the demo draws: the last one of the steady window (the track still
    feeding, as late as the measured rate holds); the last frame without a window."""
    import numpy as np

    k = int(np.searchsorted(times, steady_to + 1e-12, side="right")) - 1
    return k if np.isfinite(steady_to) and k >= 0 else -1
