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
from .chute import KIND_CODE as CHUTE
from .chute import Chute
from .joints import Joint
from .linear import MAX_SECTIONS, LinearSection
from .records import Part, number


@dataclass(frozen=True)
class BowlElement:
    """Today's vibratory bowl (vibrofeed.bowl): a helical track up its wall, then a straight
    chute through the wall to the outlet edge. Along the path it has two sections, the
    helix and the chute; ``bowl`` is its geometry (vibrofeed.bowl.Bowl)."""

    kind = "bowl"
    bowl: object

    @property
    def bounds(self) -> list[tuple[float, float]]:
        helix = self.bowl.length
        return [(0.0, helix), (helix, helix + self.bowl.chute_length)]


@dataclass(frozen=True)
class Station:
    """A tooling station where the analyses look for its rejects: on ``section`` (1-based),
    from ``start`` to ``end`` along the path [m] (a wiper: its upstream face to its bar's
    end; a side drop: its open stretch)."""

    section: int
    kind: str
    start: float
    end: float


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
        if "bowl_diameter" in values:
            from ..bowl import bowl_from

            numbers = {k: number(values, k) for k in values if _is_number(values[k])}
            return cls(part, (BowlElement(bowl_from(numbers)),), bool(recirculate), values)
        n = number(values, "sections", 1.0)
        if not (1 <= n <= MAX_SECTIONS and n == int(n)):  # (NaN fails the first test)
            raise ParameterError(f"sections={n:g} must be a whole number from 1 to {MAX_SECTIONS}")
        elements, x0, level = [], 0.0, 0.0
        for k in range(1, int(n) + 1):
            kind = number(values, f"s{k}_kind", 0.0) if k > 1 else 0.0
            if kind == CHUTE:
                s = Chute.from_values(values, k, x0, level)
            elif kind == 0:
                s = LinearSection.from_values(values, k, x0, level, part)
            else:
                raise ParameterError(f"s{k}_kind={kind:g} must be 0 (a linear section) or "
                                     f"{CHUTE} (a chute)")
            elements.append(s)
            x0, level = s.x1, s.exit_level
        return cls(part, tuple(elements), bool(recirculate), values)

    # ---------------------------------------------------------------- what the analyses ask
    @property
    def sections(self) -> int:
        """How many sections the path has (a line's elements; a bowl's helix and chute)."""
        return len(self.bounds)

    @property
    def bounds(self) -> list[tuple[float, float]]:
        """(start, end) of each section along the path [m], in conveying order: a line's x in
        the track's frame, a bowl's path coordinate (vibrofeed.bowl.path_coordinate)."""
        out = []
        for e in self.elements:
            out.extend(e.bounds)
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

    @property
    def is_line(self) -> bool:
        """A line of more than one section (its joints are checked, its rejects counted per
        section, its further sections' motion recorded)."""
        return len(self.line_elements) > 1

    @property
    def line_elements(self) -> list:
        """The elements of a line (every element but a bowl), in conveying order."""
        return [e for e in self.elements if not isinstance(e, BowlElement)]

    @property
    def linear_sections(self) -> list[LinearSection]:
        return [e for e in self.elements if isinstance(e, LinearSection)]

    @property
    def joints(self) -> list[Joint]:
        """The joints between consecutive elements of a line."""
        s = self.line_elements
        return [Joint(a, b) for a, b in zip(s[:-1], s[1:])]

    @property
    def stations(self) -> list[Station]:
        """The side drops and wipers along the path, in conveying order of sections."""
        out = []
        for e in self.elements:
            if isinstance(e, BowlElement):
                b = e.bowl
                if b.drop is not None:
                    out.append(Station(1, "side_drop", *(float(b.arc_length(t)) for t in b.drop)))
                if b.wiper is not None:
                    out.append(Station(1, "wiper", *(float(b.arc_length(t)) for t in b.wiper)))
                continue
            if getattr(e, "side_drop", None) is not None:
                d = e.side_drop
                out.append(Station(e.number, "side_drop", e.x0 + d.start * e.length,
                                   e.x0 + d.end * e.length))
            if getattr(e, "wiper", None) is not None:
                a = e.x0 + e.wiper.at * e.length
                out.append(Station(e.number, "wiper", a, a + e.wiper.length))
        return out

    def further_meshes(self) -> list:
        """The meshes at rest of a line's elements after the first (none for a single track),
        as the prepare hook appends them to the first section's."""
        return [e.mesh() for e in self.elements[1:] if not isinstance(e, BowlElement)]

    def moves(self, k: int) -> bool:
        """Whether section ``k`` (1-based) is driven (a chute stands still)."""
        return self.line_elements[k - 1].moves

    def section_values(self, k: int) -> dict | None:
        """The parameters with section ``k``'s drive (1-based) as the deck's ``freq``,
        ``amp_t``, ``amp_n``, ``phase`` and ``waveform``: what a model of one part alone on
        that section takes (a further section runs a sine); None for an undriven one (a
        chute)."""
        values = dict(self.values or {})
        if k == 1 or not self.is_line:
            return values
        if not isinstance(self.elements[k - 1], LinearSection):
            return None  # (a chute: no vibration to model)
        d = self.elements[k - 1].drive
        return {**values, "freq": d.freq, "amp_t": d.amp_t, "amp_n": d.amp_n, "phase": d.phase,
                "waveform": 0}

    # ---------------------------------------------------------------- checks
    def check(self) -> None:
        """Everything about the feeder's shape: each further section on its own and every
        joint (one-line ParameterError naming the parameter). Section 1 and the parts are
        checked with the bulk feeder's own rules (vibrofeed.parameters), a bowl by
        vibrofeed.bowl.check_bowl."""
        p = self.values or {}
        if number(p, "return_delay", 0.0) < 0:
            raise ParameterError(f"return_delay={number(p, 'return_delay'):g} s must be >= 0")
        if not self.is_line:
            if self.recirculate and self.linear_sections:
                raise ParameterError("recirculate=1: a single track has no rejects to return; "
                                     "a line (sections >= 2) has")
            return
        further = self.line_elements[1:]
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
