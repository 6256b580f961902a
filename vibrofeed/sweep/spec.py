"""The sweep file: which deck, which parameters fixed and which varied.

::

    deck = "bulk_feeder"      # a deck name, or a deck file (relative to this file's folder)
    ranks_per_run = 1         # MPI ranks of each run
    replicates = 2            # runs per setting, with seeds seed, seed+1, ...
    description = "..."       # optional, free text
    target_error = 0.05       # optional: each run stops once its feed rate is this precise

    [fixed]                   # one value each, for every job
    t_end = 1.0

    [grid]                    # every combination (cartesian product) of these lists
    amp_n = [5e-5, 1e-4]
    phase = [0.0, 90.0]

    [zip.stroke]              # lists that vary together (equal lengths): one axis
    freq = [50, 100]
    amp_t = [2e-4, 5e-5]

    [[point]]                 # explicit settings: each [[point]] is one value of one more axis
    gate_width = 0
    [[point]]
    gate_width = 4.5e-4
    fill_to = 0.68

The jobs are the cartesian product of the axes (each ``[grid]`` key, each
``[zip.NAME]`` group, the list of ``[[point]]`` tables), in the order the file
gives them, times the replicates (innermost). A parameter may appear in one
place only. ``seed`` may be fixed (the base seed of the replicates) or varied
when ``replicates = 1``.

Everything is checked before anything runs, and a problem is reported with
the line of the file it is on (``tomllib`` keeps no positions, so
:func:`key_lines` finds each key's line in the text). The fingerprint is a
SHA-256 of the parsed content (comments, layout and key order within a table
do not change it), which ties an output folder to one sweep.
"""

from __future__ import annotations

import hashlib
import json
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError, said

TOP_KEYS = ("deck", "ranks_per_run", "replicates", "description", "target_error", "fixed", "grid",
            "zip", "point")
SECTIONS = ("fixed", "grid", "zip", "point")


@dataclass
class Axis:
    """One varied axis: its values are partial settings (name -> TOML value).

    ``kind``: ``grid`` (one key), ``zip`` (several keys varying together) or
    ``point`` (explicit settings, possibly of different keys)."""

    kind: str
    name: str
    keys: list[str]
    values: list[dict]


@dataclass
class SweepSpec:
    source: Path
    text: str
    data: dict
    deck: str
    ranks_per_run: int = 1
    replicates: int = 1
    description: str = ""
    fixed: dict = field(default_factory=dict)
    axes: list[Axis] = field(default_factory=list)
    lines: dict = field(default_factory=dict)  # key path (tuple) -> line number
    target_error: float | None = None  # a run stops at this relative feed-rate error

    @property
    def fingerprint(self) -> str:
        return fingerprint(self.data)

    @property
    def varied(self) -> list[str]:
        """The varied parameter names, in the order of the file."""
        out: list[str] = []
        for axis in self.axes:
            out += [k for k in axis.keys if k not in out]
        return out

    @property
    def parameters(self) -> list[str]:
        """Every parameter the file names: fixed, then varied."""
        return list(self.fixed) + [k for k in self.varied if k not in self.fixed]

    def line_of(self, *path) -> int | None:
        """The line of a key path (``("grid", "amp_n")``, ``("point", 1, "fill_to")``; a
        dotted name written as TOML's dotted key, ``("grid", "element.2.jet.delay")``, too)."""
        return KeyReader(self.source, self.lines).line(*path)

    def where(self, *path) -> str:
        """``FILE:LINE`` of a key path (``FILE`` when it cannot be placed)."""
        line = self.line_of(*path)
        return f"{self.source}:{line}" if line else str(self.source)

    def place(self, name: str) -> tuple:
        """The key path where parameter ``name`` is set."""
        if name in self.fixed:
            return ("fixed", name)
        for axis in self.axes:
            if name in axis.keys:
                if axis.kind == "grid":
                    return ("grid", name)
                if axis.kind == "zip":
                    return ("zip", axis.name, name)
                first = next(i for i, v in enumerate(axis.values) if name in v)
                return ("point", first, name)
        return ()


def fingerprint(data: dict) -> str:
    """SHA-256 of the canonical JSON of a parsed sweep file."""
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


# ---------------------------------------------------------------- line numbers
_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\[\]]+?)\s*(\]\]?)\s*(#.*)?$")
_PART = r"""(?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*')"""  # a bare or quoted key
_KEY = re.compile(rf"^\s*({_PART}(?:\s*\.\s*{_PART})*)\s*=(.*)$")


def _split_dotted(key: str) -> list[str]:
    """The parts of a dotted key (``a . "b.c"``: a, b.c): bare or quoted, whitespace
    around the dots ignored, as TOML reads them."""
    parts = re.findall(r"\"[^\"]*\"|'[^']*'|[^.\s\"']+", key)
    return [part[1:-1] if part[:1] in "\"'" else part for part in parts]


def _record(lines: dict[tuple, int], path: tuple, number: int) -> None:
    """``path`` is on line ``number``, and so are the tables of its prefixes that no line
    has named yet (``g.h = 1`` makes table ``g`` there)."""
    for k in range(1, len(path)):
        lines.setdefault(path[:k], number)
    lines[path] = number


def _open_brackets(value: str) -> int:
    """Net ``[`` minus ``]`` of a value outside strings and comments."""
    depth, quote = 0, None
    for ch in value:
        if quote:
            if ch == quote:
                quote = None
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            break
        elif ch == "[":
            depth += 1
        elif ch == "]":
            depth -= 1
    return depth


def key_lines(text: str) -> dict[tuple, int]:
    """Line number (1-based) of every table header and key of a TOML text,
    keyed by path: ``("grid",)``, ``("grid", "amp_n")``, ``("point", 0, "x")``
    (arrays of tables are indexed by occurrence). Values that span lines
    (arrays, multi-line strings) are skipped over."""
    lines: dict[tuple, int] = {}
    table: tuple = ()
    counts: dict[tuple, int] = {}
    depth, in_string = 0, None
    for number, raw in enumerate(text.splitlines(), start=1):
        if in_string:
            if raw.count(in_string) % 2 == 1:
                in_string = None
            continue
        if depth > 0:
            depth += _open_brackets(raw)
            continue
        header = _HEADER.match(raw)
        if header and not _KEY.match(raw):
            path = tuple(_split_dotted(header[2]))
            if header[1] == "[[":
                index = counts.get(path, 0)
                counts[path] = index + 1
                lines.setdefault(path, number)
                table = path + (index,)
            else:
                table = path
            _record(lines, table, number)
            continue
        key = _KEY.match(raw)
        if key:
            _record(lines, table + tuple(_split_dotted(key[1])), number)
            value = key[2]
            for quotes in ('"""', "'''"):
                if value.count(quotes) % 2 == 1:
                    in_string = quotes
            if not in_string:
                depth = max(_open_brackets(value), 0)
    return lines


# ---------------------------------------------------------------- parsing
def flat(table: dict, prefix: tuple = (), leaf: set | frozenset = frozenset()) -> list[tuple]:
    """(name, key path, value) of each value of ``table``. A TOML dotted key written bare
    (``element.2.jet.delay = [...]``) is read by TOML as nested tables: it is the one dotted
    name it spells (a feeder description's name), as the same key quoted is. A table whose
    keys are all in ``leaf`` is a value (a study's variable, ``{ low = .., high = .. }``)."""
    out = []
    for key, value in table.items():
        path = prefix + (key,)
        if isinstance(value, dict) and value and not set(value) <= leaf:
            out += flat(value, path, leaf)
        else:
            out.append((".".join(path), path, value))
    return out


def scalar(value) -> bool:
    return isinstance(value, int | float | str) and not isinstance(value, bool)


def read_file(path, what: str) -> str:
    """The text of a TOML file (a sweep file, a study file); InputError saying why not."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read {what} {path}: {getattr(exc, 'strerror', None) or exc}") from None


def load(path) -> SweepSpec:
    """Read and check a sweep file; InputError naming the line of a problem."""
    return parse(read_file(path, "sweep file"), Path(path))


class KeyReader:
    """What the steps of :func:`parse` share: the file's name and key lines, to name the
    line of a refusal, and which key sets each parameter (a parameter is set once)."""

    # where a parameter may be set, once (the refusal of a second place says it)
    ONCE = "a parameter is fixed, or in one grid list, zip group or the points"

    def __init__(self, source: Path, lines: dict[tuple, int]):
        self.source, self.lines = source, lines
        self.owner: dict[str, tuple] = {}  # parameter -> the key path that sets it

    def line(self, *key) -> int | None:
        """The line of a key path, or of its nearest table (a dotted name written as TOML's
        dotted key, ``("variables", "element.2.drive.amp_t")``, by its own line)."""
        if key and isinstance(key[-1], str) and "." in key[-1] and key not in self.lines:
            key = key[:-1] + tuple(key[-1].split("."))
        while key and key not in self.lines:
            key = key[:-1]
        return self.lines[key] if key else None

    def where(self, *key) -> str:
        line = self.line(*key)
        return f"{self.source}:{line}" if line else str(self.source)

    def fail(self, key: tuple, message: str):
        raise InputError(f"{self.where(*key)}: {message}")

    def claim(self, name: str, key: tuple) -> None:
        if name in self.owner:
            self.fail(key, f"parameter {name} is set twice (also at line "
                           f"{self.lines.get(self.owner[name], '?')}); "
                           f"{self.ONCE}")
        self.owner[name] = key

    def values_list(self, key: tuple, name: str, value) -> list:
        if not isinstance(value, list) or not value:
            self.fail(key, f"{name} must be a non-empty list of values, got {said(value)}")
        for v in value:
            if not scalar(v):
                self.fail(key, f"{name}: {said(v)} is not a number or a string")
        if len({json.dumps(v) for v in value}) != len(value):
            self.fail(key, f"{name} lists a value twice: {said(value)} (replicates repeat a setting)")
        return value


def parse_toml(text: str, source: Path) -> tuple[dict, KeyReader]:
    """(the parsed TOML, a reader that names the line of each key); InputError when not TOML."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{source}: not valid TOML: {exc}") from None
    return data, KeyReader(source, key_lines(text))


def target_error(data: dict, r: KeyReader) -> float | None:
    """The file's ``target_error`` (the feed rate's relative error a run stops at), or None."""
    target = data.get("target_error")
    if target is not None and (isinstance(target, bool) or not isinstance(target, int | float)
                               or not 0 < target < 1):
        r.fail(("target_error",), f"target_error must be a number in (0, 1) (the feed rate's "
                                  f"relative error a run stops at), got {said(target)}")
    return target


def parse(text: str, source: Path | str = "sweep.toml") -> SweepSpec:
    source = Path(source)
    data, r = parse_toml(text, source)
    lines = r.lines
    numbers = _top_level(data, r)
    fixed = _fixed(data, r)
    axes = _grid_axes(data, r) + _zip_axes(data, r) + _point_axes(data, r)
    if "seed" in r.owner and r.owner["seed"][0] != "fixed" and numbers["replicates"] > 1:
        r.fail(r.owner["seed"], "seed is varied and replicates > 1: replicates set the seeds "
                                "(seed, seed+1, ...); fix seed or set replicates = 1")
    target = target_error(data, r)
    return SweepSpec(source=source, text=text, data=data, deck=data["deck"].strip(),
                     ranks_per_run=numbers["ranks_per_run"], replicates=numbers["replicates"],
                     description=data.get("description", ""), fixed=fixed, axes=axes, lines=lines,
                     target_error=target)


def _top_level(data: dict, r: KeyReader) -> dict[str, int]:
    """Check the top-level keys, the deck and the sections' types; ranks_per_run and replicates."""
    for key in data:
        if key not in TOP_KEYS:
            r.fail((key,), f"unknown key {key}; a sweep file has {', '.join(TOP_KEYS)} "
                           "(deck parameters go in [fixed], [grid], [zip.NAME] or [[point]])")
    if "deck" not in data:
        r.fail((), "no deck: add deck = \"bulk_feeder\" (a deck name or file)")
    if not isinstance(data["deck"], str) or not data["deck"].strip():
        r.fail(("deck",), "deck must be a deck name or a file name (a string)")
    numbers = {}
    for key, default in (("ranks_per_run", 1), ("replicates", 1)):
        value = data.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            r.fail((key,), f"{key} must be a whole number >= 1, got {said(value)}")
        numbers[key] = value
    if not isinstance(data.get("description", ""), str):
        r.fail(("description",), "description must be a string")
    for key in SECTIONS:
        if key in data and not isinstance(data[key], dict if key != "point" else list):
            form = "[[point]] tables" if key == "point" else f"a table [{key}]"
            r.fail((key,), f"{key} must be {form}")
    return numbers


def _fixed(data: dict, r: KeyReader) -> dict:
    """The [fixed] parameters: one value each."""
    fixed = {}
    for name, path, value in flat(data.get("fixed", {})):
        if not scalar(value):
            r.fail(("fixed", *path), f"[fixed] {name} must be one number or string, got {said(value)} "
                                     "(lists of values go in [grid] or [zip.NAME])")
        r.claim(name, ("fixed", *path))
        fixed[name] = value
    return fixed


def _grid_axes(data: dict, r: KeyReader) -> list[Axis]:
    """One axis per [grid] list."""
    axes = []
    for name, path, value in flat(data.get("grid", {})):
        key = ("grid", *path)
        r.claim(name, key)
        axes.append(Axis("grid", name, [name], [{name: v} for v in r.values_list(key, name, value)]))
    return axes


def _zip_axes(data: dict, r: KeyReader) -> list[Axis]:
    """One axis per [zip.NAME] group: its lists, of equal lengths, vary together."""
    axes = []
    for group, table in data.get("zip", {}).items():
        if not isinstance(table, dict) or not table:
            r.fail(("zip", group), f"zip.{group} must be a table of lists: [zip.{group}] then name = [...]")
        length = None
        columns = {}
        for name, path, value in flat(table):
            key = ("zip", group, *path)
            r.claim(name, key)
            columns[name] = r.values_list(key, f"zip.{group}.{name}", value)
            if length is not None and len(value) != length:
                r.fail(key, f"zip.{group}: {name} has {len(value)} values, the lists before it "
                            f"{length}; lists that vary together need equal lengths")
            length = len(value)
        rows = [{name: columns[name][i] for name in columns} for i in range(length)]
        if len({json.dumps(row, sort_keys=True) for row in rows}) != len(rows):
            r.fail(("zip", group), f"zip.{group} lists a setting twice")
        axes.append(Axis("zip", group, list(columns), rows))
    return axes


def _point_axes(data: dict, r: KeyReader) -> list[Axis]:
    """The [[point]] tables, explicit settings: one axis, or none without them."""
    points = data.get("point", [])
    if not points:
        return []
    keys: list[str] = []
    settings = []
    for i, point in enumerate(points):
        if not isinstance(point, dict) or not point:
            r.fail(("point", i), "each [[point]] must set at least one parameter")
        setting = {}
        for name, path, value in flat(point):
            if not scalar(value):
                r.fail(("point", i, *path), f"[[point]] {name} must be one number or string, "
                                            f"got {said(value)}")
            if name not in keys:  # first [[point]] naming it
                r.claim(name, ("point", i, *path))
                keys.append(name)
            setting[name] = value
        settings.append(setting)
    if len({json.dumps(p, sort_keys=True) for p in settings}) != len(settings):
        r.fail(("point",), "two [[point]] tables are the same setting")
    return [Axis("point", "point", keys, settings)]


def describe_change(old: dict, new: dict) -> str:
    """What differs between two parsed sweep files, as ``key.path`` names."""
    def flat(d, prefix=""):
        out = {}
        for k, v in d.items():
            name = f"{prefix}{k}"
            if isinstance(v, dict):
                out.update(flat(v, name + "."))
            else:
                out[name] = v
        return out

    def same(k):  # as the fingerprint compares them: 1 and 1.0 (or true) differ
        return k in a and k in b and json.dumps(a[k], sort_keys=True) == json.dumps(b[k], sort_keys=True)

    a, b = flat(old), flat(new)
    changed = sorted(k for k in a.keys() | b.keys() if not same(k))
    shown = ", ".join(changed[:6]) + (f" and {len(changed) - 6} more" if len(changed) > 6 else "")
    return shown or "its content"
