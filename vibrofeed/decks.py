"""Decks: LIGGGHTS input files in ``decks/`` and the tunables they declare.

A deck declares each tunable as an index variable with its unit and meaning
in a trailing comment::

    variable freq        index 50        # [Hz] vibration frequency

:class:`Deck` reads those declarations (the deck stays an ordinary LIGGGHTS
input file) and its header comment, and splits the deck into commands with
the file and line each starts on, so an engine error can be pinned to a deck
line. It follows the deck's ``include`` commands into the shared blocks of
``decks/include/`` (a path must start with ``${deck_dir}/`` or be absolute:
LIGGGHTS opens a relative path from its working directory, which is not the
deck's folder), so commands, formulas and sources cover every file a run
reads. Includes inside an ``if`` are not followed.

A deck that needs files made for each run (meshes, clump templates) declares a
prepare hook in its header::

    # vibrofeed prepare: vibrofeed.geometry:prepare_bulk_feeder

The runner calls it with the resolved parameters and the run's own folder
before LIGGGHTS starts (:meth:`Deck.prepare`); the hook returns the extra
``-var`` values, e.g. ``mesh_dir``. Such a deck may include generated files as
``include ${mesh_dir}/NAME``: they are not followed (they do not exist yet).
"""

from __future__ import annotations

import importlib
import os
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from .errors import DeckError, ParameterWarning

DECK_SUFFIX = ".liggghts"

# Set by vibrofeed itself (or its prepare hook, or for runs by hand only), never by a user's -p.
RESERVED = {"driver", "deck_dir", "dump_file", "mesh_dir", "outlet_file"}

_INDEX = re.compile(
    r"^\s*variable\s+(?P<name>\w+)\s+index\s+(?P<value>\S+)\s*(?:#\s*(?P<comment>.*))?$")
_EQUAL = re.compile(r"^variable\s+(?P<name>\w+)\s+equal\s+(?P<formula>.+)$")
_INCLUDE = re.compile(r"^include\s+(?P<path>\S+)$")
_REF = re.compile(r"\bv_(\w+)")
# What changes during a run: the clock, and the atom count and fix or compute values
_CLOCK = re.compile(r"\b(time|step|elapsed|elaplong|dt|atoms|[fc]_\w+)\b")
_UNIT = re.compile(r"^\[(?P<unit>[^\]]*)\]\s*(?P<text>.*)$")
_DECK_DIR = "${deck_dir}"
_PREPARE = re.compile(r"^#\s*vibrofeed prepare:\s*(?P<target>[\w.]+:\w+)\s*$")
_GENERATED_DIR = "${mesh_dir}/"  # files a prepare hook writes for each run
# A deck generated from a feeder description says so in its header (vibrofeed.feeders).
_GENERATED_FROM = re.compile(r"^# vibrofeed generated from: ", re.M)


def decks_dir() -> Path:
    """The folder holding the project's decks (``VIBROFEED_DECKS`` overrides).

    An installed package holds the repository's ``decks/`` folder as
    ``vibrofeed/_decks`` (package data, see pyproject.toml); in a source
    checkout (an editable install) it is ``decks/`` itself.
    """
    from . import environment

    given = environment.decks_dir()  # (a folder that does not exist is refused)
    if given is not None:
        return given
    here = Path(__file__).resolve().parent
    installed = here / "_decks"
    return installed if installed.is_dir() else here.parent / "decks"


def feeders_dir() -> Path:
    """The folder holding the example feeder descriptions: the repository's ``feeders/``
    (``vibrofeed/_feeders`` in an installed package, as decks_dir's)."""
    here = Path(__file__).resolve().parent
    installed = here / "_feeders"
    return installed if installed.is_dir() else here.parent / "feeders"


def available() -> list[str]:
    """Names of the decks in :func:`decks_dir` (its include/ blocks are not decks)."""
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
    file: Path | None = None  # the deck or the included file holding it


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


def split_commands(text: str, file: Path | None = None) -> list[Command]:
    """Commands of a deck as LIGGGHTS reads them: a line ending in '&' is joined
    to the next one as it is (no space added, indent kept), so a formula may be
    wrapped with '&' and an unindented continuation."""
    commands, buf, start = [], "", 0
    for number, raw in enumerate(text.splitlines(), start=1):
        line = strip_comment(raw).rstrip()
        if not buf:
            start = number
        if line.endswith("&"):
            buf += line[:-1]
            continue
        buf += line
        if buf.strip():
            commands.append(Command(start, normalize(buf), file))
        buf = ""
    if buf.strip():
        commands.append(Command(start, normalize(buf), file))
    return commands


def _shown(path: Path) -> str:
    """``path`` as an error message shows it: relative to the working directory
    when it is below it, else absolute."""
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def read_text(path: Path, what: str = "deck") -> str:
    """The text of a deck (or of a file it includes, ``what`` = "included
    file"); DeckError if it cannot be read or is not text."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise DeckError(f"cannot read {what} {path}: {exc.strerror}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        text = None
    if text is None or "\0" in text:
        noun = "deck" if what == "deck" else "file"
        raise DeckError(f"{path} is not a text {noun} (LIGGGHTS input files are UTF-8 text)")
    return text


class Deck:
    """A deck file, the files it includes, and the tunables it declares.

    Attributes: ``path``, ``name``, ``text`` (the deck's own text),
    ``sources`` (``{path relative to the deck's folder: text}`` of the deck and
    every file it includes, in the order LIGGGHTS reads them), ``commands``
    (every command in execution order, includes expanded, each with its file
    and line), ``variables`` (the tunables: the index variables the deck
    itself declares; included blocks only use them), ``formulas`` (equal-style
    variables defined as commands of their own, in the deck or a block; the
    first definition counts).
    """

    def __init__(self, path: str | os.PathLike, include_dir: str | os.PathLike | None = None):
        self.path = Path(path).resolve()
        self.text = read_text(Path(path))  # errors name the path as given
        self.name = self.path.stem
        # the folder ${deck_dir} names: the deck's own, or the project's decks for a deck
        # generated from a feeder description (which lives elsewhere)
        if include_dir is None and _GENERATED_FROM.search(self.text):
            include_dir = decks_dir()  # (a generated deck, wherever it is, uses the project's blocks)
        self.include_dir = Path(include_dir).resolve() if include_dir else self.path.parent
        self.description = None  # the feeder description it was generated from, if any
        self.aliases: dict[str, str] = {}  # other names of its tunables (a description's dotted ones)
        self.sources: dict[str, str] = {self.path.name: self.text}
        self.generated: list[str] = []  # includes of files the prepare hook writes
        self.formulas: dict[str, str] = {}
        self.commands = self._expand(self.path, self.text, (self.path,))
        self.variables = self.parse_variables(self.text)
        for c in self.commands:
            m = _EQUAL.match(c.text)
            if m and m["name"] not in self.formulas:
                self.formulas[m["name"]] = m["formula"]
        if not self.variables:
            raise DeckError(f"{self.path}: declares no tunables ('variable NAME index VALUE # [unit] ...')")

    @staticmethod
    def parse_variables(text: str) -> dict[str, Variable]:
        """The index variables ``text`` declares, with their units and meanings."""
        variables: dict[str, Variable] = {}
        for number, line in enumerate(text.splitlines(), start=1):
            m = _INDEX.match(line)
            if m and m["name"] not in variables:  # LIGGGHTS keeps an index variable's first value
                unit, description = "", (m["comment"] or "").strip()
                um = _UNIT.match(description)
                if um:
                    unit, description = um["unit"].strip(), um["text"].strip()
                variables[m["name"]] = Variable(m["name"], m["value"], unit, description, number)
        return variables

    def _expand(self, path: Path, text: str, chain: tuple[Path, ...]) -> list[Command]:
        """The commands of ``text`` (from ``path``) with its includes expanded."""
        out = []
        for cmd in split_commands(text, path):
            out.append(cmd)
            m = _INCLUDE.match(cmd.text)
            if not m:
                continue
            if m["path"].startswith(_GENERATED_DIR) and self.prepare_target:
                self.generated.append(m["path"])
                continue
            target = self._include_target(m["path"], cmd, path)
            if target in chain:
                raise DeckError(f"{_shown(path)}:{cmd.line}: {target.name} includes itself")
            key = self._relative(target)
            included = self.sources.get(key)
            if included is None:
                if not target.is_file():
                    raise DeckError(f"{_shown(path)}:{cmd.line}: included file {m['path']} "
                                    f"not found (looked for {target})")
                included = self.sources[key] = read_text(target, "included file")
            out.extend(self._expand(target, included, chain + (target,)))
        return out

    def _include_target(self, spec: str, cmd: Command, path: Path) -> Path:
        resolved = spec.replace(_DECK_DIR, str(self.include_dir))
        where = f"{_shown(path)}:{cmd.line}"
        if "$" in resolved:
            raise DeckError(f"{where}: cannot follow 'include {spec}': only {_DECK_DIR} is resolved "
                            "in an include path")
        if not spec.startswith(_DECK_DIR) and not Path(spec).is_absolute():
            raise DeckError(f"{where}: 'include {spec}': start the path with {_DECK_DIR}/ "
                            "(LIGGGHTS opens a relative path from its working directory)")
        return Path(resolved).resolve()

    def _relative(self, path: Path) -> str:
        """``path`` relative to the deck's folder (as in :attr:`sources`), else absolute."""
        for folder in (self.path.parent, self.include_dir):
            try:
                return path.relative_to(folder).as_posix()
            except ValueError:
                pass
        return str(path)

    @classmethod
    def find(cls, spec: str | os.PathLike) -> Deck:
        """A deck by path, or by name from the project's decks folder; a feeder description
        (FEEDER.toml, docs/feeders.md) becomes the deck that runs it."""
        p = Path(spec)
        if p.suffix == ".toml" and p.is_file():
            return cls.from_description(p)
        if p.is_file():
            return cls(p)
        candidate = decks_dir() / (p.name if p.suffix == DECK_SUFFIX else p.name + DECK_SUFFIX)
        if candidate.is_file() and len(p.parts) == 1:
            return cls(candidate)
        names = ", ".join(available()) or "none"
        raise DeckError(f"no deck {spec} (not a file; decks available by name: {names})")

    @classmethod
    def from_description(cls, path: str | os.PathLike, folder: Path | None = None) -> Deck:
        """The deck generated from the feeder description ``path`` (vibrofeed.feeders), written
        into ``folder`` (default: a cache folder named by its text's hash)."""
        from .feeders import description as fd

        described = fd.read(path)
        template = read_text(decks_dir() / f"{described.template}{DECK_SUFFIX}")
        text = fd.deck_text(described, template, cls.parse_variables(template))
        deck_path = fd.write_deck(text, fd.slug(described.name), folder)
        deck = cls(deck_path, include_dir=decks_dir())
        deck.description, deck.aliases = described, described.aliases
        return deck

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
    def prepare_target(self) -> str | None:
        """``module:function`` of the deck's prepare hook (a header line
        ``# vibrofeed prepare: module:function``), or None."""
        for line in self.text.splitlines():
            if not line.startswith("#"):
                break
            m = _PREPARE.match(line)
            if m:
                return m["target"]
        return None

    def prepare(self, values: Mapping[str, str], folder: str | os.PathLike):
        """Run the deck's prepare hook for one run: it writes its files into
        ``folder`` and returns a :class:`vibrofeed.geometry.Prepared` (None for a
        deck without a hook). ``values``: the resolved parameters."""
        target = self.prepare_target
        if target is None:
            return None
        module_name, _, function = target.partition(":")
        try:
            hook = getattr(importlib.import_module(module_name), function)
        except (ImportError, AttributeError) as exc:
            raise DeckError(f"{_shown(self.path)}: its prepare hook {target} cannot be loaded: "
                            f"{exc}") from None
        # The hook checks the feeder again (a refusal stops it), but its warnings were said
        # when the values were resolved, in the names the user gave: not said twice.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ParameterWarning)
            return hook(dict(values), Path(folder))

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

    def command_at(self, line: int, file: str | os.PathLike | None = None) -> Command | None:
        """The command starting at ``line`` of the deck, or of ``file`` (a path
        relative to the deck's folder, as in :attr:`sources`, or absolute)."""
        target = self.path if file is None else (self.path.parent / file).resolve()
        for c in self.commands:
            if c.line == line and c.file == target:
                return c
        return None

    def __repr__(self) -> str:
        return f"Deck({str(self.path)!r})"
