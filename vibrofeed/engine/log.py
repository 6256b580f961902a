"""Reading engine failures off LIGGGHTS' output: what went wrong, and where.

LIGGGHTS reports an input error by printing ``ERROR: message (source:line)``
to its screen and log and ending the process. With ``-echo log`` the log also
holds every input line before it is executed, the lines of included files
included, so the last deck command echoed before the ERROR is the one that
failed, and :attr:`Deck.commands <vibrofeed.decks.Deck>` (includes expanded,
each command with its file and line) says where it is written.

The exception classes live in :mod:`vibrofeed.errors`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..decks import Command, Deck, normalize

_ERROR_START = re.compile(r"^ERROR(?: on proc (?P<proc>\d+))?:\s?(?P<text>.*)$")
_SOURCE_LOC = re.compile(r"\s*\((?:\./)?src/[^():]+:\d+\)\s*$|\s*\([\w./-]+\.(?:cpp|h):\d+\)\s*$")


@dataclass
class LogError:
    message: str
    proc: int | None
    line_index: int  # index of the ERROR line in the log's lines


def find_error(log_text: str) -> LogError | None:
    """The first ERROR in a LIGGGHTS log or screen text, as one line of text."""
    lines = log_text.splitlines()
    for i, line in enumerate(lines):
        m = _ERROR_START.match(line)
        if not m:
            continue
        parts = [m["text"]]
        j = i
        # A message may run over several lines; it ends at the source location.
        while not _SOURCE_LOC.search(parts[-1]) and j + 1 < len(lines) and j - i < 20:
            j += 1
            if _ERROR_START.match(lines[j]) or not lines[j].strip():
                break
            parts.append(lines[j])
        text = " ".join(" ".join(parts).split())
        text = _SOURCE_LOC.sub("", text).strip()
        return LogError(text, int(m["proc"]) if m["proc"] else None, i)
    return None


def failed_command(log_text: str, deck: Deck, before: int | None = None) -> Command | None:
    """The deck command echoed last before line index ``before`` of the log.

    Log lines are matched in order against the deck's commands in execution
    order (a command inside an included file follows the ``include``), so a
    command written the same way in two places is told apart by where the
    echo has got to. ``Command.file`` and ``.line`` say where it is written.
    """
    lines = log_text.splitlines()[:before]
    commands = deck.commands
    cursor, last = 0, None
    for line in lines:
        text = normalize(line)
        if not text:
            continue
        for j in range(cursor, len(commands)):
            if commands[j].text == text:
                last, cursor = commands[j], j + 1
                break
    return last
