"""Poses of a box on a plate (vibrofeed.poses) and the rocking checks' helpers."""

import math

import numpy as np
import pytest

from vibrofeed.errors import ParameterError
from vibrofeed.models import rocking as K
from vibrofeed.poses import matrix_quaternion, pose_axes, pose_dims, pose_matrix, tilt_angle
from vibrofeed.validation.rocking_checks import impacts, regime_of, side_fit

BOX = {"part_size": "1e-3", "part_width": "5e-4", "part_thickness": "3.5e-4"}


@pytest.mark.parametrize("stand, facing, along, vertical", [
    (0, 0, 0, 2), (0, 1, 1, 2), (1, 0, 0, 1), (1, 1, 2, 1), (2, 0, 1, 0), (2, 1, 2, 0)])
def test_pose_axes_and_a_proper_rotation(stand, facing, along, vertical):
    assert pose_axes(stand, facing) == (along, vertical)
    P = pose_matrix(stand, facing)
    assert np.allclose(P @ P.T, np.eye(3), rtol=0, atol=1e-12)
    assert np.linalg.det(P) == pytest.approx(1.0, rel=0, abs=1e-12)
    assert np.allclose(P[:, along], [1, 0, 0], rtol=0, atol=1e-12)
    assert np.allclose(P[:, vertical], [0, 0, 1], rtol=0, atol=1e-12)


def test_bad_pose_is_refused():
    with pytest.raises(ParameterError):
        pose_axes(3, 0)


def test_pose_dims_give_the_clumps_pivot():
    # on its side, thickness along the track: b/h = (T - d)/W = (0.35 - 0.175)/0.5 = 0.35
    along, vertical, d = pose_dims({**BOX, "stand": "1", "facing": "1"})
    assert (along, vertical, d) == pytest.approx((3.5e-4, 5e-4, 1.75e-4), rel=1e-12)
    b, h = K.clump_pivot(along, vertical, d)
    assert b / h == pytest.approx(0.35, rel=1e-12)


def test_tilt_of_a_recorded_quaternion():
    q = np.array([matrix_quaternion(pose_matrix(2, 0, 10.0)), matrix_quaternion(pose_matrix(2, 0, -4.0))])
    signed, total = tilt_angle(q, 2, 0)
    assert np.degrees(signed) == pytest.approx([10.0, -4.0], rel=0, abs=1e-9)  # deg
    assert np.degrees(total) == pytest.approx([10.0, 4.0], rel=0, abs=1e-9)  # deg


def test_impacts_and_side_fits():
    t = np.linspace(0, 1, 101)
    theta = 0.305 - t  # crosses 0 at 0.305, between frames
    assert impacts(t, theta) == pytest.approx([0.305], rel=0, abs=1e-12)  # s: a linear crossing, exact
    w = np.where(t < 0.3, -2.0 - t, -1.0 + 0.5 * (t - 0.3))
    assert side_fit(t, w, 0.3, -0.2, -0.01) == pytest.approx(-2.3, rel=1e-9)
    assert side_fit(t, w, 0.3, 0.01, 0.2) == pytest.approx(-1.0, rel=1e-9)


def test_regime_of_a_motion():
    flat = np.zeros(5)
    assert regime_of({"total": flat, "x": flat}, math.radians(5), 1e-4) == K.REST
    assert regime_of({"total": flat, "x": np.linspace(0, 1e-3, 5)}, math.radians(5), 1e-4) == K.SLIDE
    assert regime_of({"total": np.radians([0, 10, 90, 90, 90]), "x": np.linspace(0, 1e-3, 5)},
                     math.radians(5), 1e-4) == K.TIP
