"""Validation cases: one TOML file per case in ``validation/cases/``.

A case names a comparison ``kind`` (see ``crosscheck.KINDS``), the deck and
its parameters, optionally a ``[sweep]`` (one DEM run per value), the
comparison settings and the tolerance of each quantity::

    title = "Hopping: lift-off, landings and flight times"
    kind = "flights"
    deck = "single_part"
    notes = "why these tolerances, what limits the DEM"

    [parameters]          # deck parameters of every run
    amp_t = 0
    restitution = 0.1

    [sweep]               # one run per value; gamma/gamma_t set amp_n/amp_t
    gamma = [1.5, 2.5]    # several keys: every combination, or with
                          # zip = true (top level) the i-th values together

    [compare]             # kind-specific settings
    flights = 3

    [tolerance]           # per quantity: abs (in the quantity's unit), rel, or
                          # sigma (times the combined uncertainty, DEM vs DEM)
    landing_phase = { abs = 0.01 }
    flight_duration = { rel = 0.02 }

Tolerances live here, not in code; a case file also says why they are what
they are (``notes``).
"""

from __future__ import annotations

import itertools
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CaseError

CASES_DIR = Path(__file__).resolve().parent / "cases"

# Keys (in [parameters] or [sweep]) that are not deck parameters but set one:
# Gamma = amp w^2 / g of the normal or tangential sine.
DERIVED_SWEEP_KEYS = {"gamma": "amp_n", "gamma_t": "amp_t"}


@dataclass(frozen=True)
class Tolerance:
    """``abs``: |DEM - model| <= value (the quantity's unit); ``rel``: <= value
    |model|; ``sigma``: <= value times the comparison's combined 1-sigma
    uncertainty (for a DEM measured against a DEM reference, each with its
    batch-means error). ``crosscheck.Row.passed`` applies it."""
    value: float
    kind: str  # "abs", "rel" or "sigma"


@dataclass
class Case:
    name: str
    path: Path
    title: str
    kind: str
    deck: str
    parameters: dict
    sweep: dict = field(default_factory=dict)
    compare: dict = field(default_factory=dict)
    tolerance: dict = field(default_factory=dict)
    notes: str = ""
    zip_sweep: bool = False

    def points(self) -> list[dict]:
        """The sweep's points: dicts of sweep key -> value (one empty dict if no sweep)."""
        if not self.sweep:
            return [{}]
        keys = list(self.sweep)
        combos = zip(*self.sweep.values()) if self.zip_sweep else itertools.product(*self.sweep.values())
        return [dict(zip(keys, values)) for values in combos]

    def tolerance_of(self, quantity: str) -> Tolerance:
        try:
            return self.tolerance[quantity]
        except KeyError:
            raise CaseError(f"case {self.name}: no tolerance for {quantity} in [tolerance]") from None


TOLERANCE_KINDS = ("abs", "rel", "sigma")


def _tolerance(case: str, name: str, spec) -> Tolerance:
    if not isinstance(spec, dict) or len(spec.keys() & TOLERANCE_KINDS) != 1:
        raise CaseError(f"case {case}: tolerance {name} must be {{ abs = x }}, {{ rel = x }} "
                        "or {{ sigma = x }}")
    kind = next(k for k in TOLERANCE_KINDS if k in spec)
    value = float(spec[kind])
    if value < 0:
        raise CaseError(f"case {case}: tolerance {name} must be >= 0")
    return Tolerance(value, kind)


def load(path: str | Path) -> Case:
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except OSError as exc:
        raise CaseError(f"cannot read case file {path}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"case file {path} is not valid TOML: {exc}") from None
    name = path.stem
    for key in ("title", "kind", "deck"):
        if key not in data:
            raise CaseError(f"case {name}: missing {key}")
    sweep = data.get("sweep", {})
    for key, values in sweep.items():
        if not isinstance(values, list) or not values:
            raise CaseError(f"case {name}: sweep {key} must be a non-empty list")
    zip_sweep = bool(data.get("zip", False))
    if zip_sweep and len({len(v) for v in sweep.values()}) > 1:
        raise CaseError(f"case {name}: with zip = true every sweep list needs the same length")
    return Case(
        name=name, path=path, title=data["title"], kind=data["kind"], deck=data["deck"],
        parameters=dict(data.get("parameters", {})), sweep=dict(sweep),
        compare=dict(data.get("compare", {})),
        tolerance={k: _tolerance(name, k, v) for k, v in data.get("tolerance", {}).items()},
        notes=data.get("notes", "").strip(), zip_sweep=zip_sweep)


def available() -> list[str]:
    return sorted(p.stem for p in CASES_DIR.glob("*.toml"))


def find(name: str) -> Case:
    path = Path(name)
    if path.suffix == ".toml" and path.is_file():
        return load(path)
    candidate = CASES_DIR / f"{name}.toml"
    if not candidate.is_file():
        raise CaseError(f"no validation case {name}; cases: {', '.join(available())}")
    return load(candidate)
