"""argparse types of the commands' numeric options: a value that cannot mean
anything (NaN, infinity, a negative width, a count below what the analysis
needs) is a one-line usage error naming the option, before any file is read.

Each function takes the limit and returns the type: ``type=whole(2)``,
``type=real(above=0)``.
"""

from __future__ import annotations

import argparse
import math


def real(above: float | None = None, at_least: float | None = None, at_most: float | None = None):
    """A finite number, > ``above`` or >= ``at_least``, and <= ``at_most`` when given."""
    def parse(text: str) -> float:
        try:
            x = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a number, got {text or 'nothing'}") from None
        if not math.isfinite(x):
            raise argparse.ArgumentTypeError(f"must be a finite number, got {text or 'nothing'}")
        if above is not None and not x > above:
            raise argparse.ArgumentTypeError(f"must be > {above:g}, got {text or 'nothing'}")
        if at_least is not None and not x >= at_least:
            raise argparse.ArgumentTypeError(f"must be >= {at_least:g}, got {text or 'nothing'}")
        if at_most is not None and not x <= at_most:
            raise argparse.ArgumentTypeError(f"must be <= {at_most:g}, got {text or 'nothing'}")
        return x
    return parse


def whole(at_least: int | None = None):
    """A whole number, >= ``at_least`` when given."""
    def parse(text: str) -> int:
        try:
            n = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a whole number, got {text or 'nothing'}") from None
        if at_least is not None and n < at_least:
            raise argparse.ArgumentTypeError(f"must be at least {at_least}, got {n}")
        return n
    return parse
