"""The cheap first stage: what the analytic models say of a setting before any DEM run.

Each section's drive (section 1's ``freq``, ``amp_t``, ``amp_n``, ``phase``, ``waveform``,
``duty``; a line's section 2's ``s2_*`` sine: :meth:`vibrofeed.feeders.Feeder.section_values`) is the
surface motion the decks move (:func:`vibrofeed.models.deck.waveform`), sampled over one
period for its peak acceleration (|a|, in g), its peak displacement (half the stroke of
either component) and whether it throws a part off the floor (the floor accelerates
downwards faster than gravity's normal component g cos(incline): the part hops). The
single-part model (Khan & Sarma, §2.3.2, the dilute limit the feed-rate report gives) gives
each section's conveying speed. A setting that breaks a constraint of the study is never
sent to DEM: :func:`screen` lists the constraints' margins (> 0: broken by that much, in the
constraint's own unit), as Optuna's ``constraints_func`` takes them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..feeders.feeder import Feeder
from ..models.constants import G
from .spec import StudySpec

# Samples of one period for the peaks: a sine's peak is found to 1 - cos(pi/N) ~ 5e-5.
SAMPLES = 360


@dataclass
class Drive:
    """One section's drive as the models see it."""

    section: int
    freq: float
    peak_acceleration: float  # [g]
    peak_displacement: float  # [m]
    hops: bool
    speed: float | None = None  # the single-part model's conveying speed [m/s]
    note: str = ""


@dataclass
class Screened:
    """A setting's screen: its drives, the constraints' margins (name -> amount broken, in
    the constraint's unit; <= 0 holds) and whether all hold."""

    drives: list[Drive]
    margins: dict = field(default_factory=dict)

    @property
    def feasible(self) -> bool:
        return all(m <= 0 for m in self.margins.values())

    @property
    def broken(self) -> list[str]:
        return [name for name, m in self.margins.items() if m > 0]


def sections(values: dict) -> int:
    return int(float(values.get("sections", 1)))


def drive(values: dict, k: int, with_model: bool = True) -> Drive:
    """Section ``k``'s drive (1-based) of resolved deck values (numbers or their strings)."""
    from ..models.deck import transport, waveform

    p = {name: _number(v) for name, v in Feeder.from_values(values).section_values(k).items()}
    motion = waveform(p)
    freq = float(p["freq"])
    t = np.arange(SAMPLES) / (SAMPLES * freq)
    ax, az = motion.acceleration(t)
    x, z = motion.position(t)
    beta = math.radians(float(p.get("incline", 0.0)))
    d = Drive(section=k, freq=freq,
              peak_acceleration=float(np.max(np.hypot(ax, az))) / G,
              peak_displacement=float(max(np.ptp(x), np.ptp(z))) / 2,
              hops=bool(np.min(az) < -G * math.cos(beta)))
    if with_model:
        try:
            state = transport(p)
            d.speed = float(state.velocity)
            d.note = "" if state.converged else "model not converged"
        except (KeyError, ValueError) as exc:
            d.note = f"model not applicable ({exc})"
    return d


def _number(value):
    try:
        return float(value)
    except (TypeError, ValueError):
        return value


def screen(spec: StudySpec, values: dict) -> Screened:
    """The drives and the constraints' margins of one setting (resolved deck values)."""
    c = spec.constraints
    wants_model = "min_model_speed" in c
    drives = [drive(values, k, wants_model) for k in range(1, sections(values) + 1)]
    margins: dict[str, float] = {}
    for d in drives:
        tag = f"section {d.section}"
        if "max_acceleration" in c:
            margins[f"{tag}: peak acceleration [g]"] = d.peak_acceleration - c["max_acceleration"]
        if "max_displacement" in c:
            margins[f"{tag}: peak displacement [m]"] = d.peak_displacement - c["max_displacement"]
        if "frequency" in c:
            low, high = c["frequency"]
            margins[f"{tag}: frequency [Hz]"] = max(low - d.freq, d.freq - high)
        if wants_model:
            speed = d.speed if d.speed is not None else -math.inf
            margins[f"{tag}: model speed [m/s]"] = c["min_model_speed"] - speed
        if d.section in c.get("no_hopping", ()):
            margins[f"{tag}: hops"] = 1.0 if d.hops else 0.0
    numbers = {name: _number(v) for name, v in values.items()}
    for q in spec.inequalities:
        m = q.margin(numbers)
        # a strict inequality met with equality is broken by no amount: by the least positive
        # one, so that it still rules the setting out (margin 0 would count as holding)
        margins[q.text] = m if q.holds(numbers) else max(m, math.ulp(0.0))
    return Screened(drives, margins)
