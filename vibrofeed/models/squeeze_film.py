"""Squeeze-film air damping of a part leaving the track (Khan & Sarma, §3.2).

**Stefan's law.** A disc of radius r moving normal to a plane at speed V,
with a film of viscosity mu and thickness h between them (quasi-static,
incompressible, laminar, no-slip, rigid, parallel), feels
F = 1.5 pi mu r^4 V / h^3 opposing the motion (the "p" of the report's
printed formula is pi). For a sphere of radius R the same lubrication theory
gives Reynolds' F = 6 pi mu R^2 V / h (h << R).

**The film at both ends.** At small gaps the film thickness cannot drop below
the clearance h_c the surfaces keep in contact: the roughness, and at least the
mean free path of air (68 nm), below which the no-slip law stops holding (the
report: "we are also close to the mean free path"). A part at gap x >= 0 (the
DEM's gap between the touching surfaces) has film thickness h = x + h_c.
At large gaps the squeeze film vanishes and the free-flow (Stokes) drag
remains, 16 mu r V for a disc moving face-on, 6 pi mu R V for a sphere; the
two are added: c(h) = 1.5 pi mu r^4 / h^3 + 16 mu r (disc),
6 pi mu R (R / h + 1) (sphere; the leading terms of the exact sphere-wall
drag). V is the velocity relative to the track: the air near a vibrating
plate moves with it (the report's argument; the oscillating boundary layer
sqrt(2 nu / omega) is 0.2 mm at 100 Hz, larger than the hops of interest).

**An exact integral.** The film force is -c(h) dh/dt, a total time
derivative: whatever the surface does, the momentum the film has taken from
the part once the gap has grown from h0 to h is P(h0, h) = int_h0^h c, i.e.
0.75 pi mu r^4 (1/h0^2 - 1/h^2) + 16 mu r (h - h0) for a disc. A part that
lifts off at t_l with the surface's velocity v_l therefore moves at
v_p(t) = v_l - g (t - t_l) - P(h0, h(t)) / m: its velocity deficit against
free flight depends on the gap it has reached, not on how fast it got there.
The squeeze-film part saturates at 0.75 pi mu r^4 / (m h0^2), the report's
"limit for infinitely fast withdrawal of the surface", inversely
proportional to the square of the starting clearance (Figure 13). (A sphere's
film, 6 pi mu R^2 ln(h / h0), does not saturate.)

**The ODE of §3.2**, corrected: the report prints
h_p'' = +1.5 mu pi r^4 (h_p' - h_s') / (m (h_p - h_s)^3), which would push the
part along its relative velocity (anti-damping), and leaves out gravity. Here:
m h_p'' = -m g - c(h) (h_p' - h_s'), h = h_p - h_s, surface h_s = a sin(w t),
constant Gamma = a w^2 / g (Figure 13: Gamma = 10). `launch` integrates it
(scipy solve_ivp, Radau: the film makes it stiff, m / c(h0) is ~1e-7..1e-4 s)
from lift-off at w t = asin(1 / Gamma) to the top of the relative flight (the
gap's maximum), or back to contact.

**Figure 13, read two ways.** (1) At the top of the relative flight (the
deficit the hop actually suffers): the deficit is the saturated one at every
frequency whose stroke Gamma g / w^2 is large against the clearance, i.e. at
low frequencies, and falls below it only at high frequencies, where the
stroke nears the clearance, until the part no longer gets free (deficit >=
launch velocity). (2) The report's own ODE (no gravity, the part starting at
the surface's peak velocity) read a fixed time after the start: below a few
Hz the slowly decelerating surface has not withdrawn within that time, the
part still rides on the film and its deficit is the surface's own velocity
loss, a w (1 - cos w tau), proportional to the frequency at constant Gamma;
above, the deficit is the saturated one. With tau = 10 ms this is the
figure's description exactly ("frequency dependence at low frequency",
"magnification between 0 and 3 Hz", saturation above): the low-frequency
dependence is the transient of a fixed observation window, not a property
of the launched part. tests/unit/models/test_squeeze_film.py asserts both readings.

**A square face** (a chip of side a): the Reynolds equation's solution for a
rectangle of sides B <= L (a series in tanh; e.g. Hamrock, Schmid & Jacobson,
"Fundamentals of Fluid Film Lubrication", the squeeze-film chapter) gives
F = mu V L B^3 / h^3 [1 - (192 B / (pi^5 L)) sum_odd n tanh(n pi L / (2 B)) / n^5],
for a square 0.42173 mu a^4 V / h^3 (`stefan_constant`; the disc of equal area,
1.5 pi r^4 = 0.477 a^4, squeezes 13 % harder); its free-flow drag is taken as
the equal-area disc's, 16 mu a / sqrt(pi).

**A clump's panels.** The bulk deck's chips and discs are multisphere clumps
of n spheres; each sphere carries 1/n of the face's coefficient at its own
gap (`Film.panel_force`): the sum is the face's law while the part lies flat.

Time step: a film of coefficient c on a part of mass m relaxes the relative
velocity in m / c; explicit integration resolves it with dt <= m / (10 c),
c taken at the clearance (`film_step_limit`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from .constants import G

#: Dynamic viscosity of air at 20 C [Pa s].
AIR_VISCOSITY = 1.81e-5
#: Kinematic viscosity of air at 20 C [m^2/s].
AIR_KINEMATIC_VISCOSITY = 1.51e-5
#: Mean free path of air molecules at 20 C, 1 atm [m]: the smallest film thickness used.
MEAN_FREE_PATH = 68e-9
#: The relaxation time m / c is resolved by this many steps (`film_step_limit`).
STEPS_PER_RELAXATION = 10.0

#: Figure 13's part: a silicon disc 400 um in diameter, 200 um thick, at Gamma = 10.
FIG13_RADIUS = 200e-6  # m
FIG13_THICKNESS = 200e-6  # m
FIG13_DENSITY = 2330.0  # kg/m^3
FIG13_GAMMA = 10.0
FIG13_MASS = math.pi * FIG13_RADIUS ** 2 * FIG13_THICKNESS * FIG13_DENSITY


def rectangle_factor(aspect: float, terms: int = 200) -> float:
    """The rectangle's squeeze-film factor: F = factor * mu V L B^3 / h^3 for
    sides B <= L, aspect = B / L in (0, 1] (1 - 192 aspect / pi^5 sum_odd n
    tanh(n pi / (2 aspect)) / n^5; 1 for an infinitely long strip)."""
    if not 0 < aspect <= 1:
        raise ValueError(f"aspect must be in (0, 1], got {aspect}")
    odd = np.arange(1, 2 * terms, 2, dtype=float)
    series = np.sum(np.tanh(odd * math.pi / (2.0 * aspect)) / odd ** 5)
    return float(1.0 - 192.0 * aspect / math.pi ** 5 * series)


#: Stefan's constant of a square face: F = STEFAN_SQUARE mu a^4 V / h^3.
STEFAN_SQUARE = rectangle_factor(1.0)


def stefan_force(viscosity: float, radius: float, thickness: float, speed: float) -> float:
    """Stefan's law [N]: 1.5 pi mu r^4 V / h^3 (disc of radius r, film thickness h, speed V)."""
    return 1.5 * math.pi * viscosity * radius ** 4 * speed / thickness ** 3


def clearance(roughness: float) -> float:
    """Film thickness [m] of a part resting on the track: the roughness, at least the mean free path."""
    return max(roughness, MEAN_FREE_PATH)


def stokes_layer(freq: float, nu: float = AIR_KINEMATIC_VISCOSITY) -> float:
    """Thickness [m] of the air layer a plate vibrating at ``freq`` drags along: sqrt(2 nu / w)."""
    return math.sqrt(2.0 * nu / (2.0 * math.pi * freq))


@dataclass(frozen=True)
class Film:
    """The air film under a part.

    viscosity [Pa s]; radius [m] of the part's flat face (``flat``: Stefan) or
    of the sphere (Reynolds); h_c [m] the clearance (film thickness in
    contact); free_flow: add the Stokes drag (16 mu r or 6 pi mu R);
    side [m] > 0: the flat face is a square of this side instead (radius
    ignored; module docstring).
    """
    viscosity: float
    radius: float
    h_c: float
    flat: bool = True
    free_flow: bool = True
    side: float = 0.0

    @property
    def stefan_constant(self) -> float:
        """K [m^4] of the flat face's law F = mu K V / h^3: 1.5 pi r^4, or 0.42173 a^4 for a square."""
        if self.side > 0:
            return STEFAN_SQUARE * self.side ** 4
        return 1.5 * math.pi * self.radius ** 4

    def thickness(self, gap):
        """Film thickness [m] at the DEM gap [m] (<= 0 in contact): max(gap, 0) + h_c."""
        return np.maximum(gap, 0.0) + self.h_c

    @property
    def free_coefficient(self) -> float:
        """Stokes drag coefficient [N s/m] far from the track."""
        if not self.free_flow:
            return 0.0
        mu, r = self.viscosity, self.radius
        if self.flat and self.side > 0:
            return 16.0 * mu * self.side / math.sqrt(math.pi)  # the equal-area disc's
        return 16.0 * mu * r if self.flat else 6.0 * math.pi * mu * r

    def coefficient(self, h):
        """Damping coefficient c(h) [N s/m] at film thickness h [m]: F = -c (v_p - v_s)."""
        mu, r = self.viscosity, self.radius
        film = mu * self.stefan_constant / h ** 3 if self.flat else 6.0 * math.pi * mu * r ** 2 / h
        return film + self.free_coefficient

    def impulse(self, h0, h):
        """Momentum [N s] the film takes from a part whose film grows from h0 to h: int_h0^h c."""
        mu, r = self.viscosity, self.radius
        if self.flat:
            film = 0.5 * mu * self.stefan_constant * (1.0 / h0 ** 2 - 1.0 / h ** 2)
        else:
            film = 6.0 * math.pi * mu * r ** 2 * np.log(h / h0)
        return film + self.free_coefficient * (h - h0)

    def force(self, gap, v_rel):
        """Force [N] on the part at ``gap`` [m] moving at ``v_rel`` [m/s] relative to the track."""
        return -self.coefficient(self.thickness(gap)) * v_rel

    def panel_force(self, gap, v_rel, panels: int):
        """Force [N] on one of a clump's ``panels`` spheres at its own gap and
        velocity relative to the track: 1/panels of the face's coefficient."""
        return self.force(gap, v_rel) / panels


def saturated_deficit(film: Film, mass: float, h0: float | None = None) -> float:
    """The squeeze film's velocity deficit [m/s] once the part is far from the
    track (Stokes drag left out): 0.75 pi mu r^4 / (m h0^2), h0 the clearance."""
    if not film.flat:
        raise ValueError("a sphere's film (Reynolds) has no saturated deficit: it grows as ln(h/h0)")
    h0 = film.h_c if h0 is None else h0
    return 0.5 * film.viscosity * film.stefan_constant / (mass * h0 ** 2)


def film_step_limit(film: Film, mass: float, steps: float = STEPS_PER_RELAXATION) -> float:
    """Largest timestep [s] resolving the film's relaxation time at the clearance: m / (steps c(h_c))."""
    if film.viscosity <= 0:
        return math.inf
    return mass / (steps * film.coefficient(film.h_c))


def fig13_film(h0: float, free_flow: bool = False, viscosity: float = AIR_VISCOSITY) -> Film:
    """The film under Figure 13's disc at starting clearance h0 (Stefan's law only by default, as in §3.2)."""
    return Film(viscosity, FIG13_RADIUS, h0, flat=True, free_flow=free_flow)


# ------------------------------------------------------------------ the ODE of §3.2
@dataclass
class Launch:
    """A part leaving a sinusoidally moving track through its air film.

    Arrays over the integration, time measured from the start t0 [s]:
    gap [m] (film thickness minus the clearance), v_part, v_surface [m/s] and
    deficit = free-flight velocity - v_part [m/s] (free flight: the start
    velocity minus g t). ``end`` says why the integration stopped: "apex" (the
    gap's maximum: the top of the relative flight), "contact" (back to the
    track: the part never got free), "window" (the time asked for).
    """
    t: np.ndarray
    gap: np.ndarray
    v_part: np.ndarray
    v_surface: np.ndarray
    deficit: np.ndarray
    end: str
    t0: float  # s, the start on the surface's clock (w t0 = launch phase)
    v_launch: float  # m/s, the surface's (and part's) velocity at the start

    @property
    def final_deficit(self) -> float:
        return float(self.deficit[-1])

    @property
    def max_gap(self) -> float:
        return float(self.gap.max())


def launch(film: Film, mass: float, freq: float, gamma: float, g: float = G, *,
           report_frame: bool = False, window: float | None = None, max_periods: float = 50.0,
           rtol: float = 1e-10) -> Launch:
    """Integrate the §3.2 ODE for a part leaving a track moving as a sin(w t).

    film: the part's `Film` (its clearance h_c is the starting clearance);
    mass [kg]; freq [Hz]; gamma = a w^2 / g [-]. Physical by default: gravity g,
    start at lift-off (w t0 = asin(1 / gamma), needs gamma > 1) with the
    surface's velocity, stop at the gap's maximum or back at contact.
    ``report_frame``: the report's setting instead (no gravity, start at
    t0 = 0, the surface's peak velocity). ``window`` [s]: stop that long
    after the start instead (events still end it earlier if they happen).
    """
    w = 2.0 * math.pi * freq
    a = gamma * G / w ** 2  # amplitude from Gamma in standard g, as the decks do
    gg = 0.0 if report_frame else g
    if not report_frame and gamma * G <= g:
        raise ValueError(f"gamma={gamma} <= 1: the part never leaves the surface")
    t0 = 0.0 if report_frame else math.asin(g / (gamma * G)) / w
    v0 = a * w * math.cos(w * t0)
    h_c = film.h_c

    # state: gap x (film thickness h = x + h_c), relative velocity u = v_p - v_s
    def rhs(t, y):
        x, u = y
        a_s = -a * w * w * math.sin(w * t)
        return [u, -gg - a_s - film.coefficient(x + h_c) / mass * u]

    def jac(t, y):
        x, u = y
        c = film.coefficient(x + h_c)
        if film.flat:
            dc = -3.0 * film.viscosity * film.stefan_constant / (x + h_c) ** 4
        else:
            dc = -6.0 * math.pi * film.viscosity * film.radius ** 2 / (x + h_c) ** 2
        return [[0.0, 1.0], [-dc * u / mass, -c / mass]]

    def apex(t, y):  # the gap stops growing (once it has opened: u = 0 at the start too)
        return y[1] if y[0] > 1e-3 * h_c else 1.0
    apex.terminal, apex.direction = True, -1

    def contact(t, y):  # back on the track
        return y[0] + 1e-3 * h_c
    contact.terminal, contact.direction = True, -1

    t_end = t0 + (window if window is not None else max_periods / freq)
    # First step: a small fraction of the film's relaxation time at the clearance.
    first = 1e-3 * min(mass / film.coefficient(h_c), 1.0 / freq)
    sol = solve_ivp(rhs, (t0, t_end), [0.0, 0.0], method="Radau", jac=jac, events=[apex, contact],
                    rtol=rtol, atol=[1e-9 * h_c, 1e-12], first_step=first, dense_output=False)
    if sol.status < 0:
        raise RuntimeError(f"the squeeze-film ODE failed: {sol.message}")
    if sol.status == 1:
        end = "apex" if len(sol.t_events[0]) else "contact"
    else:
        end = "window" if window is not None else "max_periods"
    t = sol.t
    x, u = sol.y
    v_s = a * w * np.cos(w * t)
    v_p = v_s + u
    free = v0 - gg * (t - t0)
    return Launch(t - t0, x, v_p, v_s, free - v_p, end, t0, v0)


def apex_deficit(h0: float, freq: float, gamma: float = FIG13_GAMMA, mass: float = FIG13_MASS,
                 free_flow: bool = False) -> Launch:
    """Figure 13 read at the top of the relative flight: the Figure 13 disc at clearance h0."""
    return launch(fig13_film(h0, free_flow), mass, freq, gamma)


def window_deficit(h0: float, freq: float, window: float, gamma: float = FIG13_GAMMA,
                   mass: float = FIG13_MASS) -> float:
    """Figure 13 read as the report's ODE over a fixed ``window`` [s] (no
    gravity, start at peak surface velocity): the deficit at the window's end,
    or at the gap's maximum if that comes first."""
    return launch(fig13_film(h0), mass, freq, gamma, report_frame=True, window=window).final_deficit


def riding_deficit(freq: float, gamma: float, window: float) -> float:
    """Deficit [m/s] of a part that rides the surface for ``window`` [s] from its
    peak velocity (the film's strong-coupling limit): a w (1 - cos w tau)."""
    w = 2.0 * math.pi * freq
    a = gamma * G / w ** 2
    return a * w * (1.0 - math.cos(w * window))
