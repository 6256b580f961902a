"""``vibrofeed params``: a deck's parameters with defaults and units."""

from __future__ import annotations

import json

DESCRIPTION = ("List the parameters a deck (or a feeder description's deck) declares, settable with "
               "`vibrofeed run -p NAME=VALUE`.")


def add_arguments(p) -> None:
    p.add_argument("deck", metavar="DECK",
                   help="deck file, a deck name from decks/, or a feeder description FEEDER.toml")
    p.add_argument("--json", action="store_true", help="print the parameters as JSON")


def run(args) -> int:
    from ..decks import Deck

    deck = Deck.find(args.deck)
    dotted = {name: alias for alias, name in deck.aliases.items()}  # a description's names
    rows = [(v.name, v.default, v.unit, v.description) for v in deck.tunables.values()]
    if args.json:
        print(json.dumps([dict(zip(("name", "default", "unit", "description"), r),
                               **({"dotted": dotted[r[0]]} if r[0] in dotted else {})) for r in rows],
                         indent=2))
        return 0
    print(f"{deck.name}: {deck.title}\n  ({deck.path})\n")
    if dotted:
        print("  (a feeder description: -p takes the dotted name in [brackets] too)\n")
    w = [max(len(str(r[i])) for r in rows) for i in range(3)]
    for name, default, unit, text in rows:
        alias = f" [{dotted[name]}]" if name in dotted else ""
        print(f"  {name:<{w[0]}}  {default:<{w[1]}}  {unit:<{w[2]}}  {text}{alias}")
    return 0
