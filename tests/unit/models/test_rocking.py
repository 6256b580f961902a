"""Rocking and tipping closed forms (vibrofeed.models.rocking) against hand-computed values."""

import math

import numpy as np
import pytest

from vibrofeed.models import rocking as K


def test_a_clumps_pivot_is_below_its_outermost_sphere_centre():
    # a 1 mm face, 2 mm tall, spheres of 0.4 mm: centres span 0.6 mm, COM 1 mm up
    b, h = K.clump_pivot(1e-3, 2e-3, 0.4e-3)
    assert (b, h) == pytest.approx((3e-4, 1e-3), abs=1e-12)
    with pytest.raises(ValueError):
        K.clump_pivot(1e-3, 2e-3, 1.5e-3)  # wider than the face


def test_onset_acceleration_flat_and_inclined():
    assert K.onset_acceleration(0.3, 1.0) == pytest.approx(9.81 * 0.3, abs=1e-12)
    # b/h = 0.5 uphill 10 deg: 9.81 (0.5 cos 10 - sin 10) = 3.12699 m/s^2
    assert K.onset_acceleration(0.5, 1.0, incline=10) == pytest.approx(3.12699, abs=1e-5)
    # the plate dropping by a_n lowers the threshold: (9.81 - 2) 0.3
    assert K.onset_acceleration(0.3, 1.0, a_n=-2.0) == pytest.approx(7.81 * 0.3, abs=1e-12)
    assert K.slides_first(0.2, 0.3, 1.0) and not K.slides_first(0.5, 0.3, 1.0)


def test_sine_threshold_amplitude():
    # b/h = 0.2 at 20 Hz: 9.81 * 0.2 / (40 pi)^2 = 1.24245e-4 m
    amp = K.sine_threshold_amplitude(0.2, 1.0, 20.0)
    assert amp == pytest.approx(1.24245e-4, abs=1e-9)
    assert K.sine_rocking_margin(0.2, 1.0, 20.0, amp) == pytest.approx(0.0, abs=1e-12)
    assert K.sine_rocking_margin(0.2, 1.0, 20.0, 0.85 * amp) == pytest.approx(-0.15 * 1.962, abs=1e-9)
    assert K.sine_threshold_amplitude(0.1, 1.0, 20.0, incline=10) == 0.0  # tan 10 > 0.1: tips alone


@pytest.mark.parametrize("amp_n, phase, incline", [(0, 0, 0), (5e-5, 0, 0), (5e-5, 30, 5),
                                                   (8e-5, 120, -7), (3e-5, 180, 3)])
def test_sine_margin_is_the_sampled_maximum(amp_n, phase, incline):
    b, h, freq, amp_t = 0.3e-3, 1e-3, 25.0, 2e-4
    w = 2 * math.pi * freq
    t = np.linspace(0, 1 / freq, 200001)
    a_t = -amp_t * w**2 * np.sin(w * t)
    a_n = -amp_n * w**2 * np.sin(w * t + math.radians(phase))
    sampled = K.rocking_margin(b, h, a_t, a_n, incline)
    assert K.sine_rocking_margin(b, h, freq, amp_t, amp_n, phase, incline) == pytest.approx(sampled, abs=1e-6)


def test_impact_ratio_general_and_block_forms_agree():
    # b = 1, h = 2: sin^2 alpha = 1/5, r = 1 - 3/10 = 0.7; I_O = 4/3 m R^2 = 20/3, cos 2 alpha = 3/5
    assert K.block_impact_ratio(1.0, 2.0) == pytest.approx(0.7, abs=1e-12)
    assert K.impact_ratio(1.0, math.sqrt(5), 20 / 3, math.atan(0.5)) == pytest.approx(0.7, abs=1e-12)
    assert K.clump_impact_ratio(1.0, 2.0, 5 / 3) == pytest.approx(0.7, abs=1e-12)


def test_clump_impact_ratio_with_its_box_inertia():
    # face 1 x height 2 (I_G/m = 5/12), spheres 0.4: b = 0.3, h = 1; r = 1 - 2 b^2 / (5/12 + 1.09)
    assert K.clump_impact_ratio(0.3, 1.0, 5 / 12) == pytest.approx(0.880531, abs=1e-6)


def test_impact_speed_from_energy():
    # b = 1, h = 2, solid block, released at 0.1 rad: 0.514203 rad/s (g = 9.81)
    assert K.impact_speed(0.1, 1.0, 2.0, 5 / 3) == pytest.approx(0.514203, abs=1e-6)
    with pytest.raises(ValueError):
        K.impact_speed(0.6, 1.0, 2.0, 5 / 3)  # beyond alpha = 0.4636: it topples
    # a pivot sphere of radius 0.5 rolling: the COM falls 1.5 cos 0.1 + sin 0.1 + 0.5 - 2 = 0.092339
    assert K.impact_speed(0.1, 1.0, 2.0, 5 / 3, rolling_radius=0.5) == pytest.approx(0.521302, abs=1e-6)


@pytest.mark.parametrize("incline, mu, regime", [
    (15, 0.3, K.REST),   # tan 15 = 0.268 < 0.3 < 0.5
    (20, 0.3, K.SLIDE),  # tan 20 = 0.364 > mu = 0.3 < b/h
    (25, 0.8, K.REST),   # tan 25 = 0.466 < b/h = 0.5 < mu
    (30, 0.8, K.TIP),    # tan 30 = 0.577 > b/h, mu > b/h
    (30, 0.55, K.TIP),   # beyond both, mu > b/h: it tips
    (-30, 0.8, K.TIP),   # downhill alike
])
def test_incline_regime(incline, mu, regime):
    assert K.incline_regime(incline, mu, 0.5, 1.0) == regime


def test_regime_map_shape_and_values():
    m = K.regime_map([10, 40], [0.2, 0.9], 0.5, 1.0)
    assert m.shape == (2, 2)
    assert m.tolist() == [[K.REST, K.REST], [K.SLIDE, K.TIP]]
