"""Sub-hopping transport: the part never leaves the surface (Khan & Sarma, §2.2.1, §2.3.1).

With a normal acceleration amplitude below g cos(beta) the part stays in
contact; normal vibration only modulates the friction limit mu N, and
tangential vibration makes the part stick and slip asymmetrically. The
steady speed comes from the event-driven model (`part_on_surface`); for the
square-wave case of report Figures 4-5 a closed form is given.

The conveying speed depends on the dimensionless peak accelerations
Gamma_t = amp_t w^2 / g, Gamma_n = amp_n w^2 / g, the phase, the incline and
the friction coefficients only; frequency just sets the scale g / w of
velocities, which is why results are also returned divided by amp_t w.
"""

from __future__ import annotations

import numpy as np

from .constants import TWO_PI, G
from .part_on_surface import PartParams, SteadyState, mean_velocity
from .surface import SineWaveform

#: Report Figure 8: delta = 0, horizontal and vertical acceleration amplitudes
#: 0.8 g (the report's A = 1.6 in units where g = 2), mu = 0.75.
FIGURE8 = dict(gamma_t=0.8, gamma_n=0.8, phase=0.0, mu=0.75)


def sine_speed(freq: float, gamma_t: float, gamma_n: float, phase: float, mu_s: float,
               mu_k: float | None = None, e: float = 0.0, incline: float = 0.0,
               g: float = G, **kw) -> SteadyState:
    """Steady mean conveying velocity for sinusoidal vibration (report 2.3.1).

    freq [Hz]; gamma_t, gamma_n: tangential and normal peak accelerations in
    units of g [-]; phase: lead of the normal motion [deg]; mu_s, mu_k [-]
    (mu_k defaults to mu_s); e: restitution (used only if gamma_n exceeds
    cos(beta), i.e. hopping); incline [deg]; g [m/s^2]. Extra keywords go to
    `mean_velocity`. Returns its SteadyState (velocity in m/s).
    """
    wf = SineWaveform.from_gamma(freq, gamma_n, gamma_t, phase, g)
    part = PartParams(mu_s, mu_s if mu_k is None else mu_k, e)
    return mean_velocity(wf, part, incline, g, **kw)


def normalised_speed(gamma_t: float, gamma_n: float, phase: float, mu_s: float,
                     mu_k: float | None = None, e: float = 0.0, incline: float = 0.0, **kw) -> float:
    """Steady mean velocity divided by the peak tangential surface speed amp_t w [-].

    Frequency-independent (see module docstring); computed at 50 Hz.
    """
    ss = sine_speed(50.0, gamma_t, gamma_n, phase, mu_s, mu_k, e, incline, **kw)
    w = TWO_PI * 50.0
    return ss.velocity / (gamma_t * G / w)


def speed_map(gamma_t: float, gammas_n, phases, inclines, mu_s: float, mu_k: float | None = None,
              e: float = 0.0, **kw) -> np.ndarray:
    """Normalised speed (see normalised_speed) on a grid.

    gammas_n [-], phases [deg], inclines [deg]: 1-D sequences. Returns an array
    of shape (len(gammas_n), len(phases), len(inclines)).
    """
    out = np.empty((len(gammas_n), len(phases), len(inclines)))
    for i, gn in enumerate(gammas_n):
        for j, ph in enumerate(phases):
            for k, inc in enumerate(inclines):
                out[i, j, k] = normalised_speed(gamma_t, gn, ph, mu_s, mu_k, e, inc, **kw)
    return out


def square_wave_speed(freq: float, acc_t: float, acc_n: float, mu_s: float, mu_k: float | None = None,
                      g: float = G) -> float:
    """Closed-form steady speed [m/s] for in-phase square-wave accelerations (report Figs 4-5).

    Surface: SquareWaveAccel(freq, acc_t, acc_n, phase=0), flat track; half A
    (forward and up: +acc_t, +acc_n) and half B (back and down). Regime of the
    report: acc_n < g, the part sticks in A (acc_t <= mu_s (g + acc_n)) and
    slips in B (acc_t > mu_s (g - acc_n)). In B the relative velocity grows
    at acc_t - mu_k (g - acc_n) for T/2; in the next A it decays at
    acc_t + mu_k (g + acc_n) over t*; the mean part speed is the mean
    relative velocity, (acc_t - mu_k (g - acc_n)) (T/2) (T/2 + t*) / (2 T).
    Raises ValueError outside the regime.
    """
    mu_k = mu_s if mu_k is None else mu_k
    T = 1.0 / freq
    if not (acc_n < g and acc_t <= mu_s * (g + acc_n) and acc_t > mu_s * (g - acc_n)):
        raise ValueError("outside the stick-in-A / slip-in-B regime")
    grow = acc_t - mu_k * (g - acc_n)
    t_star = grow * (T / 2) / (acc_t + mu_k * (g + acc_n))
    if t_star > T / 2:
        raise ValueError("the part does not re-stick within half A")
    return grow * (T / 2) * (T / 2 + t_star) / (2 * T)
