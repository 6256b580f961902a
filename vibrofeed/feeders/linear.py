"""A linear section: a straight track with its own drive and tooling, one element of a feeder.

Frame: the deck's (x along the track towards the outlet, y across, z normal to the
first section's floor). Section k runs from ``x0`` (the sum of the lengths before it) to
``x1 = x0 + length``, centred on y = 0. The first section's floor is z = 0 at its high
edge (y = +w/2); every later one lies ``step`` below the one before it at its high edge
(``level``: the steps summed) and, with a cross tilt, descends towards the reference wall
at y = -w/2: ``z(y) = -level - (w/2 - y) tan(cross_tilt)``.

The first section has a back wall; a later one has no wall at its joint and may carry a side
drop, a slot trap and a wiper (vibrofeed.line builds them). Any section may have a singulation
gate: both walls narrow at 45 degrees to its width, centred, as on the first section.

Its numbers in the deck's vocabulary: section 1 takes the bulk feeder's own names
(``track_length``, ``freq``, ``gate_width`` ...), section k >= 2 the same quantities as
``s<k>_<name>`` (``s3_amp_n``): :data:`KEYS` maps the description's keys to both.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError, ParameterWarning
from ..line import WIPER_LENGTH, Section, section_mesh, slot_offset
from ..orientation import STATES, correct_word, parse_correct, run_correct
from .records import JET_MODES, Camera, Drive, Gate, Jet, Part, SideDrop, Slot, Wiper, number

# description key (table, key) -> (section 1's deck name, later sections' suffix); None:
# that section has no such number (a step, side drop, slot and wiper on later sections only:
# the meshes of this version build them there).
KEYS: dict[tuple[str, ...], tuple[str | None, str | None]] = {
    ("length",): ("track_length", "length"),
    ("width",): ("track_width", "width"),
    ("wall_height",): ("wall_height", "wall_height"),
    ("cross_tilt",): ("cross_tilt", "cross_tilt"),
    ("step",): (None, "step"),
    ("drive", "freq"): ("freq", "freq"),
    ("drive", "amp_t"): ("amp_t", "amp_t"),
    ("drive", "amp_n"): ("amp_n", "amp_n"),
    ("drive", "phase"): ("phase", "phase"),
    ("drive", "amp_c"): ("amp_c", "amp_c"),
    ("drive", "phase_c"): ("phase_c", "phase_c"),
    ("drive", "waveform"): ("waveform", None),
    ("drive", "duty"): ("duty", None),
    ("gate", "width"): ("gate_width", "gate_width"),
    ("gate", "at"): ("gate_at", "gate_at"),
    ("side_drop", "from"): (None, "drop_from"),
    ("side_drop", "to"): (None, "drop_to"),
    ("side_drop", "width"): (None, "drop_width"),
    ("slot", "from"): (None, "slot_from"),
    ("slot", "to"): (None, "slot_to"),
    ("slot", "width"): (None, "slot_width"),
    ("slot", "offset"): (None, "slot_offset"),
    ("wiper", "height"): (None, "wiper_height"),
    ("wiper", "at"): (None, "wiper_at"),
    ("wiper", "skew"): (None, "wiper_skew"),
    ("jet", "at"): (None, "jet_at"),
    ("jet", "keep"): (None, "jet_keep"),
    ("jet", "delay"): (None, "jet_delay"),
    ("jet", "duration"): (None, "jet_duration"),
    ("jet", "offset"): (None, "jet_offset"),
    ("jet", "length"): (None, "jet_length"),
    ("jet", "force"): (None, "jet_force"),
    ("jet", "angle"): (None, "jet_angle"),
    ("jet", "mode"): (None, "jet_mode"),
    ("jet", "headway"): (None, "jet_headway"),
}
# Words, not numbers: the deck holds them as index words (no blank: "up,lengthwise").
WORDS = (("jet", "keep"), ("jet", "mode"))
# A jet's keep that names no state of its own: it keeps the part's correct state (the
# parameter ``correct``, vibrofeed.orientation.run_correct), as a jet without a keep does.
KEEP_CORRECT = "correct"
JET_DEFAULTS = {"keep": KEEP_CORRECT, "mode": "region"}
# The further sections' numbers carry the prefix s<k>_ with k from 2 to this.
MAX_SECTIONS = 9


def deck_name(k: int, key: tuple[str, ...]) -> str | None:
    """Section ``k``'s deck name of the description ``key`` (None: it has none)."""
    first, suffix = KEYS[key]
    if k == 1:
        return first
    return None if suffix is None else f"s{k}_{suffix}"


def deck_names(k: int) -> dict[tuple[str, ...], str]:
    """Section ``k``'s description keys and their deck names."""
    return {key: name for key in KEYS if (name := deck_name(k, key)) is not None}


@dataclass(frozen=True)
class LinearSection:
    """Section ``number`` (1-based) of a line (module docstring)."""

    kind = "linear"
    moves = True  # (driven: its motion is recorded and checked against its sine)
    number: int
    x0: float
    length: float
    width: float
    wall_height: float
    drive: Drive
    cross_tilt: float = 0.0
    step: float = 0.0  # below the section before it, at the high edges (0 for the first)
    level: float = 0.0  # below the first section's floor: the steps summed
    gate: Gate | None = None
    side_drop: SideDrop | None = None
    wiper: Wiper | None = None
    slot: Slot | None = None
    jet: Jet | None = None

    @classmethod
    def from_values(cls, values: Mapping, k: int, x0: float = 0.0, level: float = 0.0,
                    part: Part | None = None) -> LinearSection:
        """Section ``k`` from the deck's parameters (numbers or their strings); its tools are
        absent where their numbers say so (gate_width 0, drop_to <= drop_from, wiper_height 0,
        jet_force 0, slot_to <= slot_from); a slot's offset 0 is its default place, along the
        wall (vibrofeed.line.slot_offset)."""
        def get(key, default=0.0):  # (absent: zero, i.e. off or not moving, as the decks' tools)
            name = deck_name(k, key)
            return number(values, name, default) if name is not None else default

        first = k == 1
        drive = Drive(freq=get(("drive", "freq")), amp_t=get(("drive", "amp_t")),
                      amp_n=get(("drive", "amp_n")), phase=get(("drive", "phase"), 0.0),
                      waveform=int(get(("drive", "waveform"), 0.0)) if first else 0,
                      duty=get(("drive", "duty"), 0.7) if first else 0.7,
                      amp_c=get(("drive", "amp_c"), 0.0), phase_c=get(("drive", "phase_c"), 0.0))
        step = 0.0 if first else get(("step",))
        gate = side_drop = wiper = jet = slot = None
        if get(("gate", "width"), 0.0) > 0:
            gate = Gate(width=get(("gate", "width")), at=get(("gate", "at"), 0.7))
        if not first:
            start, end = get(("side_drop", "from"), 0.0), get(("side_drop", "to"), 0.0)
            if end > start:
                side_drop = SideDrop(start=start, end=end, width=get(("side_drop", "width"), 0.0))
            start, end = get(("slot", "from"), 0.0), get(("slot", "to"), 0.0)
            if end > start:
                width, offset = get(("slot", "width"), 0.0), get(("slot", "offset"), 0.0)
                if offset == 0:
                    offset = slot_offset(width)
                slot = Slot(start=start, end=end, width=width, offset=offset)
            if get(("wiper", "height"), 0.0) > 0:
                wiper = Wiper(height=get(("wiper", "height")), at=get(("wiper", "at"), 0.5),
                              length=WIPER_LENGTH * (part.size if part else number(values, "part_size")),
                              skew=get(("wiper", "skew"), 0.0))
            jet = read_jet(values, k, get, part)
        return cls(number=k, x0=x0, length=get(("length",)), width=get(("width",)),
                   wall_height=get(("wall_height",)), drive=drive, cross_tilt=get(("cross_tilt",), 0.0),
                   step=step, level=level + step, gate=gate, side_drop=side_drop, wiper=wiper,
                   jet=jet, slot=slot)

    # ---------------------------------------------------------------- geometry
    @property
    def x1(self) -> float:
        """The section's end: its joint with the next, or the outlet edge."""
        return self.x0 + self.length

    @property
    def exit_band(self) -> tuple[float, float]:
        """Across its outlet edge, from wall to wall (y, its frame) [m]."""
        return -self.width / 2, self.width / 2

    @property
    def exit_width(self) -> float:
        """The width parts leave the section through (the gate's, if it has one)."""
        return self.gate.width if self.gate else self.width

    @property
    def wiper_reach(self) -> float:
        """How far along the track its wiper reaches from its upstream face at the reference wall
        [m]: its bar's length, and a skewed bar's run across (vibrofeed.line.Section)."""
        return self.mesh_section().wiper_reach

    def floor_z(self, y):
        """Height of the floor at rest at ``y`` [m] (module docstring)."""
        return -self.level - (self.width / 2 - y) * math.tan(math.radians(self.cross_tilt))

    @property
    def lowest(self) -> float:
        """The floor's lowest point at rest (at the reference wall) [m]."""
        return self.floor_z(-self.width / 2)

    exit_direction = (1.0, 0.0, 0.0)  # (level along x)

    def floor_at(self, x, y):
        """The floor's height at rest over (``x``, ``y``) [m] (level along x)."""
        return self.floor_z(y) + 0.0 * np.asarray(x, dtype=float)

    def entry_z(self, y):
        """The floor's height at rest where parts come onto it, at ``y`` [m]."""
        return self.floor_z(y)

    def exit_z(self, y):
        """The floor's height at rest where parts leave it, at ``y`` [m]."""
        return self.floor_z(y)

    @property
    def exit_level(self) -> float:
        """How far below the first section's floor this one ends, at its high edge [m]."""
        return self.level

    @property
    def bounds(self) -> list[tuple[float, float]]:
        return [(self.x0, self.x1)]

    @property
    def jet_length(self) -> float:
        """The jet's block along the path [m] (0 without a jet)."""
        j = self.jet
        return 0.0 if j is None else j.length

    @property
    def sensing(self) -> float:
        """Where the jet's camera senses the parts along the path [m] (here its x)."""
        return self.x0 + self.jet.at * self.length

    def jet_span(self, size: float) -> tuple[float, float]:
        """The jet's block along the path [m] (here along x; its length 0: one part ``size``)."""
        return jet_span(self.jet, self.sensing, size)

    def camera(self, part: Part, origin=(0.0, 0.0, 0.0)) -> Camera:
        """Where the driver senses parts for the jet (the section shifted by ``origin``): the
        deck's x, along +x, its floor's normal; below its lowest floor by a part: falling."""
        return Camera(at=origin[0] + self.sensing, tangent=(1.0, 0.0, 0.0), up=self.floor_normal(),
                      z_floor=origin[2] + self.lowest - part.size)

    def floor_normal(self) -> tuple[float, float, float]:
        """The floor's unit normal (up, tilted towards -y by the cross tilt)."""
        a = math.radians(self.cross_tilt)
        return 0.0, -math.sin(a), math.cos(a)

    def jet_direction(self) -> tuple[float, float, float]:
        """The jet's unit direction: ``angle`` up from the floor, across towards +y."""
        a = math.radians(self.jet.angle + self.cross_tilt)
        return 0.0, math.cos(a), math.sin(a)

    def jet_block(self, part: Part) -> tuple[float, ...]:
        """The jet's block (xlo, xhi, ylo, yhi, zlo, zhi) [m] in the section's frame: its span
        along x, across the track and two parts beyond each wall, from below the lowest floor
        (by the normal amplitude and a part) to a part above the walls' top (as they move): a
        part blown off leaves it over the wall at +y, and flies on."""
        xlo, xhi = self.jet_span(part.size)
        margin = 2 * part.widest
        return (xlo, xhi, -self.width / 2 - margin, self.width / 2 + margin,
                self.lowest - self.drive.amp_n - part.widest,
                -self.level + self.wall_height + self.drive.amp_n + part.widest)

    def jet_throw(self, part: Part, mass: float, g: float = 9.81) -> tuple[float, float]:
        """How fast [m/s] and how far beyond the track's open side (+y) [m] the jet can throw
        a part of ``mass`` [kg] at most: its whole force on the part and nothing against it
        (no weight, no friction) for its duration or until the part has crossed its block
        along the blow, then a free flight from the block's top to a part below its bottom."""
        xlo, xhi, ylo, yhi, zlo, zhi = self.jet_block(part)
        return jet_throw(self.jet, mass, self.jet.angle + self.cross_tilt, yhi + self.width / 2,
                         zhi - zlo, yhi - self.width / 2, part.widest, g)

    def mesh_section(self) -> Section:
        """The section as vibrofeed.line meshes it (a further section of a line)."""
        drop, wiper, slot = self.side_drop, self.wiper, self.slot
        slotted = {} if slot is None else {"slot_from": slot.start, "slot_to": slot.end,
                                           "slot_width": slot.width, "slot_offset": slot.offset}
        gated = {} if self.gate is None else {"gate_width": self.gate.width, "gate_at": self.gate.at}
        return Section(
            x0=self.x0, length=self.length, width=self.width, wall_height=self.wall_height,
            step=self.level, cross_tilt=self.cross_tilt, drop_from=drop.start if drop else 0.0,
            drop_to=drop.end if drop else 0.0, drop_width=drop.width if drop else 0.0,
            wiper_height=wiper.height if wiper else 0.0, wiper_at=wiper.at if wiper else 0.5,
            wiper_length=wiper.length if wiper else 0.0, wiper_skew=wiper.skew if wiper else 0.0,
            **slotted, **gated)

    def mesh(self):
        """The mesh at rest of a further section (vertices (V, 3) [m], triangles (T, 3))."""
        return section_mesh(self.mesh_section())

    def deck_commands(self) -> dict[str, list[str]]:
        """A further section's commands in the deck (vibrofeed.feeders.deck): ``derived``
        (its angular frequency, phase, lowest floor, peak speed, catch plane), ``mesh`` (its
        mesh placed where its sine puts it at t = 0) and ``motion`` (its movers and recorded
        motion, s<k>_surface_*)."""
        k, s = self.number, f"s{self.number}"
        level = "+".join(f"v_s{j}_step" for j in range(2, k + 1))
        out = sine_commands(k, cross=self.drive.amp_c != 0)
        out["derived"].append(
            f"variable {s}_low equal -({level}+v_{s}_width*tan(v_{s}_cross_tilt*PI/180))")
        return out

    def jet_commands(self, part: Part, origin=(0.0, 0.0, 0.0)) -> list[str]:
        """The jet's commands (none without one): its block (``s<k>_jet``, in the deck's frame:
        the section's shifted by ``origin``), a ``fix addforce`` on the spheres in it, each a
        share 1/body_spheres of ``s<k>_jet_force`` along the jet's direction, switched by
        ``s<k>_jet_on`` (0: off). Only the driver switches it on (vibrofeed.engine.jets: an
        equal-style window variable; ``ideal``: atom-style, the sensed body's atoms only); by
        hand it never fires, and the deck says so."""
        if self.jet is None:
            return []
        s = f"s{self.number}"
        ox, oy, oz = origin
        b = self.jet_block(part)
        block = " ".join(repr(float(v)) for v in (b[0] + ox, b[1] + ox, b[2] + oy, b[3] + oy,
                                                   b[4] + oz, b[5] + oz))
        style = "atom" if self.jet.mode == "ideal" else "equal"
        share = f"v_{s}_jet_force/v_body_spheres"
        angle = f"(v_{s}_jet_angle+v_{s}_cross_tilt)*PI/180"
        return [
            f"# section {self.number}'s air jet ({self.jet.mode}): fired by vibrofeed run only",
            f"region {s}_jet block {block} units box",
            f"variable {s}_jet_on {style} 0",
            f"variable {s}_jet_fy {style} v_{s}_jet_on*$({share}*cos({angle}))",
            f"variable {s}_jet_fz {style} v_{s}_jet_on*$({share}*sin({angle}))",
            *jet_group(self.number, self.jet.mode),
            self.jet_fix(),
            f'if "${{driver}} == 0" then "print \'WARNING: the air jet of section {self.number} is '
            "inactive in a run by hand: only vibrofeed run senses the parts it fires at'\""]

    def jet_fix(self) -> str:
        """The jet's ``fix addforce`` (:meth:`jet_commands`; the driver removes and places it again,
        vibrofeed.engine.jets)."""
        s, group = f"s{self.number}", jet_fix_group(self.number, self.jet.mode)
        return f"fix {s}_jet {group} addforce 0 v_{s}_jet_fy v_{s}_jet_fz region {s}_jet"

    def name(self, key: tuple[str, ...]) -> str:
        """The deck name of ``key`` on this section (for messages)."""
        return deck_name(self.number, key) or ".".join(key)

    # ---------------------------------------------------------------- checks
    def check(self, part: Part, last: bool = True) -> None:
        """The section on its own: a part fits, its walls hold it, its tools lie on it
        (one-line ParameterError naming the parameter); ``last``: its end is the outlet edge."""
        n = self.name
        end = "the outlet edge" if last else f"the end of section {self.number}"
        # parts arrive at a later section through the joint, whose check keeps its width at least
        # the exit's before it: one that a gate filed lengthwise needs room for a box's width only
        need = part.widest if self.number == 1 else part.abreast
        if self.width < need:
            raise ParameterError(f"{n(('width',))}={self.width:g} m is narrower than a part "
                                 f"({need:g} m across{' riding lengthwise' if need < part.widest else ''})")
        if self.gate is not None and self.number > 1:  # (section 1's: vibrofeed.parameters calls it)
            self.check_gate(part, end)
        radius = part.tallest / 2
        if self.wall_height <= radius:
            raise ParameterError(f"{n(('wall_height',))}={self.wall_height:g} m is no higher than a "
                                 f"part's centre ({radius:g} m): parts would leave over the walls")
        w = self.wiper
        if w is not None:
            if w.height < part.tallest:
                raise ParameterError(f"{n(('wiper', 'height'))}={w.height:g} m is lower than a part's "
                                     f"thickness ({part.tallest:g} m): no part would pass the wiper")
            if w.height >= self.wall_height:
                raise ParameterError(f"{n(('wiper', 'height'))}={w.height:g} m is not below the walls "
                                     f"({n(('wall_height',))}={self.wall_height:g} m): the wiper would "
                                     "not exist")
            reach = self.wiper_reach
            if not 0 <= w.at or w.at * self.length + reach > self.length:
                raise ParameterError(f"{n(('wiper', 'at'))}={w.at:g}: the wiper's bar ({reach:g} m "
                                     f"along the track) runs past {end}; lower {n(('wiper', 'at'))}")
            if w.skew and self.gate is not None:
                a, z = self.gate.at * self.length, self.gate.at * self.length + self.gate.taper(self.width)
                if w.at * self.length < z and a < w.at * self.length + reach:
                    raise ParameterError(f"{n(('wiper', 'skew'))}={w.skew:g}: the skewed bar meets the "
                                         f"gate's taper ({n(('gate', 'at'))}={self.gate.at:g}), where the "
                                         "walls close in: put it before the taper or past it")
        d = self.side_drop
        if d is not None:
            if not 0 <= d.start < d.end <= 1:
                raise ParameterError(f"{n(('side_drop', 'from'))}={d.start:g}, {n(('side_drop', 'to'))}="
                                     f"{d.end:g}: the side drop lies outside section {self.number} "
                                     "(0 <= from < to <= 1)")
            if not 0 < d.width < self.width:
                raise ParameterError(f"{n(('side_drop', 'width'))}={d.width:g} m must be > 0 and "
                                     f"narrower than {n(('width',))}={self.width:g} m (the side drop "
                                     "narrows the track)")
            if d.width < 0.5 * part.abreast:  # (a box lengthwise: its width; crosswise ones fall)
                raise ParameterError(f"{n(('side_drop', 'width'))}={d.width:g} m is less than half a "
                                     f"part ({part.abreast / 2:g} m across it in a file): every part "
                                     "would fall off the drop")
            if part.shape == 3:
                # A crosswise box falls when its centre of mass lies past the edge: on the floor
                # tilted towards the wall it leans (T/2) tan(tilt) nearer the wall than its
                # footprint's centre (docs/orientation.md, "A ledge instead of a gate").
                held = part.widest / 2 - part.thickness / 2 * math.tan(math.radians(self.cross_tilt))
                if d.width >= held:
                    warnings.warn(
                        f"{n(('side_drop', 'width'))}={d.width:g} m: a box lying crosswise against the "
                        f"wall has its centre of mass {held:.3g} m out (half its length less "
                        f"{part.thickness / 2:g} m x tan {self.cross_tilt:g} deg of cross tilt), over "
                        "the floor: the side drop keeps crosswise boxes; narrow it below that",
                        SideDropWarning, stacklevel=3)
        if self.slot is not None:
            self._check_slot(part)
        if self.jet is not None:
            check_jet(self, part)

    def check_gate(self, part: Part, end: str) -> None:
        """The section's gate, on any section: a part passes it (a box riding lengthwise), its
        taper lies on the section before ``end``, and the side drop and slot (placed from the
        reference wall) end before it."""
        g, n = self.gate, self.name
        wide, at = n(("gate", "width")), n(("gate", "at"))
        if g.width < part.abreast:
            riding = " riding lengthwise" if part.abreast < part.widest else ""
            raise ParameterError(f"{wide}={g.width:g} m is narrower than a part ({part.abreast:g} m "
                                 f"across{riding})")
        if g.width >= self.width:
            raise ParameterError(f"{wide}={g.width:g} m must be narrower than {n(('width',))}="
                                 f"{self.width:g} m ({wide}=0: no gate)")
        taper = g.taper(self.width)
        if not 0 <= g.at or g.at * self.length + taper > self.length:
            raise ParameterError(f"{at}={g.at:g}: the gate's 45 degree taper ({taper:g} m "
                                 f"long) runs past {end}; lower {at}")
        # the side drop and the slot are placed from the reference wall, which the gate moves in
        # (a wiper's bar spans the walls where it stands)
        tools = [(n(("side_drop", "to")), "side drop", self.side_drop and self.side_drop.end),
                 (n(("slot", "to")), "slot", self.slot and self.slot.end)]
        for name, tool, stop in tools:
            if stop and stop > g.at + 1e-12:
                raise ParameterError(f"{name}: the {tool} reaches past the gate ({at}={g.at:g}), whose "
                                     f"walls narrow the section: end it before, or put the gate after it")

    def _check_slot(self, part: Part) -> None:
        """The slot lies on the section and its floor, apart from the side drop and the wiper
        (their rejects could not be told from its own); a width that rejects every part or
        none is a warning (:class:`SlotWarning`), as is what it does to spheres."""
        n, s = self.name, self.slot
        frm, to, wide, off = (n(("slot", key)) for key in ("from", "to", "width", "offset"))
        if not 0 <= s.start < s.end <= 1:
            raise ParameterError(f"{frm}={s.start:g}, {to}={s.end:g}: the slot lies outside section "
                                 f"{self.number} (0 <= from < to <= 1)")
        if not 0 < s.width < self.width:
            raise ParameterError(f"{wide}={s.width:g} m must be > 0 and narrower than the floor "
                                 f"({n(('width',))}={self.width:g} m)")
        if s.offset - s.width / 2 < -1e-12 or s.offset + s.width / 2 > self.width + 1e-12:
            raise ParameterError(f"{off}={s.offset:g} m: the slot ({s.width:g} m across) runs under a "
                                 f"wall; its centre must lie {s.width / 2:g} to "
                                 f"{self.width - s.width / 2:g} m from the reference wall")
        a, b = self.x0 + s.start * self.length, self.x0 + s.end * self.length
        spans = []
        if self.side_drop is not None:
            spans.append(("side drop", ("side_drop", "from"), self.side_drop.start * self.length,
                          self.side_drop.end * self.length))
        if self.wiper is not None:
            w0 = self.wiper.at * self.length
            spans.append(("wiper", ("wiper", "at"), w0, w0 + self.wiper_reach))
        for tool, key, t0, t1 in spans:
            if a < self.x0 + t1 and self.x0 + t0 < b:
                raise ParameterError(f"{frm}={s.start:g}, {to}={s.end:g}: the slot overlaps the {tool} "
                                     f"({n(key)}); their rejects could not be told apart: move one")
        if (b - a) < part.widest:
            warn(f"{frm}, {to}: the slot is {b - a:g} m long, shorter than a part ({part.widest:g} m): "
                 "a part lying along the track may step over it")
        if part.shape == 0:
            warn(f"{wide}={s.width:g} m: spheres bridge the slot or fall through it by their diameter "
                 f"alone: smaller than {s.width:g} m they fall when over it (against the wall: always, "
                 "at the default offset), larger ones roll over")
            return
        thin, longest = thinnest(part), part.widest
        if s.width <= thin:
            warn(f"{wide}={s.width:g} m is no wider than a part's thinnest dimension ({thin:g} m): "
                 "no part falls through, the slot rejects nothing")
            return
        if s.width >= longest:
            warn(f"{wide}={s.width:g} m is no narrower than a part's longest dimension ({longest:g} m): "
                 "every part falls through, the slot rejects everything")
            return
        ledge = s.offset - s.width / 2
        if ledge > 1e-12:
            warn(f"{off}={s.offset:g} m leaves a ledge {ledge:g} m wide between the wall and the slot: a "
                 "part on its side against the wall tips over it and lands flat across the slot "
                 "(it bridges it); the slot along the wall (offset 0) drops it")
        across = part.width if part.shape == 3 else part.widest
        if ledge <= 1e-12 and s.width >= across / 2:
            warn(f"{wide}={s.width:g} m is no narrower than half a part's width ({across / 2:g} m): a "
                 "part lying flat against the wall has its centre over the slot and tips in; "
                 "lying flat, only a part crosswise bridges it (keep it below half the width)")



class SlotWarning(ParameterWarning):
    """A slot that runs but cannot sort the parts (it rejects all of them, or none)."""


class SideDropWarning(ParameterWarning):
    """A side drop that runs but keeps the boxes it is there to drop (those lying crosswise)."""


def warn(text: str) -> None:
    warnings.warn(text, SlotWarning, stacklevel=3)


def check_jet(e, part: Part) -> None:
    """The jet of element ``e`` (a linear section or a mesh element: its ``jet``, ``name(key)``,
    ``number``, ``x0`` and ``length`` along the path, ``sensing``, ``jet_span`` and ``drive``):
    one-line ParameterError naming the parameter; a ParameterWarning for a delay after which a
    part would be past the element's end."""
    j, n = e.jet, e.name
    if j.force < 0:
        raise ParameterError(f"{n(('jet', 'force'))}={j.force:g} N must be > 0 (0: no jet)")
    if part.shape == 0:
        raise ParameterError(f"{n(('jet', 'force'))}={j.force:g} N: a jet sorts parts by their "
                             "orientation, and spheres (shape 0) have none")
    k = j.keep
    if set(k.states) == set(STATES) and not k.lengthwise and not k.lead and not j.headway > 0:
        if j.keeps_correct:
            raise ParameterError(f"correct=\"{keep_word(str(k))}\" counts every state correct, and "
                                 f"the jet of section {e.number} keeps it: the jet would never "
                                 f"fire; give it a keep of its own ({n(('jet', 'keep'))}), e.g. \"up\"")
        raise ParameterError(f"{n(('jet', 'keep'))}=\"{keep_word(str(k))}\" keeps every state: "
                             "the jet would never fire; name the state(s) to keep, e.g. \"up\", "
                             f"or space the stream ({n(('jet', 'headway'))} > 0)")
    for key, value in (("delay", j.delay), ("offset", j.offset), ("length", j.length),
                       ("headway", j.headway)):
        if key != "offset" and value < 0:
            raise ParameterError(f"{n(('jet', key))}={value:g} must be >= 0")
    if not j.duration > 0:
        raise ParameterError(f"{n(('jet', 'duration'))}={j.duration:g} s must be > 0")
    if not 0 <= j.at <= 1:
        raise ParameterError(f"{n(('jet', 'at'))}={j.at:g}: the sensing point lies outside section "
                             f"{e.number} (0 <= at <= 1)")
    if not 0 <= j.angle <= 90:
        raise ParameterError(f"{n(('jet', 'angle'))}={j.angle:g} deg must be in [0, 90] (up from "
                             "the floor, across towards +y)")
    lo, hi = e.jet_span(part.size)
    end = e.x0 + e.length
    if lo < e.x0 - 1e-12 or hi > end + 1e-12:
        raise ParameterError(f"{n(('jet', 'offset'))}={j.offset:g} m, {n(('jet', 'length'))}="
                             f"{hi - lo:g} m: the jet's block ({lo - e.x0:g} to {hi - e.x0:g} m "
                             f"along section {e.number}) lies past its ends (0 to {e.length:g} m)")
    speed = 2 * math.pi * e.drive.freq * e.drive.amp_t  # no part conveys faster
    reach = e.sensing + speed * j.delay
    if reach > end:
        warnings.warn(f"{n(('jet', 'delay'))}={j.delay:g} s: a part conveyed at the surface's peak "
                      f"speed along ({speed:.3g} m/s) is {reach - end:.3g} m past section "
                      f"{e.number}'s end when the jet fires", ParameterWarning, stacklevel=2)


def jet_throw(jet: Jet, mass: float, angle: float, across: float, height: float, beyond: float,
              widest: float, g: float) -> tuple[float, float]:
    """How fast [m/s] and how far [m] beyond the track's open side a jet can throw a part of
    ``mass`` [kg] at most: its whole force on the part and nothing against it (no weight, no
    friction) for its duration or until the part has crossed its block along the blow (``across``
    from the far wall to the block's side, ``height`` its height [m]; the blow ``angle`` [deg]
    up from horizontal), then a free flight from the block's top to a part below its bottom,
    from the block's side ``beyond`` the open side."""
    a = math.radians(angle)
    path = min(across / max(math.cos(a), 1e-12), height / max(math.sin(a), 1e-12))
    push = jet.force / mass
    v = min(push * jet.duration, math.sqrt(2 * push * path))
    up, out = v * math.sin(a), v * math.cos(a)
    flight = (up + math.sqrt(up * up + 2 * g * (height + widest))) / g
    return v, beyond + out * flight


def block_planes(centre, along, left, half_along: float, half_across: float, bottom: float,
                 top: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """A block turned with a path as six half-spaces (a point on each plane, its unit normal into
    the block): ``half_along`` either way of ``centre`` (3,) along the level unit vector
    ``along``, ``half_across`` either way along ``left``, from height ``bottom`` to ``top`` [m]."""
    c, t, n = (np.asarray(v, dtype=float) for v in (centre, along, left))
    up = np.array([0.0, 0.0, 1.0])
    return [(c - half_along * t, t), (c + half_along * t, -t), (c - half_across * n, n),
            (c + half_across * n, -n), (np.array([c[0], c[1], bottom]), up),
            (np.array([c[0], c[1], top]), -up)]


def turned_jet_commands(k: int, what: str, mode: str, planes, left, force: str, angle: str) -> list[str]:
    """An air jet's commands whose block is turned with its path (a mesh element's, a bowl's
    helix: LIGGGHTS 3.8's blocks are axis-aligned): the intersection of the half-spaces
    ``planes`` (a point on each, its normal into the block, the deck's frame) named
    ``s<k>_jet``, switched by ``s<k>_jet_on`` (0: the driver sets it, vibrofeed.engine.jets),
    blowing ``force`` (the deck's variable) shared by a part's spheres, ``angle`` (an
    expression, radians) up from the horizontal towards the unit vector ``left`` across the
    path. ``what`` names the element in the comments."""
    s = f"s{k}"
    regions = []
    for i, (point, normal) in enumerate(planes, 1):
        numbers = " ".join(repr(float(v)) for v in (*point, *normal))
        regions.append(f"region {s}_jet_{i} plane {numbers} units box")
    style = "atom" if mode == "ideal" else "equal"
    share = f"{force}/v_body_spheres"
    return [
        f"# {what}'s air jet ({mode}): fired by vibrofeed run only",
        *regions,
        f"region {s}_jet intersect {len(regions)} " + " ".join(r.split()[1] for r in regions),
        f"variable {s}_jet_on {style} 0",
        f"variable {s}_jet_fx {style} v_{s}_jet_on*$({share}*cos({angle})*{float(left[0])!r})",
        f"variable {s}_jet_fy {style} v_{s}_jet_on*$({share}*cos({angle})*{float(left[1])!r})",
        f"variable {s}_jet_fz {style} v_{s}_jet_on*$({share}*sin({angle}))",
        *jet_group(k, mode),
        turned_jet_fix(k, mode),
        f'if "${{driver}} == 0" then "print \'WARNING: the air jet of {what} is '
        "inactive in a run by hand: only vibrofeed run senses the parts it fires at'\""]


def turned_jet_fix(k: int, mode: str) -> str:
    """The ``fix addforce`` of :func:`turned_jet_commands` (the driver removes and places it
    again, vibrofeed.engine.jets)."""
    s, group = f"s{k}", jet_fix_group(k, mode)
    return f"fix {s}_jet {group} addforce v_{s}_jet_fx v_{s}_jet_fy v_{s}_jet_fz region {s}_jet"


def jet_fix_group(k: int, mode: str) -> str:
    """The group the jet's ``fix addforce`` of element ``k`` acts on: every atom for a
    ``region`` jet; for an ``ideal`` one ``s<k>_jet_parts``, the atoms of the parts it fires at
    (the driver fills it, vibrofeed.engine.jets). LIGGGHTS evaluates an atom-style force for
    each atom of the fix's group at every step: over every atom, that was a third of the
    orientation demo's run (BENCHMARKS.md, "The orientation demo")."""
    return f"s{k}_jet_parts" if mode == "ideal" else "all"


def jet_group(k: int, mode: str) -> list[str]:
    """The deck's commands that create :func:`jet_fix_group` empty (none for a ``region`` jet)."""
    return [f"group {jet_fix_group(k, mode)} subtract all all"] if mode == "ideal" else []


def jet_span(jet: Jet, sensing: float, size: float) -> tuple[float, float]:
    """A jet's block along the path [m]: ``length`` (0: one part ``size``) centred ``offset``
    past the sensing point ``sensing``."""
    length = jet.length if jet.length > 0 else size
    centre = sensing + jet.offset
    return centre - length / 2, centre + length / 2


def thinnest(part: Part) -> float:
    """A part's thinnest dimension [m]: a sphere's smallest diameter, else its thickness."""
    return part.size * (1 - part.size_spread) if part.shape == 0 else part.thickness


def read_jet(values: Mapping, k: int, get, part: Part | None = None, name=None) -> Jet | None:
    """Element ``k``'s jet (a linear section's, a mesh element's or, with ``name`` (key -> its
    deck name), a bowl's) from the deck's parameters (none where its force is 0 or absent); its
    words read here (one-line ParameterError naming the parameter). A keep of
    :data:`KEEP_CORRECT` (the deck's default) is the part's correct state (``part.correct``,
    else the parameter ``correct`` read here); an explicit keep wins over it."""
    force = get(("jet", "force"), 0.0)
    if force == 0:
        return None
    name = name or (lambda key: deck_name(k, key))
    words = {key[1]: str(values.get(name(key), JET_DEFAULTS[key[1]])).strip() for key in WORDS}
    inherits = words["keep"].lower() == KEEP_CORRECT
    if inherits:
        keep = part.correct if part is not None else run_correct(values)
    else:
        keep = parse_correct(words["keep"], name(("jet", "keep")))
    mode = words["mode"].lower()
    if mode not in JET_MODES:
        raise ParameterError(f"{name(('jet', 'mode'))}={words['mode']} must be "
                             f"{' or '.join(JET_MODES)}")
    return Jet(force=force, keep=keep, at=get(("jet", "at"), 0.5), delay=get(("jet", "delay"), 0.0),
               duration=get(("jet", "duration"), 0.01), offset=get(("jet", "offset"), 0.0),
               length=get(("jet", "length"), 0.0), angle=get(("jet", "angle"), 60.0), mode=mode,
               keeps_correct=inherits, headway=get(("jet", "headway"), 0.0))


def keep_word(text: str, name: str = "jet.keep") -> str:
    """A jet's ``keep`` (parse_correct's words, or :data:`KEEP_CORRECT`) as the deck's word,
    without blanks: "up, lengthwise" -> "up,lengthwise" (a ParameterError naming ``name``)."""
    if str(text).strip().lower() == KEEP_CORRECT:
        return KEEP_CORRECT
    return correct_word(text, name)


def sine_commands(k: int, cross: bool = False) -> dict[str, list[str]]:
    """Element ``k``'s commands as a sine drive along x and z moves its mesh
    ``track_s<k>.stl``, its tunables ``s<k>_freq``, ``amp_t``, ``amp_n``, ``phase``: ``derived``
    (its angular frequency and phase; the element adds its lowest floor ``s<k>_low``),
    ``peak``, ``catch`` (below ``s<k>_low``), ``mesh`` (placed where its sine puts it at
    t = 0) and ``motion`` (the movers and the recorded motion, s<k>_surface_*). ``cross``: a
    third sine across (y), ``s<k>_amp_c`` leading by ``s<k>_phase_c``, moved as z is; without
    it the commands are those of a drive along x and z alone, to the character."""
    s = f"s{k}"
    half = f"$(v_{s}_omega*v_dt_used/2)"
    gain = f"$(v_{s}_amp_{{a}}*v_{s}_omega*v_dt_used/sin(v_{s}_omega*v_dt_used/2))"

    def riemann(a: str, phi: str) -> str:
        # where the viblin mover puts the mesh at step n: its placed offset plus the movers'
        # sum of v dt (check.sine_drive's closed form)
        return (f"$(v_{s}_amp_{a}*sin(v_{s}_{phi}))&\n+{gain.format(a=a)}&\n"
                f"*sin(step*{half})*cos((step+1)*{half}+$(v_{s}_{phi}))")

    def mover(a: str, axis: str, phi: str) -> str:
        return (f"fix {s}_shake_{a} all move/mesh mesh track_{s} viblin axis {axis} order 1 "
                f"amplitude ${{{s}_amp_{a}}} &\n     phase $(v_{s}_{phi}-PI/2) period $(1/v_{s}_freq)")

    amps = f"v_{s}_amp_t^2+v_{s}_amp_n^2" + (f"+v_{s}_amp_c^2" if cross else "")
    y = f"$(v_{s}_amp_c*sin(v_{s}_phic))" if cross else "0"
    return {
        "derived": [f"variable {s}_omega equal 2*PI*v_{s}_freq",
                    f"variable {s}_phi equal v_{s}_phase*PI/180"]
        + ([f"variable {s}_phic equal v_{s}_phase_c*PI/180"] if cross else []),
        "peak": [f"variable {s}_peak equal v_{s}_omega*sqrt({amps})"],
        "catch": [f"variable {s}_catch equal v_{s}_low-(v_{s}_amp_n+2*v_r_ext)"],
        "mesh": [f"fix track_{s} all mesh/surface file ${{mesh_dir}}/track_{s}.stl type 2 "
                 f"move 0 {y} $(v_{s}_amp_n*sin(v_{s}_phi))"],
        "motion": [
            f"fix {s}_shake_t all move/mesh mesh track_{s} wiggle amplitude ${{{s}_amp_t}} 0 0 "
            f"period $(1/v_{s}_freq)",
            mover("n", "0 0 1", "phi")]
        + ([mover("c", "0 1 0", "phic")] if cross else [])
        + [f"variable {s}_surface_x equal &\n"
           f"{gain.format(a='t')}&\n"
           f"*sin(step*{half})*cos((step+1)*{half})",
           f"variable {s}_surface_y equal " + (f"&\n{riemann('c', 'phic')}" if cross else "0"),
           f"variable {s}_surface_z equal &\n{riemann('n', 'phi')}",
           f"variable {s}_surface_vx equal $(v_{s}_amp_t*v_{s}_omega)*cos($(v_{s}_omega)*time)",
           f"variable {s}_surface_vy equal "
           + (f"$(v_{s}_amp_c*v_{s}_omega)*cos($(v_{s}_omega)*time+$(v_{s}_phic))" if cross else "0"),
           f"variable {s}_surface_vz equal "
           f"$(v_{s}_amp_n*v_{s}_omega)*cos($(v_{s}_omega)*time+$(v_{s}_phi))"],
    }
