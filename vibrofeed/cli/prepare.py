"""``vibrofeed prepare``: write a deck's per-run files for a run by hand."""

from __future__ import annotations

import shlex

from .options import add_deck_arguments

DESCRIPTION = ("Write the files a deck needs for a run (e.g. the bulk feeder's track mesh and clump "
               "templates) into DIR, as `vibrofeed run` does in its own folder, and print the "
               "`liggghts -in` line that runs the deck by hand with them.")


def add_arguments(p) -> None:
    add_deck_arguments(p, "the geometry depends on them")
    p.add_argument("-o", "--output", metavar="DIR", required=True,
                   help="folder for the files (created if missing)")


def liggghts_line(deck, given: dict[str, str], values: dict[str, str], extra: dict[str, str]) -> str:
    """The command that runs ``deck`` by hand with the parameters the user gave
    (as the run would resolve them) and the prepared ``-var`` values."""
    words = ["liggghts", "-in", str(deck.path), "-var", "deck_dir", str(deck.path.parent)]
    for name, value in extra.items():
        words += ["-var", name, value]
    for name in given:
        words += ["-var", name, values[name]]
    return shlex.join(words)


def run(args) -> int:
    from pathlib import Path

    from ..decks import Deck
    from ..errors import OutputError
    from ..parameters import parse_assignments, resolve

    deck = Deck.find(args.deck)
    given = parse_assignments(args.param)
    values = resolve(deck, given)
    folder = Path(args.output).expanduser()
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"{args.output} exists and is not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create folder {args.output}: {exc.strerror}") from None
    prepared = deck.prepare(values, folder.resolve())
    extra = dict(prepared.variables) if prepared is not None else {}
    if prepared is None:
        print(f"vibrofeed: deck {deck.name} needs no prepared files; run it as it is:")
    else:
        written = ", ".join(sorted(p.name for p in folder.iterdir()))
        print(f"vibrofeed: wrote {written} in {folder}")
    print(liggghts_line(deck, given, values, extra))
    return 0
