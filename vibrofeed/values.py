"""Figures as reports hold them: JSON-ready (NaN as None) and as a table prints them."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from .errors import ParameterError


def to_json(value):
    """``value`` with numpy arrays and scalars as lists and numbers, NaN as None."""
    if isinstance(value, dict):
        return {str(k): to_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_json(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_json(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def duration(seconds: float) -> str:
    """A time span as progress lines print it: 1h05m, 3m07s, 42s."""
    seconds = int(round(seconds))
    h, rest = divmod(seconds, 3600)
    m, s = divmod(rest, 60)
    return f"{h}h{m:02d}m" if h else f"{m}m{s:02d}s" if m else f"{s}s"


def fmt(value, scale: float = 1.0, spec: str = ".4g") -> str:
    """A figure of a table: ``value * scale`` in ``spec``, n/a when missing or not finite."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return format(value * scale, spec)


def number(values: Mapping, name: str, default: float | None = None) -> float:
    """``values[name]`` as a float (``default`` when absent); a one-line ParameterError
    naming the parameter when it is missing or not a number."""
    if name not in values:
        if default is None:
            raise ParameterError(f"the feeder needs the parameter {name}")
        return float(default)
    try:
        return float(values[name])
    except (TypeError, ValueError):
        raise ParameterError(f"parameter {name}={values[name]} is not a number") from None
