"""``vibrofeed prepare``: write a deck's per-run files for a run by hand."""

from __future__ import annotations

import re
import shlex
import sys
import tempfile
from pathlib import Path

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
    words = ["liggghts", "-in", str(deck.path), "-var", "deck_dir", str(deck.include_dir)]
    for name, value in extra.items():
        words += ["-var", name, value]
    for name in given:
        words += ["-var", name, values[name]]
    return shlex.join(words)


def _stamps(folder) -> dict:
    """name -> (inode, mtime) of the files in ``folder``: what a hook wrote or replaced."""
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in folder.iterdir() if p.is_file()}


def _inputs(deck, values: dict[str, str]) -> list[Path]:
    """The files a prepare reads: the deck and what it includes (a description, and the project
    deck it is made from), an stl part's STL and a mesh element's."""
    from ..decks import DECK_SUFFIX, decks_dir
    from ..engine.runner import deck_inputs

    files = list(deck_inputs(deck))  # (a description's included: its generated deck's)
    if deck.description is not None:
        files.append(decks_dir() / f"{deck.description.template}{DECK_SUFFIX}")
    return files + [Path(v) for k, v in values.items() if v and re.fullmatch(r"part_file|s\d+_file", k)]


def _names(deck, values: dict[str, str]) -> list[str]:
    """The files a prepare of ``deck`` with ``values`` writes, by a prepare into a scratch
    folder (cheap: meshes and templates), so that none replaces an input before it is read."""
    from ..decks import Deck

    with tempfile.TemporaryDirectory(prefix="vibrofeed-prepare-") as scratch:
        if deck.description is not None:
            deck = Deck.from_description(deck.description.path, Path(scratch))
        deck.prepare(values, scratch)
        return sorted(p.name for p in Path(scratch).iterdir())


def run(args) -> int:
    from ..decks import Deck
    from ..parameters import parse_assignments, resolve
    from .outputs import folder_destination, names_in, not_an_input, written

    deck = Deck.find(args.deck)
    given = parse_assignments(args.param)
    values = resolve(deck, given)
    folder = folder_destination("-o", args.output, parents=True)
    names = _names(deck, values)
    inputs = _inputs(deck, values)
    for name in names:
        not_an_input("-o", args.output, folder / name, inputs)
    names_in("-o", folder, names)
    before = _stamps(folder)
    if deck.description is not None:  # the generated deck goes with its meshes, to be run by hand
        deck = Deck.from_description(deck.description.path, folder.resolve())
        given = {deck.aliases.get(k, k): v for k, v in given.items()}
    prepared = deck.prepare(values, folder.resolve())
    extra = dict(prepared.variables) if prepared is not None else {}
    if prepared is None:
        print(f"vibrofeed: deck {deck.name} needs no prepared files; run it as it is:")
    else:
        after = _stamps(folder)
        new = sorted(name for name, stamp in after.items() if before.get(name) != stamp)
        for name in new:
            written(folder / name)
        print(f"vibrofeed: wrote {', '.join(new)} in {folder}")
    if values.get("shape") == "4":  # an stl part: its sizes are the STL's (resolve), and its clump's fidelity
        from ..stl_part import StlPart, fidelity_line

        given = {**given, **{n: values[n] for n in ("part_size", "part_width", "part_thickness")}}
        print(f"vibrofeed: stl part: {fidelity_line(StlPart.of(values))}")
    print(liggghts_line(deck, given, values, extra))
    if float(values.get("recirculate", 0) or 0):  # a line's returns are the driver's
        print("vibrofeed: note: recirculate=1 is done by `vibrofeed run` (it returns the rejects "
              "to the inlet); by hand the deck refuses it: run with -var recirculate 0 (rejects "
              "removed)", file=sys.stderr)
    return 0
