"""What several commands share: DECK and -p, the counts (-n RANKS, -j JOBS), --json and
--plot DIR, and how the analysis commands print their figures."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path


def count(what: str) -> Callable[[str], int]:
    """argparse type of a positive whole number of ``what`` (MPI ranks, jobs)."""
    def parse(text: str) -> int:
        import argparse

        try:
            n = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"must be a whole number of {what}, got {text or 'nothing'}") from None
        if n < 1:
            raise argparse.ArgumentTypeError(f"must be at least 1, got {n}")
        return n

    return parse


ranks = count("MPI ranks")
jobs = count("jobs")


def dispatched(args, serve: Callable, main: Callable) -> int:
    """A command whose runs spread over the ranks of an ``mpirun`` (sweep, optimize): ``-o``
    checked first; the other ranks ``serve(comm)`` until rank 0, running ``main(comm)`` (comm
    None without MPI), releases them."""
    from ..engine import batch

    comm = batch.world()
    if args.output is not None:
        from .outputs import folder_destination

        folder_destination("-o", args.output, create=False, parents=True)
    if comm is not None and comm.Get_rank() != 0:
        return serve(comm)
    try:
        return main(comm)
    finally:
        if comm is not None:
            batch.release(comm)


def no_effect(option: str, why: str) -> None:
    """One warning line for an option the command was given but will not use (the rest
    of the request is carried out): ``vibrofeed: warning: OPTION has no effect: WHY``."""
    import sys

    print(f"vibrofeed: warning: {option} has no effect: {why}", file=sys.stderr)


def slips(*options) -> None:
    """One warning line per option whose value looks like a unit slip: ``(option, value,
    unit)`` (:func:`vibrofeed.plausibility.option_advice`); the command goes on."""
    import sys

    from ..plausibility import option_advice

    for option, value, unit in options:
        line = option_advice(option, value, unit)
        if line:
            print(f"vibrofeed: warning: {line}", file=sys.stderr)


def add_deck_arguments(p, param_help: str) -> None:
    """DECK and -p NAME=VALUE, shared by the commands that run or prepare a deck."""
    p.add_argument("deck", metavar="DECK",
                   help="deck file, or a deck name from decks/ (see `vibrofeed decks`)")
    p.add_argument("-p", "--param", action="append", metavar="NAME=VALUE",
                   help=f"set a deck parameter (repeatable; {param_help})")


def add_output_arguments(p) -> None:
    """--json and --plot DIR, shared by the analysis commands."""
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--plot", metavar="DIR",
                   help="write the figures (PNG) into DIR (created if missing; its parent must exist)")


def plot_folder(path: str | None) -> Path | None:
    """The figures' folder of --plot DIR, checked before any work (see
    :func:`~vibrofeed.cli.outputs.folder_destination`); None without --plot."""
    from .outputs import folder_destination

    return None if path is None else folder_destination("--plot", path)


def figures_written(paths) -> list:
    """The figures a --plot wrote, each checked to exist and hold something."""
    from .outputs import written

    return [written(path) for path in paths]


def unmeasured(summary: dict, keys) -> str | None:
    """The summary's reason for measuring nothing (too few exits or arrivals), its
    ``keys`` set to None then; None when it measured."""
    reason = summary.get("reason")
    if reason:
        summary.update(dict.fromkeys(keys))
    return reason


def refuse(path, reason: str | None) -> int:
    """The exit status of an analysis: 1, with the reason on stderr, when it measured nothing."""
    if not reason:
        return 0
    import sys

    from ..errors import EXIT_FAILED

    print(f"vibrofeed: error: {path}: {reason}", file=sys.stderr)
    return EXIT_FAILED


def print_figures(summary: dict, figures: list, as_json: bool, table: Callable[[dict], str]) -> None:
    """An analysis command's output: the summary as JSON, or its table then the figures written."""
    if as_json:
        print(json.dumps(summary, indent=2))
    else:
        print(table(summary))
        for path in figures:
            print(f"figure: {path}")


def open_result(args):
    """``args.result`` opened for a command that takes ``--allow-incomplete``: a run that did
    not complete is refused with a pointer to the option (the library's message names none)."""
    from ..errors import IncompleteResult
    from ..results.reader import Result

    try:
        return Result(args.result, allow_incomplete=args.allow_incomplete)
    except IncompleteResult as exc:
        raise IncompleteResult(f"{exc}; --allow-incomplete reads the frames it holds") from None
