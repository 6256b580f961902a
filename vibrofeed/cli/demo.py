"""``vibrofeed demo``: the main job — a bulk feeder, its feed rate and its singulation.

Runs the ``bulk_feeder`` deck at its defaults (hundreds of parts pre-filled
on a vibrating track, so feeding is steady at once), then prints the
feed-rate and singulation reports and writes the result, a picture of the
last frame and the plots into one folder.
"""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

DESCRIPTION = ("Run the default bulk-feeder case (hundreds of micro-parts on a vibrating track), then "
               "print its feed rate and singulation and write DIR/bulk_feeder.h5, a picture "
               "(DIR/bulk_feeder.png) and the plots (DIR/plots/).")
DECK = "bulk_feeder"


def add_arguments(p) -> None:
    from .run import ranks

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
    from ..progress import RunProgress
    from ..summary import run_summary
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
    from .feedrate import refuse

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
    from .outputs import written

    lines, figures = [], []
    with Result(path) as result:
        fr = FeedRate(result).run()
        summary = F.add_dilute_limit(fr.summary(), result.parameters)
        reason = F.unmeasured(summary, F.RATE_KEYS)
        sg = Singulation(result).run()
        singulation = sg.summary()
        reason = reason or F.unmeasured(singulation, S.ARRIVAL_KEYS)
        lines += ["", "Feed rate", F.table(summary), "", "Singulation", S.table(singulation)]
        if folder is not None:
            from ..pictures.render import render

            plots = folder / "plots"
            plots.mkdir(parents=True, exist_ok=True)
            figures += F.figures_written(fr.plot(plots) + sg.plot(plots))
            # The picture shows the middle of the steady window: the track full and feeding.
            picture = folder / f"{Path(path).stem}.png"
            t_mid = 0.5 * (summary["steady_from"] + summary["steady_to"])
            frame = int(abs(result.time - t_mid).argmin()) if t_mid == t_mid else -1
            figures.append(written(render(result, picture, frame=frame).path))
    lines += [f"figure: {f}" for f in figures]
    return "\n".join(lines), reason
