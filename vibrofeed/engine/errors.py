"""Engine failures as exceptions: what went wrong, and where in the deck.

LIGGGHTS reports an input error by printing ``ERROR: message (source:line)``
to its screen and log and ending the process. With ``-echo log`` the log also
holds every input line before it is executed, so the last deck command echoed
before the ERROR is the one that failed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..decks import Deck, normalize

_ERROR_START = re.compile(r"^ERROR(?: on proc (?P<proc>\d+))?:\s?(?P<text>.*)$")
_SOURCE_LOC = re.compile(r"\s*\((?:\./)?src/[^():]+:\d+\)\s*$|\s*\([\w./-]+\.(?:cpp|h):\d+\)\s*$")


class RunError(RuntimeError):
    """Base of the errors a run reports to its user (one line, no traceback).

    ``partial`` is ``(path, frames)`` when a failed run left frames behind.
    """

    partial: tuple | None = None


class EngineError(RunError):
    """LIGGGHTS stopped with an error.

    Attributes: ``message`` (LIGGGHTS' text), ``deck`` (path), ``line`` and
    ``command`` (the deck command that failed, when it is known), ``phase``
    (``deck``, ``setup`` or ``run``), ``step`` and ``time`` (of the last frame
    written before the error), ``log``.
    """

    def __init__(self, message: str, *, deck: str | None = None, line: int | None = None,
                 command: str | None = None, phase: str | None = None,
                 step: int | None = None, time: float | None = None, log: str | None = None):
        self.message, self.deck, self.line, self.command = message, deck, line, command
        self.phase, self.step, self.time, self.log = phase, step, time, log
        super().__init__(str(self))

    def __str__(self) -> str:
        where = ""
        if self.line is not None:
            where = f" at {self.deck}:{self.line}: {self.command}"
        elif self.phase == "run" and self.step is not None:
            where = f" during the run, after the frame at t = {self.time:.6g} s (step {self.step})"
        elif self.phase == "run":
            where = " during the run"
        elif self.phase == "setup":
            where = " while setting up the run"
        return f"LIGGGHTS error: {self.message}{where}"


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


def failed_command(log_text: str, deck: Deck, before: int | None = None):
    """The deck command echoed last before line index ``before`` of the log."""
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
