"""A feeder description: a TOML file naming the parts, their supply and the elements in
conveying order (docs/feeders.md), and the deck it becomes.

A description is read once (:func:`load`): every key is checked against the vocabulary
below (an unknown or misspelled key is a one-line error naming its table and the key it
was probably meant to be), and its numbers become the deck's parameters
(:attr:`Description.values`). Each number also has a dotted name (``element.3.drive.amp_n``,
``parts.size``: :attr:`Description.aliases`) that ``-p``, sweeps and studies take beside the
deck's own name (``s3_amp_n``). :func:`deck_text` writes the deck that runs it: the
project deck of its first element (decks/bulk_feeder.liggghts for a linear section,
decks/bowl_feeder.liggghts for a bowl) with the description's numbers as its defaults and
every further element's tunables declared, so that ``liggghts -in`` runs it as it runs the
project's decks.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import math
import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from .. import stl_part
from ..errors import ParameterError
from ..orientation import correct_word
from . import mesh_element
from .kinds import KINDS
from .linear import MAX_SECTIONS, keep_word
from .records import JET_MODES, SHAPES, shape_code

SUFFIX = ".toml"
ELEMENT_KINDS = tuple(KINDS)
# The deck a description becomes: the project deck its first element's kind runs on.
TEMPLATES = {name: kind.template for name, kind in KINDS.items() if kind.template}
# table -> {key: deck name}; the element's keys are vibrofeed.feeders.linear.KEYS
TABLES: dict[str, dict[str, str]] = {
    "feeder": {"incline": "incline"},
    "parts": {"shape": "shape", "size": "part_size", "thickness": "part_thickness", "width": "part_width",
              "bump_height": "bump_height", "bump_diameter": "bump_diameter", "bump_at": "bump_at",
              "clump_spacing": "clump_spacing",
              "file": "part_file", "unit": "part_unit", "method": "clump_method", "spheres": "clump_spheres",
              "resolution": "clump_resolution", "overlap": "clump_overlap",
              "size_spread": "size_spread", "density": "density", "youngs": "youngs",
              "poisson": "poisson", "restitution": "restitution", "restitution_pp": "restitution_pp",
              "mu": "mu", "mu_pp": "mu_pp", "rolling_friction": "rolling_friction",
              "surface_energy": "surface_energy", "surface_energy_pp": "surface_energy_pp",
              "hamaker": "hamaker", "roughness": "roughness", "air_viscosity": "air_viscosity",
              "correct": "correct"},
    "surface": {"youngs": "youngs_track", "poisson": "poisson_track"},
    "supply": {k: k for k in ("n_parts", "fill_from", "fill_to", "inlet_rate", "inlet_batch",
                              "recirculate", "return_delay", "n_track")},
    "run": {k: k for k in ("t_end", "t_settle", "output_dt", "dt", "dt_unchecked", "seed", "skin")},
}
TEXT_KEYS = {"feeder": ("name", "description")}  # words, not numbers
_TUNABLES = "# ------------------------------------------------------------------ tunables"
_LINE = "# ------------------------------------------------------------------ line"
_REFUSALS = "# ------------------------------------------------------------------ refusals"


@dataclass
class Description:
    """A feeder description read from ``path``: its ``name``, ``text`` (what it says it is),
    ``sections`` (linear sections), ``values`` (the deck's parameters it sets, as strings),
    ``aliases`` (dotted name -> deck name, for every number it may set) and ``source`` (the
    file's text)."""

    path: Path
    name: str
    text: str
    sections: int
    kinds: list[str] = field(default_factory=list)

    @property
    def template(self) -> str:
        """The project deck the description's deck is made from (its first element's kind)."""
        return TEMPLATES[self.kinds[0]]
    values: dict[str, str] = field(default_factory=dict)
    aliases: dict[str, str] = field(default_factory=dict)
    source: str = ""


def _toml(value) -> str:
    """A value as TOML writes it (a message cites the line the user wrote)."""
    return json.dumps(value, ensure_ascii=False, default=str)


def _fail(path: Path, message: str) -> ParameterError:
    return ParameterError(f"{path.name}: {message}")


def _unknown(path: Path, where: str, key: str, known) -> ParameterError:
    close = difflib.get_close_matches(key, list(known), n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return _fail(path, f"unknown key {key!r} in {where}{hint}; keys there: {', '.join(known)}")


def _value(path: Path, dotted: str, value) -> str:
    """A description's number (a shape's name, what is correct: words) as the deck's string."""
    if dotted == "parts.correct":  # words: what counts as correctly oriented
        if not isinstance(value, str):
            raise _fail(path, f"{dotted} = {_toml(value)} must be text, e.g. \"up, lengthwise\"")
        try:
            return correct_word(value, dotted)
        except ParameterError as exc:
            raise _fail(path, str(exc)) from None
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, int | float):
        if isinstance(value, float) and not math.isfinite(value):
            raise _fail(path, f"{dotted} = {value} is not finite")
        return repr(value) if isinstance(value, float) else str(value)
    if dotted.endswith(".jet.keep") or dotted.endswith(".jet.mode"):  # words (linear.WORDS)
        return _jet_word(path, dotted, value)
    if isinstance(value, str) and dotted == "parts.shape":  # the deck's code: LIGGGHTS compares numbers
        try:
            return str(shape_code(value))
        except ParameterError as exc:
            raise _fail(path, f"parts.{exc}".replace("parameter ", "")) from None
    raise _fail(path, f"{dotted} = {_toml(value)} must be a number")


def _jet_word(path: Path, dotted: str, value) -> str:
    """A jet's keep (parse_correct's words) or mode as the deck's word (no blanks)."""
    if not isinstance(value, str):
        raise _fail(path, f"{dotted} = {_toml(value)} must be text")
    if dotted.endswith(".keep"):
        try:
            return keep_word(value)
        except ParameterError as exc:
            raise _fail(path, str(exc).replace("jet.keep", dotted, 1)) from None
    if value.strip().lower() not in JET_MODES:
        raise _fail(path, f"{dotted} = {_toml(value)} must be {' or '.join(map(_toml, JET_MODES))}")
    return value.strip().lower()


def aliases(kinds: list[str]) -> dict[str, str]:
    """Every dotted name of a description whose elements are of ``kinds``, and its deck name."""
    out = {f"{table}.{key}": name for table, keys in TABLES.items() for key, name in keys.items()}
    for k, kind in enumerate(kinds, start=1):
        out.update({f"element.{k}." + ".".join(key): name
                    for key, name in KINDS[kind].keys(k)[1].items()})
    return out


def read(path: str | os.PathLike, text: str | None = None) -> Description:
    """The description in ``path`` (its ``text`` if given), checked key by key."""
    path = Path(path)
    if text is None:
        try:
            text = path.read_text()
        except (OSError, UnicodeDecodeError) as exc:
            raise ParameterError(f"cannot read feeder description {path}: "
                                 f"{getattr(exc, 'strerror', None) or exc}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _fail(path, f"not valid TOML: {exc}") from None
    values: dict[str, str] = {}
    for table, body in data.items():
        if table == "element":
            continue
        if table not in TABLES:
            raise _unknown(path, "the description", table, [*TABLES, "element"])
        if not isinstance(body, dict):
            raise _fail(path, f"{table} must be a table ([{table}])")
        keys = TABLES[table]
        for key, value in body.items():
            if key in TEXT_KEYS.get(table, ()):
                if not isinstance(value, str):
                    raise _fail(path, f"{table}.{key} must be text")
                continue
            if key not in keys:
                raise _unknown(path, f"[{table}]", key, [*TEXT_KEYS.get(table, ()), *keys])
            if table == "parts" and key in PART_WORDS:
                values[keys[key]] = _part_word(path, key, value)
                continue
            values[keys[key]] = _value(path, f"{table}.{key}", value)
    if values.get("shape") == str(SHAPES["stl"]):
        derived = [k for k in ("size", "width", "thickness", "clump_spacing") if k in data["parts"]]
        if derived:
            raise _fail(path, f"parts.{derived[0]}: an stl part's sizes are its STL's (its principal "
                              "extents); leave it out")
        if "file" not in data["parts"]:
            raise _fail(path, "parts.shape = \"stl\" needs parts.file, the part's STL")
    elif any(k in data.get("parts", {}) for k in PART_WORDS):
        key = next(k for k in PART_WORDS if k in data["parts"])
        raise _fail(path, f"parts.{key} shapes an stl part: give parts.shape = \"stl\"")
    if "correct" in data.get("parts", {}) and values.get("shape", "0") == str(SHAPES["sphere"]):
        raise _fail(path, "parts.correct: spheres have no orientation; correct is for chips, discs, "
                          "boxes and stl parts (parts.shape)")
    elements = data.get("element")
    if not isinstance(elements, list) or not elements or not all(isinstance(e, dict) for e in elements):
        raise _fail(path, "a feeder needs its elements, in conveying order: one [[element]] table each")
    if len(elements) > MAX_SECTIONS:
        raise _fail(path, f"{len(elements)} elements: at most {MAX_SECTIONS} in this version")
    for k, element in enumerate(elements, start=1):
        values.update(_element(path, k, element))
    values["sections"] = str(len(elements))
    kinds = [e["kind"] for e in elements]
    feeder = data.get("feeder", {})
    return Description(path=path, name=feeder.get("name", path.stem),
                       text=feeder.get("description", ""), sections=len(elements), kinds=kinds,
                       values=values, aliases=aliases(kinds), source=text)


def _element(path: Path, k: int, element: dict) -> dict[str, str]:
    """Element ``k``'s numbers as the deck's parameters."""
    where = f"element {k}"
    kind = element.get("kind")
    if kind not in ELEMENT_KINDS:
        raise _fail(path, f"{where}: kind = {_toml(kind)}: this version builds "
                          f"{', '.join(ELEMENT_KINDS[:-1])} and {ELEMENT_KINDS[-1]} elements")
    if k == 1 and kind not in TEMPLATES:
        raise _fail(path, f"{where}: kind = {_toml(kind)}: the first element is a linear section or a "
                          "bowl (the supply falls onto it)")
    if k > 1 and not KINDS[kind].later:
        raise _fail(path, f"{where}: kind = {_toml(kind)}: a {kind} is the first element (the supply's "
                          "store); elements after it are its exit line")
    known, names = KINDS[kind].keys(k)
    singles = [key[0] for key in known if len(key) == 1]
    tables = sorted({key[0] for key in known if len(key) == 2})
    code = KINDS[kind].code
    out = {f"s{k}_kind": str(code)} if code else {}  # (a linear section's 0 is the default)
    for key, value in element.items():
        if key == "kind":
            continue
        if kind == "mesh" and key in mesh_element.NOT_HERE:
            raise _fail(path, f"{where}: {key}: {mesh_element.NOT_HERE[key]}")
        if isinstance(value, dict):
            if key not in tables:
                raise _unknown(path, where, key, singles + tables)
            for sub, x in value.items():
                full = (key, sub)
                if full not in known:
                    raise _unknown(path, f"{where}'s {key}", sub, [k[1] for k in known if k[0] == key
                                                                    and len(k) == 2])
                if full not in names:
                    raise _fail(path, f"{where}: {key}.{sub}: {_not_here(k, full)}")
                out[names[full]] = _value(path, f"element.{k}.{key}.{sub}", x)
            continue
        if (key,) not in known:
            raise _unknown(path, where, key, singles + tables)
        if (key,) not in names:
            raise _fail(path, f"{where}: {key}: {_not_here(k, (key,))}")
        if kind == "mesh" and key in ("file", "unit", "path"):
            out[names[(key,)]] = _mesh_word(path, k, key, value)
            continue
        out[names[(key,)]] = _value(path, f"element.{k}.{key}", value)
    if isinstance(element.get("jet"), dict) and "force" not in element["jet"]:
        raise _fail(path, f"{where}'s jet has no force: give jet.force [N] (on a part wholly in it)")
    for key in KINDS[kind].needed:
        if (key,) not in set(_given(element)):
            raise _fail(path, f"{where} has no {key}: every {kind} element states its own")
    return out


def _mesh_word(path: Path, k: int, key: str, value) -> str:
    """A mesh element's file (relative to the description's folder), unit ("mm" or "m") or path
    (a list of [x, y, z] in the STL's unit) as the deck's word."""
    where = f"element {k}: {key}"
    if key == "unit":
        if value not in mesh_element.UNITS:
            raise _fail(path, f"{where} = {_toml(value)}: the STL's unit is \"mm\" (as CAD exports) or \"m\"")
        return repr(mesh_element.UNITS[value])
    if key == "file":
        if not isinstance(value, str) or not value.strip():
            raise _fail(path, f"{where} must be the STL's path, relative to the description's folder")
        full = (path.parent / value).resolve()
        if any(c.isspace() or c in "#$\"'" for c in str(full)):
            raise _fail(path, f"{where}: {full} has a space or a character LIGGGHTS' variables cannot "
                              "hold; move the STL to a plain path")
        return str(full)
    ok = (isinstance(value, list) and len(value) >= 2
          and all(isinstance(q, list) and len(q) == 3 and all(isinstance(c, int | float)
                                                              and not isinstance(c, bool) for c in q)
                  for q in value))
    if not ok or not all(math.isfinite(c) for q in value for c in q):
        raise _fail(path, f"{where} must be a list of at least two points [x, y, z] (numbers, in the "
                          "STL's unit), on its floor's centre line in conveying order")
    return mesh_element.path_text(value)


PART_WORDS = ("file", "unit", "method")  # an stl part's words: [parts] file, unit, method


def _part_word(path: Path, key: str, value) -> str:
    """An stl part's file (relative to the description's folder), unit ("mm" or "m") or CLUMP
    method (its name) as the deck's word."""
    if key == "file":
        if not isinstance(value, str) or not value.strip():
            raise _fail(path, "parts.file must be the part's STL, relative to the description's folder")
        full = (path.parent / value).resolve()
        if any(c.isspace() or c in "#$\"'" for c in str(full)):
            raise _fail(path, f"parts.file: {full} has a space or a character LIGGGHTS' variables cannot "
                              "hold; move the STL to a plain path")
        if not full.is_file():
            raise _fail(path, f"parts.file = {_toml(value)}: no such file ({full})")
        return str(full)
    if key == "unit":
        if value not in stl_part.UNITS:
            raise _fail(path, f"parts.unit = {_toml(value)}: the STL's unit is \"mm\" (as CAD exports) "
                              "or \"m\"")
        return repr(stl_part.UNITS[value])
    if value not in stl_part.METHODS:
        raise _fail(path, f"parts.method = {_toml(value)}: CLUMP's methods are "
                          f"{', '.join(repr(m) for m in stl_part.METHODS)}")
    return str(stl_part.METHODS[value])


def _given(element: dict):
    for key, value in element.items():
        if isinstance(value, dict):
            yield from ((key, sub) for sub in value)
        else:
            yield (key,)


def _not_here(k: int, key: tuple[str, ...]) -> str:
    if key[0] == "step":
        return "the first section has no joint before it to step down at"
    if key[0] == "jet":
        return "a jet is built on the second section on in this version"
    if key[0] in ("side_drop", "wiper", "slot"):
        return f"a {key[0].replace('_', ' ')} is built on the second section on in this version"
    return "only the first section's drive takes a waveform other than a sine in this version"


# ------------------------------------------------------------------ the deck
def _declaration(name: str, value: str, unit: str, text: str) -> str:
    comment = f"# [{unit}] {text}" if unit else f"# {text}"
    return f"variable {name:<12} index {value:<12} {comment}"


def deck_text(description: Description, template: str, variables: dict) -> str:
    """The deck that runs ``description``: ``template`` (the project deck of its first element,
    :attr:`Description.template`: decks/bulk_feeder.liggghts or bowl_feeder.liggghts, whose
    tunables are ``variables``: vibrofeed.decks.Variable by name) with a header of its own,
    the description's numbers as the tunables' defaults and each further section's tunables
    (section 2's, numbered) declared."""
    lines = template.splitlines()
    try:
        _, _, c = lines.index(_TUNABLES), lines.index(_LINE), lines.index(_REFUSALS)
    except ValueError:
        raise ParameterError(f"decks/{description.template}.liggghts lacks the block markers a feeder "
                             "description's deck is made from") from None
    values = description.values
    n = description.sections
    further = re.compile(r"^s(\d+)_")
    # a number the template has no tunable for (a bowl's inlet) would be dropped silently
    by_name = {name: dotted for dotted, name in description.aliases.items()}
    for name in values:
        if name not in variables and name != "sections" and not further.match(name):
            raise _fail(description.path, f"{by_name.get(name, name)}: a feeder whose first element "
                                          f"is a {description.kinds[0]} has no such number "
                                          f"({description.template} does not declare {name})")
    out = [_TUNABLES]
    for v in variables.values():
        if re.match(r"^s2_", v.name) or v.name == "sections":
            continue
        out.append(_declaration(v.name, values.get(v.name, v.default), v.unit, v.description))
    out += ["", _LINE, f"# {n} element(s) (the description's, in conveying order); element 1's",
            "# numbers are the tunables above, element k's the s<k>_* below.",
            _declaration("sections", str(n), "-", "elements of the feeder")]
    seconds = [v for v in variables.values() if v.name.startswith("s2_")]
    for k in range(2, n + 1):
        kind = KINDS[description.kinds[k - 1]]
        if kind.tunables is not None:  # (its own declarations, after its kind's code)
            out.append(_declaration(f"s{k}_kind", str(kind.code), "-",
                                    f"element {k}'s kind: {kind.code} a {kind.name}"))
            for suffix, unit, text in kind.tunables.values():
                name = f"s{k}_{suffix}"
                default = variables[f"s2_{suffix}"].default if f"s2_{suffix}" in variables else "0"
                out.append(_declaration(name, values.get(name, default), unit, text))
            continue
        for v in seconds:
            name = f"s{k}_" + v.name[3:]
            text = v.description.replace("section 2", f"section {k}").replace(
                "section 1's exit", f"section {k - 1}'s exit")
            out.append(_declaration(name, values.get(name, v.default), v.unit, text))
    # a further element's number its deck would not declare would be dropped silently, as a
    # bowl's exit section's gate once was: refused, naming it
    declared = {m[1] for line in out if (m := re.match(r"^variable (\S+) ", line))}
    for name in values:
        if further.match(name) and name not in declared:
            raise _fail(description.path, f"{by_name.get(name, name)}: a feeder whose first element is a "
                                          f"{description.kinds[0]} has no such number in this version "
                                          f"({description.template} does not declare {name})")
    body = lines[c:]
    header = _header(description, n, template)
    return "\n".join(header + [""] + out + [""] + body) + "\n"


def _header(description: Description, n: int, template: str) -> list[str]:
    kinds = ", ".join(description.kinds)
    said = " ".join(description.text.split()) or f"A feeder of {n} element(s): {kinds}."
    hook = next((line for line in template.splitlines() if line.startswith("# vibrofeed prepare:")),
                "# vibrofeed prepare: vibrofeed.geometry:prepare_bulk_feeder")
    return [f"# vibrofeed deck: {description.name}", hook,
            f"# vibrofeed generated from: {description.path.name}",
            "#", *("# " + line for line in _wrap(said, 78)), "#",
            f"# {n} element(s) ({kinds}), generated from the feeder description named",
            f"# above (docs/feeders.md). The commands are decks/{description.template}.liggghts's",
            "# (its header says what they do); the tunables hold the description's numbers.",
            "#", "# Run by hand: `vibrofeed prepare FEEDER.toml -o DIR` writes this deck, the",
            "# meshes and the generated includes into DIR and prints the liggghts line.",
            "#", "# Units: SI (m, kg, s, Pa, J/m^2); angles in degrees."]


def _wrap(text: str, width: int) -> list[str]:
    out, line = [], ""
    for word in text.split():
        if line and len(line) + 1 + len(word) > width:
            out.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    return out + ([line] if line else [])


def slug(name: str) -> str:
    """A deck's file name from a description's name: letters, digits, _ and -."""
    return re.sub(r"[^A-Za-z0-9_-]+", "_", name).strip("_") or "feeder"


def cache_dir() -> Path:
    """Where generated decks are kept: $XDG_CACHE_HOME/vibrofeed/decks (~/.cache/...)."""
    root = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(root) / "vibrofeed" / "decks"


def write_deck(text: str, stem: str, folder: Path | None = None) -> Path:
    """``text`` as ``stem``.liggghts in ``folder`` (default: the cache, in a folder named by
    the text's hash, so that one deck text has one path); written whole or not at all."""
    digest = hashlib.sha256(text.encode()).hexdigest()[:16]
    folder = folder if folder is not None else cache_dir() / digest
    path = folder / f"{stem}.liggghts"
    if path.is_file() and path.read_text() == text:
        return path
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tmp = folder / f".{stem}.{os.getpid()}.tmp"
        tmp.write_text(text)
        os.replace(tmp, path)
    except OSError as exc:
        raise ParameterError(f"cannot write the generated deck {path}: {exc.strerror}") from None
    return path
