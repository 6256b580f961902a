"""The analytic model of a deck run: the same surface motion and contact.

One place translates the deck vocabulary (README, "Decks") into the model
objects of this package, so the DEM and the model (of a validation case, of
a feed-rate report's dilute limit, of a sweep row) are driven by the same
numbers. The waveform formulas of
``decks/single_part.liggghts`` and the classes here are checked against each
other through the engine (tests/engine/test_waveform_decks.py).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping

from .adhesion import Adhesion
from .constants import G
from .part_on_surface import PartParams, SteadyState, mean_velocity
from .squeeze_film import Film, clearance
from .surface import (
    CoulombPumpWaveform,
    SineWaveform,
    SquareWaveAccel,
    StickSlipWaveform,
    SurfaceMotion,
)
from .vertical import Contact

SINE, SQUARE, STICK_SLIP, COULOMB_PUMP = 0, 1, 2, 3


def _f(p: Mapping, name: str, default=None) -> float:
    value = p.get(name, default)
    if value is None:
        raise KeyError(f"parameter {name!r} is needed")
    return float(value)


def amp_from_gamma(gamma: float, freq: float, g: float = G) -> float:
    """Displacement amplitude [m] of a sine with peak acceleration gamma g."""
    return gamma * g / (2 * math.pi * freq) ** 2


def gamma_from_amp(amp: float, freq: float, g: float = G) -> float:
    return amp * (2 * math.pi * freq) ** 2 / g


def waveform(p: Mapping) -> SurfaceMotion:
    """The surface motion of deck parameters ``p`` (freq, amp_t, amp_n,
    phase, waveform, duty), as the deck moves the plate. Both the
    part-on-surface and the vertical model take it as it is."""
    kind = int(_f(p, "waveform", SINE))
    freq, amp_t, amp_n = _f(p, "freq"), _f(p, "amp_t", 0.0), _f(p, "amp_n", 0.0)
    phase, duty = _f(p, "phase", 0.0), _f(p, "duty", 0.7)
    if kind == SINE:
        return SineWaveform(freq, amp_t, amp_n, phase)
    if kind == SQUARE:
        # square-wave acceleration a has displacement amplitude a / (32 f^2)
        return SquareWaveAccel(freq, 32 * freq ** 2 * amp_t, 32 * freq ** 2 * amp_n, phase)
    if kind == STICK_SLIP:
        # zero-mean triangular velocity of peak vp has displacement amplitude vp / (8 f)
        return StickSlipWaveform.from_peak_speed(freq, 8 * amp_t * freq, duty)
    if kind == COULOMB_PUMP:
        T = 1.0 / freq
        tb = (1 - duty) * T / 2
        accel = 2 * amp_t / (tb ** 2 * (1 - tb / T) ** 2)
        return CoulombPumpWaveform(freq, accel * tb ** 2 / T, accel)
    raise ValueError(f"waveform must be 0, 1, 2 or 3, got {kind}")


def part(p: Mapping, weighed: bool = True) -> PartParams:
    """The model part of a deck run: LIGGGHTS has one friction coefficient,
    so mu_s = mu_k = mu; e = restitution (below 1: a perfectly elastic part
    never settles). ``weighed``: its mass from the deck (:func:`mass`), else
    the model's unit mass, which only scales the forces the model reports,
    never its motion."""
    mu = _f(p, "mu")
    e = min(_f(p, "restitution"), 0.999)
    return PartParams(mu_s=mu, mu_k=mu, e=e, mass=mass(p) if weighed else PartParams.mass)


def transport(p: Mapping, g: float = G) -> SteadyState:
    """The steady conveying of one part of a deck run alone on its track
    (Khan & Sarma, §2.3.2: hopping and sliding): the deck's surface motion,
    part and ``incline`` (default 0); ``g`` the gravity it feels."""
    return mean_velocity(waveform(p), part(p, weighed=False), incline=_f(p, "incline", 0.0), g=g)


def mass(p: Mapping) -> float:
    """Mass [kg] of the deck's part: the single-part deck's sphere of
    ``radius``, or the bulk deck's ``shape`` 0 sphere (diameter ``part_size``,
    nominal size), 1 chip (part_size^2 x part_thickness), 2 disc, 3 box (with its bump)
    or 4 stl (its solid)."""
    rho = _f(p, "density")
    if "radius" in p:
        return 4.0 / 3.0 * math.pi * _f(p, "radius") ** 3 * rho
    shape = int(_f(p, "shape", 0))
    if shape == 4:  # the STL's solid (vibrofeed.stl_part reads and checks it before a run)
        if not p.get("part_file"):
            raise ValueError("an stl part (shape 4) is weighed from its STL: part_file is missing")
        return _stl_volume(str(p["part_file"]), _f(p, "part_unit", 1e-3)) * rho
    size = _f(p, "part_size")
    if shape == 0:
        return math.pi / 6.0 * size ** 3 * rho
    thickness = _f(p, "part_thickness")
    if shape == 1:
        return size ** 2 * thickness * rho
    if shape == 2:
        return math.pi / 4.0 * size ** 2 * thickness * rho
    if shape == 3:  # a box and its bump's cap above the face (vibrofeed.parts)
        h, r = _f(p, "bump_height", 0.0), _f(p, "bump_diameter", 0.0) / 2
        cap = math.pi * h * h * (3 * r - h) / 3 if h > 0 else 0.0
        return (size * _f(p, "part_width") * thickness + cap) * rho
    raise ValueError(f"shape must be 0, 1, 2, 3 or 4, got {shape}")


@functools.lru_cache(maxsize=16)
def _stl_volume(file: str, unit: float) -> float:
    """The volume [m^3] of a closed STL at ``unit`` metres per unit (read here, not through
    vibrofeed.stl_part, so that the models stay free of the package beyond them)."""
    import trimesh

    mesh = trimesh.load(file, force="mesh")
    return abs(float(mesh.volume)) * unit**3


def adhesion(p: Mapping) -> Adhesion:
    """The van der Waals adhesion of the deck's part to the track (``hamaker``,
    ``roughness``): the single-part deck's sphere of ``radius`` (on a flat face
    of ``face_radius`` when > 0), or the bulk deck's ``shape`` 0 sphere of
    diameter ``part_size``, 1 chip or 2 disc lying on its face."""
    hamaker, roughness = _f(p, "hamaker"), _f(p, "roughness")
    if "radius" in p:
        return Adhesion(hamaker, roughness, radius=_f(p, "radius"), face_radius=_f(p, "face_radius", 0.0))
    shape, size = int(_f(p, "shape", 0)), _f(p, "part_size")
    if shape not in (0, 1, 2):
        raise ValueError(f"shape must be 0, 1 or 2 (a box's adhesion is not modelled yet), got {shape}")
    face = ({"radius": size / 2}, {"face_side": size}, {"face_radius": size / 2})[shape]
    return Adhesion(hamaker, roughness, **face)


def film(p: Mapping) -> Film:
    """The squeeze film under the single-part deck's part (``air_viscosity``, the
    clearance of ``roughness``): under its flat face of ``face_radius`` when > 0,
    else under the sphere of ``radius``; flowing freely out at the rim."""
    face = _f(p, "face_radius", 0.0)
    return Film(_f(p, "air_viscosity"), face if face > 0 else _f(p, "radius"), clearance(_f(p, "roughness")),
                flat=face > 0, free_flow=True)


def vertical_contact(p: Mapping) -> Contact:
    """The vertical-transport contact of a deck run with incline = 90 and a
    pressing ``normal_force``: mu_s = mu_k = mu."""
    mu = _f(p, "mu")
    return Contact(mass=mass(p), normal_force=_f(p, "normal_force"), mu_s=mu, mu_k=mu, g=G)
