"""Values that are legal but make no sense: unit slips and options without effect.

:mod:`vibrofeed.parameters` refuses what cannot run. Here is what runs but is
almost certainly not what the user meant: a density in g/cm³ (2.33 for
silicon's 2330 kg/m³), a modulus in GPa, a length in mm or µm where the decks
take metres, a frequency in rad/s, an angle in radians; and a parameter the
chosen setting ignores (a duty cycle with a sine, a gate position without a
gate, a chip thickness for spheres). The limits of values no material
or micro-feeder has are here too (:data:`vibrofeed.parameters.RULES` refuses
beyond them); :func:`advice` names the rest, one line each,
naming the parameter (:func:`vibrofeed.parameters.resolve` issues them as
:class:`ParameterWarning`, which the command line prints as
``vibrofeed: warning: ...``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Collection, Mapping

from .feeders.feeder import side_tools_unprefixed

# Solids span about 500 (polymer foams excepted) to 22 590 kg/m³ (osmium).
DENSITY_PLAUSIBLE = (100.0, 25_000.0)  # kg/m³
DENSITY_MAX = 1e5  # kg/m³: four times osmium; no material
# A micro-part: microns to a centimetre; a metre is no micro-part.
PART_PLAUSIBLE = (1e-6, 0.01)  # m
PART_MAX = 1.0  # m
# A feeder track: millimetres to a metre or two long; its width, walls and tooling are
# millimetres to centimetres (a width or height "in mm" typed as metres is 0.5 .. 20).
TRACK_PLAUSIBLE = (1e-4, 2.0)  # m
ACROSS_PLAUSIBLE = (1e-4, 0.1)  # m, widths
HEIGHT_PLAUSIBLE = (1e-4, 0.05)  # m, wall heights
TOOLING_PLAUSIBLE = (0.0, 0.01)  # m, steps and the wiper's height: up to a large part's size
# Vibratory feeders: tens of Hz (bowls) to kHz (piezo); beyond 10 kHz ultrasonic.
FREQ_PLAUSIBLE_MAX = 1e4  # Hz
# Coulomb friction of solids: 0.05 to about 1.5.
MU_PLAUSIBLE_MAX = 2.0
# Surface energies of solids: 0.01 to 2 J/m² (silicon ~1.4).
SURFACE_ENERGY_PLAUSIBLE_MAX = 10.0  # J/m²

PART_LENGTHS = ("radius", "part_size", "part_thickness", "part_width", "face_radius")
# A feeder line's section 2 (s2_*) takes section 1's units: its twins share its limits.
TRACK_LENGTHS = {
    "track_length": TRACK_PLAUSIBLE, "s2_length": TRACK_PLAUSIBLE,
    "track_width": ACROSS_PLAUSIBLE, "gate_width": ACROSS_PLAUSIBLE, "s2_width": ACROSS_PLAUSIBLE,
    "s2_drop_width": ACROSS_PLAUSIBLE, "s2_gate_width": ACROSS_PLAUSIBLE,
    "wall_height": HEIGHT_PLAUSIBLE, "s2_wall_height": HEIGHT_PLAUSIBLE,
    "s2_step": TOOLING_PLAUSIBLE, "s2_wiper_height": TOOLING_PLAUSIBLE,
}
FREQUENCIES = ("freq", "s2_freq")
ANGLES = ("phase", "incline", "cross_tilt", "s2_phase", "s2_cross_tilt")


def _round_multiple(x: float, step: float, rel: float = 1e-3) -> bool:
    """Whether ``x`` is within ``rel`` x ``step`` of a non-zero whole multiple of ``step``."""
    k = round(x / step)
    return k != 0 and abs(x - k * step) <= rel * step


def advice(p: Mapping[str, float], given: Collection[str] = ()) -> list[str]:
    """One line per implausible value of ``p`` (numbers by name) and per parameter
    in ``given`` (the names the user set) that has no effect with the others."""
    out = []

    def say(name: str, text: str) -> None:
        out.append(f"parameter {name}={p[name]:g} {text}")

    lo, hi = DENSITY_PLAUSIBLE
    if "density" in p and p["density"] < lo:
        say("density", f"kg/m³ is lighter than any solid: a density in g/cm³? (silicon: 2330 kg/m³, "
                       f"not {p['density']:g})")
    elif "density" in p and p["density"] > hi:
        say("density", "kg/m³ is denser than any solid (osmium: 22590 kg/m³)")
    for name in PART_LENGTHS:
        x = p.get(name, 0.0)
        if x > PART_PLAUSIBLE[1]:
            say(name, f"m is {x * 1e3:g} mm: a length in mm or µm? (lengths are in metres)")
        elif 0 < x < PART_PLAUSIBLE[0]:
            say(name, f"m is {x * 1e9:g} nm: smaller than a micro-part (lengths are in metres)")
    for name, (lo, hi) in TRACK_LENGTHS.items():
        x = p.get(name, 0.0)
        if x > hi:
            size = f"{x:g} metres" if x >= 1 else f"{x * 1e3:g} mm"
            say(name, f"m is {size}: a length in mm? (lengths are in metres)")
        elif 0 < x < lo:
            say(name, f"m is {x * 1e6:g} µm: narrower than a feeder's track (lengths are in metres)")
    for name in FREQUENCIES:
        freq = p.get(name, 0.0)
        if freq > FREQ_PLAUSIBLE_MAX:
            say(name, f"Hz is beyond vibratory feeders (up to {FREQ_PLAUSIBLE_MAX:g} Hz): in rad/s?")
        elif freq > 0 and freq != round(freq) and _round_multiple(freq, 2 * math.pi * 5):
            say(name, f"Hz is 2 pi x {freq / (2 * math.pi):.4g}: an angular frequency in rad/s? "
                      f"({name} is in Hz)")
    for name in ANGLES:
        x = p.get(name, 0.0)
        if x != round(x) and abs(x) <= 2 * math.pi and _round_multiple(x, math.pi / 36):
            say(name, f"deg is {x / math.pi:.4g} pi: an angle in radians? (angles are in degrees)")
    for name in ("mu", "mu_pp"):
        if p.get(name, 0.0) > MU_PLAUSIBLE_MAX:
            say(name, "exceeds the friction of solids (0.05 to 1.5)")
    for name in ("surface_energy", "surface_energy_pp"):
        if p.get(name, 0.0) > SURFACE_ENERGY_PLAUSIBLE_MAX:
            say(name, "J/m² exceeds the surface energies of solids (0.01 to 2 J/m²): in mJ/m²?")
    # a skin reaching past a whole part holds every sphere that near in each list: slow, and
    # almost always a length in mm (the decks' own is 0.4 of the smallest sphere's radius)
    if p.get("skin", 0.0) > p.get("part_size", math.inf):
        say("skin", f"m is wider than a part ({p['part_size']:g} m): every sphere within it is a "
                    "neighbour and each step slows; a length in mm? (lengths are in metres)")
    out += _without_effect(p, given)
    return out


# The analysis commands' options take SI units as the run's parameters do: beyond these a
# value is almost always one in other units (a gap in um typed as metres, a mass in grams).
OPTION_PLAUSIBLE = {
    "m": (0.1, "is longer than a feeder's gaps and parts: a length in mm or µm? ({option} is in "
               "metres)"),
    "s": (10.0, "is longer than a feeder's parts arrive apart: a time in ms? ({option} is in seconds)"),
    "kg": (1.0, "is heavier than a part a finger grasps: a mass in g? ({option} is in kg)"),
    "-": (MU_PLAUSIBLE_MAX, "exceeds the friction of solids (0.05 to 1.5)"),
}


def option_advice(option: str, x: float | None, unit: str) -> str | None:
    """One line when the value ``x`` of a command's ``option`` (in ``unit``: m, s, kg, or -
    for a friction coefficient) is beyond what it can mean in that unit, else None."""
    limit, why = OPTION_PLAUSIBLE[unit]
    if x is None or not x > limit:
        return None
    shown = f"{x:g} {unit}" if unit != "-" else f"{x:g}"
    return f"{option} {shown} {why.format(option=option)}"


def _without_effect(p: Mapping[str, float], given: Collection[str]) -> list[str]:
    """The given parameters that the others make idle."""
    idle = {}
    waveform = int(p.get("waveform", 0))
    if "duty" in p and waveform not in (2, 3):
        idle["duty"] = f"applies to waveforms 2 and 3 (stick-slip, Coulomb pump), not waveform={waveform}"
    if waveform in (2, 3, 4):  # (decks/include/surface_motion.liggghts: along x only; 0 says so)
        for name in ("amp_n", "phase"):
            if p.get(name, 0.0) != 0:
                idle[name] = (f"shapes the motion normal to the track: waveform={waveform} moves it "
                              "along the track only")
    sections = [int(m[1]) for n in p if (m := re.match(r"^s(\d)_", n))]
    for s in ("", *(f"s{k}_" for k in sorted(set(sections)))):
        phase, amp_t, amp_n = f"{s}phase", f"{s}amp_t", f"{s}amp_n"
        if phase in p and waveform in (0, 1) and (p.get(amp_t, 1.0) == 0 or p.get(amp_n, 1.0) == 0):
            idle[phase] = "shifts the normal motion against the tangential one: one of them is 0"
        if f"{s}phase_c" in p and p.get(f"{s}amp_c", 0.0) == 0:
            idle[f"{s}phase_c"] = f"shifts the cross stroke: {s}amp_c=0 has none"
        if f"{s}gate_at" in p and p.get(f"{s}gate_width", 0.0) == 0:
            idle[f"{s}gate_at"] = f"places the gate: {s}gate_width=0 has none"
    if "part_size" in p and int(p.get("shape", 0)) == 0:
        idle["part_thickness"] = "applies to chips, discs and boxes (shape 1, 2, 3), not to spheres"
    if "part_size" in p and int(p.get("shape", 0)) != 3:
        for name in ("part_width", "bump_height", "bump_diameter", "bump_at", "clump_spacing"):
            idle[name] = "shapes a box (shape 3) only"
    if "part_size" in p and int(p.get("shape", 0)) != 4:
        for name in ("part_unit", "clump_method", "clump_spheres", "clump_resolution", "clump_overlap"):
            idle[name] = "shapes an stl part (shape 4) only"
    if "part_size" in p and int(p.get("shape", 0)) == 3 and p.get("bump_height", 0.0) == 0:
        for name in ("bump_diameter", "bump_at"):
            idle[name] = "shapes the bump: bump_height=0 has none"
    if p.get("inlet_rate", 1.0) == 0:
        idle["inlet_batch"] = "groups the inlet's parts: inlet_rate=0 has no inlet"
    if p.get("n_parts", 1.0) == 0:
        for name in ("fill_from", "fill_to"):
            idle[name] = "places the pre-fill: n_parts=0 has none"
    if p.get("hamaker", 0.0) == 0 and p.get("air_viscosity", 0.0) == 0:
        for name in ("roughness", "face_radius"):
            idle[name] = "shapes the surface forces: hamaker=0 and air_viscosity=0 turn them off"
    if p.get("dt", 0.0) == 0:
        idle["dt_unchecked"] = "allows a fixed dt beyond the contact's limits: dt=0 is automatic"
    if p.get("recirculate", 0.0) == 0:
        idle["return_delay"] = "delays the rejects' return to the inlet: recirculate=0 removes them"
    # a line's tooling, section by section; the first element's if its own names place a side
    # drop and a wiper (no prefix: a bowl's, on its helix, vibrofeed.bowl)
    tooled = [f"s{k}_" for k in sorted(set(sections))] + ([""] if side_tools_unprefixed(p) else [])
    for s in tooled:
        if p.get(f"{s}wiper_height", 1.0) == 0:
            idle[f"{s}wiper_at"] = f"places the wiper: {s}wiper_height=0 has none"
            if s:  # (a bowl's wiper is not skewed)
                idle[f"{s}wiper_skew"] = f"turns the wiper: {s}wiper_height=0 has none"
        drop_to = p.get(f"{s}drop_to", 1.0 if s else 0.0)  # (the bowl's drop_to=0: no side drop)
        if drop_to <= p.get(f"{s}drop_from", 0.0):  # (vibrofeed.line: no side drop)
            for name in (f"{s}drop_width", f"{s}drop_from", f"{s}drop_to"):
                idle[name] = f"shapes the side drop: {s}drop_to <= {s}drop_from has none"
    if "sections" in p:  # (last: no section k says it all)
        for name in p:
            if (m := re.match(r"^s(\d)_", name)) and int(m[1]) > int(p["sections"]):
                idle[name] = (f"shapes a feeder line's section {m[1]}: sections={int(p['sections'])} "
                              "has none")
    return [f"parameter {name} has no effect: it {why}" for name, why in idle.items()
            if name in given and name in p]
