"""Contact and flight of parts above a flat vibrating surface.

The gap of a part is the height of its lowest point above the surface plane,
``gap = z - radius - z_surface(t)``, for decks whose surface is the plane
z = 0 displaced by ``observables/surface/position`` (the single-part decks
and the floor of a flat track). A part is airborne when its gap exceeds
``contact_tolerance``; while in contact the gap is minus the small elastic
overlap of the soft DEM contact.
"""

from __future__ import annotations

import numpy as np


def _crossings(t: np.ndarray, y: np.ndarray, level: float, rising: bool) -> np.ndarray:
    """Times where ``y`` crosses ``level``, linearly interpolated between frames."""
    a, b = y[:-1] - level, y[1:] - level
    idx = np.nonzero((a <= 0) & (b > 0) if rising else (a > 0) & (b <= 0))[0]
    frac = a[idx] / (a[idx] - b[idx])
    return t[idx] + frac * (t[idx + 1] - t[idx])


class Flights:
    """Take-offs, landings and flight durations of one part.

    Parameters
    ----------
    contact_tolerance:
        Gap [m] above which the part counts as airborne. Default: 0.2 % of the
        part's radius (1 um for a 0.5 mm part), well above the elastic overlap
        under the part's weight and well below any hop worth the name.

    Results (after :meth:`compute`): ``time``, ``gap`` (frames,), ``airborne``
    (frames,) bool, ``takeoffs`` and ``landings`` [s] (a landing is the gap
    crossing zero downwards, interpolated between frames; a take-off the gap
    rising through the tolerance, which lags the true separation because the
    part leaves the surface tangentially), ``durations`` [s] of complete
    flights, ``n_hops``, ``airborne_fraction``, ``max_gap`` [m].
    """

    def __init__(self, contact_tolerance: float | None = None):
        self.contact_tolerance = contact_tolerance

    def compute(self, result, part_id: int | None = None) -> "Flights":
        if part_id is None:
            part_id = int(result.part_ids[0])
        t, pos = result.track(part_id, "position")
        _, radius = result.track(part_id, "radius")
        frames = np.isin(result.time, t)
        zs = result.surface_position[frames, 2]
        gap = pos[:, 2] - radius - zs
        tol = 0.002 * float(np.nanmax(radius)) if self.contact_tolerance is None else self.contact_tolerance

        self.part_id, self.time, self.gap, self.tolerance = part_id, t, gap, tol
        self.airborne = gap > tol
        self.takeoffs = _crossings(t, gap, tol, rising=True)
        self.landings = _crossings(t, gap, 0.0, rising=False)
        # Pair each take-off with the first landing after it.
        pairs = []
        for t_up in self.takeoffs:
            later = self.landings[self.landings > t_up]
            if len(later):
                pairs.append((t_up, later[0]))
        self.flights = np.array(pairs).reshape(-1, 2)
        self.durations = self.flights[:, 1] - self.flights[:, 0]
        self.n_hops = len(self.flights)
        self.airborne_fraction = float(self.airborne.mean()) if len(t) else 0.0
        self.max_gap = float(np.max(gap)) if len(t) else float("nan")
        return self
