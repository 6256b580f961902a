"""Clusters of touching parts: known configurations, edge cases of touching, laws for all inputs."""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from vibrofeed.errors import InputError
from vibrofeed.postproc.clusters import (
    clump_labels,
    cluster_labels,
    cluster_sizes,
    pairs_touch,
    quaternion_matrices,
)


def brute_labels(positions, radii, tolerance):
    """The partition by the definition, all pairs and a flood fill (small N only)."""
    n = len(positions)
    d = np.linalg.norm(positions[:, None] - positions[None], axis=-1)
    adjacent = d <= radii[:, None] + radii[None] + tolerance
    labels = np.full(n, -1)
    for seed in range(n):
        if labels[seed] >= 0:
            continue
        labels[seed] = seed
        stack = [seed]
        while stack:
            i = stack.pop()
            for j in np.nonzero(adjacent[i] & (labels < 0))[0]:
                labels[j] = seed
                stack.append(j)
    return labels


def partition(labels):
    """The partition as a set of frozensets of indices (label names do not matter)."""
    groups = {}
    for i, label in enumerate(labels):
        groups.setdefault(int(label), set()).add(i)
    return {frozenset(g) for g in groups.values()}


def chains(sizes, radius=0.5, rng=None, spacing=100.0):
    """Chains of touching spheres (each along a random direction), far apart."""
    rng = rng or np.random.default_rng(0)
    pos, rad, truth = [], [], []
    for k, size in enumerate(sizes):
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        start = np.array([k * spacing, 0.0, 0.0])
        for j in range(size):
            pos.append(start + j * 2 * radius * direction)
            rad.append(radius)
            truth.append(k)
    return np.array(pos), np.array(rad), np.array(truth)


def test_chains_of_known_sizes_are_found():
    sizes = [1, 2, 3, 5, 8, 1, 13, 2]
    pos, rad, truth = chains(sizes)
    # the chains' links touch to round-off: a tolerance of 1e-9 of a radius joins them
    labels = cluster_labels(pos, rad, tolerance=1e-9)
    assert partition(labels) == partition(truth)
    assert cluster_sizes(labels) == {1: 2, 2: 2, 3: 1, 5: 1, 8: 1, 13: 1}
    # labels numbered in the order of each cluster's first part
    assert labels[0] == 0 and labels.max() == len(sizes) - 1
    assert np.all(np.diff([labels[truth == k][0] for k in range(len(sizes))]) == 1)


def test_touching_is_inclusive_and_the_tolerance_is_added():
    # exactly representable: centres 1.0 apart, radii 0.25 + 0.75
    pos = np.array([[0.0, 0, 0], [1.0, 0, 0], [3.0, 0, 0]])
    rad = np.array([0.25, 0.75, 0.5])
    assert cluster_labels(pos, rad).tolist() == [0, 0, 1]          # d == r_i + r_j: touching
    pos[1, 0] = np.nextafter(1.0, 2.0)                              # a hair apart
    assert cluster_labels(pos, rad).tolist() == [0, 1, 2]
    assert cluster_labels(pos, rad, tolerance=1e-12).tolist() == [0, 0, 1]
    pos[1, 0] = 1.0
    # gap between parts 1 and 2: 2.0 - 0.75 - 0.5 = 0.75
    assert cluster_labels(pos, rad, tolerance=0.75).tolist() == [0, 0, 0]
    assert cluster_labels(pos, rad, tolerance=0.7499).tolist() == [0, 0, 1]
    # a negative tolerance asks for an overlap
    assert cluster_labels(pos, rad, tolerance=-0.01).tolist() == [0, 1, 2]


def test_polydisperse_parts_use_their_own_radii():
    # a big part touches a small one whose distance exceeds twice the small radius
    pos = np.array([[0.0, 0, 0], [1.2, 0, 0], [1.9, 0, 0]])
    rad = np.array([1.0, 0.2, 0.2])
    assert cluster_labels(pos, rad).tolist() == [0, 0, 1]   # 1.2 = 1.0 + 0.2; 0.7 > 0.4


def test_matches_all_pairs_on_random_packings():
    rng = np.random.default_rng(7)
    for n, box in ((1, 1.0), (2, 1.0), (300, 12.0), (1500, 30.0)):
        pos = rng.uniform(0, box, (n, 3))
        rad = rng.uniform(0.3, 0.7, n)
        for tol in (0.0, 0.05):
            labels = cluster_labels(pos, rad, tolerance=tol)
            assert partition(labels) == partition(brute_labels(pos, rad, tol))
    assert cluster_labels(np.empty((0, 3)), np.empty(0)).shape == (0,)
    assert cluster_sizes([]) == {}


def test_ten_thousand_parts_do_not_need_all_pairs():
    # dense enough to form large clusters; the k-d tree keeps it fast (O(N log N))
    rng = np.random.default_rng(1)
    pos = rng.uniform(0, 0.02, (20000, 3)) * [1, 0.1, 0.02]
    rad = np.full(20000, 1.5e-4)
    labels = cluster_labels(pos, rad, tolerance=3e-6)
    sizes = cluster_sizes(labels)
    assert sum(s * c for s, c in sizes.items()) == 20000
    # a random subset's clusters agree with the definition on that subset
    sub = rng.choice(20000, 1000, replace=False)
    assert partition(cluster_labels(pos[sub], rad[sub], 3e-6)) == \
        partition(brute_labels(pos[sub], rad[sub], 3e-6))


def test_bad_inputs_are_refused():
    with pytest.raises(InputError, match=r"\(N, 3\)"):
        cluster_labels(np.zeros((3, 2)), np.ones(3))
    with pytest.raises(InputError, match="radii"):
        cluster_labels(np.zeros((3, 3)), np.ones(2))
    with pytest.raises(InputError, match="finite"):
        cluster_labels(np.array([[0, 0, np.nan]]), np.ones(1))


# -- multisphere parts ------------------------------------------------------------------
R_S = 75e-6
CHIP = np.array([[x, y, 0.0, R_S] for x in (-1e-4, 0, 1e-4) for y in (-1e-4, 0, 1e-4)])


def quat_z(angle):
    return np.array([np.cos(angle / 2), 0.0, 0.0, np.sin(angle / 2)])


def test_quaternions_rotate_as_w_x_y_z():
    rot = quaternion_matrices([quat_z(np.pi / 2), [np.cos(np.pi / 4), np.sin(np.pi / 4), 0, 0]])
    assert rot[0] @ [1, 0, 0] == pytest.approx([0, 1, 0], abs=1e-15)      # about z
    assert rot[1] @ [0, 0, 1] == pytest.approx([0, -1, 0], abs=1e-15)     # about x
    assert np.allclose(rot @ rot.transpose(0, 2, 1), np.eye(3), rtol=0, atol=1e-15)


def test_chips_touch_by_their_spheres_not_their_circumscribed_spheres():
    # chip edge 2e-4 + 2 * 75e-6 = 3.5e-4; circumscribed radius ~2.2e-4
    circumscribed = np.sqrt(2) * 1e-4 + R_S
    ident = np.array([1.0, 0, 0, 0])
    gap = 2e-5
    centres = np.array([[0.0, 0, 0], [3.5e-4 + gap, 0, 0], [7e-4 + gap, 0, 0]])
    q = np.array([ident, ident, ident])
    # chips 1 and 2 are edge to edge (spheres 2 R_S apart), chip 0 is 20 um away
    assert clump_labels(centres, q, CHIP, tolerance=1e-12).tolist() == [0, 1, 1]
    assert clump_labels(centres, q, CHIP, tolerance=gap * 1.01).tolist() == [0, 0, 0]
    # the circumscribed spheres would join all three
    assert cluster_labels(centres, np.full(3, circumscribed)).tolist() == [0, 0, 0]
    # a quarter turn about z maps the square chip onto itself: same contacts
    q_turned = np.array([quat_z(np.pi / 2), ident, quat_z(-np.pi / 2)])
    assert clump_labels(centres, q_turned, CHIP, tolerance=1e-12).tolist() == [0, 1, 1]


def test_clump_labels_match_sphere_level_brute_force():
    rng = np.random.default_rng(3)
    n = 40
    centres = rng.uniform(0, 1.5e-3, (n, 3)) * [1, 1, 0.3]
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    labels = clump_labels(centres, q, CHIP, tolerance=1e-6)
    rot = quaternion_matrices(q)
    spheres = (centres[:, None, :] + np.einsum("nij,kj->nki", rot, CHIP[:, :3])).reshape(-1, 3)
    sphere_labels = brute_labels(spheres, np.full(len(spheres), R_S), 1e-6)
    body_partition = partition(sphere_labels.reshape(n, 9)[:, 0])
    assert partition(labels) == body_partition
    assert len(body_partition) < n  # the test has contacts to find
    # a template given off its centre describes the same body (centres are sphere means)
    shifted = CHIP + [3e-4, -1e-4, 2e-4, 0.0]
    assert np.array_equal(clump_labels(centres, q, shifted, tolerance=1e-6), labels)


def test_pairs_touch_agrees_with_the_labels_of_each_pair():
    rng = np.random.default_rng(8)
    k = 300
    a = rng.uniform(0, 6e-4, (k, 3))
    b = a + rng.normal(size=(k, 3)) * 2e-4
    qa, qb = rng.normal(size=(k, 4)), rng.normal(size=(k, 4))
    got = pairs_touch(a, b, orientations_a=qa, orientations_b=qb, template=CHIP, tolerance=1e-6)
    want = [clump_labels(np.stack([a[i], b[i]]), np.stack([qa[i], qb[i]]), CHIP, 1e-6)[1] == 0
            for i in range(k)]
    assert got.tolist() == want and 0 < got.sum() < k
    ra, rb = rng.uniform(1e-4, 2e-4, k), rng.uniform(1e-4, 2e-4, k)
    spheres = pairs_touch(a, b, ra, rb, tolerance=1e-6)
    assert spheres.tolist() == [cluster_labels(np.stack([a[i], b[i]]), np.array([ra[i], rb[i]]),
                                               1e-6)[1] == 0 for i in range(k)]


# -- laws for all inputs ------------------------------------------------------------------
coords = st.lists(st.tuples(st.integers(0, 40), st.integers(0, 40), st.integers(0, 8)),
                  min_size=1, max_size=60)


def _config(points, radii_seed):
    pos = np.array(points, dtype=float) * 0.5
    rad = np.random.default_rng(radii_seed).uniform(0.2, 0.6, len(pos))
    return pos, rad


def _margin(pos, rad, tol):
    """Smallest distance of any pair from the touching threshold."""
    if len(pos) < 2:
        return np.inf
    d = np.linalg.norm(pos[:, None] - pos[None], axis=-1)
    m = np.abs(d - rad[:, None] - rad[None] - tol)
    return m[np.triu_indices(len(pos), 1)].min()


@settings(max_examples=60, deadline=None)
@given(coords, st.integers(0, 1000), st.integers(0, 1000),
       st.tuples(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3), st.floats(-1e3, 1e3)))
def test_clusters_do_not_depend_on_order_or_place(points, radii_seed, perm_seed, shift):
    pos, rad = _config(points, radii_seed)
    tol = 0.01
    assume(_margin(pos, rad, tol) > 1e-9)  # no pair on the threshold: rounding may not decide
    labels = cluster_labels(pos, rad, tol)
    perm = np.random.default_rng(perm_seed).permutation(len(pos))
    moved = cluster_labels(pos[perm] + np.array(shift), rad[perm], tol)
    assert partition(labels[perm]) == partition(moved)
    # equal configurations give equal labels (canonical numbering)
    assert np.array_equal(cluster_labels(pos, rad, tol), labels)


@settings(max_examples=60, deadline=None)
@given(coords, st.integers(0, 1000), st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_a_larger_tolerance_only_merges_clusters(points, radii_seed, tol_a, tol_b):
    pos, rad = _config(points, radii_seed)
    small, large = sorted((tol_a, tol_b))
    fine = cluster_labels(pos, rad, small)
    coarse = cluster_labels(pos, rad, large)
    # every fine cluster lies inside one coarse cluster
    for group in partition(fine):
        assert len({int(coarse[i]) for i in group}) == 1
    assert sum(s * c for s, c in cluster_sizes(coarse).items()) == len(pos)


def test_pairs_touch_of_many_clump_pairs_at_once():
    # more pairs than one block (2048): every pair the same two chips, side by side 2 r apart
    # (outer spheres 2e-4 + 2 r apart, less 1 nm: touching) or 1 um farther (not)
    k = 5000
    a = np.column_stack([np.arange(k) * 1e-2, np.zeros(k), np.zeros(k)])
    gap = np.where(np.arange(k) % 3 == 0, 1e-6, -1e-9)   # 1 nm overlap: touching beyond rounding
    b = a + np.column_stack([2e-4 + 2 * R_S + gap, np.zeros(k), np.zeros(k)])
    q = np.tile([1.0, 0, 0, 0], (k, 1))
    got = pairs_touch(a, b, orientations_a=q, orientations_b=q, template=CHIP)
    assert got.tolist() == (gap < 0).tolist()


def test_cluster_sizes_skip_unused_labels_and_negative_tolerances_join_nothing():
    assert cluster_sizes([0, 2, 2, 5]) == {1: 2, 2: 1}           # labels 1, 3, 4 unused
    assert cluster_sizes([]) == {}
    pos = np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]])
    assert cluster_labels(pos, np.full(3, 0.5), tolerance=-1.5).tolist() == [0, 1, 2]
    assert cluster_labels(pos, np.full(3, 0.5)).tolist() == [0, 0, 0]


def test_pairs_touch_is_inclusive_and_adds_the_tolerance():
    # exact binary values: touching means a centre distance of exactly r_a + r_b (+ tolerance)
    a = np.zeros((3, 3))
    b = np.array([[1.0, 0, 0], [1.25, 0, 0], [1.5, 0, 0]])
    assert pairs_touch(a, b, np.full(3, 0.5), np.full(3, 0.5)).tolist() == [True, False, False]
    assert pairs_touch(a, b, np.full(3, 0.5), np.full(3, 0.5), tolerance=0.25).tolist() == [True, True, False]
    # two-sphere rods along x (spheres at +-0.5, r = 0.25): end to end, their outer spheres
    # exactly touch 1.5 apart; 0.25 farther they touch only by a tolerance of 0.25
    rod = np.array([[-0.5, 0, 0, 0.25], [0.5, 0, 0, 0.25]])
    q = np.tile([1.0, 0, 0, 0], (3, 1))
    ends = np.array([[1.5, 0, 0], [1.75, 0, 0], [2.0, 0, 0]])
    assert pairs_touch(a, ends, orientations_a=q, orientations_b=q, template=rod).tolist() == \
        [True, False, False]
    assert pairs_touch(a, ends, orientations_a=q, orientations_b=q, template=rod,
                       tolerance=0.25).tolist() == [True, True, False]


def test_one_clump_is_one_cluster():
    assert clump_labels(np.zeros((1, 3)), [[1.0, 0, 0, 0]], CHIP).tolist() == [0]
    assert clump_labels(np.zeros((0, 3)), np.zeros((0, 4)), CHIP).tolist() == []
