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

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
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
        if n != int(n) or not 1 <= n <= MAX_SECTIONS:
            raise ParameterError(f"sections={n:g} must be a whole number from 1 to {MAX_SECTIONS}")
        elements, x0, level = [], 0.0, 0.0
        for k in range(1, int(n) + 1):
            s = LinearSection.from_values(values, k, x0, level, part)
            elements.append(s)
            x0, level = s.x1, s.level
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
            out.extend(e.bounds if isinstance(e, BowlElement) else [(e.x0, e.x1)])
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
        s = np.asarray(s, dtype=float)
        which = np.searchsorted(np.asarray(self.joint_positions, dtype=float), s, side="right")
        return np.where(s <= self.path_end, which, -1)

    @property
    def is_line(self) -> bool:
        """A line of more than one driven section (its joints are checked, its rejects counted
        per section, its further sections' motion recorded)."""
        return sum(isinstance(e, LinearSection) for e in self.elements) > 1

    @property
    def linear_sections(self) -> list[LinearSection]:
        return [e for e in self.elements if isinstance(e, LinearSection)]

    @property
    def joints(self) -> list[Joint]:
        """The joints between consecutive linear sections."""
        s = self.linear_sections
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
            if e.side_drop is not None:
                d = e.side_drop
                out.append(Station(e.number, "side_drop", e.x0 + d.start * e.length,
                                   e.x0 + d.end * e.length))
            if e.wiper is not None:
                a = e.x0 + e.wiper.at * e.length
                out.append(Station(e.number, "wiper", a, a + e.wiper.length))
        return out

    def section_values(self, k: int) -> dict:
        """The parameters with section ``k``'s drive (1-based) as the deck's ``freq``,
        ``amp_t``, ``amp_n``, ``phase`` and ``waveform``: what a model of one part alone on
        that section takes (a further section runs a sine)."""
        values = dict(self.values or {})
        if k == 1 or not self.is_line:
            return values
        d = self.linear_sections[k - 1].drive
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
        for s in self.linear_sections[1:]:
            s.check(self.part, last=s is self.linear_sections[-1])
        for j in self.joints:
            j.check(self.part)
        if number(p, "hamaker", 0.0) > 0 or number(p, "air_viscosity", 0.0) > 0:
            raise ParameterError("hamaker and air_viscosity act on section 1's floor only: a line "
                                 "(sections >= 2) runs without them in this version")
        if self.linear_sections[0].drive.waveform != 0:
            raise ParameterError("a line (sections >= 2) drives its sections with sines (waveform=0) "
                                 "in this version")


def _is_number(value) -> bool:
    try:
        float(value)
    except (TypeError, ValueError):
        return False
    return True
