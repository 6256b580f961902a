"""A DEM run's objective values and their errors, from the metrics a sweep row holds.

The sweep's metrics (:func:`vibrofeed.sweep.metrics.metrics`) give the feed rate with its
batch-means error (``parts_per_s_err``) and the singulation fractions over the arrivals
counted (``n_arrivals``). What a designer asks for: ``singulated_rate`` = parts_per_s x
singulated_fraction (single parts per second), a product, and ``oriented_rate``, the parts
per second delivered correctly oriented and single (``vibrofeed orientation``: counted part by
part, not a product of fractions; its own batch-means error ``oriented_rate_err``); correctly
oriented is each run's own parameter ``correct`` (the feeder description's ``[parts] correct``,
or the study's ``[fixed] correct``), as ``correct_fraction``'s. A fraction
f over n arrivals has the binomial error sqrt(f (1 - f) / n); a product's relative errors add
in quadrature (independent estimates: the rate's from batch means of the counts, the
fraction's from which arrivals were single).

A metric the run could not measure (too few exits, a bed not steady: its ``*_reason``) is
None, never a number: such a run is a failed evaluation for the search.
"""

from __future__ import annotations

import math

from .spec import MINIMISED

# metric -> (its error's key in the row, or the fraction whose error is binomial)
_FRACTIONS = ("singulated_fraction", "orientation_yield", "correct_fraction")
_PRODUCTS = {"singulated_rate": ("parts_per_s", "singulated_fraction")}


def value_and_error(row: dict, name: str) -> tuple[float | None, float | None]:
    """(value, 1-sigma error) of metric ``name`` in a row of metrics; (None, None) when the
    run did not measure it; the error None when nothing gives one."""
    if name in _PRODUCTS:
        (a, ea), (b, eb) = (value_and_error(row, n) for n in _PRODUCTS[name])
        if a is None or b is None:
            return None, None
        value = a * b
        if ea is None or eb is None:
            return value, None
        return value, math.hypot(ea * b, eb * a)
    value = row.get(name)
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return None, None
    value = float(value)
    if name in _FRACTIONS:
        n = row.get("n_arrivals")
        return value, (math.sqrt(max(value * (1 - value), 0.0) / n) if n else None)
    err = row.get(f"{name}_err")
    return value, (float(err) if err is not None else None)


def direction(name: str) -> str:
    return "minimize" if name in MINIMISED else "maximize"


def better(a: float, b: float, name: str) -> bool:
    """Whether ``a`` is better than ``b`` for metric ``name``."""
    return a < b if name in MINIMISED else a > b


def cautious(value: float, error: float | None, name: str) -> float:
    """The value one standard error towards worse: what ranks settings without chasing a
    lucky run (a noisy high value ranks below a steady one just under it)."""
    e = error or 0.0
    return value + e if name in MINIMISED else value - e
