"""A deck's parameters as the models' inputs (vibrofeed.models.deck): amplitudes turned into
accelerations, the waveforms' shapes, the part's mass, adhesion and air film -- each against
a closed form computed by hand, at the quantity's own scale."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vibrofeed.models import deck
from vibrofeed.models.adhesion import Adhesion
from vibrofeed.models.squeeze_film import Film
from vibrofeed.models.surface import (
    CoulombPumpWaveform,
    SineWaveform,
    SquareWaveAccel,
    StickSlipWaveform,
)


def half_swing(motion) -> float:
    """Half the peak-to-peak tangential displacement over a period, sampled finely
    (the extrema of these motions are parabolic: the sampling error is ~1e-6 of it)."""
    x, _ = motion.position(np.linspace(0.0, motion.period, 20001))
    return float(x.max() - x.min()) / 2


# -- sine: Gamma = A (2 pi f)^2 / g, and back ---------------------------------------------

def test_gamma_of_an_amplitude_is_its_peak_acceleration_in_g():
    # 50 Hz, 0.1 mm: (100 pi)^2 x 1e-4 = pi^2 m/s^2 -> pi^2 / g
    assert deck.gamma_from_amp(1e-4, 50.0, g=9.81) == pytest.approx(math.pi ** 2 / 9.81, rel=1e-12)
    # twice the frequency, four times the acceleration (the square of omega)
    assert deck.gamma_from_amp(1e-4, 100.0, g=9.81) == pytest.approx(4 * math.pi ** 2 / 9.81, rel=1e-12)
    assert deck.gamma_from_amp(1e-4, 50.0, g=2 * 9.81) == pytest.approx(math.pi ** 2 / (2 * 9.81), rel=1e-12)


def test_amplitude_of_a_gamma_inverts_it():
    # Gamma = 1 at 50 Hz: A = g / (100 pi)^2 = 9.81 / (1e4 pi^2) m, about 0.1 mm
    assert deck.amp_from_gamma(1.0, 50.0, g=9.81) == pytest.approx(9.81e-4 / math.pi ** 2, rel=1e-12)
    # twice the gamma at twice the frequency: half the amplitude
    assert deck.amp_from_gamma(2.0, 100.0, g=9.81) == pytest.approx(9.81e-4 / (2 * math.pi ** 2), rel=1e-12)
    amp = deck.amp_from_gamma(1.7, 80.0)
    assert deck.gamma_from_amp(amp, 80.0) == pytest.approx(1.7, rel=1e-12)


def test_a_sine_deck_moves_the_plate_with_its_amplitudes_and_phase():
    w = deck.waveform({"freq": 50, "amp_t": 2e-5, "amp_n": 1e-5, "phase": 30, "waveform": 0})
    assert isinstance(w, SineWaveform)
    assert (w.freq, w.amp_t, w.amp_n, w.phase) == (50.0, 2e-5, 1e-5, 30.0)
    # peak accelerations A (2 pi f)^2 = A (100 pi)^2
    ax, az = w.max_abs_acceleration()
    assert ax == pytest.approx(2e-5 * 1e4 * math.pi ** 2, rel=1e-12)
    assert az == pytest.approx(1e-5 * 1e4 * math.pi ** 2, rel=1e-12)


def test_the_waveform_defaults_to_a_sine_without_the_amplitudes_not_given():
    w = deck.waveform({"freq": 50, "amp_n": 1e-5})
    assert isinstance(w, SineWaveform)
    assert (w.amp_t, w.amp_n, w.phase) == (0.0, 1e-5, 0.0)


# -- square wave: acceleration a has displacement amplitude a / (32 f^2) ------------------

def test_a_square_wave_deck_has_the_acceleration_of_its_amplitudes():
    # 50 Hz: 32 f^2 = 8e4 1/s^2; 1e-5 m -> 0.8 m/s^2, 2e-5 m -> 1.6 m/s^2
    w = deck.waveform({"freq": 50, "amp_t": 1e-5, "amp_n": 2e-5, "phase": 0, "waveform": 1})
    assert isinstance(w, SquareWaveAccel)
    assert w.acc_t == pytest.approx(0.8, rel=1e-12)
    assert w.acc_n == pytest.approx(1.6, rel=1e-12)
    # ... which swings the plate by the amplitude the deck asked for (a T^2 / 32)
    assert half_swing(w) == pytest.approx(1e-5, rel=1e-4)


def test_a_square_wave_scales_with_the_square_of_the_frequency():
    w = deck.waveform({"freq": 200, "amp_t": 1e-6, "amp_n": 1e-6, "waveform": 1})
    # 32 x 200^2 x 1e-6 = 1.28 m/s^2 on both axes
    assert (w.acc_t, w.acc_n) == (pytest.approx(1.28, rel=1e-12), pytest.approx(1.28, rel=1e-12))


# -- stick-slip: triangular velocity of peak vp has displacement amplitude vp / (8 f) -----

def test_a_stick_slip_deck_has_the_peak_speed_of_its_amplitude_and_the_default_duty():
    # 50 Hz, 1e-5 m: vp = 8 x 1e-5 x 50 = 4 mm/s; forward for duty 0.7 of T = 20 ms
    w = deck.waveform({"freq": 50, "amp_t": 1e-5, "waveform": 2})
    assert isinstance(w, StickSlipWaveform)
    assert w.peak_speed == pytest.approx(4e-3, rel=1e-12)
    assert w.durations[0] == pytest.approx(0.7 * 0.02, rel=1e-12)
    # velocity swings by 2 vp in 14 ms forward and in 6 ms back
    assert w.a_forward == pytest.approx(8e-3 / 0.014, rel=1e-12)
    assert w.a_backward == pytest.approx(8e-3 / 0.006, rel=1e-12)
    assert half_swing(w) == pytest.approx(1e-5, rel=1e-4)


def test_a_stick_slip_deck_takes_its_duty():
    w = deck.waveform({"freq": 100, "amp_t": 2e-6, "waveform": 2, "duty": 0.6})
    assert w.durations[0] == pytest.approx(0.6 * 0.01, rel=1e-12)
    assert w.peak_speed == pytest.approx(8 * 2e-6 * 100, rel=1e-12)


# -- Coulomb pump: forward at +vp for duty T, then -a and +a for t_B = (1 - duty) T / 2 each

def test_a_coulomb_pump_deck_has_the_forward_fraction_and_swing_it_asks_for():
    # 100 Hz, duty 0.6: T = 10 ms, t_B = 2 ms. The backward excursion (velocity < 0) is a
    # triangle of height v_back = a t_B (1 - t_B / T) and base 2 v_back / a: its area
    # v_back^2 / a is the peak-to-peak swing 2 A, so a = 2 A / (t_B^2 (1 - t_B / T)^2)
    # = 2e-5 / (4e-6 x 0.64) = 7.8125 m/s^2, vp = a t_B^2 / T = 3.125 mm/s.
    w = deck.waveform({"freq": 100, "amp_t": 1e-5, "waveform": 3, "duty": 0.6})
    assert isinstance(w, CoulombPumpWaveform)
    assert w.accel == pytest.approx(7.8125, rel=1e-12)
    assert w.peak_speed == pytest.approx(3.125e-3, rel=1e-12)
    assert w.back_speed == pytest.approx(7.8125 * 2e-3 - 3.125e-3, rel=1e-9)
    assert w.forward_fraction == pytest.approx(0.6, rel=1e-12)
    assert half_swing(w) == pytest.approx(1e-5, rel=1e-4)


def test_a_coulomb_pump_deck_takes_the_default_duty():
    # duty 0.7 at 50 Hz: t_B = 0.15 x 20 ms = 3 ms, 1 - t_B / T = 0.85
    w = deck.waveform({"freq": 50, "amp_t": 1e-5, "waveform": 3})
    assert w.forward_fraction == pytest.approx(0.7, rel=1e-12)
    assert w.accel == pytest.approx(2e-5 / (9e-6 * 0.85 ** 2), rel=1e-12)


@pytest.mark.parametrize("kind", [4, -1, 7])
def test_an_unknown_waveform_is_refused(kind):
    with pytest.raises(ValueError, match="waveform must be 0, 1, 2 or 3"):
        deck.waveform({"freq": 50, "amp_t": 1e-5, "amp_n": 1e-5, "waveform": kind})


# -- the part ------------------------------------------------------------------------------

def test_the_part_has_one_friction_and_a_restitution_below_one():
    p = deck.part({"mu": 0.4, "restitution": 0.5, "radius": 1e-3, "density": 1000}, weighed=False)
    assert (p.mu_s, p.mu_k, p.e, p.mass) == (0.4, 0.4, 0.5, 1.0)
    # a perfectly elastic part is modelled just below 1 (it would never settle)
    assert deck.part({"mu": 0.4, "restitution": 1.0}, weighed=False).e == 0.999


def test_a_weighed_part_has_the_mass_of_its_sphere():
    # 4/3 pi (1 mm)^3 x 3000 kg/m^3 = 4 pi 1e-6 kg
    p = deck.part({"mu": 0.4, "restitution": 0.5, "radius": 1e-3, "density": 3000})
    assert p.mass == pytest.approx(4 * math.pi * 1e-6, rel=1e-12)


def test_the_mass_of_a_single_part_sphere():
    # 4/3 pi r^3 rho: r = 0.5 mm, rho = 2400 -> 4/3 pi 1.25e-10 x 2400 = 4e-7 pi kg
    assert deck.mass({"radius": 5e-4, "density": 2400}) == pytest.approx(4e-7 * math.pi, rel=1e-12)
    # r^3 and rho: twice the radius is eight times the mass, twice the density twice
    assert deck.mass({"radius": 1e-3, "density": 2400}) == pytest.approx(32e-7 * math.pi, rel=1e-12)
    assert deck.mass({"radius": 5e-4, "density": 4800}) == pytest.approx(8e-7 * math.pi, rel=1e-12)


def test_the_mass_of_a_bulk_part_by_shape():
    base = {"density": 2000, "part_size": 1e-3, "part_thickness": 2e-4}
    # a sphere of diameter d: pi/6 d^3 rho (shape 0, also when no shape is given)
    sphere = math.pi / 6 * 1e-9 * 2000
    assert deck.mass(base) == pytest.approx(sphere, rel=1e-12)
    assert deck.mass({**base, "shape": 0}) == pytest.approx(sphere, rel=1e-12)
    assert deck.mass({**base, "shape": 1}) == pytest.approx(1e-6 * 2e-4 * 2000, rel=1e-12)
    assert deck.mass({**base, "shape": 2}) == pytest.approx(math.pi / 4 * 1e-6 * 2e-4 * 2000, rel=1e-12)
    # a box L x W x T, with a bump: plus the cap pi h^2 (3r - h)/3 above its face
    box = {**base, "shape": 3, "part_width": 5e-4}
    assert deck.mass(box) == pytest.approx(1e-3 * 5e-4 * 2e-4 * 2000, rel=1e-12)
    cap = math.pi * 5e-5 ** 2 * (3e-4 - 5e-5) / 3
    assert deck.mass({**box, "bump_height": 5e-5, "bump_diameter": 2e-4}) == pytest.approx(
        (1e-3 * 5e-4 * 2e-4 + cap) * 2000, rel=1e-12)
    with pytest.raises(ValueError, match="shape must be 0, 1, 2, 3 or 4"):
        deck.mass({**base, "shape": 5})
    with pytest.raises(ValueError, match="part_file is missing"):
        deck.mass({**base, "shape": 4})


def test_the_mass_of_an_stl_part_is_its_solids(tmp_path):
    # a 0.6 x 0.4 x 0.3 mm block written in mm: 0.072 mm^3 of solid
    import trimesh

    trimesh.creation.box(extents=(0.6, 0.4, 0.3)).export(tmp_path / "block.stl")
    p = {"density": 2000, "shape": 4, "part_file": str(tmp_path / "block.stl"), "part_unit": 1e-3}
    assert deck.mass(p) == pytest.approx(0.6e-3 * 0.4e-3 * 0.3e-3 * 2000, rel=1e-6)  # float32 STL


# -- adhesion and the air film ---------------------------------------------------------------

@pytest.mark.parametrize("shape, face", [
    (0, {"radius": 5e-4}),        # a sphere of diameter part_size
    (1, {"face_side": 1e-3}),     # a chip on its square face of side part_size
    (2, {"face_radius": 5e-4}),   # a disc on its round face of diameter part_size
])
def test_the_adhesion_of_a_bulk_part_by_shape(shape, face):
    a = deck.adhesion({"hamaker": 1e-19, "roughness": 1e-8, "part_size": 1e-3, "shape": shape})
    want = Adhesion(1e-19, 1e-8, **face)
    for name in ("hamaker", "roughness", "radius", "face_radius", "face_side"):
        assert getattr(a, name) == pytest.approx(getattr(want, name), rel=1e-12, abs=1e-15), name


def test_the_adhesion_of_a_bulk_part_without_a_shape_is_a_sphere_and_others_are_refused():
    a = deck.adhesion({"hamaker": 1e-19, "roughness": 0.0, "part_size": 1e-3})
    assert (a.radius, a.flat) == (pytest.approx(5e-4, rel=1e-12), False)
    with pytest.raises(ValueError, match="shape must be 0, 1 or 2"):
        deck.adhesion({"hamaker": 1e-19, "roughness": 0.0, "part_size": 1e-3, "shape": 3})


def test_the_adhesion_of_the_single_part_sphere_with_or_without_a_face():
    a = deck.adhesion({"hamaker": 1e-19, "roughness": 1e-8, "radius": 5e-4})
    assert (a.radius, a.face_radius, a.flat) == (5e-4, 0.0, False)
    a = deck.adhesion({"hamaker": 1e-19, "roughness": 1e-8, "radius": 5e-4, "face_radius": 1e-4})
    assert (a.radius, a.face_radius, a.flat) == (5e-4, 1e-4, True)


def test_the_film_is_under_the_sphere_without_a_face():
    # roughness 1 µm, above air's mean free path: it is the clearance
    f = deck.film({"air_viscosity": 1.81e-5, "radius": 5e-4, "roughness": 1e-6})
    assert f == Film(1.81e-5, 5e-4, 1e-6, flat=False, free_flow=True)


@pytest.mark.parametrize("face", [1e-4, 2e-3])
def test_the_film_is_under_the_flat_face_when_there_is_one(face):
    f = deck.film({"air_viscosity": 1.81e-5, "radius": 5e-4, "roughness": 1e-6, "face_radius": face})
    assert f == Film(1.81e-5, face, 1e-6, flat=True, free_flow=True)
