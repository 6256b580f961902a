"""A vibratory bowl as the first element of a feeder: today's bowl (vibrofeed.bowl), and the
frame an exit line after it is built in.

Its numbers in the deck's vocabulary are decks/bowl_feeder.liggghts's own names
(:data:`KEYS` maps a description's keys to them); an exit line's elements are the deck's
``s<k>_*`` from k = 2, as a line's further sections.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .linear import block_planes, jet_span, turned_jet_commands, turned_jet_fix
from .records import Camera, Drive, Jet, Part, number

# description key (table, key) -> the bowl deck's name
KEYS: dict[tuple[str, ...], str] = {
    ("diameter",): "bowl_diameter",
    ("width",): "track_width",
    ("wall_height",): "wall_height",
    ("cross_tilt",): "cross_tilt",
    ("helix_angle",): "helix_angle",
    ("turns",): "turns",
    ("cone_angle",): "cone_angle",
    ("lip_height",): "lip_height",
    ("chute_length",): "chute_length",
    ("drive", "freq"): "freq",
    ("drive", "amp_t"): "amp_t",
    ("drive", "amp_n"): "amp_n",
    ("drive", "phase"): "phase",
    ("side_drop", "from"): "drop_from",
    ("side_drop", "to"): "drop_to",
    ("side_drop", "width"): "drop_width",
    ("wiper", "height"): "wiper_height",
    ("wiper", "at"): "wiper_at",
    **{("jet", key): f"jet_{key}" for key in ("force", "at", "keep", "delay", "duration", "offset",
                                              "length", "angle", "mode", "headway")},
}
# A description's bowl must state these (the rest have the deck's defaults).
NEEDED = ("diameter", "width", "turns", "helix_angle")


# The deck's parameters a bowl's recorded motion follows from (:class:`Turn`): its drive, and
# its diameter and track width (the stroke amp_t is along the track's centre line).
TURN_NAMES = ("freq", "amp_t", "amp_n", "phase", "bowl_diameter", "track_width")


@dataclass(frozen=True)
class Turn:
    """A bowl's surface motion as its deck's movers make it (decks/bowl_feeder.liggghts:
    riggle about z, viblin along z): sines of ``freq`` [Hz], a turn of amplitude ``angle``
    [rad] (the stroke amp_t along the track's centre line, at radius r_mid = bowl_diameter / 2 -
    track_width / 2, over that radius) and a lift of amplitude ``lift`` [m], ``phase`` [deg]
    ahead of the turn. What `vibrofeed check` holds a bowl's recorded angle and lift to."""

    freq: float
    angle: float
    lift: float
    phase: float

    @classmethod
    def from_values(cls, values) -> Turn:
        """From the deck's parameters :data:`TURN_NAMES` alone (numbers or their strings; a
        file's parameters may hold no more of the bowl): ParameterError naming one missing."""
        r_mid = number(values, "bowl_diameter") / 2 - number(values, "track_width") / 2
        return cls(freq=number(values, "freq"), angle=number(values, "amp_t") / r_mid,
                   lift=number(values, "amp_n"), phase=number(values, "phase"))


@dataclass(frozen=True)
class BowlElement:
    """Today's vibratory bowl (vibrofeed.bowl): a helical track up its wall, then a straight
    chute through the wall to the outlet edge. Along the path it has two sections, the
    helix and the chute; ``bowl`` is its geometry (vibrofeed.bowl.Bowl), ``drive`` its
    torsion and lift (the stroke along the track at its centre line, the lift).

    A bowl may hand its parts to an exit line (elements 2, 3 ... after it): the line's frame
    is the bowl's moved to the chute's end (:attr:`line_origin`), so that the line runs on
    along +x from the outlet edge, centred on the chute's centre line, its floors' heights
    counted from the chute's floor at its end at the high (inner) edge. Seen from there the
    chute's end is an exit as a linear section's: its width, its floor tilted down towards
    the wall, the torsion's stroke along it; the torsion also sways it across (:attr:`sway`)."""

    kind = "bowl"
    moves = True
    number = 1
    x0 = 0.0  # (its helix starts the path)
    bowl: object
    drive: Drive = Drive(freq=0.0, amp_t=0.0, amp_n=0.0)
    jet: Jet | None = None  # an air jet on the helix, blowing parts off its open inner edge

    @property
    def bounds(self) -> list[tuple[float, float]]:
        helix = self.bowl.length
        return [(0.0, helix), (helix, helix + self.bowl.chute_length)]

    # the chute's end as the exit of an element (vibrofeed.feeders.joints), in the line's frame
    @property
    def x1(self) -> float:
        return self.bowl.outlet_x

    @property
    def exit_band(self) -> tuple[float, float]:
        """Across the chute's end, from wall to wall (y, the bowl's frame) [m]."""
        b = self.bowl
        return -b.r_mid - b.track_width / 2, -b.r_mid + b.track_width / 2

    @property
    def exit_width(self) -> float:
        return self.bowl.track_width

    def exit_z(self, y):
        return -(self.bowl.track_width / 2 - y) * math.tan(math.radians(self.bowl.cross_tilt))

    @property
    def exit_level(self) -> float:
        return 0.0

    @property
    def exit_direction(self) -> tuple[float, float, float]:
        """The chute's direction: +x, rising at the helix angle."""
        a = math.radians(self.bowl.helix_angle)
        return math.cos(a), 0.0, math.sin(a)

    @property
    def sway(self) -> float:
        """How far the torsion moves the chute's end across [m]: the turn's amplitude
        amp_t / r_mid times the end's distance from the axis along x."""
        return self.drive.amp_t / self.bowl.r_mid * self.bowl.outlet_x

    @property
    def line_origin(self) -> tuple[float, float, float]:
        """Where an exit line's frame lies in the bowl's [m]: x unchanged (the line starts at
        the outlet edge x), y on the chute's centre line, z the chute's floor at its end at
        its high edge (the chute rises at the helix angle, its floor tilts down outwards)."""
        b = self.bowl
        rise = b.chute_length * math.sin(math.radians(b.helix_angle))
        return 0.0, -b.r_mid, b.end_z + rise + b.track_width / 2 * math.tan(math.radians(b.cross_tilt))

    def name(self, key: tuple[str, ...]) -> str:
        """The deck name of ``key`` on the bowl (for messages)."""
        return KEYS.get(key, ".".join(key))

    # ---------------------------------------------------------------- the air jet on the helix
    # As a mesh element's (vibrofeed.feeders.mesh_element): its camera senses along the path
    # coordinate (vibrofeed.bowl.path_coordinate), its block is turned with the helix where it
    # stands, and it blows towards the path's left, the track's open inner edge: a part blown
    # off falls back into the bowl, as a real bowl's jets return their parts.
    @property
    def length(self) -> float:
        """The helix's length along its centre line [m]: a tool's ``at`` is a fraction of it."""
        return self.bowl.length

    @property
    def sensing(self) -> float:
        """Where the jet's camera senses the parts: its path coordinate [m]."""
        return self.jet.at * self.length

    def jet_span(self, size: float) -> tuple[float, float]:
        """The jet's block along the path [m] (its length 0: one part ``size``)."""
        return jet_span(self.jet, self.sensing, size)

    def jet_frame(self, size: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(the centre line's floor point at the block's centre (3,), the path's direction in
        plan there (3,), its left, towards the axis (3,))."""
        lo, hi = self.jet_span(size)
        theta = float(self.bowl.theta_at((lo + hi) / 2))
        c, s = math.cos(theta), math.sin(theta)
        return (self.bowl.helix_point(theta), np.array([-s, c, 0.0]), np.array([-c, -s, 0.0]))

    def jet_planes(self, part: Part) -> list[tuple[np.ndarray, np.ndarray]]:
        """The jet's block as six half-spaces (a point on each plane, its normal into the block)
        in the bowl's frame: along the path over :meth:`jet_span` (straight: the helix's bend
        over a block of a few parts is a few um), across the track and two parts beyond each
        edge, from below its floor there (its tilt across, the lift and a part) up to
        9/10 of a pitch (the turn above, if any, lies a pitch up: its parts stay out)."""
        from ..bowl import WIPER_REACH

        b = self.bowl
        lo, hi = self.jet_span(part.size)
        c, t, n = self.jet_frame(part.size)
        half_w = b.track_width / 2 + 2 * part.widest
        bottom = c[2] - half_w * math.tan(math.radians(b.cross_tilt)) - self.drive.amp_n - part.widest
        return block_planes(c, t, n, (hi - lo) / 2, half_w, bottom, c[2] + WIPER_REACH * b.pitch)

    def camera(self, part: Part, origin=(0.0, 0.0, 0.0)) -> Camera:
        """Where the driver senses parts for the jet: along the path (the bowl at rest; the
        torsion turns it by amp_t / r_mid, a part's few percent), the path's direction in plan
        at the camera, up; below the helix's floor there by a part: falling into the bowl.
        (``origin``: an exit line's, not the bowl's: unused.)"""
        from ..bowl import path_coordinate

        b = self.bowl
        theta = float(b.theta_at(self.sensing))
        return Camera(at=self.sensing, tangent=(-math.sin(theta), math.cos(theta), 0.0), up=(0.0, 0.0, 1.0),
                      z_floor=float(b.floor_z(theta, b.radius)) - part.size,
                      along=lambda points: path_coordinate(b, points))

    def jet_commands(self, part: Part, origin=(0.0, 0.0, 0.0)) -> list[str]:
        """The jet's commands (none without one): its turned block (:meth:`jet_planes`), its force
        ``jet_force`` blowing ``jet_angle`` up from the floor (tilted down outwards by
        cross_tilt) towards the axis (vibrofeed.feeders.linear.turned_jet_commands, as
        element 1: ``s1_jet``, ``s1_jet_on``). ``origin`` is unused (the bowl's frame is the
        deck's)."""
        if self.jet is None:
            return []
        _, _, left = self.jet_frame(part.size)
        return turned_jet_commands(1, "the bowl", self.jet.mode, self.jet_planes(part), left,
                                   "v_jet_force", "(v_jet_angle+v_cross_tilt)*PI/180")

    def jet_fix(self) -> str:
        """The jet's ``fix addforce`` (:meth:`jet_commands`)."""
        return turned_jet_fix(1, self.jet.mode)
