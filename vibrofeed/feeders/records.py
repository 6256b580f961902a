"""The typed records a feeder is made of: its parts, a drive, the tooling stations.

Each record is read once from the deck's vocabulary (numbers, or the strings a deck's
parameters are) and then passed around: no code converts ``p["amp_t"]`` again.
Lengths in metres, angles in degrees, frequencies in hertz.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from ..errors import ParameterError
from ..orientation import Correct, run_correct
from ..values import number  # noqa: F401 (the feeders' parameters are read with it)

SHAPES = {"sphere": 0, "chip": 1, "disc": 2, "box": 3, "stl": 4}


def shape_code(value) -> int:
    """A part's shape as the deck's code: 0 sphere, 1 chip, 2 disc, 3 box, 4 stl (names accepted)."""
    text = str(value).strip().lower()
    if text in SHAPES:
        return SHAPES[text]
    try:
        code = float(text)
    except ValueError:
        code = -1.0
    if code not in (0.0, 1.0, 2.0, 3.0, 4.0):
        raise ParameterError(f"parameter shape={value} must be sphere, chip, disc, box or stl "
                             "(0, 1, 2, 3 or 4)")
    return int(code)


@dataclass(frozen=True)
class Part:
    """The parts a feeder conveys: ``shape`` (0 sphere, 1 chip, 2 disc, 3 box), ``size`` (a
    sphere's diameter, a chip's edge, a disc's diameter, a box's length L), ``thickness``
    (a chip's, disc's or box's), ``size_spread`` (spheres: radii R(1-s), R, R(1+s)); a
    box's ``width`` W, its bump (``bump_height`` 0: none, ``bump_diameter``, ``bump_at``) and
    its clump's ``clump_spacing`` (vibrofeed.parts); an stl part's STL and clump (``stl``, a
    vibrofeed.stl_part.StlPart; its size, width and thickness are its principal extents);
    ``correct``, what counts as correctly oriented (a vibrofeed.orientation.Correct, from the
    parameter ``correct``: the analyses' and the air jets' default)."""

    shape: int
    size: float
    thickness: float
    size_spread: float = 0.0
    width: float = 0.0
    bump_height: float = 0.0
    bump_diameter: float = 0.0
    bump_at: float = 0.5
    clump_spacing: float = 0.75
    stl: object = None
    correct: Correct = Correct()

    @classmethod
    def from_values(cls, values: Mapping) -> Part:
        size = number(values, "part_size", 0.0)  # (absent: a result that records no part)
        thickness = number(values, "part_thickness", size)
        return cls(shape=shape_code(values.get("shape", 0)), size=size, thickness=thickness,
                   size_spread=number(values, "size_spread", 0.0),
                   width=number(values, "part_width", thickness),
                   bump_height=number(values, "bump_height", 0.0),
                   bump_diameter=number(values, "bump_diameter", 0.0),
                   bump_at=number(values, "bump_at", 0.5),
                   clump_spacing=number(values, "clump_spacing", 0.75),
                   stl=_stl(values) if shape_code(values.get("shape", 0)) == 4 else None,
                   correct=run_correct(values))

    @property
    def widest(self) -> float:
        """Across a part lying flat: the largest sphere, the chip's or disc's edge, or the box's
        length [m]."""
        return self.size * (1 + self.size_spread) if self.shape == 0 else self.size

    @property
    def abreast(self) -> float:
        """Across a part lying flat along the path as it rides in a file [m]: a box's width W
        (lengthwise), every other part's widest."""
        return self.width if self.shape == 3 else self.widest

    @property
    def tallest(self) -> float:
        """A part's height lying flat: the largest sphere, or the thickness (a box's with its
        bump up) [m]."""
        if self.shape == 3:
            return self.thickness + self.bump_height
        return self.widest if self.shape == 0 else self.thickness

    @property
    def reach(self) -> float:
        """The circumscribed radius [m] (the decks' r_ext): the largest sphere's; a chip's
        corner sphere reaches (size - thickness)/sqrt(2) + thickness/2 from its centre; a
        disc's rim, size/2; a box's clump about its centre of mass, the bump included
        (vibrofeed.parts.box_reach)."""
        if self.shape == 3:
            from ..parts import Box, box_reach

            return box_reach(Box.of(self))
        if self.shape == 4:
            from ..stl_part import part_reach

            return part_reach(self.stl)
        if self.shape == 0:
            return self.widest / 2
        if self.shape == 1:
            return (self.size - self.thickness) / math.sqrt(2) + self.thickness / 2
        return self.size / 2


def _stl(values: Mapping):
    from ..stl_part import StlPart

    return StlPart.of(values)


@dataclass(frozen=True)
class Drive:
    """An element's vibration: ``freq`` [Hz], displacement amplitudes along (``amp_t``) and
    normal to (``amp_n``, vertical: a floor tilted across is also moved up its tilt, by
    amp_n sin(cross_tilt)) its floor [m], the normal motion's lead ``phase`` [deg], and the
    waveform (0 sine; 1-4 as include/surface_motion.liggghts, with ``duty``). A linear
    section may also move across its track: ``amp_c`` [m] along +y, leading the
    tangential motion by ``phase_c`` [deg] (a cross stroke: it rocks a part on its side over
    onto a broad face, docs/orientation.md)."""

    freq: float
    amp_t: float
    amp_n: float
    phase: float = 0.0
    waveform: int = 0
    duty: float = 0.7
    amp_c: float = 0.0
    phase_c: float = 0.0

    @property
    def peak_speed(self) -> float:
        """The sine's peak surface speed [m/s] (at most: the cross stroke's phase ignored)."""
        return 2 * math.pi * self.freq * math.hypot(self.amp_t, self.amp_n, self.amp_c)

    def sway_from(self, other: Drive) -> float:
        """How far two floors driven by this and ``other`` move apart across the track at most
        [m]: the amplitude of their cross strokes' difference (as :meth:`relative_to` along z)."""
        return _apart(self.freq, other.freq, self.amp_c, other.amp_c, self.phase_c, other.phase_c)

    def relative_to(self, other: Drive) -> tuple[float, float]:
        """How far two floors driven by this and ``other`` move apart at most [m]: normal (dz)
        and along (dx). Sines of one frequency: the amplitude of their difference,
        sqrt(a1^2 + a2^2 - 2 a1 a2 cos(phase1 - phase2)) normal, |amp_t1 - amp_t2| along
        (both start at sin(w t)); of two frequencies: the sum of the amplitudes (the phases
        drift)."""
        dz = _apart(self.freq, other.freq, self.amp_n, other.amp_n, self.phase, other.phase)
        if self.freq != other.freq:
            return dz, self.amp_t + other.amp_t
        return dz, abs(self.amp_t - other.amp_t)


def _apart(f1: float, f2: float, a1: float, a2: float, phase1: float, phase2: float) -> float:
    """The largest difference of a1 sin(w1 t + phase1) and a2 sin(w2 t + phase2) [m], phases
    in degrees: the amplitude of the difference at one frequency, the sum at two."""
    if f1 != f2:
        return a1 + a2
    dphi = math.radians(phase1 - phase2)
    return math.sqrt(max(a1 * a1 + a2 * a2 - 2 * a1 * a2 * math.cos(dphi), 0.0))


# ------------------------------------------------------------------ tooling stations
@dataclass(frozen=True)
class Gate:
    """A singulation gate: the walls narrow at 45 degrees from ``at`` (a fraction of the
    element's length) to ``width`` and stay narrow to the element's end."""

    kind = "gate"
    width: float
    at: float = 0.7

    def taper(self, width: float) -> float:
        """How long its 45-degree taper is along the path [m], from an element ``width`` wide."""
        return (width - self.width) / 2


@dataclass(frozen=True)
class SideDrop:
    """A side drop: from ``start`` to ``end`` (fractions of the element's length) the floor
    narrows to ``width`` from the reference wall and the other wall is missing; a part not
    against the wall falls off."""

    kind = "side_drop"
    start: float
    end: float
    width: float


@dataclass(frozen=True)
class Slot:
    """A slot trap: from ``start`` to ``end`` (fractions of the element's length) a hole
    ``width`` across in the floor, its centre ``offset`` from the reference wall (0: the
    default, vibrofeed.line.slot_offset). A part lying flat across it bridges it; one narrower
    than the slot where it rides (on its side, on its end) falls through."""

    kind = "slot"
    start: float
    end: float
    width: float
    offset: float = 0.0


@dataclass(frozen=True)
class Wiper:
    """A wiper: a bar across the element at ``at`` (a fraction of its length), ``length`` long,
    whose underside follows the floor ``height`` above it; a taller part is swept off.
    ``skew`` [deg] turns the bar from straight across: from the reference wall, where its
    upstream face stands at ``at``, it runs downstream to the far wall, so that a part taller
    than ``height`` conveyed against it is pushed towards the far wall: a box on a long side
    tips over onto a broad face there (docs/orientation.md, "The tipping rail")."""

    kind = "wiper"
    height: float
    at: float = 0.5
    length: float = 0.0
    skew: float = 0.0


JET_MODES = ("region", "ideal")


@dataclass(frozen=True)
class Jet:
    """An orienting station: a camera senses each part as its centre crosses ``at`` (a fraction
    of the element's length) and, for a part not in the state ``keep`` (a
    vibrofeed.orientation.Correct; ``keeps_correct``: the part's own correct state, the jet
    naming none of its own), an air jet fires ``delay`` seconds later for ``duration``
    seconds. The jet blows in a block ``length`` long along the path (0: one part size) centred
    ``offset`` downstream of the sensing point, across the track and up past its walls, with
    ``force`` [N] on a part wholly in it (shared by its spheres), ``angle`` degrees up from the
    floor towards the side away from the reference wall (+y). ``mode``: "region" blows
    everything in the block (as a real jet), "ideal" only the part that was sensed.
    ``headway`` [s] (0: none) spaces the stream as well: a part sensed less than ``headway``
    after the last part the jet let pass is fired at too, whatever its state."""

    kind = "jet"
    force: float
    keep: object  # vibrofeed.orientation.Correct
    at: float = 0.5
    delay: float = 0.0
    duration: float = 0.01
    offset: float = 0.0
    length: float = 0.0
    angle: float = 60.0
    mode: str = "region"
    keeps_correct: bool = False
    headway: float = 0.0


@dataclass(frozen=True)
class Camera:
    """Where and how a jet's camera looks, as the driver senses (vibrofeed.engine.jets): a part
    is sensed as the coordinate ``along`` gives its centre ((n, 3) points of the deck's frame
    -> (n,) [m]; None: their x) crosses ``at``; its state is classified along ``tangent`` with
    ``up`` the floor's normal; a part whose centre lies below ``z_floor`` [m] is falling, not
    sensed."""

    at: float
    tangent: tuple
    up: tuple
    z_floor: float
    along: object = None  # Callable[[np.ndarray], np.ndarray] | None
