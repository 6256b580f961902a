"""``vibrofeed params``: a deck's parameters with defaults and units."""

from __future__ import annotations

import json

DESCRIPTION = "List the parameters a deck declares (settable with `vibrofeed run -p NAME=VALUE`)."


def add_arguments(p) -> None:
    p.add_argument("deck", metavar="DECK", help="deck file, or a deck name from decks/")
    p.add_argument("--json", action="store_true", help="print the parameters as JSON")


def run(args) -> int:
    from ..decks import Deck

    deck = Deck.find(args.deck)
    rows = [(v.name, v.default, v.unit, v.description) for v in deck.tunables.values()]
    if args.json:
        print(json.dumps([dict(zip(("name", "default", "unit", "description"), r)) for r in rows],
                         indent=2))
        return 0
    print(f"{deck.name}: {deck.title}\n  ({deck.path})\n")
    w = [max(len(str(r[i])) for r in rows) for i in range(3)]
    for name, default, unit, text in rows:
        print(f"  {name:<{w[0]}}  {default:<{w[1]}}  {unit:<{w[2]}}  {text}")
    return 0
