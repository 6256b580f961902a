"""``vibrofeed run``: run a deck through LIGGGHTS into one H5MD result."""

from __future__ import annotations

import importlib
import shlex
import sys
import threading

from .numbers import real
from .options import add_deck_arguments, ranks

DESCRIPTION = ("Run a deck through LIGGGHTS and write one H5MD result file "
               "(OUT.h5, with the LIGGGHTS log next to it as OUT.log).")


def add_arguments(p) -> None:
    add_deck_arguments(p, "see `vibrofeed params DECK`")
    p.add_argument("-o", "--output", metavar="OUT.h5", help="result file (default: DECK.h5 here)")
    p.add_argument("-n", "--ranks", type=ranks, default=1, metavar="RANKS",
                   help="MPI ranks for LIGGGHTS (default 1)")
    p.add_argument("--reuse", action="store_true",
                   help="keep OUT.h5 if it is a complete run of the same deck, parameters and "
                        "vibrofeed version (same run id) instead of running again")
    p.add_argument("--target-error", type=real(), metavar="E",
                   help="a bulk feeder: stop as soon as the feed rate's relative error (as "
                        "`vibrofeed feedrate` reports it) is at or below E, in (0, 1), else at t_end")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def run(args) -> int:
    from ..decks import Deck
    from ..engine.runner import check_output, run_deck
    from ..parameters import parse_assignments
    from ..run_progress import RunProgress
    from .outputs import file_destination, written

    # The result's check and the summary import h5py and postproc (~0.04 s): load them
    # while the worker runs, not before it starts (an import thread would slow the start, GIL).
    deck = Deck.find(args.deck)
    params = parse_assignments(args.param)
    output = str(file_destination("-o", args.output or f"{deck.name}.h5", parents=True))
    check_output(deck, output, "-o" if args.output else "output")
    progress = RunProgress(deck.name, enabled=False if args.quiet else None)
    warm = threading.Thread(target=_import, args=("vibrofeed.results.check", "vibrofeed.run_summary"),
                            daemon=True)

    def on_event(event: dict) -> None:
        if warm.ident is None:  # the worker's first word: it has started
            warm.start()
        progress(event)

    try:
        result = run_deck(deck, params, output, ranks=args.ranks, on_event=on_event,
                          reuse=args.reuse, command=shlex.join(["vibrofeed"] + sys.argv[1:]),
                          target_error=args.target_error)
    finally:
        progress.close()
        # Joined on every way out: a run that fails at once would otherwise end the
        # interpreter mid-import in this thread, and Python can crash (SIGSEGV) doing so.
        if warm.ident is not None:
            warm.join()
    if result.reused:
        print(f"vibrofeed: kept {result.output}: a complete result of the same run "
              f"(run id {result.run_id[:12]}...)", file=sys.stderr)
    written(result.output)
    from ..run_summary import run_summary

    print(run_summary(result))
    return 0


def _import(*modules: str) -> None:
    for name in modules:
        importlib.import_module(name)
