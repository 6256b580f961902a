"""A sliding block on a track whose in-plane drive also shakes it across: a bowl's chute.

The chute of a bowl (vibrofeed.bowl) is the helix's tangent and turns with the bowl. At a
distance x along it from the slot, the torsion moves the floor by theta(t) (r_mid, x): along
the chute as at the helix's centre line, and across it by x theta, growing along the chute
(docs/bowl.md, "The chute"). Khan & Sarma's block (§2.3.2, the single-part model of
:mod:`.part_on_surface`) slides in one dimension. Here the block slides in the plane, under
isotropic Coulomb friction: the friction force, mu N, opposes the block's velocity relative
to the floor, whatever its direction. Part of the friction then goes into the slip across
the track, and less of it carries the block along.

The model (per unit mass, the track inclined by ``incline`` along x, no cross tilt):
the floor moves by Im(A e^{i w t}) along x, across (y) and along its normal, with complex
amplitudes ``along``, ``across``, ``normal`` [m] (a sine sin(w t + p) is the phasor a e^{i p}).
The normal force is g cos(incline) + the floor's normal acceleration; it must stay positive
(the block slides, never hops: this model has no flights). The block's in-plane velocity v
follows dv/dt = -g sin(incline) e_x - mu N (v - u)/|v - u| while it slips (u the floor's
in-plane velocity) and v = u while the friction it needs stays within mu N (it sticks).
With ``clearance`` the chute's two walls, moving with the floor, leave the block that much
play across: at a wall the block's velocity across becomes the wall's (a plastic impact: the
wall's impulse J) and the wall's friction, up to mu J, brakes its slip along. A drive skewed
across the track conveys the block across it too, so it ends against one wall, pressed on
it in every period, and that wall's friction slows it.

It is integrated by steps with the friction impulse limited at each one (the maximal
dissipation step of DEM codes, first order in the step): the trial velocity without
friction, v*, is set to the floor's velocity when |v* - u| <= mu N dt (it sticks), and is
otherwise moved towards it by mu N dt. Started at the floor's velocity, it runs until the
motion settles into a cycle of whole periods (against a wall it can take many periods),
over which the speeds are averaged. With ``across`` 0 it is the one-dimensional block,
and its speed matches the event-driven model of :mod:`.part_on_surface` (tested).
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import numpy as np

from .constants import G

# Steps per period: the friction step's error is first order in it (0.02-0.5 % of the speed
# here, tested against the event-driven 1D model).
STEPS = 2000
# Periods run between checks, and the most run before the motion must have settled.
AVERAGE, MAX_PERIODS = 10, 300
# Settled: each period's mean velocity repeats a cycle's to this fraction of the floor's peak
# speed along the track.
SETTLED = 1e-3


@dataclass(frozen=True)
class ChuteState:
    """The block's steady motion: ``velocity`` along the track and ``across`` it [m/s], means
    over its cycle of whole periods (or, when none repeats in MAX_PERIODS, over the last
    half of them); ``periods`` run in all."""

    velocity: float
    across: float
    periods: int
    cycle: int  # periods of the cycle averaged; 0: none found, the mean of the last half


def sliding_speed(freq: float, along: complex, across: complex, normal: complex, mu: float,
                  incline: float = 0.0, clearance: float | None = None, g: float = G) -> ChuteState:
    """The steady sliding of a block on a floor shaken along, across and normal to itself
    (module docstring); ``incline`` [deg] up along x; ``clearance`` [m] the play between the
    walls (None: no walls). Raises ValueError when the block would leave the floor (the
    normal force reaches 0: hopping, which this model leaves out)."""
    if freq <= 0 or mu < 0:
        raise ValueError(f"need freq > 0 and mu >= 0, got freq={freq}, mu={mu}")
    w = 2 * math.pi * freq
    dt = 1 / (freq * STEPS)
    a = math.radians(incline)
    pull = g * math.sin(a)  # gravity down the incline (-x)
    if abs(normal) * w * w >= g * math.cos(a):
        raise ValueError(f"the floor's normal acceleration ({abs(normal) * w * w:.3g} m/s^2) reaches "
                         f"g cos(incline) ({g * math.cos(a):.3g}): the block would hop; this model "
                         "only slides")
    # one period of the floor at the steps' ends: in-plane velocity and the normal force
    # (plain floats in the loop: numpy's small arrays would cost more than the arithmetic)
    t = (np.arange(STEPS) + 1) * dt
    phasor = np.exp(1j * w * t)
    ux = (1j * w * along * phasor).imag.tolist()
    uy = (1j * w * across * phasor).imag.tolist()
    cap = (mu * (g * math.cos(a) - w * w * (normal * phasor).imag) * dt).tolist()
    vx, vy = (1j * w * along).imag, (1j * w * across).imag  # at rest on the floor, t = 0
    side = math.inf if clearance is None else clearance / 2
    y = 0.0  # across, from the middle between the walls, in the floor's frame
    drop = pull * dt
    per_period = []  # each period's mean velocity (along, across)
    scale = SETTLED * w * abs(along)
    while len(per_period) < MAX_PERIODS:
        for _ in range(AVERAGE):
            sx = sy = 0.0
            for k in range(STEPS):
                vx -= drop
                rx, ry = vx - ux[k], vy - uy[k]
                slip = math.hypot(rx, ry)
                if slip <= cap[k]:
                    vx, vy = ux[k], uy[k]
                else:
                    f = cap[k] / slip
                    vx -= f * rx
                    vy -= f * ry
                y += (vy - uy[k]) * dt
                if abs(y) > side:  # at a wall: it stops the slip across, its friction the slip along
                    y = math.copysign(side, y)
                    impulse = abs(vy - uy[k])
                    vy = uy[k]
                    along_slip = vx - ux[k]
                    vx -= math.copysign(min(abs(along_slip), mu * impulse), along_slip)
                sx += vx
                sy += vy
            per_period.append((sx / STEPS, sy / STEPS))
        cycle = _cycle(np.array(per_period), scale)
        if cycle:
            mean = np.mean(per_period[-cycle:], axis=0)
            drifting = clearance is not None and abs(mean[1]) > scale  # not yet at a wall
            if not drifting:
                return ChuteState(float(mean[0]), float(mean[1]), len(per_period), cycle)
    # no cycle (a wall's stick-slip can drift quasi-periodically): the mean of the last half
    mean = np.mean(per_period[len(per_period) // 2:], axis=0)
    return ChuteState(float(mean[0]), float(mean[1]), len(per_period), 0)


def _cycle(per_period: np.ndarray, tol: float) -> int:
    """The shortest c (periods) with which the last 2c periods' means repeat to ``tol``: the
    block's motion has settled into a cycle of c periods (a stick-slip against a wall can
    take many); 0 if none of up to a third of the periods run."""
    n = len(per_period)
    for c in range(1, n // 3 + 1):
        if np.abs(per_period[n - c:] - per_period[n - 2 * c:n - c]).max() <= tol:
            return c
    return 0


def chute_drive(amp_t: float, amp_n: float, phase: float, helix_angle: float, r_mid: float,
                x: float) -> tuple[complex, complex, complex]:
    """(along, across, normal) phasors [m] of a bowl's chute at x along it from the slot
    (vibrofeed.bowl's drive: the bowl turns by (amp_t / r_mid) sin(w t) and rises by amp_n
    sin(w t + phase)): the floor point (x cos a, -r_mid) moves by (amp_t, amp_t x cos(a) / r_mid)
    sin(w t) in the plane and amp_n sin(w t + phase) up; projected on the chute's axis (rising
    at the helix angle a) and its normal as :func:`vibrofeed.bowl.track_drive` projects the
    helix's, and across as it is."""
    a = math.radians(helix_angle)
    u = complex(amp_t)  # along +x (the torsion's phase is the reference)
    vz = amp_n * cmath.exp(1j * math.radians(phase))
    along = u * math.cos(a) + vz * math.sin(a)
    normal = -u * math.sin(a) + vz * math.cos(a)
    across = complex(amp_t * x * math.cos(a) / r_mid)
    return along, across, normal
