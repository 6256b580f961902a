"""Decks: LIGGGHTS input files in ``decks/`` and the tunables they declare.

A deck declares each tunable as an index variable with its unit and meaning
in a trailing comment::

    variable freq        index 50        # [Hz] vibration frequency

:class:`Deck` reads those declarations (the deck stays an ordinary LIGGGHTS
input file) and its header comment, and splits the deck into commands with
the line each starts on, so an engine error can be pinned to a deck line.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

DECK_SUFFIX = ".liggghts"

# Set by vibrofeed itself, never by a user's -p.
RESERVED = {"driver", "deck_dir", "dump_file"}

_INDEX = re.compile(
    r"^\s*variable\s+(?P<name>\w+)\s+index\s+(?P<value>\S+)\s*(?:#\s*(?P<comment>.*))?$")
_EQUAL = re.compile(r"^\s*variable\s+(?P<name>\w+)\s+equal\s+(?P<formula>.*)$")
_REF = re.compile(r"\bv_(\w+)")
_CLOCK = re.compile(r"\b(time|step|elapsed|elaplong|dt)\b")
_UNIT = re.compile(r"^\[(?P<unit>[^\]]*)\]\s*(?P<text>.*)$")


class DeckError(ValueError):
    """A deck cannot be found or does not follow the deck conventions."""


def decks_dir() -> Path:
    """The folder holding the project's decks (``VIBROFEED_DECKS`` overrides)."""
    env = os.environ.get("VIBROFEED_DECKS")
    if env:
        return Path(env)
    return Path(__file__).resolve().parent.parent / "decks"


def available() -> list[str]:
    return sorted(p.stem for p in decks_dir().glob(f"*{DECK_SUFFIX}"))


@dataclass(frozen=True)
class Variable:
    name: str
    default: str
    unit: str
    description: str
    line: int

    @property
    def is_numeric(self) -> bool:
        try:
            float(self.default)
        except ValueError:
            return False
        return True


@dataclass(frozen=True)
class Command:
    line: int  # 1-based line where the command starts
    text: str  # joined continuation lines, comment stripped, whitespace collapsed


def strip_comment(line: str) -> str:
    """Drop a trailing # comment unless the # is inside quotes."""
    quote = None
    for i, ch in enumerate(line):
        if ch in "\"'" and quote in (None, ch):
            quote = None if quote else ch
        elif ch == "#" and quote is None:
            return line[:i]
    return line


def normalize(command: str) -> str:
    return " ".join(strip_comment(command).split())


def split_commands(text: str) -> list[Command]:
    """Commands of a deck as LIGGGHTS reads them ('&' joins lines)."""
    commands, buf, start = [], "", 0
    for number, raw in enumerate(text.splitlines(), start=1):
        line = strip_comment(raw).rstrip()
        if not buf:
            start = number
        if line.endswith("&"):
            buf += line[:-1] + " "
            continue
        buf += line
        if buf.strip():
            commands.append(Command(start, normalize(buf)))
        buf = ""
    if buf.strip():
        commands.append(Command(start, normalize(buf)))
    return commands


class Deck:
    """A deck file and the tunables it declares."""

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path).resolve()
        try:
            self.text = self.path.read_text()
        except OSError as exc:
            raise DeckError(f"cannot read deck {path}: {exc.strerror}") from exc
        self.name = self.path.stem
        self.variables: dict[str, Variable] = {}
        self.formulas: dict[str, str] = {}  # equal-style variables defined at line start
        for number, line in enumerate(self.text.splitlines(), start=1):
            m = _INDEX.match(line)
            if m:
                unit, description = "", (m["comment"] or "").strip()
                um = _UNIT.match(description)
                if um:
                    unit, description = um["unit"].strip(), um["text"].strip()
                self.variables[m["name"]] = Variable(m["name"], m["value"], unit, description, number)
                continue
            m = _EQUAL.match(strip_comment(line))
            if m and m["name"] not in self.formulas:
                self.formulas[m["name"]] = m["formula"].strip()
        if not self.variables:
            raise DeckError(f"{self.path}: declares no tunables ('variable NAME index VALUE # [unit] ...')")
        self.commands = split_commands(self.text)

    @classmethod
    def find(cls, spec: str | os.PathLike) -> "Deck":
        """A deck by path, or by name from the project's decks folder."""
        p = Path(spec)
        if p.is_file():
            return cls(p)
        candidate = decks_dir() / (p.name if p.suffix == DECK_SUFFIX else p.name + DECK_SUFFIX)
        if candidate.is_file() and len(p.parts) == 1:
            return cls(candidate)
        names = ", ".join(available()) or "none"
        raise DeckError(f"no deck {str(spec)!r} (not a file; decks available by name: {names})")

    @property
    def header(self) -> str:
        """The leading comment block, without the '#' marks."""
        lines = []
        for line in self.text.splitlines():
            if not line.startswith("#"):
                break
            lines.append(line[1:].removeprefix(" "))
        return "\n".join(lines).strip()

    @property
    def title(self) -> str:
        """First sentence of the header's description paragraph."""
        paragraphs = [p for p in self.header.split("\n\n") if p.strip()]
        body = paragraphs[1] if len(paragraphs) > 1 else (paragraphs[0] if paragraphs else "")
        return " ".join(body.split()).split(". ")[0].rstrip(".")

    @property
    def constants(self) -> list[str]:
        """Equal-style variables that do not change during a run: those whose
        formula never reaches ``time`` or ``step``, directly or through other
        variables. Their values are worth recording once per run."""
        clock: dict[str, bool] = {}

        def depends(name: str, seen: frozenset = frozenset()) -> bool:
            if name not in clock:
                formula = self.formulas.get(name, "")
                refs = [r for r in _REF.findall(formula) if r in self.formulas and r not in seen]
                clock[name] = bool(_CLOCK.search(formula)) or any(
                    depends(r, seen | {name}) for r in refs)
            return clock[name]

        return [name for name in self.formulas if not depends(name)]

    @property
    def tunables(self) -> dict[str, Variable]:
        """The variables a user may set (reserved ones excluded)."""
        return {k: v for k, v in self.variables.items() if k not in RESERVED}

    def command_at(self, line: int) -> Command | None:
        for c in self.commands:
            if c.line == line:
                return c
        return None

    def __repr__(self) -> str:
        return f"Deck({str(self.path)!r})"
