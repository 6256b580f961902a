"""Van der Waals adhesion (vibrofeed/models/adhesion.py) against Khan & Sarma,
"Vibratory Assembly Update: Part Transportation Mechanics Analysis", §3.1.

The flat-surface figures of §3.1 follow from its formulas; the sphere figures
follow from no radius convention (see the module docstring): these tests state
that finding as assertions, so that a change of formula or constant shows.
"""

import math

import pytest
from scipy.integrate import quad

from vibrofeed.models import adhesion as ad
from vibrofeed.models.constants import G

A = ad.REPORT_HAMAKER
D = ad.D0


def test_flat_surface_figures_follow_from_the_formulas():
    p = ad.flat_pressure(A, D)
    assert p == pytest.approx(663.1e6, rel=1e-3)
    assert abs(p / ad.REPORT_FLAT_PRESSURE - 1) < 0.06  # "of the order of 700 MPa"
    # The quoted -67 mJ/m^2 is the interaction energy per area at contact, the
    # work of adhesion A / (12 pi D^2) = 2 gamma, not the surface energy gamma.
    w = -ad.flat_energy(A, D)
    assert w == pytest.approx(ad.REPORT_FLAT_ENERGY, rel=0.015)
    assert ad.surface_energy(A) == pytest.approx(w / 2, rel=1e-12)
    assert ad.surface_energy(A) == pytest.approx(33.2e-3, rel=2e-3)


def test_pressure_is_minus_the_derivative_of_the_flat_energy():
    h = 1e-4 * D
    deriv = (ad.flat_energy(A, D + h) - ad.flat_energy(A, D - h)) / (2 * h)
    assert ad.flat_pressure(A, D) == pytest.approx(deriv, rel=1e-6)


def test_sphere_force_is_minus_the_derivative_of_the_sphere_energy():
    r, h = 50e-6, 1e-4 * D
    deriv = (ad.sphere_plane_energy(A, r, D + h) - ad.sphere_plane_energy(A, r, D - h)) / (2 * h)
    assert ad.sphere_plane_force(A, r, D) == pytest.approx(deriv, rel=1e-6)


def test_no_radius_convention_reproduces_both_sphere_figures():
    # Force over energy is 1/D for any radius: the pair quoted implies D = 5 pm.
    for r in (1e-6, 50e-6, 1e-3):
        ratio = ad.sphere_plane_force(A, r, D) / -ad.sphere_plane_energy(A, r, D)
        assert ratio == pytest.approx(1 / D, rel=1e-12)
    d_implied = ad.separation_for(ad.REPORT_SPHERE_FORCE, ad.REPORT_SPHERE_ENERGY)
    assert d_implied == pytest.approx(5e-12, rel=1e-12, abs=0)  # 5 pm: approx's default abs is 20 % of it
    assert D / d_implied == pytest.approx(40, rel=1e-12)
    # One at a time: the force needs R* = 480 um (10x the stated size), the energy 12 um.
    assert ad.radius_for_force(ad.REPORT_SPHERE_FORCE) == pytest.approx(480e-6, rel=1e-12, abs=0)
    assert ad.radius_for_energy(ad.REPORT_SPHERE_ENERGY) == pytest.approx(12e-6, rel=1e-12, abs=0)
    # Two spheres of 1 mm radius (or one of 1 mm diameter on a plane) give the force to 4 %.
    f_1mm = ad.sphere_plane_force(A, ad.effective_radius(1e-3, 1e-3), D)
    assert f_1mm / ad.REPORT_SPHERE_FORCE == pytest.approx(1.04, abs=0.005)


def test_every_reading_of_two_100_um_spheres_misses_the_quoted_figures():
    readings = ad.sphere_figure_readings()
    assert len(readings) == 4
    forces = [x.force for x in readings]
    energies = [x.energy for x in readings]
    # 10.4 to 41.7 uN: 4.8x to 19x below 200 uN; 2.1e-15 to 8.3e-15 J: 2x to 8x above 1e-15 J.
    assert min(forces) == pytest.approx(10.42e-6, rel=1e-3, abs=0)
    assert max(forces) == pytest.approx(41.67e-6, rel=1e-3, abs=0)
    assert all(ad.REPORT_SPHERE_FORCE / f >= 4.7 for f in forces)
    # ~1e-15 J: approx's default abs=1e-12 J alone would pass any energy below a picojoule
    assert min(energies) == pytest.approx(2.083e-15, rel=1e-3, abs=0)
    assert max(energies) == pytest.approx(8.333e-15, rel=1e-3, abs=0)
    assert all(e / ad.REPORT_SPHERE_ENERGY >= 2 for e in energies)
    # The likeliest reading, two spheres of radius 100 um: the force 10x too small
    # for the quoted one (a decimal slip), the energy of the quoted order of magnitude.
    likeliest = next(x for x in readings if x.name.startswith("sphere-sphere, radius"))
    assert likeliest.r_eff == pytest.approx(50e-6, rel=1e-12, abs=0)
    assert ad.REPORT_SPHERE_FORCE / likeliest.force == pytest.approx(9.6, rel=1e-3)
    assert 1 <= likeliest.energy / ad.REPORT_SPHERE_ENERGY < 10


def test_roughness_is_a_larger_standoff():
    smooth = ad.Adhesion(A, 0.0, radius=150e-6)
    rough = ad.Adhesion(A, 9 * D, radius=150e-6)  # standoff 10 D0
    assert smooth.pulloff == pytest.approx(ad.sphere_plane_force(A, 150e-6, D), rel=1e-12, abs=0)
    assert rough.pulloff == pytest.approx(smooth.pulloff / 100, rel=1e-12, abs=0)
    with pytest.raises(ValueError):
        ad.standoff(-1e-9)


def test_the_force_acts_in_flight_as_a_shifted_tail_and_is_constant_in_contact():
    adh = ad.Adhesion(A, 2e-9, radius=150e-6)
    s = adh.s
    assert adh.force(-1e-7) == adh.force(0.0) == adh.pulloff
    for gap in (s, 10 * s, 1e-6):
        # abs=0: down to 2e-12 N, where approx's default abs=1e-12 would be half the force
        assert adh.force(gap) == pytest.approx(adh.pulloff * s ** 2 / (gap + s) ** 2, rel=1e-12, abs=0)


@pytest.mark.parametrize("face_radius", [0.0, 100e-6])
def test_stiffness_and_work_are_the_derivative_and_integral_of_the_force(face_radius):
    adh = ad.Adhesion(A, 5e-9, radius=150e-6, face_radius=face_radius)
    h = 1e-6 * adh.s
    slope = (adh.force(2 * h) - adh.force(h)) / h  # just outside contact
    assert -slope == pytest.approx(adh.stiffness, rel=1e-4)
    # in units of the standoff, so that quad sees the force's own scale
    work, _ = quad(lambda u: adh.force(u * adh.s) * adh.s, 0, math.inf, epsabs=0, epsrel=1e-10)
    assert work == pytest.approx(adh.work(), rel=1e-8, abs=0)  # ~1e-16 J: no absolute slack
    assert adh.work() > 0


def test_a_flat_face_pulls_with_the_flat_pressure_over_its_area():
    adh = ad.Adhesion(A, 1e-6, face_radius=200e-6)
    # ~5e-10 N: approx's default abs=1e-12 N would be 0.2 % of it
    assert adh.pulloff == pytest.approx(ad.flat_pressure(A, 1e-6 + D) * math.pi * (200e-6) ** 2,
                                        rel=1e-12, abs=0)
    square = ad.Adhesion(A, 1e-6, face_side=300e-6)  # a chip's face
    assert square.flat and square.face_area == pytest.approx(9e-8, rel=1e-12, abs=0)
    assert square.pulloff == pytest.approx(ad.flat_pressure(A, 1e-6 + D) * 9e-8, rel=1e-12, abs=0)
    h = 1e-6 * square.s
    assert -(square.force(2 * h) - square.force(h)) / h == pytest.approx(square.stiffness, rel=1e-4)


def test_sticking_threshold_grows_linearly_with_the_hamaker_constant():
    radius, density, roughness = 150e-6, 2330.0, 3e-9
    mass = 4 / 3 * math.pi * radius ** 3 * density
    s = D + roughness
    # Gamma_c - 1 = F / (m g) = A / (8 pi s^2 R^2 rho g) for a sphere.
    for hamaker in (0.0, 0.4e-19, 1e-19, 4e-19):
        gamma_c = ad.sticking_gamma(ad.Adhesion(hamaker, roughness, radius=radius), mass)
        assert gamma_c - 1 == pytest.approx(hamaker / (8 * math.pi * s ** 2 * radius ** 2 * density * G),
                                            rel=1e-12, abs=1e-15)
    assert ad.sticking_gamma(ad.Adhesion(0.0, roughness, radius=radius), mass) == 1.0


def test_vdw_step_limit_resolves_the_force_near_contact():
    radius, density = 150e-6, 2330.0
    mass = 4 / 3 * math.pi * radius ** 3 * density
    adh = ad.Adhesion(1e-19, 3e-9, radius=radius)
    dt = ad.vdw_step_limit(adh, mass)
    assert dt == pytest.approx(math.pi / 50 * math.sqrt(mass / adh.stiffness), rel=1e-12, abs=0)  # ~1e-6 s
    # A standoff twice as large: stiffness / 8, step x 2^1.5.
    wider = ad.Adhesion(1e-19, 2 * adh.s - D, radius=radius)
    assert ad.vdw_step_limit(wider, mass) / dt == pytest.approx(2 ** 1.5, rel=1e-9)
    assert ad.vdw_step_limit(ad.Adhesion(0.0, 3e-9, radius=radius), mass) == math.inf
    # In one such step a part moving at the relative speed the force itself gives
    # over the standoff, sqrt(2 F s / m), crosses a small fraction of the standoff.
    v = math.sqrt(2 * adh.pulloff * adh.s / mass)
    assert v * dt < 0.2 * adh.s


def test_the_reports_quoted_figures_are_transcribed_as_printed():
    # §3.1: A = 1e-19 J, D = 0.2 nm, "two 100 um spheres": 200 uN and -1e-15 J; flat: ~700 MPa, -67 mJ/m^2
    assert (ad.REPORT_HAMAKER, ad.D0, ad.REPORT_SPHERE_SIZE) == (1e-19, 0.2e-9, 100e-6)
    assert (ad.REPORT_SPHERE_FORCE, ad.REPORT_SPHERE_ENERGY) == (200e-6, 1e-15)
    assert (ad.REPORT_FLAT_PRESSURE, ad.REPORT_FLAT_ENERGY) == (700e6, 67e-3)


def test_the_four_readings_are_named_by_pair_and_size_convention():
    names = [x.name for x in ad.sphere_figure_readings()]
    assert names == ["sphere-sphere, radius 100 um", "sphere-plane, radius 100 um",
                     "sphere-sphere, diameter 100 um", "sphere-plane, diameter 100 um"]
    assert ad.sphere_figure_readings(size=2.5e-6)[0].name == "sphere-sphere, radius 2.5 um"
    # in micrometres to six significant digits (:g): 123.4564 um shows as 123.456
    assert ad.sphere_figure_readings(size=123.4564e-6)[0].name == "sphere-sphere, radius 123.456 um"
    # R* = R1 R2 / (R1 + R2): 50, 100, 25, 50 um
    assert [x.r_eff for x in ad.sphere_figure_readings()] == pytest.approx([50e-6, 100e-6, 25e-6, 50e-6],
                                                                          rel=1e-12, abs=0)


def test_an_adhesion_defaults_to_a_smooth_sphere():
    r = 150e-6
    sphere = ad.Adhesion(A, radius=r)
    assert sphere == ad.Adhesion(A, 0.0, r, 0.0, 0.0)
    assert not sphere.flat and sphere.face_area == 0.0 and sphere.s == D
    assert sphere.pulloff == pytest.approx(A * r / (6 * D ** 2), rel=1e-12, abs=0)
    assert sphere.work() == pytest.approx(A * r / (6 * D), rel=1e-12, abs=0)
    chip = ad.Adhesion(A, face_side=300e-6)
    assert chip == ad.Adhesion(A, 0.0, 0.0, 0.0, 300e-6)
    assert chip.pulloff == pytest.approx(A / (6 * math.pi * D ** 3) * 9e-8, rel=1e-12, abs=0)


def test_adhesions_and_readings_are_immutable_values():
    import dataclasses
    adh = ad.Adhesion(A, 1e-9, radius=1e-4)
    assert hash(adh) == hash(ad.Adhesion(A, 1e-9, radius=1e-4))
    with pytest.raises(dataclasses.FrozenInstanceError):
        adh.roughness = 0.0
    reading = ad.sphere_figure_readings()[0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        reading.force = 0.0
