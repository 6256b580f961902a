"""What a validation case produces: its DEM runs, its compared rows and its outcome.

Shared by the comparison kinds (``crosscheck``, ``micro_checks``) and the
command that prints them; it imports none of them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .cases import Case


@dataclass
class Row:
    case: str
    quantity: str
    model: float
    dem: float
    tolerance: float
    tolerance_type: str  # "abs", "rel" or "sigma" (cases.Tolerance)
    unit: str = ""
    error: float = 0.0  # combined 1-sigma uncertainty of dem - model (tolerance "sigma")

    @property
    def rel_diff(self) -> float | None:
        """(dem - model) / |model|; None when the model value is 0."""
        if self.model == 0:
            return None
        return (self.dem - self.model) / abs(self.model)

    @property
    def passed(self) -> bool:
        diff = abs(self.dem - self.model)
        if self.tolerance_type == "sigma":
            limit = self.tolerance * self.error
        elif self.tolerance_type == "abs":
            limit = self.tolerance
        else:
            limit = self.tolerance * abs(self.model)
        return bool(diff <= limit)

    def as_dict(self) -> dict:
        return {"case": self.case, "quantity": self.quantity, "model": self.model,
                "dem": self.dem, "rel_diff": self.rel_diff, "tolerance": self.tolerance,
                "tolerance_type": self.tolerance_type, "unit": self.unit, "error": self.error,
                "passed": self.passed}


@dataclass
class Run:
    """One DEM run of a case: sweep values, full deck parameters, result file."""
    label: str
    values: dict
    params: dict  # name -> string, as given to the deck (defaults included)
    output: Path
    request: object = None  # the engine.batch.RunRequest that computes it

    def number(self, name: str) -> float:
        return float(self.params[name])


@dataclass
class Outcome:
    case: Case
    rows: list = field(default_factory=list)
    figures: list = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.rows)


def label(values: dict) -> str:
    """A sweep point's name: ``key=value,...``; ``base`` without sweep values."""
    return ",".join(f"{k}={v:g}" if isinstance(v, (int, float)) else f"{k}={v}"
                    for k, v in values.items()) or "base"


def row(case: Case, quantity: str, label: str, model: float, dem: float, unit: str = "",
        error: float = 0.0) -> Row:
    """The row of ``quantity`` at sweep point ``label`` (none for the base point), with the
    case's tolerance of that quantity."""
    tol = case.tolerance_of(quantity)
    name = f"{quantity}[{label}]" if label != "base" else quantity
    return Row(case.name, name, float(model), float(dem), tol.value, tol.kind, unit, float(error))
