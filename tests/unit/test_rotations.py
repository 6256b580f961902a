"""Quaternions as results store them (vibrofeed.rotations): a matrix's quaternion turns back
into the matrix, and the product turns by its right factor first; each against rotations
built by hand."""

import math

import numpy as np
import pytest

from vibrofeed.rotations import matrix_quaternion, quaternion_matrices, quaternion_product


def about(axis: int, degrees: float) -> np.ndarray:
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j = [k for k in range(3) if k != axis]
    m = np.eye(3)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


@pytest.mark.parametrize("axis, degrees", [(0, 0.0), (0, 30.0), (1, -75.0), (2, 120.0), (1, 179.0)])
def test_a_matrix_s_quaternion_turns_back_into_it_with_w_not_negative(axis, degrees):
    m = about(axis, degrees)
    q = matrix_quaternion(m)
    assert q[0] >= 0 and np.linalg.norm(q) == pytest.approx(1.0, rel=0, abs=1e-12)
    # half the angle in w, the axis in the vector part (exact closed form)
    assert q[0] == pytest.approx(math.cos(math.radians(degrees) / 2), rel=0, abs=1e-12)
    assert quaternion_matrices(q) == pytest.approx(m, rel=0, abs=1e-12)


def test_the_product_turns_by_its_right_factor_first():
    a, b = about(2, 90.0), about(0, 90.0)
    qa, qb = matrix_quaternion(a), matrix_quaternion(b)
    both = quaternion_product(qa[None, :], qb)
    assert quaternion_matrices(both[0]) == pytest.approx(a @ b, rel=0, abs=1e-12)
    assert np.abs(a @ b - b @ a).max() > 0.5  # (the order is seen: these two differ by order one)
