"""Van der Waals adhesion of a part to the track (Khan & Sarma, §3.1).

Non-retarded, pairwise-additive van der Waals interaction with Hamaker
constant A (condensed phases: 0.4e-19 to 4e-19 J, typically 1e-19 J), as the
report writes it (Israelachvili, "Intermolecular and Surface Forces", ch. 11):

* sphere of radius R at distance D from a plane: energy W = -A R / (6 D),
  force F = A R / (6 D^2); two spheres: R replaced by R1 R2 / (R1 + R2);
* two flat surfaces: energy per area W = -A / (12 pi D^2), pressure
  P = A / (6 pi D^3);
* contact: the surfaces cannot come closer than D0 = 0.2 nm (the report's
  "in contact" distance), and the surface energy is gamma = A / (24 pi D0^2),
  half the work of adhesion A / (12 pi D0^2).

Roughness: a rough or contaminated surface touches on asperities that hold the
mean surfaces apart; to first order it is a larger standoff, s = D0 +
roughness (the report: grit-blasted tracks let 300 um parts move; "the
practical adhesion pressures and energies are several orders of magnitude
smaller"). The force acts in flight too, as the 1/D^2 tail of the same law:
a part at gap x >= 0 above the track feels F(x + s).

**The §3.1 figures.** The flat-surface figures follow from the formulas at
D = 0.2 nm, A = 1e-19 J: P = 663 MPa ("of the order of 700 MPa") and
W = 66.3 mJ/m^2 ("-67 mJ m^-2": the work of adhesion, i.e. 2 gamma; gamma
itself is 33.2 mJ/m^2). The sphere figures ("two 100 um spheres in contact",
200 uN and -1e-15 J) follow from no radius convention: the Derjaguin formulas
give F / |W| = 1 / D whatever the radius, and the quoted pair has
F / |W| = 2e11 1/m, i.e. D = 5 pm, 40x smaller than the stated 0.2 nm.
Taken one at a time, the force needs an effective radius of 480 um (two spheres
of 1 mm radius, or a sphere of 1 mm diameter on a plane: 208 uN), 10x the
stated size; the energy needs 12 um. The four readings of "two 100 um spheres"
(radius or diameter 100 um; sphere-sphere or sphere-plane) give 10-42 uN
(4.8-19x below 200 uN) and 2.1e-15 to 8.3e-15 J (2-8x above 1e-15 J). The
likeliest reading, two spheres of 100 um radius (R* = 50 um), gives 20.8 uN
and -4.2e-15 J: the quoted force is then 10x too large (a slip of a decimal)
and the energy right to its order of magnitude. `sphere_figure_readings`
computes this table; tests/unit/models/test_adhesion.py asserts it.

Time step: the force near contact is stiff. Its gradient at the standoff,
kappa = A R / (3 s^3) for a sphere (A S / (2 pi s^4) for a flat face of area
S), is a negative spring of time scale sqrt(m / kappa); resolving it as the
decks resolve the Hertz contact (1/50 of pi sqrt(m / k)) needs
dt <= (pi / 50) sqrt(m / kappa) (`vdw_step_limit`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .constants import G

#: Contact separation [m] of two atomically smooth surfaces (Khan & Sarma, §3.1: D = 0.2 nm).
D0 = 0.2e-9

#: The §3.1 examples: A = 1e-19 J at D = 0.2 nm, "two 100 um spheres".
REPORT_HAMAKER = 1e-19  # J
REPORT_SPHERE_SIZE = 100e-6  # m, the "100 um" of the text (radius or diameter: see the module docstring)
REPORT_SPHERE_FORCE = 200e-6  # N
REPORT_SPHERE_ENERGY = 1e-15  # J (magnitude)
REPORT_FLAT_PRESSURE = 700e6  # Pa, "of the order of 700 MPa"
REPORT_FLAT_ENERGY = 67e-3  # J/m^2 (magnitude)

#: Fraction of the vdW time scale pi sqrt(m / kappa) used as the step, as the decks do for Hertz.
STEP_FRACTION = 1.0 / 50.0


# ------------------------------------------------------------------ the laws
def sphere_plane_force(hamaker: float, radius: float, distance: float) -> float:
    """Attraction [N] of a sphere of ``radius`` [m] at ``distance`` [m] from a plane: A R / (6 D^2)."""
    return hamaker * radius / (6.0 * distance ** 2)


def sphere_plane_energy(hamaker: float, radius: float, distance: float) -> float:
    """Interaction energy [J] of a sphere and a plane: -A R / (6 D)."""
    return -hamaker * radius / (6.0 * distance)


def effective_radius(r1: float, r2: float = math.inf) -> float:
    """Derjaguin's R1 R2 / (R1 + R2); a plane is r2 = inf."""
    return r1 if math.isinf(r2) else r1 * r2 / (r1 + r2)


def flat_pressure(hamaker: float, distance: float) -> float:
    """Attractive pressure [Pa] between two flat surfaces: A / (6 pi D^3)."""
    return hamaker / (6.0 * math.pi * distance ** 3)


def flat_energy(hamaker: float, distance: float) -> float:
    """Interaction energy per area [J/m^2] of two flat surfaces: -A / (12 pi D^2)."""
    return -hamaker / (12.0 * math.pi * distance ** 2)


def surface_energy(hamaker: float, d0: float = D0) -> float:
    """Surface energy gamma [J/m^2] = A / (24 pi D0^2): half the work of adhesion."""
    return hamaker / (24.0 * math.pi * d0 ** 2)


def standoff(roughness: float, d0: float = D0) -> float:
    """Separation [m] of the mean surfaces of a part resting on the track: D0 + roughness."""
    if roughness < 0:
        raise ValueError(f"roughness must be >= 0, got {roughness}")
    return d0 + roughness


@dataclass(frozen=True)
class Adhesion:
    """A part's van der Waals attraction to the track.

    hamaker [J]; roughness [m] (standoff D0 + roughness); radius [m] of a
    spherical part, or face_radius [m] > 0 for a part lying on a flat disc
    face (flat-flat pressure over pi face_radius^2), or face_side [m] > 0 on
    a square face (a chip: over face_side^2).
    """
    hamaker: float
    roughness: float = 0.0
    radius: float = 0.0
    face_radius: float = 0.0
    face_side: float = 0.0

    @property
    def s(self) -> float:
        return standoff(self.roughness)

    @property
    def flat(self) -> bool:
        return self.face_radius > 0 or self.face_side > 0

    @property
    def face_area(self) -> float:
        """Area [m^2] of the flat face (0 for a sphere)."""
        if self.face_side > 0:
            return self.face_side ** 2
        return math.pi * self.face_radius ** 2

    def force(self, gap: float) -> float:
        """Attraction [N] at ``gap`` [m] (the DEM's gap between the touching
        surfaces; <= 0 in contact, where it is the pull-off)."""
        d = max(gap, 0.0) + self.s
        if self.flat:
            return flat_pressure(self.hamaker, d) * self.face_area
        return sphere_plane_force(self.hamaker, self.radius, d)

    @property
    def pulloff(self) -> float:
        """Force [N] needed to pull the part off the track: the attraction in contact."""
        return self.force(0.0)

    @property
    def stiffness(self) -> float:
        """|dF/dgap| [N/m] at contact: A R / (3 s^3), or A S / (2 pi s^4) for a flat face."""
        if self.flat:
            return self.hamaker * self.face_area / (2.0 * math.pi * self.s ** 4)
        return self.hamaker * self.radius / (3.0 * self.s ** 3)

    def work(self) -> float:
        """Work [J] to take the part from contact to infinity: A R / (6 s) (flat: A S / (12 pi s^2))."""
        if self.flat:
            return -flat_energy(self.hamaker, self.s) * self.face_area
        return -sphere_plane_energy(self.hamaker, self.radius, self.s)


def sticking_gamma(adhesion: Adhesion, mass: float, g: float = G) -> float:
    """Peak normal acceleration, in g, above which a part first leaves a track
    vibrating normal to itself: 1 + F_pulloff / (m g). The part leaves when the
    track's downward acceleration exceeds what gravity and adhesion together
    can give it (Khan & Sarma, §3.1, Figure 11: "snap-off")."""
    return 1.0 + adhesion.pulloff / (mass * g)


def vdw_step_limit(adhesion: Adhesion, mass: float, fraction: float = STEP_FRACTION) -> float:
    """Largest timestep [s] that resolves the vdW force near contact:
    fraction * pi sqrt(m / kappa) (module docstring); inf without adhesion."""
    if adhesion.hamaker <= 0:
        return math.inf
    return fraction * math.pi * math.sqrt(mass / adhesion.stiffness)


# ------------------------------------------------------------------ the §3.1 sphere figures
@dataclass(frozen=True)
class SphereReading:
    """One reading of "two 100 um spheres in contact": what the formulas give."""
    name: str
    r_eff: float  # m, the radius in A R / (6 D^2)
    force: float  # N
    energy: float  # J (magnitude)


def sphere_figure_readings(size: float = REPORT_SPHERE_SIZE, hamaker: float = REPORT_HAMAKER,
                           d: float = D0) -> list[SphereReading]:
    """Force and energy of the four readings of "two spheres of size ``size``":
    the size a radius or a diameter, two spheres or one sphere on a plane."""
    out = []
    for what, radius in (("radius", size), ("diameter", size / 2)):
        for pair, r_eff in (("sphere-sphere", effective_radius(radius, radius)),
                            ("sphere-plane", effective_radius(radius))):
            out.append(SphereReading(f"{pair}, {what} {size * 1e6:g} um", r_eff,
                                     sphere_plane_force(hamaker, r_eff, d),
                                     -sphere_plane_energy(hamaker, r_eff, d)))
    return out


def radius_for_force(force: float, hamaker: float = REPORT_HAMAKER, d: float = D0) -> float:
    """Effective radius [m] whose Derjaguin force at ``d`` is ``force``: 6 D^2 F / A."""
    return 6.0 * d ** 2 * force / hamaker


def radius_for_energy(energy: float, hamaker: float = REPORT_HAMAKER, d: float = D0) -> float:
    """Effective radius [m] whose energy magnitude at ``d`` is ``energy``: 6 D |W| / A."""
    return 6.0 * d * abs(energy) / hamaker


def separation_for(force: float, energy: float) -> float:
    """The separation [m] at which a force and an energy magnitude belong to the
    same sphere (any radius): D = |W| / F."""
    return abs(energy) / force
