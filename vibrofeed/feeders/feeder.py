"""The feeder: its parts and its elements in conveying order, the one object every part of
vibrofeed asks about the geometry.

A feeder is read once from the deck's vocabulary (:meth:`Feeder.from_values`: the
parameters a run records, so a result's feeder is rebuilt from its file) or from a
description (:mod:`vibrofeed.feeders.description`, which produces the same vocabulary).
What kind of feeder it is, is decided here and only here: a bowl where the parameters
name a ``bowl_diameter``, else a line of ``sections`` linear sections (1: the single
track).

The analyses ask it where its sections lie along the path (:attr:`Feeder.bounds`), where
the outlet edge is (:attr:`Feeder.path_end`), which section a part is over
(:meth:`Feeder.section_at`), and each section's drive (:meth:`Feeder.section_values`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from .bowl import KEYS as BOWL_KEYS
from .bowl import BowlElement
from .joints import Joint
from .kinds import BY_CODE, later_kinds_text
from .linear import MAX_SECTIONS, LinearSection, check_jet, read_jet
from .mesh_element import MeshElement
from .records import Drive, Part, number


@dataclass(frozen=True)
class Station:
    """A tooling station: on path ``section`` (1-based) of ``element`` (its number, 1-based),
    from ``start`` to ``end`` along the path [m] (a wiper: its upstream face to its bar's end;
    a side drop: its open stretch; a slot: its hole's; a gate: where its walls start to narrow to where they
    reach its width; a tool at a point, e.g. an air jet: ``start == end``). ``name`` says
    which (``s2.side_drop``). The rejects are looked for over [start, end]; a part passes
    the station between ``x_in`` and ``x_out``, ``margin`` (a part's size) before its start
    and after its end, where it is wholly before and wholly past the tool."""

    section: int
    kind: str
    start: float
    end: float
    element: int = 0
    name: str = ""
    margin: float = 0.0

    @property
    def x_in(self) -> float:
        """Where a part arrives at the station along the path [m]."""
        return self.start - self.margin

    @property
    def x_out(self) -> float:
        """Where a part has passed the station along the path [m]."""
        return self.end + self.margin


# The tool attributes an element may carry, in the order its stations are listed.
TOOLS = ("gate", "side_drop", "slot", "wiper", "jet")


def element_count(values: Mapping) -> int:
    """How many elements a feeder of these parameters has, and so how many surface motions its
    result records (FORMAT.md, "Feeder lines"): its ``sections`` (a bowl is the first), at least
    1; 1 where it is absent or no number. Read from the parameters alone, without building the
    feeder: a result stays readable whatever its geometry, and :attr:`Feeder.n_elements` of a
    feeder that builds is the same number."""
    try:
        n = float(values.get("sections", 1))
    except (TypeError, ValueError):
        return 1
    return max(1, int(round(n))) if math.isfinite(n) else 1


@dataclass(frozen=True)
class Feeder:
    """A feeder (module docstring): ``part``, ``elements`` in conveying order,
    ``recirculate`` (rejects come back to the inlet) and ``values``, the parameters it was
    read from (numbers)."""

    part: Part
    elements: tuple
    recirculate: bool = False
    values: Mapping | None = None

    @classmethod
    def from_values(cls, values: Mapping) -> Feeder:
        """The feeder of a deck's parameters (numbers or their strings)."""
        part = Part.from_values(values)
        recirculate = number(values, "recirculate", 0.0)
        if recirculate not in (0, 1):
            raise ParameterError(f"recirculate={recirculate:g} must be 0 (rejects removed) or 1 "
                                 "(returned to the inlet)")
        if starts_with_bowl(values):
            from ..bowl import bowl_from

            numbers = {k: number(values, k) for k in values if _is_number(values[k])}
            drive = Drive(freq=number(values, "freq", 0.0), amp_t=number(values, "amp_t", 0.0),
                          amp_n=number(values, "amp_n", 0.0), phase=number(values, "phase", 0.0))
            jet = read_jet(values, 1, lambda key, default=None: number(values, BOWL_KEYS[key], default),
                           part, name=BOWL_KEYS.get)
            first = BowlElement(bowl_from(numbers), drive, jet)
        else:
            first = None
        n = number(values, "sections", 1.0)
        if not (1 <= n <= MAX_SECTIONS and n == int(n)):  # (NaN fails the first test)
            raise ParameterError(f"sections={n:g} must be a whole number from 1 to {MAX_SECTIONS}")
        elements, x0, level = ([first], first.x1, 0.0) if first else ([], 0.0, 0.0)
        for k in range(len(elements) + 1, int(n) + 1):
            code = number(values, f"s{k}_kind", 0.0) if k > 1 else 0.0
            kind = BY_CODE.get(code)
            if kind is None:
                raise ParameterError(f"s{k}_kind={code:g} must be {later_kinds_text()}")
            s = kind.build(values, k, x0, level, part)
            elements.append(s)
            x0, level = s.x1, s.exit_level
        return cls(part, tuple(elements), bool(recirculate), values)

    # ---------------------------------------------------------------- what the analyses ask
    @property
    def bowl(self):
        """The bowl's geometry (vibrofeed.bowl.Bowl) of a feeder that starts with one, else None."""
        first = self.elements[0]
        return first.bowl if isinstance(first, BowlElement) else None

    @property
    def line_origin(self) -> tuple[float, float, float]:
        """Where the frame of the elements after the first lies in the deck's [m] (a line's:
        the deck's own; after a bowl, at its chute's end: BowlElement.line_origin)."""
        first = self.elements[0]
        return first.line_origin if isinstance(first, BowlElement) else (0.0, 0.0, 0.0)

    def origin_of(self, e) -> tuple[float, float, float]:
        """Where element ``e``'s frame lies in the deck's [m]: the first element's is the deck's,
        the further ones' :attr:`line_origin`."""
        return (0.0, 0.0, 0.0) if e is self.elements[0] else self.line_origin

    @property
    def path_shift(self) -> float:
        """What the path coordinate adds to an x of the line's frame [m]: 0 for a line (its
        path coordinate is x), a bowl's path length less its outlet edge's x for its exit
        line (the path runs on from the chute's end)."""
        b = self.bowl
        return b.length + b.chute_length - b.outlet_x if b is not None else 0.0

    @property
    def offsets(self) -> list[float]:
        """What each element's path coordinate adds to an x of the line's frame [m], in
        conveying order: 0 for a bowl (its path coordinate is its own), then :attr:`path_shift`,
        grown past each mesh element by how much longer its path is than its run along x (its
        path turns: the elements after it lie that much further along the path than along x)."""
        out, shift = [], self.path_shift
        for e in self.elements:
            if isinstance(e, BowlElement):
                out.append(0.0)
                continue
            out.append(shift)
            if isinstance(e, MeshElement):
                shift += e.path_length - (e.x1 - e.x0)
        return out

    @property
    def path_is_x(self) -> bool:
        """Whether the path coordinate is the deck's x all along (straight sections only): a
        bowl's helix and a mesh element's path are not."""
        return not any(isinstance(e, (BowlElement, MeshElement)) for e in self.elements)

    @property
    def sections(self) -> int:
        """How many sections the path has (a line's elements; a bowl's helix and chute)."""
        return len(self.bounds)

    @property
    def bounds(self) -> list[tuple[float, float]]:
        """(start, end) of each section along the path [m], in conveying order: a line's x in
        the track's frame, a bowl's path coordinate (vibrofeed.bowl.path_coordinate), then an
        exit line's x shifted on from the bowl's path end (:attr:`path_shift`)."""
        out = []
        for e, shift in zip(self.elements, self.offsets):
            out.extend((a + shift, b + shift) for a, b in e.bounds)
        return out

    @property
    def catch_x(self) -> list[float]:
        """Where each section along the path starts in the deck's x [m], for the rejects a
        catch plane sorts by x: a line's bounds; a bowl's helix from -inf, its chute from
        the slot (x = 0, the chute runs along +x from the helix's end), its exit line's."""
        out = []
        for e in self.elements:
            out += [-math.inf, 0.0] if isinstance(e, BowlElement) else [a for a, _ in e.bounds]
        return out

    @property
    def path_end(self) -> float:
        """The outlet edge's coordinate along the path [m]."""
        return self.bounds[-1][1]

    @property
    def joint_positions(self) -> list[float]:
        """Where one section hands over to the next along the path [m]."""
        return [b[0] for b in self.bounds[1:]]

    def section_at(self, s) -> np.ndarray:
        """Which section (0-based) a part at path coordinate ``s`` is over; -1 beyond the
        outlet edge (falling) or for NaN (no part)."""
        return section_index(s, self.joint_positions, self.path_end)

    def line_coordinate(self, points) -> np.ndarray:
        """Where points (..., 3) of the deck's frame are along the path over the elements after
        a bowl (its exit line) or from a line's first mesh element on: over a straight one, x
        plus its :attr:`offsets` (between its entry and its end, within its walls, above its
        floor by less than its walls' height and a part); over a mesh element its path
        coordinate (MeshElement.coordinate; past its end, the last one's only) plus its
        offset, NaN farther from its path than half its width and a part; NaN elsewhere. A
        line's coordinate over its straight elements before any mesh is its x
        (vibrofeed.postproc.path): NaN there."""
        p = np.asarray(points, dtype=float)
        out = np.full(p.shape[:-1], np.nan)
        ox, oy, oz = self.line_origin
        x, y, z = p[..., 0] - ox, p[..., 1] - oy, p[..., 2] - oz
        curved = self.bowl is not None
        for e, shift in zip(self.elements[1:], self.offsets[1:]):
            if isinstance(e, MeshElement):
                curved = True
                at = e.coordinate(np.stack([x, y, z], axis=-1), e.width / 2 + self.part.size)
                if e is not self.elements[-1]:  # (past its end: over the next element, which says)
                    at = np.where(at > e.x0 + e.path_length, np.nan, at)
                out = np.where(np.isnan(out), at + shift, out)
                continue
            if not curved:
                continue
            over = (x >= e.x0) & (x <= e.x1) & (np.abs(y) <= e.width / 2)
            floor = e.floor_at(x, y)
            over &= (z >= floor - self.part.tallest) & (z < floor + e.wall_height + self.part.size)
            out = np.where(over & np.isnan(out), x + shift, out)
        return out

    def path_at_x(self, x) -> np.ndarray:
        """The path coordinate [m] of the deck's ``x`` [m] over the elements after the first
        (where a reject fell, as far as its x tells): x plus the offset of the element holding
        it (:meth:`element_at_x`; before the second, the second's), along a mesh element's
        path where it first reaches x (MeshElement.arc_at_x)."""
        x = np.asarray(x, dtype=float)
        if len(self.elements) < 2:
            return x + self.path_shift
        ox = self.line_origin[0]
        which = np.clip(self.element_at_x(x), 1, len(self.elements) - 1)
        out = np.empty(x.shape)
        for i in np.unique(which):
            e, shift, on = self.elements[i], self.offsets[i], which == i
            out[on] = (e.x0 + e.arc_at_x(x[on] - ox) if isinstance(e, MeshElement)
                       else x[on] - ox) + shift
        return out

    @property
    def mesh_start(self) -> float:
        """Where a mesh element starts in the deck's x [m] (its joint): from there on a part's
        path coordinate is along its path (:meth:`line_coordinate`); inf without one."""
        return next((e.x0 + self.line_origin[0] for e in self.elements if isinstance(e, MeshElement)),
                    math.inf)

    def height_at(self, s):
        """A bowl's floor height on the centre line at path coordinate ``s`` [m] (the profile in
        height: up the helix and the chute, then its exit line's floors); None for a feeder
        without a bowl (its path is level or its own track's frame)."""
        b = self.bowl
        if b is None:
            return None
        s = np.asarray(s, dtype=float)
        h = b.height_at(np.minimum(s, b.length + b.chute_length))
        oz = self.line_origin[2]
        for e, shift in zip(self.elements[1:], self.offsets[1:]):
            start = e.x0 + shift
            floor = (e.height_along(s - start) if isinstance(e, MeshElement)
                     else e.floor_at(s - shift, 0.0))
            h = np.where(s >= start, oz + floor, h)
        return h

    @property
    def exit_direction(self) -> np.ndarray:
        """The unit vector along which parts leave over the outlet edge (the last element's)."""
        return np.asarray(self.elements[-1].exit_direction, dtype=float)

    @property
    def exit_band(self) -> tuple[float, float] | None:
        """Across the outlet edge in the deck's frame (y from, to) [m]: the last element's walls
        widened by a part's widest either way, the band a part that left over the edge falls
        through (one falling farther across was blown or fell off a side); None where the path
        does not leave along x."""
        e, d = self.elements[-1], self.exit_direction
        if abs(d[1]) > 1e-3 * float(np.linalg.norm(d)):
            return None
        lo, hi = e.exit_band
        shift = self.origin_of(e)[1]
        return lo + shift - self.part.widest, hi + shift + self.part.widest

    def element_at_x(self, x) -> np.ndarray:
        """Which element (0-based) holds the deck's ``x`` [m]: the last one starting at or before
        it (a bowl from -inf; beyond the outlet edge, the last element)."""
        starts = [-math.inf] + [e.x0 + self.line_origin[0] for e in self.elements[1:]]
        return np.searchsorted(np.asarray(starts), np.asarray(x, dtype=float), side="right") - 1

    def element_of(self, k: int):
        """The element path section ``k`` (1-based) belongs to."""
        owners = [e for e in self.elements for _ in e.bounds]
        return owners[k - 1]

    # ---------------------------------------------------------------- what it can do
    @property
    def n_elements(self) -> int:
        """How many elements it has (the deck's ``sections``; a bowl is the first): each moves
        with its own surface, whose motion a run records (section 1's, then each further
        element's, FORMAT.md)."""
        return len(self.elements)

    @property
    def further_elements(self) -> tuple:
        """The elements after the first (a line's sections 2, 3 ...; a bowl's exit line): empty
        for a single track or a bowl alone."""
        return self.elements[1:]

    @property
    def several_sections(self) -> bool:
        """Whether its path has more than one section (a line's elements; a bowl's helix and
        chute): the analyses report it section by section."""
        return len(self.bounds) > 1

    @property
    def rotates(self) -> bool:
        """Whether its first element's surface turns about the z axis (a bowl's torsion): a
        run records its angle and rate beside its position (FORMAT.md)."""
        return isinstance(self.elements[0], BowlElement)

    @property
    def has_rejects(self) -> bool:
        """Whether parts that leave it over a side before the outlet edge are caught and
        counted, by the section they fell from (a catch plane under its further elements: a
        line, a bowl's exit line). A single track's walls hold its parts; a bowl alone drops
        them back into itself (:func:`vibrofeed.postproc.path.falls`)."""
        return bool(self.further_elements)

    @property
    def returns_rejects(self) -> bool:
        """Whether its rejects come back to the inlet (``recirculate``; a feeder with rejects)."""
        return self.has_rejects and self.recirculate

    @property
    def has_jets(self) -> bool:
        """Whether an element carries an air jet (an orienting station the driver senses and
        fires, vibrofeed.engine.jets; a run records its firings)."""
        return any(getattr(e, "jet", None) is not None for e in self.elements)

    @property
    def linear_sections(self) -> list[LinearSection]:
        return [e for e in self.elements if isinstance(e, LinearSection)]

    @property
    def joints(self) -> list[Joint]:
        """The joints between consecutive elements."""
        s = self.elements
        return [Joint(a, b) for a, b in zip(s[:-1], s[1:])]

    @property
    def stations(self) -> list[Station]:
        """The tooling stations along the path, in conveying order of elements (a bowl's side
        drop and wiper; each further element's tools of :data:`TOOLS`, whichever it carries),
        each on the path section (1-based) it lies on. A tool record placed by ``start`` and
        ``end`` (fractions of its element's length) spans them; one placed by ``at`` spans
        from there on by its ``length`` [m] if it has one (a wiper's bar); an air jet spans its
        block (from its sensing point by its offset, its length); a gate spans its 45-degree
        narrowing from its element's width to its own."""
        out = []
        margin = self.part.size
        for e, shift in zip(self.elements, self.offsets):
            if isinstance(e, BowlElement):
                b = e.bowl
                for kind, span in (("side_drop", b.drop), ("wiper", b.wiper)):
                    if span is not None:
                        out.append(Station(1, kind, *(float(b.arc_length(t)) for t in span),
                                           element=1, name=f"s1.{kind}", margin=margin))
                if e.jet is not None:
                    out.append(Station(1, "jet", *e.jet_span(self.part.size), element=1, name="s1.jet",
                                       margin=margin))
                continue
            k = int(self.section_at(e.x0 + shift)) + 1
            for attr in TOOLS:
                tool = getattr(e, attr, None)
                if tool is None:
                    continue
                if attr == "jet":  # its block: from the sensing point by its offset and length
                    a, z = e.jet_span(self.part.size)
                elif hasattr(tool, "start") and hasattr(tool, "end"):
                    a, z = e.x0 + tool.start * e.length, e.x0 + tool.end * e.length
                else:
                    a = e.x0 + tool.at * e.length
                    z = a + float(getattr(tool, "length", 0.0) or 0.0)
                    if attr == "wiper" and tool.skew:  # its bar runs on across the track
                        z = a + e.wiper_reach
                    if attr == "gate":  # its walls narrow at 45 degrees to its width
                        z = min(a + max(tool.taper(getattr(e, "width", 0.0)), 0.0), e.x0 + e.length)
                kind = getattr(tool, "kind", attr)
                out.append(Station(k, kind, a + shift, z + shift, element=e.number,
                                   name=f"s{e.number}.{kind}", margin=margin))
        return out

    def further_meshes(self) -> list:
        """The meshes at rest of the elements after the first (none for a single track or a
        bowl alone), in the deck's frame, as the prepare hook appends them to the first's."""
        origin = np.asarray(self.line_origin)
        return [(v + origin, t) for v, t in (e.mesh() for e in self.elements[1:])]

    def moves(self, k: int) -> bool:
        """Whether element ``k`` (1-based) is driven (a chute stands still)."""
        return self.elements[k - 1].moves

    def section_values(self, k: int) -> dict | None:
        """The parameters with path section ``k``'s drive (1-based) as the deck's ``freq``,
        ``amp_t``, ``amp_n``, ``phase`` and ``waveform``: what a model of one part alone on
        that section takes (a further section runs a sine); None for an undriven one (a
        chute) and for a mesh element (its path turns: no model of one part on it). A bowl's
        sections take the bowl's parameters (its drive seen from the helix:
        vibrofeed.bowl.track_drive)."""
        values = dict(self.values or {})
        e = self.element_of(k)
        if e is self.elements[0]:
            return values
        if not isinstance(e, LinearSection):
            return None  # (a chute: no vibration to model; a mesh: no straight track)
        d = e.drive
        out = {**values, "freq": d.freq, "amp_t": d.amp_t, "amp_n": d.amp_n, "phase": d.phase,
               "waveform": 0}
        if self.bowl is not None:  # after a bowl: a part alone on a level linear section
            del out["bowl_diameter"]
            out["incline"] = 0.0
        return out

    # ---------------------------------------------------------------- checks
    @classmethod
    def check_values(cls, values: Mapping) -> None:
        """The feeder's rules as the parameter rules apply them (vibrofeed.parameters), to a
        set that may be partial: a line's (or a single track's) whole :meth:`check` once its
        part and section 1's track are given; else only its rejects' return (``recirculate``,
        ``return_delay``): a partial set, or a bowl, whose exit line is checked with its
        geometry (vibrofeed.geometry.prepare_bowl_feeder)."""
        if "part_size" in values and "track_width" in values and not starts_with_bowl(values):
            cls.from_values(values).check()  # (recirculate and return_delay among its checks)
            return
        recirculate = number(values, "recirculate", 0.0)
        if recirculate not in (0, 1):
            raise ParameterError(f"recirculate={recirculate:g} must be 0 (rejects removed) or 1 "
                                 "(returned to the inlet)")
        if number(values, "return_delay", 0.0) < 0:
            raise ParameterError(f"return_delay={number(values, 'return_delay'):g} s must be >= 0")

    def check(self) -> None:
        """Everything about the feeder's shape: each further section on its own and every
        joint (one-line ParameterError naming the parameter). Section 1 and the parts are
        checked with the bulk feeder's own rules (vibrofeed.parameters), a bowl by
        vibrofeed.bowl.check_bowl."""
        p = self.values or {}
        if number(p, "return_delay", 0.0) < 0:
            raise ParameterError(f"return_delay={number(p, 'return_delay'):g} s must be >= 0")
        first = self.elements[0]
        if isinstance(first, BowlElement) and first.jet is not None:  # (a line's first has none)
            check_jet(first, self.part)
        if not self.further_elements:
            if self.recirculate and self.linear_sections:
                raise ParameterError("recirculate=1: a single track has no rejects to return; "
                                     "a line (sections >= 2) has")
            return
        further = self.further_elements
        if self.recirculate and self.bowl is not None:
            raise ParameterError("recirculate=1: a bowl returns its rejects itself (they fall back "
                                 "into it); its exit line's rejects are removed")
        for s in further:
            s.check(self.part, last=s is further[-1])
        for j in self.joints:
            j.check(self.part)
        if number(p, "hamaker", 0.0) > 0 or number(p, "air_viscosity", 0.0) > 0:
            raise ParameterError("hamaker and air_viscosity act on section 1's floor only: a line "
                                 "(sections >= 2) runs without them in this version")
        if self.elements[0].drive.waveform != 0:
            raise ParameterError("a line (sections >= 2) drives its sections with sines (waveform=0) "
                                 "in this version")


# ---------------------------------------------------------------- the parameters' feeder
# What the parameter rules ask of a set of parameters that may be partial (vibrofeed.parameters,
# vibrofeed.plausibility), before a Feeder can be read from it.
def starts_with_bowl(values: Mapping) -> bool:
    """Whether the feeder of these parameters starts with a bowl: they name its
    ``bowl_diameter`` (module docstring; :meth:`Feeder.from_values` decides by this too)."""
    return "bowl_diameter" in values


def inserts_between_walls(values: Mapping) -> bool:
    """Whether the feeder of these parameters inserts its parts (its inlet's and its pre-fill's)
    into blocks between its first track's walls (decks/bulk_feeder.liggghts, regions inlet and
    fill), whose room and rate the parameter rules check; a bowl drops them into itself."""
    return not starts_with_bowl(values)


def side_tools_unprefixed(values: Mapping) -> bool:
    """Whether the side drop's and the wiper's names without a prefix (``drop_from``,
    ``wiper_height`` ...) place tools of the first element: a bowl's, on its helix. A line's
    section 1 carries none (a gate only); its further sections' are ``s<k>_drop_from`` ...
    (vibrofeed.feeders.linear.KEYS)."""
    return starts_with_bowl(values)


def section_index(s, joints, edge: float) -> np.ndarray:
    """Which section (0-based) a part at path coordinate ``s`` is over, the sections handing
    over at ``joints``; -1 beyond the outlet ``edge`` (falling) or for NaN (no part); with an
    infinite edge nothing is beyond it."""
    s = np.asarray(s, dtype=float)
    which = np.searchsorted(np.asarray(joints, dtype=float), s, side="right")
    off = ~(s <= edge) if math.isfinite(edge) else np.isnan(s)
    return np.where(off, -1, which)


def _is_number(value) -> bool:
    try:
        float(value)
    except (TypeError, ValueError):
        return False
    return True


def section_from(values: Mapping, k: int = 2):
    """Section ``k``'s (>= 2) mesh geometry (vibrofeed.line.Section) from the deck's
    parameters (numbers or their strings), even where ``sections`` says fewer."""
    sections = max(k, int(float(values.get("sections", 1))))
    return Feeder.from_values({**values, "sections": sections}).elements[k - 1].mesh_section()
