"""``vibrofeed decks``: list the decks in decks/."""

from __future__ import annotations

DESCRIPTION = "List the decks of the project's decks/ folder (VIBROFEED_DECKS overrides it)."


def add_arguments(p) -> None:
    pass


def run(args) -> int:
    from ..decks import Deck, available, decks_dir
    from ..errors import DeckError

    names = available()
    if not names:
        raise DeckError(f"no decks in {decks_dir()}")
    width = max(map(len, names))
    for name in names:
        print(f"{name:<{width}}  {Deck.find(name).title}")
    return 0
