"""``vibrofeed run``: run a deck through LIGGGHTS into one H5MD result."""

from __future__ import annotations

import importlib
import shlex
import sys
import threading

DESCRIPTION = ("Run a deck through LIGGGHTS and write one H5MD result file "
               "(OUT.h5, with the LIGGGHTS log next to it as OUT.log).")


def ranks(text: str) -> int:
    """argparse type of -n: a positive whole number of MPI ranks."""
    import argparse

    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number of MPI ranks, got {text!r}") from None
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {n}")
    return n


def add_arguments(p) -> None:
    p.add_argument("deck", metavar="DECK",
                   help="deck file, or a deck name from decks/ (see `vibrofeed decks`)")
    p.add_argument("-p", "--param", action="append", metavar="NAME=VALUE",
                   help="set a deck parameter (repeatable; see `vibrofeed params DECK`)")
    p.add_argument("-o", "--output", metavar="OUT.h5", help="result file (default: DECK.h5 here)")
    p.add_argument("-n", "--ranks", type=ranks, default=1, metavar="RANKS",
                   help="MPI ranks for LIGGGHTS (default 1)")
    p.add_argument("--reuse", action="store_true",
                   help="keep OUT.h5 if it is a complete run of the same deck, parameters and "
                        "vibrofeed version (same run id) instead of running again")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def run(args) -> int:
    from ..decks import Deck
    from ..engine.runner import run_deck
    from ..parameters import parse_assignments
    from ..progress import RunProgress
    from .outputs import file_destination, written

    # The summary's analyses import scipy (~0.3 s): load them while the worker starts
    # and runs, not before (a short single-part run lasts about as long).
    warm = threading.Thread(target=importlib.import_module, args=("vibrofeed.summary",), daemon=True)
    warm.start()
    deck = Deck.find(args.deck)
    params = parse_assignments(args.param)
    output = str(file_destination("-o", args.output or f"{deck.name}.h5", parents=True))
    progress = RunProgress(deck.name, enabled=False if args.quiet else None)
    try:
        result = run_deck(deck, params, output, ranks=args.ranks, on_event=progress,
                          reuse=args.reuse, command=shlex.join(["vibrofeed"] + sys.argv[1:]))
    finally:
        progress.close()
    if result.reused:
        print(f"vibrofeed: kept {result.output}: a complete result of the same run "
              f"(run id {result.run_id[:12]}...)", file=sys.stderr)
    written(result.output)
    warm.join()
    from ..summary import run_summary

    print(run_summary(result))
    return 0
