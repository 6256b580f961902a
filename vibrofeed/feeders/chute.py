"""A declining chute: an undriven straight track that descends along the path, an element of
a feeder after its first section.

Parts slide or roll down it under gravity alone (a gravity chute between two feeders, or a
feeder's discharge). Frame: the deck's, as a linear section's (vibrofeed.feeders.linear):
it runs along x from ``x0`` to ``x1 = x0 + length`` (``length`` is its run along x, so the
analyses' path coordinate stays x), its floor starts ``step`` below the element before it
at the high edge (y = +w/2) and descends at ``slope`` degrees below the first section's
floor plane, across it tilts down towards the wall at -y by ``cross_tilt``:
``z(x, y) = -level - (x - x0) tan(slope) - (w/2 - y) tan(cross_tilt)``. Walls on both
sides follow the floor ``wall_height`` above its high edge; no wall at its joint or end.

Its numbers in the deck's vocabulary: ``s<k>_kind = 1`` (a chute), ``s<k>_length``,
``s<k>_width``, ``s<k>_wall_height``, ``s<k>_step``, ``s<k>_cross_tilt``, ``s<k>_slope``.
It does not move: its recorded motion (``s<k>_surface_*``) is zero, and the fastest a
part goes on it is the free fall down its drop, sqrt(2 g h), which sets the contact speed
(the step) if it is the fastest surface of the line.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..mesh import MeshBuilder
from .records import Drive, Part, number

KIND_CODE = 1  # s<k>_kind: 0 a linear section, 1 a chute
# description key -> (deck suffix, unit, meaning)
KEYS: dict[str, tuple[str, str, str]] = {
    "length": ("length", "m", "chute: its run along x, joint to end"),
    "width": ("width", "m", "chute: between its walls, at least the exit before it"),
    "wall_height": ("wall_height", "m", "chute: wall height above its floor's high edge"),
    "step": ("step", "m", "step down at the joint, to the chute's floor at its high edge"),
    "cross_tilt": ("cross_tilt", "deg", "chute's floor tilt across, down towards the wall at -y"),
    "slope": ("slope", "deg", "chute: its floor's descent along x below the first section's floor"),
}
# Steepest chute: beyond it parts fall rather than slide.
MAX_SLOPE = 60.0
# The mesh's stations along x, at most this far apart [m] (as a linear section's).
SPACING = 1e-3


def deck_name(k: int, key: str) -> str:
    return f"s{k}_{KEYS[key][0]}"


@dataclass(frozen=True)
class Chute:
    """Element ``number`` (>= 2): a declining chute (module docstring)."""

    kind = "chute"
    moves = False  # (it stands still: its recorded motion is zero)
    number: int
    x0: float
    length: float
    width: float
    wall_height: float
    slope: float
    cross_tilt: float = 0.0
    step: float = 0.0
    level: float = 0.0  # below the first section's floor where the chute starts
    drive: Drive = Drive(freq=0.0, amp_t=0.0, amp_n=0.0)  # (it does not move)
    side_drop = None
    wiper = None
    gate = None

    @classmethod
    def from_values(cls, values: Mapping, k: int, x0: float = 0.0, level: float = 0.0) -> Chute:
        def get(key, default=0.0):
            return number(values, deck_name(k, key), default)

        step = get("step")
        return cls(number=k, x0=x0, length=get("length"), width=get("width"),
                   wall_height=get("wall_height"), slope=get("slope"), cross_tilt=get("cross_tilt"),
                   step=step, level=level + step)

    # ---------------------------------------------------------------- geometry
    @property
    def x1(self) -> float:
        return self.x0 + self.length

    @property
    def drop(self) -> float:
        """How far its floor descends from start to end [m]."""
        return self.length * math.tan(math.radians(self.slope))

    @property
    def exit_band(self) -> tuple[float, float]:
        """Across its outlet edge, from wall to wall (y, its frame) [m]."""
        return -self.width / 2, self.width / 2

    @property
    def exit_width(self) -> float:
        return self.width

    def floor_z(self, x, y):
        """Height of the floor at ``x``, ``y`` [m] (module docstring)."""
        return (-self.level - (np.asarray(x, dtype=float) - self.x0) * math.tan(math.radians(self.slope))
                - (self.width / 2 - np.asarray(y, dtype=float)) * math.tan(math.radians(self.cross_tilt)))

    @property
    def exit_direction(self) -> tuple[float, float, float]:
        """+x, descending at its slope."""
        a = math.radians(self.slope)
        return math.cos(a), 0.0, -math.sin(a)

    def floor_at(self, x, y):
        """The floor's height at rest over (``x``, ``y``) [m]."""
        return self.floor_z(x, y)

    def entry_z(self, y):
        return self.floor_z(self.x0, y)

    def exit_z(self, y):
        return self.floor_z(self.x1, y)

    @property
    def exit_level(self) -> float:
        return self.level + self.drop

    @property
    def lowest(self) -> float:
        """The floor's lowest point at rest (its end, at the reference wall) [m]."""
        return float(self.floor_z(self.x1, -self.width / 2))

    @property
    def bounds(self) -> list[tuple[float, float]]:
        return [(self.x0, self.x1)]

    def name(self, key) -> str:
        key = key[0] if isinstance(key, tuple) else key
        return deck_name(self.number, key) if key in KEYS else key

    def mesh(self):
        """The chute at rest: its floor and two side walls, open at its joint and its end."""
        n = max(1, math.ceil(self.length / min(self.width, SPACING) - 1e-9))
        xs = np.linspace(self.x0, self.x1, n + 1)
        lo, hi = -self.width / 2, self.width / 2
        b = MeshBuilder()

        def z(x, y):
            return float(self.floor_z(x, y))

        def top(x):
            return z(x, hi) + self.wall_height

        for x0, x1 in zip(xs[:-1], xs[1:]):
            b.quad((x0, lo, z(x0, lo)), (x1, lo, z(x1, lo)), (x1, hi, z(x1, hi)), (x0, hi, z(x0, hi)))
            b.quad((x1, lo, z(x1, lo)), (x0, lo, z(x0, lo)), (x0, lo, top(x0)), (x1, lo, top(x1)))
            b.quad((x0, hi, z(x0, hi)), (x1, hi, z(x1, hi)), (x1, hi, top(x1)), (x0, hi, top(x0)))
        return b.mesh()

    def deck_commands(self) -> dict[str, list[str]]:
        """Its commands in the deck (vibrofeed.feeders.deck): the mesh standing still, a zero
        recorded motion, its lowest floor (its end) and the free-fall speed down its drop."""
        k, s = self.number, f"s{self.number}"
        level = "+".join(f"v_s{j}_step" for j in range(2, k + 1))
        return {
            "derived": [f"variable {s}_low equal -({level}+v_{s}_length*tan(v_{s}_slope*PI/180)"
                        f"+v_{s}_width*tan(v_{s}_cross_tilt*PI/180))"],
            "peak": [f"variable {s}_peak equal sqrt(2*v_g*v_{s}_length*tan(v_{s}_slope*PI/180))"],
            "catch": [f"variable {s}_catch equal v_{s}_low-2*v_r_ext"],
            "mesh": [f"fix track_{s} all mesh/surface file ${{mesh_dir}}/track_{s}.stl type 2"],
            "motion": [f"variable {s}_surface_{axis} equal 0"
                       for axis in ("x", "y", "z", "vx", "vy", "vz")],
        }

    # ---------------------------------------------------------------- checks
    def check(self, part: Part, last: bool = True) -> None:
        n = self.name
        if not 0 < self.slope <= MAX_SLOPE:
            raise ParameterError(f"{n('slope')}={self.slope:g} deg must be in (0, {MAX_SLOPE:g}]: a "
                                 "chute descends (a level or rising track is a linear section)")
        if self.width < part.widest:
            raise ParameterError(f"{n('width')}={self.width:g} m is narrower than a part "
                                 f"({part.widest:g} m across)")
        if self.wall_height <= part.tallest / 2:
            raise ParameterError(f"{n('wall_height')}={self.wall_height:g} m is no higher than a "
                                 f"part's centre ({part.tallest / 2:g} m): parts would leave over the walls")
        if not 0 <= self.cross_tilt <= 45:
            raise ParameterError(f"{n('cross_tilt')}={self.cross_tilt:g} deg must be in [0, 45]")
