"""Checking run parameters before a deck is handed to LIGGGHTS.

The decks share one vocabulary (README, "Decks"); the physical limits of each
name are stated here once. A bad value is refused with a message naming the
parameter, the value and the limit, before anything is started or written.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Mapping

from .decks import RESERVED, Deck
from .errors import ParameterError

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


def _integer(lo=None, choices=None):
    def check(x):
        if x != int(x):
            return "must be an integer"
        if choices is not None and int(x) not in choices:
            return f"must be one of {', '.join(map(str, choices))}"
        if lo is not None and x < lo:
            return f"must be >= {lo}"
        return None
    return check


# name -> check(value) returning an error text or None
RULES: dict[str, Callable[[float], str | None]] = {
    "freq": _positive,
    "amp_t": _between(0, MAX_AMPLITUDE, lo_open=False, hi_open=False,
                      why="a feeder's stroke is um to mm; amplitudes are in metres"),
    "amp_n": _between(0, MAX_AMPLITUDE, lo_open=False, hi_open=False,
                      why="a feeder's stroke is um to mm; amplitudes are in metres"),
    "phase": _finite,
    "incline": _between(-90, 90, lo_open=False, hi_open=False),
    "radius": _positive,
    "density": _positive,
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
}


def parse_assignments(items) -> dict[str, str]:
    """``["freq=50", "amp_n=2e-4"]`` -> ``{"freq": "50", "amp_n": "2e-4"}``."""
    out = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        name, value = name.strip(), value.strip()
        if not sep or not name or not value:
            raise ParameterError(f"parameter {item!r} is not of the form name=value")
        out[name] = value
    return out


def resolve(deck: Deck, given: Mapping[str, str]) -> dict[str, str]:
    """Deck defaults overridden by ``given``, checked; values as strings."""
    tunables = deck.tunables
    for name in given:
        if name in RESERVED:
            raise ParameterError(f"parameter {name!r} is set by vibrofeed itself, not by -p")
        if name not in tunables:
            close = difflib.get_close_matches(name, tunables, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ParameterError(
                f"unknown parameter {name!r} for deck {deck.name}{hint}; "
                f"valid parameters: {', '.join(tunables)}")
    values = {name: str(given.get(name, v.default)) for name, v in tunables.items()}

    numbers = {}
    for name, value in values.items():
        var = tunables[name]
        if not (var.is_numeric or name in RULES):
            continue
        try:
            x = float(value)
        except ValueError:
            raise ParameterError(f"parameter {name}={value!r} is not a number") from None
        if not math.isfinite(x):
            raise ParameterError(f"parameter {name}={value} is not finite")
        numbers[name] = x
        rule = RULES.get(name)
        problem = rule(x) if rule else None
        if problem:
            unit = f" {var.unit}" if var.unit and var.unit != "-" else ""
            raise ParameterError(f"parameter {name}={value}{unit} {problem}")
    _check_relations(numbers)
    return values


# A run asking for more frames than this is almost always a unit slip (output_dt
# in ms or us); with the automatic timestep it would also force dt = output_dt
# and run for hours before anyone noticed. Runs that really need it split t_end.
MAX_FRAMES = 1_000_000


def _check_relations(p: Mapping[str, float]) -> None:
    """Limits that involve several parameters."""
    for amp in ("amp_n", "amp_t"):
        if amp in p and "freq" in p:
            speed = 2 * math.pi * p["freq"] * p[amp]
            if speed > MAX_SURFACE_SPEED:
                raise ParameterError(
                    f"{amp}={p[amp]:g} m at freq={p['freq']:g} Hz moves the surface at "
                    f"{speed:.3g} m/s peak (limit {MAX_SURFACE_SPEED:g} m/s: real feeders stay "
                    f"below 0.5 m/s); lower {amp} or freq")
    if "output_dt" in p and "t_end" in p:
        if p["output_dt"] > p["t_end"]:
            raise ParameterError(
                f"output_dt={p['output_dt']:g} s is longer than the run, t_end={p['t_end']:g} s")
        frames = p["t_end"] / p["output_dt"]
        if frames > MAX_FRAMES:
            raise ParameterError(
                f"t_end={p['t_end']:g} s with output_dt={p['output_dt']:g} s would write "
                f"{frames:.3g} frames (limit {MAX_FRAMES:.0e}); raise output_dt or shorten t_end")
    dt = p.get("dt", 0.0)
    if dt > 0:
        if "output_dt" in p and p["output_dt"] < dt:
            raise ParameterError(
                f"output_dt={p['output_dt']:g} s is shorter than the timestep dt={dt:g} s")
        if "t_end" in p and p["t_end"] < dt:
            raise ParameterError(f"t_end={p['t_end']:g} s is shorter than the timestep dt={dt:g} s")
