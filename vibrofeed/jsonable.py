"""Values as JSON holds them: one conversion for every report, row and summary."""

from __future__ import annotations

import math

import numpy as np


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
