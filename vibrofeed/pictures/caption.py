"""Which run a figure shows: one line naming the file, the deck and its key parameters.

Every picture and plot carries this line, so that a figure taken out of its
folder (into a report, a slide) still says what was simulated.
"""

from __future__ import annotations

from pathlib import Path

from ..results import layout as L

# Always named when the deck has them: the vibration and the parts.
KEY_PARAMETERS = ("freq", "amp_n", "amp_t", "shape", "part_size", "n_parts")
# Other parameters changed from the deck's defaults, named up to this many.
MAX_CHANGED = 4
SHAPE_NAMES = {0: "sphere", 1: "chip", 2: "disc"}


def _value(name: str, value, unit: str) -> str:
    if name == "shape" and isinstance(value, float) and value in SHAPE_NAMES:
        return f"{name} {SHAPE_NAMES[int(value)]}"
    if unit == "m" and isinstance(value, float) and 0 < abs(value) < 1:
        value, unit = value * 1e3, "mm"  # micro-parts: 0.05 mm reads better than 5e-05 m
    text = f"{value:.4g}" if isinstance(value, float) else str(value)
    return f"{name} {text}" + (f" {unit}" if unit and unit != "-" else "")


def _defaults(result) -> dict:
    """The deck's default of each variable, as recorded in the result ({} if none)."""
    group = result.file.get(L.VARIABLES) if hasattr(result, "file") else None
    out = {}
    for name, ds in (group or {}).items():
        default = ds.attrs.get("default")
        if default is not None:
            out[name] = default.decode() if isinstance(default, bytes) else str(default)
    return out


def _changed(value, default: str) -> bool:
    try:
        return float(default) != value
    except (TypeError, ValueError):
        return str(value) != default


def parameters_text(result) -> str:
    """The key parameters, then the others that differ from the deck's defaults."""
    params, defaults = result.parameters, _defaults(result)
    names = [k for k in KEY_PARAMETERS if k in params]
    changed = [k for k in params if k not in names and k in defaults and _changed(params[k], defaults[k])]
    names += changed[:MAX_CHANGED]
    text = ", ".join(_value(k, params[k], result.units(k)) for k in names)
    if len(changed) > MAX_CHANGED:
        text += f" (+{len(changed) - MAX_CHANGED} more changed)"
    return text


def run_caption(result) -> str:
    """``FILE; deck DECK; key parameters; seed N``: the run a figure shows."""
    parts = [Path(result.path).name]
    if result.deck_name:
        parts.append(f"deck {result.deck_name}")
    text = parameters_text(result)
    if text:
        parts.append(text)
    try:
        parts.append(f"seed {result.seed}")
    except (KeyError, ValueError):
        pass
    return "; ".join(parts)
