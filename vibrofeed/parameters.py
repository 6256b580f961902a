"""Checking run parameters before a deck is handed to LIGGGHTS.

The decks share one vocabulary (README, "Decks"); the physical limits of each
name are stated here once. A bad value is refused with a message naming the
parameter, the value and the limit, before anything is started or written.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import re
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path

from .bowl import check_bowl, climb_advice
from .decks import RESERVED, Deck
from .errors import ParameterError, ParameterWarning
from .feeders.feeder import Feeder, inserts_between_walls, starts_with_bowl
from .feeders.linear import MAX_SECTIONS, LinearSection, keep_word
from .feeders.records import Part
from .limits import JET_THROW, MIN_SPEED_LIMIT, SPEED_FACTOR
from .line import MAX_SKEW
from .models.constants import G
from .models.deck import mass as part_mass
from .orientation import correct_word
from .parts import Box, box_template, check_box, clump_count, mass_properties
from .plausibility import DENSITY_MAX, PART_MAX, advice

NO_MICRO_PART = "a metre is no micro-part; lengths are in metres"



# A feeder's stroke is micrometres (piezo micro-feeders) to a few millimetres
# (bowl feeders); a larger amplitude is almost always a unit slip (metres).
MAX_AMPLITUDE = 0.01  # m
# A track moving faster than this (amp * 2 pi freq) throws parts metres high:
# the simulation box and its neighbour bins would grow beyond what LIGGGHTS
# can allocate ("Domain too large for neighbor bins"). Real feeders: < 0.5 m/s.
MAX_SURFACE_SPEED = 2.0  # m/s


def _positive(x):
    return None if x > 0 else "must be > 0"


def _non_negative(x):
    return None if x >= 0 else "must be >= 0"


def _finite(x):
    return None


def _between(lo, hi, lo_open=True, hi_open=True, why=""):
    def check(x):
        ok_lo = x > lo if lo_open else x >= lo
        ok_hi = x < hi if hi_open else x <= hi
        if ok_lo and ok_hi:
            return None
        interval = f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
        return f"must be in {interval}" + (f" ({why})" if why else "")
    return check


def _positive_up_to(hi, why, zero=False):
    """> 0 (>= 0 with ``zero``) and <= ``hi``, the upper limit explained by ``why``."""
    def check(x):
        if not (x >= 0 if zero else x > 0):
            return "must be >= 0" if zero else "must be > 0"
        return None if x <= hi else f"must be <= {hi:g} ({why})"
    return check


def _youngs_or_zero(x):
    return None if x == 0 or x > 5e6 else (
        "must be 0 (the parts' softening applied to aluminium) or > 5e+06 (LIGGGHTS' Hertz "
        "model needs youngsModulus > 5e6 Pa)")


def _integer(lo=None, choices=None):
    def check(x):
        if x != int(x):
            return "must be an integer"
        if choices is not None and int(x) not in choices:
            return f"must be one of {', '.join(map(str, choices))}"
        if lo is not None and x < lo:
            return f"must be >= {lo}"
        return None
    check.integer = True  # (the engine reads such a value as a whole number: engine_text)
    return check


_amplitude = _between(0, MAX_AMPLITUDE, lo_open=False, hi_open=False,
                      why="a feeder's stroke is um to mm; amplitudes are in metres")

# name -> check(value) returning an error text or None
RULES: dict[str, Callable[[float], str | None]] = {
    "freq": _positive,
    "amp_t": _amplitude,
    "amp_n": _amplitude,
    "phase": _finite,
    "amp_c": _amplitude,
    "phase_c": _finite,
    "incline": _between(-90, 90, lo_open=False, hi_open=False),
    "radius": _positive_up_to(PART_MAX, NO_MICRO_PART),
    "density": _positive_up_to(DENSITY_MAX, "no material is denser (osmium: 22590 kg/m³); densities "
                                            "are in kg/m³"),
    # (no upper limit: a modulus beyond any solid's is how a contact is made rigid, as
    # the replay's DEM wall does)
    "youngs": _between(5e6, math.inf, why="LIGGGHTS' Hertz model needs youngsModulus > 5e6 Pa"),
    "poisson": _between(-1, 0.5, hi_open=False),
    "restitution": _between(0.05, 1, hi_open=False,
                            why="LIGGGHTS needs coefficientRestitution > 0.05"),
    "mu": _non_negative,
    "rolling": _integer(choices=(0, 1)),
    "tangential_damping": _integer(choices=(0, 1)),
    "limit_force": _integer(choices=(0, 1)),
    "waveform": _integer(choices=(0, 1, 2, 3, 4)),
    "duty": _between(0, 1),
    "normal_force": _non_negative,
    "t_end": _positive,
    "output_dt": _positive,
    "dt": _non_negative,
    "seed": _integer(lo=1),
    # the bulk feeder (decks/bulk_feeder.liggghts)
    "skin": _non_negative,  # (the bowl too)
    "shape": _integer(choices=(0, 1, 2, 3, 4)),
    "pair": _integer(choices=(0, 1)),
    "pull_speed": _positive,
    "overlap0": _positive,
    "part_size": _positive_up_to(PART_MAX, NO_MICRO_PART),
    "part_thickness": _positive_up_to(PART_MAX, NO_MICRO_PART),
    "part_width": _positive_up_to(PART_MAX, NO_MICRO_PART),
    "bump_height": _non_negative,
    "bump_diameter": _non_negative,
    "bump_at": _between(-1, 1, lo_open=False, hi_open=False),
    "clump_spacing": _between(0.5, 1, lo_open=False, hi_open=False),
    # an stl part (shape 4, vibrofeed.stl_part): its STL's unit and CLUMP's method and knobs
    "part_unit": _positive,
    "clump_method": _integer(choices=(0, 1, 2)),
    "clump_spheres": _integer(lo=1),
    "clump_resolution": _integer(lo=4),
    "clump_overlap": _between(0, 1, lo_open=False),
    "size_spread": _between(0, 1, lo_open=False),
    "n_parts": _integer(lo=0),
    "fill_from": _between(0, 1, lo_open=False, hi_open=False),
    "fill_to": _between(0, 1, lo_open=False, hi_open=False),
    "inlet_rate": _non_negative,
    "inlet_batch": _integer(lo=1),
    "track_length": _positive,
    "track_width": _positive,
    "wall_height": _positive,
    "gate_width": _non_negative,
    "gate_at": _between(0, 1, lo_open=False),
    "cross_tilt": _between(0, 45, lo_open=False, hi_open=False),
    "youngs_track": _youngs_or_zero,
    "poisson_track": _between(-1, 0.5, hi_open=False),
    "restitution_pp": _between(0.05, 1, hi_open=False,
                               why="LIGGGHTS needs coefficientRestitution > 0.05"),
    "mu_pp": _non_negative,
    "rolling_friction": _non_negative,
    "surface_energy": _non_negative,
    "surface_energy_pp": _non_negative,
    "t_settle": _non_negative,
    # micro-scale surface forces (decks/include/surface_forces.liggghts)
    "hamaker": _between(0, 1e-17, lo_open=False, hi_open=False,
                        why="Hamaker constants of solids are 0.4e-19 to 4e-19 J"),
    "roughness": _between(0, 1e-4, lo_open=False, hi_open=False,
                          why="asperity heights are nm to um; lengths are in metres"),
    "air_viscosity": _between(0, 1e-3, lo_open=False, hi_open=False,
                              why="air is 1.81e-5 Pa s"),
    "face_radius": _positive_up_to(PART_MAX, NO_MICRO_PART, zero=True),
    "dt_unchecked": _integer(choices=(0, 1)),
    # a feeder line's section 2 (vibrofeed.line; docs/feeder-lines.md); the twins of
    # section 1's parameters follow below
    "sections": _integer(choices=tuple(range(1, MAX_SECTIONS + 1))),
    "s2_step": _positive,
    "s2_drop_from": _between(0, 1, lo_open=False, hi_open=False),
    "s2_drop_to": _between(0, 1, lo_open=False, hi_open=False),
    "s2_drop_width": _non_negative,
    "s2_wiper_height": _non_negative,
    "s2_wiper_at": _between(0, 1, lo_open=False),
    "s2_wiper_skew": _between(0, MAX_SKEW, lo_open=False, hi_open=False,
                              why="0: straight across; towards 90 the bar would run along the track"),
    # the bowl feeder (decks/bowl_feeder.liggghts; vibrofeed.bowl)
    "n_track": _integer(lo=0),
    "bowl_diameter": _positive_up_to(0.5, "a micro-part bowl is cm across; lengths are in metres"),
    "cone_angle": _between(0, 45, lo_open=False, hi_open=False),
    "helix_angle": _between(0, 45, why="the track climbs: 0 < helix_angle < 45 deg"),
    "turns": _positive,
    "lip_height": _non_negative,
    "chute_length": _positive,
    "wiper_height": _non_negative,
    "wiper_at": _between(0, 1, lo_open=False),
}
# Section 2's drive and walls are section 1's kind: the same limits.
SECTION_2_TWINS = {"s2_length": "track_length", "s2_width": "track_width",
                   "s2_wall_height": "wall_height", "s2_freq": "freq", "s2_amp_t": "amp_t",
                   "s2_amp_n": "amp_n", "s2_phase": "phase", "s2_cross_tilt": "cross_tilt",
                   "s2_amp_c": "amp_n", "s2_phase_c": "phase", "s2_gate_width": "gate_width",
                   "s2_gate_at": "gate_at"}
RULES.update({twin: RULES[name] for twin, name in SECTION_2_TWINS.items()})
# A line's section k >= 3 (a feeder description's, docs/feeders.md) has section 2's names
# with its own number: s3_amp_n takes s2_amp_n's rule.
_FURTHER = re.compile(r"^s([3-9])_(\w+)$")


def rule_for(name: str) -> Callable[[float], str | None] | None:
    """The limit of parameter ``name`` (None: no limit of its own)."""
    m = _FURTHER.match(name)
    return RULES.get(f"s2_{m[2]}" if m else name)

# Parameters that name orientation states (vibrofeed.orientation.parse_correct's words): what
# counts as correct, and each air jet's keep (which may also be "correct": the part's).
STATE_WORDS = re.compile(r"^(?:correct|(?:s\d+_)?jet_keep)$")


def state_word(name: str, value: str) -> str:
    """Parameter ``name`` of :data:`STATE_WORDS` as the deck holds it (no blank), checked: a
    one-line ParameterError naming it."""
    return correct_word(value, name) if name == "correct" else keep_word(value, name)

# Parameters that also take names; a name is replaced by the deck's number.
NAMED_VALUES: dict[str, dict[str, str]] = {
    "shape": {"sphere": "0", "chip": "1", "disc": "2", "box": "3", "stl": "4"},
    "clump_method": {"euclidean": "0", "favier": "1", "ferellec-mcdowell": "2"},
}


def parse_assignments(items) -> dict[str, str]:
    """``["freq=50", "amp_n=2e-4"]`` -> ``{"freq": "50", "amp_n": "2e-4"}``. A name given
    twice with two values is refused: which one was meant is not for vibrofeed to guess."""
    out = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        name, value = name.strip(), value.strip()
        if not sep or not name or not value:
            raise ParameterError(f"parameter {item or '(nothing)'} is not of the form name=value")
        if out.get(name, value) != value:
            raise ParameterError(f"parameter {name} given twice, as -p {name}={out[name]} and "
                                 f"-p {name}={value}; give it once")
        out[name] = value
    return out


# A number as C's atof and LIGGGHTS' numeric() read it the way Python's float() does: ASCII
# digits, one point, an exponent. Python also reads what they read otherwise or not at all:
# other scripts' digits ("５０": LIGGGHTS reads 0), underscores ("1_000": atof reads 1),
# surrounding blanks; an integer parameter ("1e2", "5.0") is no integer to LIGGGHTS.
_PLAIN_NUMBER = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?")
_PLAIN_INTEGER = re.compile(r"[+-]?[0-9]+")


def engine_text(text: str, x: float, integer: bool = False) -> str:
    """The value ``text`` (which Python read as ``x``) in a form LIGGGHTS reads as the same
    number: ``text`` itself when plain, else the number Python read (a whole number for an
    ``integer`` parameter), so that the engine never runs with another value than the one
    checked."""
    if integer:
        return text if _PLAIN_INTEGER.fullmatch(text) else str(int(x))
    return text if _PLAIN_NUMBER.fullmatch(text) else repr(x)


# Hints for a refused value that is a unit slip: name -> (test, hint).
UNIT_SLIPS: dict[str, tuple[Callable[[float], bool], str]] = {
    "youngs": (lambda x: 0 < x < 1e4, "a modulus in GPa? (moduli are in Pa: silicon 1.3e11)"),
    "youngs_track": (lambda x: 0 < x < 1e4, "a modulus in GPa? (moduli are in Pa: aluminium 7e10)"),
}


def resolve(deck: Deck, given: Mapping[str, str]) -> dict[str, str]:
    """Deck defaults overridden by ``given``, checked; values as strings. A value
    that runs but looks like a slip (:func:`vibrofeed.plausibility.advice`) is a
    :class:`ParameterWarning` naming it. A feeder description's refusals and warnings name
    each value as the user gave it: its dotted name in the file (``element.2.jet.delay``),
    or the name given to ``-p``."""
    if not deck.aliases:
        return _resolve(deck, given)
    named: dict[str, str] = {}
    said: dict[str, str] = {}  # the deck's name -> the name it was given by
    for name, value in given.items():
        own = deck.aliases.get(name, name)
        if own not in deck.tunables and own not in RESERVED:
            raise ParameterError(_unknown(deck, name))
        if own in named:
            raise ParameterError(f"parameter {own} given twice, as {said[own]} and as {name}")
        named[own], said[own] = value, name
    dotted = {own: alias for alias, own in deck.aliases.items() if own not in said}
    speak = speaker(dotted, said, getattr(deck.description, "path", None))
    try:
        with warnings.catch_warnings(record=True) as heard:
            warnings.simplefilter("always", ParameterWarning)
            values = _resolve(deck, named)
    except ParameterError as exc:
        raise ParameterError(speak(str(exc))) from None
    for w in heard:
        if issubclass(w.category, ParameterWarning):  # (a tool's own kind kept: SlotWarning, ...)
            warnings.warn(speak(str(w.message)), w.category, stacklevel=2)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return values


def speaker(described: Mapping[str, str], said: Mapping[str, str], path=None) -> Callable[[str], str]:
    """A function that puts each deck name in a message as the user gave it: the name given
    to ``-p`` (``said``), else its dotted name in the description (``described``), with the
    description's file name before a message that names a value from the file."""
    names = {**described, **said}
    if not names:
        return lambda text: text
    # A name spelt as code (amp_n, s2_drop_to) is a value wherever it stands, but for the
    # prose's names in general ("the two drives' amp_n"), which both spellings accept. A name
    # that is also a word (phase, correct, shape) only where it is plainly the value: citing it
    # ("freq=50 Hz"), the message's subject ("parameter duty has no effect", "correct: ..."),
    # in a list of values to change ("(amp_t, s2_amp_t)") or as the value to change ("lower
    # amp_n or freq").
    def either(group):
        return "|".join(map(re.escape, sorted(group, key=len, reverse=True))) or "(?!)"
    code = either(n for n in names if re.search(r"[_\d]", n))
    every = either(names)
    pattern = re.compile(
        rf"(?<![\w.'])(?<!' )({code})(?![\w.])"
        rf"|(?<![\w.])({every})(?==)|(?<=parameter )({every})(?![\w.])|^({every})(?=: )"
        rf"|(?:^|(?<=\()|(?<=, )|(?<=: )|(?<=lower )|(?<=raise )|(?<= or ))({every})(?=[,)?]| or | and |;|$)")
    prefix = f"{Path(path).name}: " if path else ""

    def speak(text: str) -> str:
        from_file = False

        def name(m: re.Match) -> str:
            nonlocal from_file
            found = next(g for g in m.groups() if g)
            from_file = from_file or found not in said
            return names[found]
        spoken = pattern.sub(name, text)
        return prefix + spoken if from_file and prefix and not text.startswith(prefix) else spoken
    return speak


def _unknown(deck: Deck, name: str) -> str:
    """The refusal of a name ``deck`` does not know; a description's in its words: its
    elements, its dotted names (and the deck's own for a name given undotted)."""
    description = deck.description
    kinds = getattr(description, "kinds", [])
    file = Path(description.path).name if description is not None else f"deck {deck.name}"
    if description is not None and (m := re.fullmatch(r"element\.(\d+)\.(.+)", name)):
        k, key = int(m[1]), m[2]
        if not 1 <= k <= len(kinds):
            return (f"unknown parameter {name}: {file} has element{'s 1 to' if len(kinds) > 1 else ''} "
                    f"{len(kinds)}")
        if key == "kind":
            return (f"parameter {name} is the element's kind ({kinds[k - 1]}), not a number -p "
                    f"varies: change it in {file}")
    spoken = {}  # each tunable by its dotted name where it has one
    for alias, own in deck.aliases.items():
        spoken.setdefault(own, alias)
    valid = [spoken.get(n, n) for n in deck.tunables]
    candidates = valid if "." in name else list(deck.tunables)
    close = difflib.get_close_matches(name, candidates, n=1)
    hint = f" (did you mean {close[0]}?)" if close else ""
    return f"unknown parameter {name} for {file}{hint}; valid parameters: {', '.join(valid)}"


def _resolve(deck: Deck, given: Mapping[str, str]) -> dict[str, str]:
    tunables = deck.tunables
    for name in given:
        if name in RESERVED:
            raise ParameterError(f"parameter {name} is set by vibrofeed itself, not by -p")
        if name not in tunables:
            raise ParameterError(_unknown(deck, name))
    values = {name: str(given.get(name, v.default)) for name, v in tunables.items()}
    for name, names in NAMED_VALUES.items():
        if name in values and values[name].strip().lower() in names:
            values[name] = names[values[name].strip().lower()]

    numbers = {}
    for name, value in values.items():
        x = checked_value(deck, name, value)
        if name in tunables and STATE_WORDS.match(name):  # as the deck holds it: no blank
            values[name] = state_word(name, value)
        if x is None:
            continue
        numbers[name] = x
        values[name] = engine_text(value, x, getattr(rule_for(name), "integer", False))
    declared = max((int(m[1]) for n in tunables if (m := re.match(r"^s(\d)_(?:length|kind)$", n))), default=1)
    if numbers.get("sections", 1) > declared:
        raise ParameterError(
            f"parameter sections={values['sections']}: deck {deck.name} declares "
            f"{'one section' if declared == 1 else f'sections 1 to {declared}'}; a line of more "
            "sections is a feeder description (docs/feeders.md)")
    # a mesh element's STL and path, a jet's keep and mode, an stl part's STL, what is correct
    # are words its checks read beside the numbers
    words = {name: value for name, value in values.items()
             if re.match(r"^(?:s\d+_(?:file|path)|(?:s\d+_)?jet_(?:keep|mode)|part_file|correct)$", name)}
    # (the deck's own default is no choice: values resolved once resolve again, as a
    # validation case's runs do)
    chosen = "correct" in given and given["correct"] != getattr(tunables.get("correct"), "default", None)
    if chosen and numbers.get("shape", 0) == 0:
        raise ParameterError(f"parameter correct={given['correct']}: spheres (shape 0) have no "
                             "orientation; correct is for chips, discs, boxes and stl parts")
    if numbers.get("shape") == 4:
        _stl_sizes(values, numbers, given)
    try:
        _check_relations({**words, **numbers})
    except ParameterError as exc:
        raise ParameterError(_with_slips(str(exc), numbers)) from None
    # An idle parameter is worth a word only when the user moved it from the deck's default
    # (callers such as the validation cases pass every value).
    moved = [n for n in given if n in numbers and (not tunables[n].is_numeric
                                                  or numbers[n] != float(tunables[n].default))]
    # a description's numbers are its deck's defaults, yet each one the file writes is a choice
    written = getattr(deck.description, "values", None) or {}
    moved += [n for n in written if n in numbers and n not in moved and n != "sections"]
    for line in advice(numbers, moved) + climb_advice(numbers):
        warnings.warn(line, ParameterWarning, stacklevel=3)
    return values


def _stl_sizes(values: dict[str, str], numbers: dict[str, float], given: Mapping[str, str]) -> None:
    """An stl part's part_size, part_width and part_thickness: its principal extents
    (vibrofeed.stl_part.sizes), written into ``values`` and ``numbers``; one given otherwise
    is refused."""
    from .stl_part import StlPart, check_part, sizes

    part = StlPart.of({**values, **numbers})
    check_part(part)
    for name, x in zip(("part_size", "part_width", "part_thickness"), sizes(part)):
        if name in given and not math.isclose(numbers.get(name, x), x, rel_tol=1e-6):
            raise ParameterError(f"parameter {name}={given[name]}: an stl part's sizes are its STL's "
                                 f"({name}={x:.6g} m, its principal extents); leave it out")
        values[name], numbers[name] = repr(x), x


def checked_value(deck: Deck, name: str, value: str) -> float | None:
    """The number parameter ``name`` of ``deck`` takes from the text ``value`` (a name of
    :data:`NAMED_VALUES` as its number), checked against its own limit (:data:`RULES`);
    None for a parameter that is no number. ParameterError naming it otherwise. The limits
    between parameters are :func:`resolve`'s."""
    var = deck.tunables[name]
    if STATE_WORDS.match(name):  # words: what counts as correct, a jet's keep
        state_word(name, value)
        return None
    if not (var.is_numeric or rule_for(name)):
        return None
    value = NAMED_VALUES.get(name, {}).get(value.strip().lower(), value)
    try:
        x = float(value)
    except ValueError:
        if name in NAMED_VALUES:
            choices = ", ".join(f"{k} ({v})" for k, v in NAMED_VALUES[name].items())
            raise ParameterError(f"parameter {name}={value} must be one of {choices}") from None
        raise ParameterError(f"parameter {name}={value} is not a number") from None
    if not math.isfinite(x):
        raise ParameterError(f"parameter {name}={value} is not finite")
    rule = rule_for(name)
    problem = rule(x) if rule else None
    if problem:
        unit = f" {var.unit}" if var.unit and var.unit != "-" else ""
        slip = UNIT_SLIPS.get(name)
        hint = f"; {slip[1]}" if slip and slip[0](x) else ""
        raise ParameterError(f"parameter {name}={value}{unit} {problem}{hint}")
    return x


def _with_slips(message: str, p: Mapping[str, float]) -> str:
    """A refusal, with the likely unit slip of each value it names (:func:`advice`): the
    warning would not be reached, and a slip is often why the relation fails."""
    slips = [line for line in advice(p) if re.search(rf"\b{line.split()[1].split('=')[0]}=", message)]
    return "; ".join([message, *slips])


# A run asking for more frames than this is almost always a unit slip (output_dt
# in ms or us); with the automatic timestep it would also force dt = output_dt
# and run for hours before anyone noticed. Runs that really need it split t_end.
MAX_FRAMES = 1_000_000


def _check_relations(p: Mapping[str, float]) -> None:
    """Limits that involve several parameters."""
    drives = ((f"{s}amp_{a}", f"{s}freq")
              for s in ("", *(f"s{k}_" for k in range(2, MAX_SECTIONS + 1))) for a in "ntc")
    for amp, freq in drives:
        if amp in p and freq in p:
            speed = 2 * math.pi * p[freq] * p[amp]
            if speed > MAX_SURFACE_SPEED:
                raise ParameterError(
                    f"{amp}={p[amp]:g} m at {freq}={p[freq]:g} Hz moves the surface at "
                    f"{speed:.3g} m/s peak (limit {MAX_SURFACE_SPEED:g} m/s: real feeders stay "
                    f"below 0.5 m/s); lower {amp} or {freq}")
    if "output_dt" in p and "t_end" in p:
        if p["output_dt"] > p["t_end"]:
            raise ParameterError(
                f"output_dt={p['output_dt']:g} s is longer than the run, t_end={p['t_end']:g} s")
        frames = p["t_end"] / p["output_dt"]
        if frames > MAX_FRAMES:
            raise ParameterError(
                f"t_end={p['t_end']:g} s with output_dt={p['output_dt']:g} s would write "
                f"{frames:.3g} frames (limit {MAX_FRAMES:.0e}); raise output_dt or shorten t_end")
    if p.get("amp_c", 0.0) != 0 and p.get("waveform", 0) != 0:
        raise ParameterError(f"amp_c={p['amp_c']:g} m: a cross stroke is a sine, and waveform="
                             f"{int(p['waveform'])} is not (waveform=0, or amp_c=0)")
    _check_bulk_feeder(p)
    _check_feeder(p)
    _check_jet_throw(p)
    check_bowl(p)
    _check_surface_forces(p)
    dt = p.get("dt", 0.0)
    if dt > 0:
        if "output_dt" in p and p["output_dt"] < dt:
            raise ParameterError(
                f"output_dt={p['output_dt']:g} s is shorter than the timestep dt={dt:g} s")
        if "t_end" in p and p["t_end"] < dt:
            raise ParameterError(f"t_end={p['t_end']:g} s is shorter than the timestep dt={dt:g} s")
    _check_contact_step(p)


def _check_feeder(p: Mapping[str, float]) -> None:
    """A line's sections and joints, and its rejects' return (vibrofeed.feeders: the rules
    live there, the deck repeats none of them)."""
    Feeder.check_values(p)


def _check_jet_throw(p: Mapping[str, float]) -> None:
    """A warning for an air jet strong enough to throw the part it blows off faster or farther
    than ``vibrofeed check`` accepts of any part (vibrofeed.limits): the run would fail its
    check. Judged on the throw's upper bound (the elements' jet_throw): a warning, not a
    refusal, as friction and the part's weight take some of it."""
    if not any(p.get(f"s{k}_jet_force", 0.0) > 0 for k in range(2, MAX_SECTIONS + 1)) \
            or "part_size" not in p or "density" not in p:
        return
    feeder = Feeder.from_values(p)
    try:
        mass = part_mass(p)
    except (ValueError, OSError):  # an stl part's STL: its own check names what is wrong
        return
    sections = [e for e in feeder.elements if hasattr(e, "jet_throw")]  # (those that may carry one)
    fastest = max(MIN_SPEED_LIMIT, SPEED_FACTOR * max(s.drive.peak_speed for s in sections))
    farthest = JET_THROW * max(s.x1 for s in sections)
    for s in sections:
        if getattr(s, "jet", None) is None:
            continue
        speed, reach = s.jet_throw(feeder.part, mass, G)
        if speed > fastest or reach > farthest:
            name = s.name(("jet", "force"))
            warnings.warn(
                f"{name}={s.jet.force:g} N ({s.jet.force / (mass * G):.3g} times the part's weight) "
                f"may throw a part it blows off at up to {speed:.3g} m/s, {reach:.3g} m beyond the track; "
                f"vibrofeed check fails a run whose parts fly faster than {fastest:.3g} m/s or "
                f"farther than {farthest:.3g} m from the track (a few weights blow a part off)",
                ParameterWarning, stacklevel=5)


def circumscribed_radius(p: Mapping[str, float]) -> float:
    """A bulk feeder's part's circumscribed radius [m], as decks/include/part_shape.liggghts
    takes it (r_ext): a sphere's with its size spread, a chip's corner sphere, a disc's rim,
    a box's clump about its centre of mass."""
    size, shape = p["part_size"], int(p.get("shape", 0))
    if shape in (3, 4):
        return Part.from_values(p).reach
    if shape == 0:
        return size / 2 * (1 + p.get("size_spread", 0.0))
    if shape == 1:
        thickness = p.get("part_thickness", size)
        return (size - thickness) / math.sqrt(2) + thickness / 2
    return size / 2


def _check_insertion(p: Mapping[str, float]) -> None:
    """The bulk feeder inserts its parts whole (LIGGGHTS' all_in) into blocks between the
    walls, 5 % of a part size in from each (decks/bulk_feeder.liggghts, regions inlet and
    fill): a track no wider than that and a part leaves them no volume, and LIGGGHTS stops
    with 'Unable to calculate region volume'."""
    if not inserts_between_walls(p) or (p.get("n_parts", 1) <= 0 and p.get("inlet_rate", 0) <= 0):
        return
    across = 2 * circumscribed_radius(p) + 0.1 * p["part_size"]
    if p["track_width"] <= across:
        feeds = [f"the {what} ({n})" for n, what in (("inlet_rate", "inlet"), ("n_parts", "pre-fill"))
                 if p.get(n, 0) > 0]
        verb = "places" if len(feeds) == 1 else "place"
        raise ParameterError(
            f"track_width={p['track_width']:g} m leaves no room to insert a part of part_size="
            f"{p['part_size']:g} m: {' and '.join(feeds)} {verb} each part whole between the walls, "
            f"5 % of a part in from each, so the track must be wider than {across:.3g} m; widen the "
            "track or use smaller parts")


# The inlet's block (decks/bulk_feeder.liggghts, region inlet), in part sizes: from r_ext +
# 0.05 to r_ext + 3 along the track, 0.05 in from each wall, 0.1 to 3 above the floor's top.
INLET_LENGTH, INLET_HEIGHT, INLET_MARGIN = 2.95, 2.9, 0.05
GRAVITY = 9.81  # m/s^2, as the decks take it


def inlet_capacity(p: Mapping[str, float]) -> tuple[float, float]:
    """(the most parts the bulk feeder's inlet block holds at once, at the packing of a
    settled fill (FILL_PACKING); the time [s] a part dropped at rest from its top takes to
    fall out of it). A part is in the block a fall time at most, so the inlet drops at most
    capacity / time parts a second (:func:`_check_inlet`)."""
    size = p["part_size"]
    width = p["track_width"] - 2 * INLET_MARGIN * size
    block = INLET_LENGTH * size * max(width, 0.0) * INLET_HEIGHT * size
    parts = FILL_PACKING * block / volume_of(p)
    return parts, math.sqrt(2 * INLET_HEIGHT * size / GRAVITY)


def _check_inlet(p: Mapping[str, float]) -> None:
    """An inlet asked for more than its block can ever hold: LIGGGHTS tries each step to
    insert what does not fit (a run a thousand times slower, or 'Unable to calculate region
    volume'), and what the run measures is the block's limit, not the rate asked for."""
    rate = p.get("inlet_rate", 0.0)
    if not inserts_between_walls(p) or rate <= 0:
        return
    capacity, fall = inlet_capacity(p)
    size = f"part_size={p['part_size']:g} m"
    batch = p.get("inlet_batch", 1.0)
    if batch > capacity:
        raise ParameterError(
            f"inlet_batch={batch:g} parts do not fit in the inlet's block above the track's start: "
            f"it holds at most {capacity:.0f} parts of {size} on track_width={p['track_width']:g} m; "
            f"lower inlet_batch to {max(math.floor(capacity), 1):d} or less")
    most = capacity / fall
    if rate > most:
        raise ParameterError(
            f"inlet_rate={rate:g} /s is more than the inlet can drop: its block above the track's "
            f"start holds at most {capacity:.0f} parts of {size} on track_width="
            f"{p['track_width']:g} m, and a part falls through it in {fall * 1e3:.2g} ms, so at most "
            f"{most:.3g} parts/s; lower inlet_rate, or pre-fill the track (n_parts)")


def volume_of(p: Mapping[str, float]) -> float:
    """A part's volume [m^3] from a deck's parameters (a box's with its bump's cap)."""
    if int(p.get("shape", 0)) == 3:
        return mass_properties(Box.of(Part.from_values(p)), 1.0).mass
    if int(p.get("shape", 0)) == 4:
        from .stl_part import StlPart, solid

        return solid(StlPart.of(p)).volume
    size = p["part_size"]
    return part_volume(int(p.get("shape", 0)), size, p.get("part_thickness", size))


# Random loose packing of a settled pre-fill, to tell whether it stays between the walls.
FILL_PACKING = 0.6


def part_volume(shape: int, size: float, thickness: float | None = None) -> float:
    """Volume [m^3] of a part: ``shape`` 0 a sphere of diameter ``size``, 1 a chip (``size``
    x ``size`` x ``thickness``), 2 a disc of diameter ``size`` (``thickness`` defaults to
    ``size``), as :func:`vibrofeed.models.deck.mass` weighs it."""
    thickness = size if thickness is None else thickness
    if shape == 0:
        return math.pi / 6 * size ** 3
    if shape == 1:
        return size ** 2 * thickness
    if shape == 2:
        return math.pi / 4 * size ** 2 * thickness
    raise ParameterError(f"shape={shape} must be one of 0, 1, 2")


# The softest contact over which the bulk feeder's feed rate was measured to
# stay within its own uncertainty (2e7 to 1e9 Pa, README "Decks"): softening
# moves the realised restitution, so a softer contact is not a free choice.
BULK_MIN_YOUNGS = 2e7  # Pa


def _check_bulk_feeder(p: Mapping[str, float]) -> None:
    """Relations between the bulk feeder's parameters (decks/bulk_feeder.liggghts refuses
    the same for runs by hand)."""
    if "part_size" not in p or "track_width" not in p:
        return
    size, shape = p["part_size"], int(p.get("shape", 0))
    spread = p.get("size_spread", 0.0)
    if p.get("youngs", BULK_MIN_YOUNGS) < BULK_MIN_YOUNGS:
        raise ParameterError(
            f"youngs={p['youngs']:g} Pa is softer than the bulk feeder is validated for: its feed "
            f"rate was measured independent of youngs from {BULK_MIN_YOUNGS:g} to 1e9 Pa "
            "(vibrofeed validate stiffness_independence); stiffer is closer to silicon")
    widest = size * (1 + spread) if shape == 0 else size
    if shape == 3:
        check_box(Box.of(Part.from_values(p)))
    if shape in (3, 4) and (p.get("hamaker", 0.0) > 0 or p.get("air_viscosity", 0.0) > 0):
        raise ParameterError(f"hamaker and air_viscosity act on spheres, chips and discs: a "
                             f"{'box (shape 3)' if shape == 3 else 'stl part (shape 4)'} runs without "
                             "them in this version")
    if p.get("n_parts", 1) <= 0 and p.get("inlet_rate", 1) <= 0:
        raise ParameterError("n_parts=0 and inlet_rate=0: no part would ever be fed; "
                             "set n_parts (pre-fill) or inlet_rate")
    if shape != 0 and p.get("part_thickness", 0.0) > size:
        raise ParameterError(f"part_thickness={p['part_thickness']:g} m exceeds part_size={size:g} m: "
                             "a chip or disc is thinner than its edge")
    if shape != 0 and spread > 0:
        raise ParameterError(f"size_spread={spread:g} applies to spheres only (shape=0), "
                             f"not shape={shape}")
    if p["track_width"] < widest:
        raise ParameterError(f"track_width={p['track_width']:g} m is narrower than a part "
                             f"({widest:g} m across)")
    _check_insertion(p)
    _check_inlet(p)
    length = p.get("track_length", math.inf)
    if p.get("gate_width", 0.0) > 0:  # the gate's rules are every section's (LinearSection)
        section = LinearSection.from_values(p, 1)
        if "track_length" not in p:  # a partial set of parameters: no end to run past
            section = dataclasses.replace(section, length=math.inf)
        last = p.get("sections", 1) <= 1
        section.check_gate(Part.from_values(p), "the outlet edge" if last else "the end of section 1")
        if p.get("n_parts", 1) > 0 and p.get("fill_to", 0.0) > p.get("gate_at", 0.7):
            raise ParameterError(f"fill_to={p['fill_to']:g} reaches into the gate (gate_at="
                                 f"{p.get('gate_at', 0.7):g}); lower fill_to")
    fill_from, fill_to = p.get("fill_from", 0.0), p.get("fill_to", 1.0)
    if p.get("n_parts", 1) > 0 and fill_from >= fill_to:  # (only a pre-fill has a place)
        raise ParameterError(f"fill_from={fill_from:g} must be below fill_to={fill_to:g}")
    radius = size / 2 if shape == 0 else (p.get("part_thickness", size) + p.get("bump_height", 0.0)) / 2
    if "wall_height" in p and p["wall_height"] <= radius:
        raise ParameterError(f"wall_height={p['wall_height']:g} m is no higher than a part's centre "
                             f"({radius:g} m): parts would leave over the walls")
    n = p.get("n_parts", 0)
    if n > 0 and "wall_height" in p and math.isfinite(length):
        volume = volume_of(p)
        pile = n * volume / (FILL_PACKING * (fill_to - fill_from) * length * p["track_width"])
        if pile > p["wall_height"]:
            raise ParameterError(f"n_parts={n:g} settle {pile:.3g} m high, above the walls "
                                 f"(wall_height={p['wall_height']:g} m); fewer parts, a longer fill "
                                 "(fill_from, fill_to) or higher walls")


# Step limits of the micro-scale surface forces, as decks/include/surface_forces.liggghts
# derives them (vibrofeed/models/adhesion.py and squeeze_film.py hold the same laws):
# a limit below this would mean hours of steps for a fraction of a second.
SURFACE_FORCES_MIN_DT = 1e-9  # s
VDW_D0 = 2e-10  # m, contact distance of smooth surfaces (Khan & Sarma, §3.1)
AIR_MEAN_FREE_PATH = 6.8e-8  # m, the smallest air-film clearance


# Stefan's law for a square plate of side a: F = STEFAN_SQUARE mu a^4 V / h^3 (the
# rectangle's series solution of the Reynolds equation; vibrofeed/models/squeeze_film.py
# computes it, tests/unit/models/test_squeeze_film.py checks this copy).
STEFAN_SQUARE = 0.421731044868524


def surface_forces_part(p: Mapping[str, float]) -> dict | None:
    """The part the surface forces' step limit is taken for, in either deck's
    vocabulary: ``mass`` [kg], sphere ``radius`` [m], and for a part lying on
    a flat face its ``area`` [m^2], Stefan's constant ``stefan`` [m^4] (F = mu K
    V / h^3) and free-flow drag length ``drag`` [m] (F = mu L V); None without
    the vocabulary. single_part: ``radius``, ``face_radius`` (a disc face).
    bulk_feeder: ``part_size``, ``shape`` (0 spheres, the smallest of a size
    spread: the stiffest; 1 chips, a square face; 2 discs), ``part_thickness``,
    ``size_spread`` -- the whole clump (its spheres share the face's force)."""
    if "density" not in p:
        return None
    rho = p["density"]
    if "radius" in p:  # single_part
        r, face = p["radius"], p.get("face_radius", 0.0)
        part = {"mass": part_volume(0, 2 * r) * rho, "radius": r}
        if face > 0:
            part.update(area=math.pi * face ** 2, stefan=1.5 * math.pi * face ** 4, drag=16 * face)
        return part
    if "part_size" not in p:
        return None
    size, shape = p["part_size"], int(p.get("shape", 0))
    if shape == 0:
        smallest = size * (1 - p.get("size_spread", 0.0))
        return {"mass": part_volume(0, smallest) * rho, "radius": smallest / 2}
    thickness = p.get("part_thickness", size)
    if shape == 3:  # (refused with the surface forces: no face of its own here)
        return {"mass": volume_of(p) * rho, "radius": Box.of(Part.from_values(p)).sphere_diameter / 2}
    if shape == 4:  # (as a box)
        from .stl_part import StlPart, template

        return {"mass": volume_of(p) * rho, "radius": float(template(StlPart.of(p))[:, 3].max())}
    mass = part_volume(shape, size, thickness) * rho
    if shape == 1:
        return {"mass": mass, "radius": thickness / 2, "area": size ** 2,
                "stefan": STEFAN_SQUARE * size ** 4, "drag": 16 * size / math.sqrt(math.pi)}
    face = size / 2
    return {"mass": mass, "radius": thickness / 2,
            "area": math.pi * face ** 2, "stefan": 1.5 * math.pi * face ** 4, "drag": 16 * face}


def surface_forces_step_limit(p: Mapping[str, float]) -> float:
    """Largest timestep [s] the vdW and squeeze-film forces allow (inf when both
    are off, or without a part's vocabulary; see :func:`surface_forces_part`)."""
    hamaker, mu = p.get("hamaker", 0.0), p.get("air_viscosity", 0.0)
    part = surface_forces_part(p) if (hamaker > 0 or mu > 0) else None
    if part is None:
        return math.inf
    mass, radius, flat = part["mass"], part["radius"], "area" in part
    roughness = p.get("roughness", 0.0)
    limit = math.inf
    if hamaker > 0:
        s = VDW_D0 + roughness
        kappa = (hamaker * part["area"] / (2 * math.pi * s ** 4)) if flat else hamaker * radius / (3 * s ** 3)
        if kappa > 0:  # (not underflowed)
            limit = math.pi / 50 * math.sqrt(mass / kappa)
    if mu > 0:
        h = max(roughness, AIR_MEAN_FREE_PATH)
        c = (mu * (part["stefan"] / h ** 3 + part["drag"]) if flat
             else 6 * math.pi * mu * radius * (radius / h + 1))
        if c > 0:
            limit = min(limit, mass / (10 * c))
    return limit


def _check_surface_forces(p: Mapping[str, float]) -> None:
    """The timestep the vdW and air-film forces need (the deck refuses the same by hand)."""
    if p.get("cross_tilt", 0.0) > 0 and (p.get("hamaker", 0.0) > 0 or p.get("air_viscosity", 0.0) > 0):
        raise ParameterError("cross_tilt: the surface forces (hamaker, air_viscosity) act on a level "
                             "floor; set cross_tilt=0 or turn them off")
    limit = surface_forces_step_limit(p)
    if limit < SURFACE_FORCES_MIN_DT:
        raise ParameterError(
            f"hamaker={p.get('hamaker', 0):g} J, air_viscosity={p.get('air_viscosity', 0):g} Pa s with "
            f"roughness={p.get('roughness', 0):g} m need a timestep of {limit:.2g} s (below "
            f"{SURFACE_FORCES_MIN_DT:g} s: the forces are too stiff at contact); raise roughness")
    dt = p.get("dt", 0.0)
    if dt > limit:
        raise ParameterError(f"dt={dt:g} s is longer than the {limit:.3g} s the surface forces need "
                             "(hamaker, air_viscosity); lower dt or set dt=0 (automatic)")


# A step beyond these fractions of the contact's times is one LIGGGHTS warns about
# (fix check/timestep/gran): a contact then lasts a few steps, overlaps jump and parts
# gain energy from nothing. The automatic dt is 2 % of the Hertz time.
MAX_HERTZ_FRACTION = 0.1
MAX_RAYLEIGH_FRACTION = 0.2
# The decks' Hertz time is taken at the surface's peak speed, at least this [m/s].
MIN_CONTACT_SPEED = 0.01


def _hertz_time(mass: float, radius: float, e_star: float, speed: float) -> float:
    """Hertz contact time [s] of an effective ``mass`` and ``radius`` at impact ``speed``:
    2.87 (m^2 / (R E*^2 v))^(1/5), taken as (m / E*)^(2/5) / R^(1/5) / v^(1/5): no square
    of E* overflows (youngs has no upper limit; past ~1e154 Pa, E*^2 is beyond a float) and
    no product of small values rounds to 0."""
    return 2.87 * (mass / e_star) ** 0.4 / radius ** 0.2 / speed ** 0.2


def _rayleigh_time(radius: float, density: float, youngs: float, poisson: float) -> float:
    """Rayleigh time [s] of a sphere of ``radius`` (the time a surface wave crosses it)."""
    shear = youngs / (2 * (1 + poisson))
    return math.pi * radius * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)


def _clump(p: Mapping[str, float]):
    """The part's clump, (n, 4) x y z r [m] (vibrofeed.parts, vibrofeed.stl_part,
    vibrofeed.geometry); None for a sphere."""
    shape = int(p.get("shape", 0))
    if shape == 3:
        return box_template(Box.of(Part.from_values(p)))
    if shape == 4:
        from .stl_part import StlPart, template

        return template(StlPart.of(p))
    if shape in (1, 2):
        from .geometry import chip_template, disc_template

        size = p["part_size"]
        return (chip_template if shape == 1 else disc_template)(size, p.get("part_thickness", size))
    return None


def part_spheres(p: Mapping[str, float]) -> int:
    """How many spheres a part of ``p`` is (1 for a sphere, or without a part's numbers)."""
    if "part_size" not in p or (int(p.get("shape", 0)) == 4 and "part_file" not in p):
        return 1
    if int(p.get("shape", 0)) == 3:
        return clump_count(Box.of(Part.from_values(p)))  # (counted: a refused film is not built)
    rows = _clump(p)
    return 1 if rows is None else len(rows)


def contact_times(p: Mapping[str, float]) -> dict[str, float] | None:
    """``{"hertz": s, "rayleigh": s}``: the shortest contact times of a deck's parts,
    as the decks derive their automatic dt (decks/*.liggghts, "derived"); None
    without a contact vocabulary. single_part: a sphere of ``radius`` on a plate
    of its material. bulk_feeder and pulloff: the smallest contact sphere with its
    share of the part's mass, part-part (half of it, R* = r/2) and part-track
    (E* with the track's modulus, R* = r); the shorter time counts."""
    if not {"density", "youngs", "poisson"} <= set(p):
        return None
    if int(p.get("shape", 0)) == 4 and "part_file" not in p:  # (numbers alone: no STL to clump)
        return None
    rho, youngs, nu = p["density"], p["youngs"], p["poisson"]
    v_peak = 2 * math.pi * p.get("freq", 0.0) * math.hypot(p.get("amp_t", 0.0), p.get("amp_n", 0.0))
    speed = max(v_peak, MIN_CONTACT_SPEED)
    if "radius" in p:  # single_part
        r = p["radius"]
        mass = part_volume(0, 2 * r) * rho
        hertz = _hertz_time(mass, r, youngs / (2 * (1 - nu ** 2)), speed)
        return {"hertz": hertz, "rayleigh": _rayleigh_time(r, rho, youngs, nu)}
    if "part_size" not in p:
        return None
    size, shape = p["part_size"], int(p.get("shape", 0))
    thickness = p.get("part_thickness", size)
    r_sph = size / 2 if shape == 0 else thickness / 2
    r_min = r_sph * (1 - p.get("size_spread", 0.0))
    mass = part_volume(shape, size, thickness) * rho if shape < 3 else volume_of(p) * rho
    rows = _clump(p)
    if rows is not None and shape >= 3:  # a box's or an STL's: its largest and smallest spheres
        r_sph, r_min = float(rows[:, 3].max()), float(rows[:, 3].min())
    spheres = 1 if rows is None else len(rows)  # (a clump's spheres share the mass)
    m = mass * (r_min / r_sph) ** 3 / spheres
    youngs_track = p.get("youngs_track", 0.0) or youngs * 70 / 130
    e_pp = youngs / (2 * (1 - nu ** 2))
    e_pw = 1 / ((1 - nu ** 2) / youngs + (1 - p.get("poisson_track", nu) ** 2) / youngs_track)
    if "pair" in p:  # pulloff: nothing vibrates, the deck takes 1 cm/s
        speed = MIN_CONTACT_SPEED
    hertz = min(_hertz_time(m / 2, r_min / 2, e_pp, speed), _hertz_time(m, r_min, e_pw, speed))
    return {"hertz": hertz, "rayleigh": _rayleigh_time(r_min, rho, youngs, nu)}


def step_beyond_contact(p: Mapping[str, float]) -> str | None:
    """What is wrong with the fixed ``dt`` of ``p`` if it exceeds the contact's limits
    (:data:`MAX_HERTZ_FRACTION`, :data:`MAX_RAYLEIGH_FRACTION`, the fractions the
    decks' check/timestep/gran warns at); None for the automatic dt (dt = 0), without
    a contact vocabulary, or for a dt no longer than the automatic one (1/50 of the
    Hertz time, which a stiff material may put past the Rayleigh fraction)."""
    dt = p.get("dt", 0.0)
    times = contact_times(p) if dt > 0 else None
    if times is None or dt <= times["hertz"] / 50:
        return None
    limits = {"rayleigh": MAX_RAYLEIGH_FRACTION, "hertz": MAX_HERTZ_FRACTION}
    over = [f"{dt / times[k]:.0%} of the {k.capitalize()} time (limit {limit:.0%})"
            for k, limit in limits.items() if dt > limit * times[k]]
    return f"dt={dt:g} s is " + " and ".join(over) if over else None


def _check_contact_step(p: Mapping[str, float]) -> None:
    """A fixed dt beyond the contact's limits, unless the user insists (dt_unchecked=1:
    the run goes, and fails at its end, as ``vibrofeed check`` rejects its result; its frames
    are kept in OUT.h5.part)."""
    problem = step_beyond_contact(p)
    if problem and p.get("dt_unchecked", 0):
        warnings.warn(f"{problem}, run as dt_unchecked=1 asks: vibrofeed check rejects the result, "
                      "so the run fails (its frames kept in OUT.h5.part)",
                      ParameterWarning, stacklevel=5)
    elif problem:
        anyway = ("; to run it anyway add -p dt_unchecked=1 (the run then fails, as vibrofeed check "
                  "rejects its result, with its frames kept)"
                  if "dt_unchecked" in p else "")  # (a deck of one's own may not declare it)
        raise ParameterError(f"{problem}: contacts would last a few steps and parts gain energy; "
                             f"lower dt or set dt=0 (automatic){anyway}")


# The engine's cost of a step on one core [s], the run time's estimate: a fixed share (a lone
# part on its plate ~5 us; a feeder's meshes, movers and tooling 15.7 us for a track and
# 32.6 us for the demo's line with ~10 parts; a bowl's 602 triangles, turned and lifted, 150
# us: its demo of 50 nine-sphere dies steps 3 505 times a second) and one per sphere of the
# parts held (0.28-0.31 us per sphere-step for spheres, chips and boxes alike); BENCHMARKS.md,
# bench_bulk and bench_parts. It tells hours from days, and a line of 36-sphere boxes from one
# of spheres.
STEP_SECONDS = {"single": 5e-6, "feeder": 30e-6, "bowl": 150e-6}
SPHERE_STEP_SECONDS = 0.3e-6


def parts_held(p: Mapping[str, float]) -> float:
    """The parts a run holds on average, for its cost: the pile and the track's, and half of
    those fed over the run (a line fills as it runs), but no more fed ones than cover its
    linear sections' floors once (:func:`floor_capacity`: what a line delivers or rejects
    leaves it); one for the single part."""
    if "radius" in p:
        return 1.0
    fed = p.get("inlet_rate", 0.0) * p.get("t_end", 0.0) / 2
    capacity = floor_capacity(p)
    if capacity is not None:
        fed = min(fed, capacity)
    return max(p.get("n_parts", 0.0) + p.get("n_track", 0.0) + fed, 1.0)


def floor_capacity(p: Mapping[str, float]) -> float | None:
    """How many parts lie on a feeder line's floors side by side, one layer: its linear
    sections' length x width over the footprint of a part lying flat along the path (its
    widest by what it takes abreast: L x W for a box); None for a bowl, a line with another
    kind of element (a chute, a mesh), or without the part's or the floors' sizes."""
    if "part_size" not in p or starts_with_bowl(p):
        return None
    try:
        feeder = Feeder.from_values(p)
    except (ParameterError, KeyError, ValueError):
        return None
    if not all(isinstance(e, LinearSection) and e.length > 0 and e.width > 0 for e in feeder.elements):
        return None
    return sum(e.length * e.width for e in feeder.elements) / (feeder.part.widest * feeder.part.abreast)


def step_seconds(p: Mapping[str, float]) -> float:
    """Estimated wall seconds per step on one core of a run of ``p``: the fixed share and each
    sphere of the parts held (:func:`parts_held`, :func:`part_spheres`)."""
    base = STEP_SECONDS["single" if "radius" in p else "bowl" if starts_with_bowl(p) else "feeder"]
    return base + SPHERE_STEP_SECONDS * parts_held(p) * part_spheres(p)


def run_steps(p: Mapping[str, float]) -> tuple[float, float] | None:
    """(the steps of a run, its timestep [s]) as the decks derive them: ``t_end`` (and a
    given ``t_settle``) over the given ``dt``, or over the automatic one (decks/*.liggghts,
    "derived": ``output_dt`` split into whole steps no longer than 1/50 of the Hertz time at
    the fastest section's surface speed, nor than the surface forces' step limit); None
    without ``t_end`` or a contact vocabulary."""
    if "t_end" not in p:
        return None
    dt = p.get("dt", 0.0)
    if dt <= 0:
        # (a cross stroke adds to the along one: the decks' peak speed is the amplitudes' norm)
        drives = [(p.get(f"{s}freq", 0.0), math.hypot(p.get(f"{s}amp_t", 0.0), p.get(f"{s}amp_c", 0.0)),
                   p.get(f"{s}amp_n", 0.0))
                  for s in ("", *(f"s{k}_" for k in range(2, int(p.get("sections", 1)) + 1)))]
        freq, amp_t, amp_n = max(drives, key=lambda d: d[0] * math.hypot(d[1], d[2]))
        times = contact_times({**p, "freq": freq, "amp_t": amp_t, "amp_n": amp_n})
        if times is None:
            return None
        limit = min(times["hertz"] / 50, surface_forces_step_limit(p))
        out = p.get("output_dt", limit)
        dt = out / math.ceil(out / limit)
    return (p["t_end"] + p.get("t_settle", 0.0)) / dt, dt
