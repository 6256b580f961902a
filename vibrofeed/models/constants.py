"""Constants shared by the models, defined once."""

from __future__ import annotations

import math

#: Standard gravity [m/s^2]: the decks' value and the experiment's (Yako et al., ICRA 2024).
G = 9.81

TWO_PI = 2.0 * math.pi
