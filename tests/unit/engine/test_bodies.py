"""Parts as bodies (vibrofeed.engine.bodies): known answers from rotated, moved templates."""

import numpy as np
import pytest

from vibrofeed.engine.bodies import aggregate, fit_quaternions, quaternion_matrix, spheres
from vibrofeed.rotations import quaternion_matrices

# a chip: 3 x 3 spheres in a plane (planar: the hardest case for a fit), and a 3-D clump
CHIP = np.array([[x, y, 0.0] for x in (-7.5e-5, 0, 7.5e-5) for y in (-7.5e-5, 0, 7.5e-5)])
CLUMP = np.array([[0, 0, 0], [1e-4, 0, 0], [0, 2e-4, 0], [0, 0, 3e-4], [1e-4, 1e-4, 1e-4]])


def random_quaternions(n, seed=0):
    q = np.random.default_rng(seed).standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 0] < 0] *= -1
    return q


def test_quaternion_matrix_is_a_rotation():
    r = quaternion_matrix(random_quaternions(50))
    assert np.allclose(r @ np.swapaxes(r, 1, 2), np.eye(3), rtol=0, atol=1e-14)
    assert np.allclose(np.linalg.det(r), 1.0, rtol=0, atol=1e-14)
    # 90 degrees about z carries x to y
    q = np.array([np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)])
    assert np.allclose(quaternion_matrix(q) @ [1, 0, 0], [0, 1, 0], rtol=0, atol=1e-15)


def test_quaternions_are_normalised_and_an_empty_one_is_the_identity():
    # 90 degrees about z, given 3 times too long: normalised first, it still carries x to y
    c = np.cos(np.pi / 4)
    r = quaternion_matrices([3 * c, 0, 0, 3 * c])
    assert np.allclose(r, [[0, -1, 0], [1, 0, 0], [0, 0, 1]], rtol=0, atol=1e-15)
    # NaN (an empty slot), zero (no orientation), infinite: the identity, and no
    # floating-point warning on the way (an empty slot is in every frame)
    with np.errstate(all="raise"):
        r = quaternion_matrices([[np.nan] * 4, [0.0] * 4, [np.nan, 0, 0, 0], [np.inf, 0, 0, 0], [c, c, 0, 0]])
    assert r.shape == (5, 3, 3)
    assert np.array_equal(r[:4], np.broadcast_to(np.eye(3), (4, 3, 3)))
    assert np.allclose(r[4], [[1, 0, 0], [0, 0, -1], [0, 1, 0]], rtol=0, atol=1e-15)  # about x


@pytest.mark.parametrize("template", [CHIP, CLUMP], ids=["planar chip", "3-D clump"])
def test_fit_recovers_the_rotation_exactly(template):
    q = random_quaternions(400, seed=1)
    q[0] = [1, 0, 0, 0]                       # identity
    q[1] = [0, 1, 0, 0]                       # half turn (w = 0)
    q[2] = [np.cos(1e-9), 0, np.sin(1e-9), 0]  # a tiny rotation
    centres = np.random.default_rng(2).uniform(-0.02, 0.02, (len(q), 3))
    t0 = template - template.mean(axis=0)
    positions = centres[:, None, :] + np.einsum("bij,nj->bni", quaternion_matrix(q), t0)
    fitted = fit_quaternions(template, positions)
    # the same rotation (q and -q are one rotation; the fit returns w >= 0)
    same = np.minimum(np.abs(fitted - q).max(axis=1), np.abs(fitted + q).max(axis=1))
    assert same.max() < 1e-12
    assert np.all(fitted[:, 0] >= 0)
    assert np.allclose(np.linalg.norm(fitted, axis=1), 1, rtol=0, atol=1e-15)


def clump_atoms(template, q, centres, v_c, omega, first_id=1, rmass=1e-9, shuffle=0):
    """The atoms LIGGGHTS would hold for rigid clumps (molecule = body id)."""
    n, b = len(template), len(q)
    t0 = template - template.mean(axis=0)
    arm = np.einsum("bij,nj->bni", quaternion_matrix(q), t0)
    x = centres[:, None, :] + arm
    v = v_c[:, None, :] + np.cross(omega[:, None, :], arm)
    atoms = {
        "id": (first_id + np.arange(b * n)).astype(np.int32),
        "molecule": np.repeat(100 + np.arange(b), n).astype(np.int32),
        "type": np.ones(b * n, np.int32), "radius": np.full(b * n, 7.5e-5),
        "rmass": np.full(b * n, rmass), "x": x.reshape(-1, 3), "v": v.reshape(-1, 3),
        "omega": np.repeat(omega, n, axis=0),
        "f": np.tile(np.arange(n, dtype=float)[:, None] * [1, 2, 3], (b, 1)),
    }
    if shuffle:  # ranks hand atoms over in any order
        order = np.random.default_rng(shuffle).permutation(b * n)
        atoms = {k: a[order] for k, a in atoms.items()}
    return atoms


def test_aggregate_bodies():
    b = 30
    q = random_quaternions(b, seed=3)
    rng = np.random.default_rng(4)
    centres, v_c = rng.normal(size=(b, 3)) * 1e-2, rng.normal(size=(b, 3))
    omega = rng.normal(size=(b, 3)) * 50
    atoms = clump_atoms(CHIP, q, centres, v_c, omega, shuffle=5)
    parts, incomplete = aggregate(atoms, np.column_stack([CHIP, np.full(9, 7.5e-5)]), 9)
    assert incomplete == 0
    assert parts["id"].tolist() == list(range(100, 100 + b))
    assert np.allclose(parts["position"], centres, atol=1e-17, rtol=0)
    assert np.allclose(parts["velocity"], v_c, atol=1e-13, rtol=0)   # mean of v_c + w x r
    assert np.allclose(parts["angular_velocity"], omega, rtol=0, atol=0)
    # LIGGGHTS: each sphere carries the body's mass (atol 1e-12 of it: numpy's default atol=1e-8 kg
    # would pass the nine spheres' sum, 9e-9 kg)
    assert np.allclose(parts["mass"], 1e-9, rtol=0, atol=1e-21)
    # not reachable for clumps (see bodies.aggregate): a NaN 3-vector a part, as for spheres
    assert parts["force"].shape == (b, 3) and np.isnan(parts["force"]).all()
    # enclosing radius: corner sphere at sqrt(2) * 75 um plus its radius
    assert np.allclose(parts["radius"], 7.5e-5 * (1 + np.sqrt(2)), rtol=1e-12, atol=0)
    same = np.minimum(np.abs(parts["orientation"] - q).max(1), np.abs(parts["orientation"] + q).max(1))
    assert same.max() < 1e-12


def test_an_incomplete_body_keeps_sums_and_gets_the_identity():
    q = random_quaternions(3, seed=6)
    atoms = clump_atoms(CLUMP, q, np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)))
    keep = np.ones(15, bool)
    keep[5] = False  # body 101 loses its first sphere
    atoms = {k: a[keep] for k, a in atoms.items()}
    parts, incomplete = aggregate(atoms, CLUMP, 5)
    assert incomplete == 1
    assert parts["orientation"][1].tolist() == [1, 0, 0, 0]
    assert np.abs(parts["orientation"][[0, 2]] - q[[0, 2]]).max() < 1e-12


def test_plain_spheres_are_their_own_bodies():
    atoms = {"id": np.array([3, 1]), "type": np.array([1, 1]), "radius": np.array([1e-4, 2e-4]),
             "rmass": np.array([1.0, 2.0]), "x": np.ones((2, 3)), "v": np.zeros((2, 3)),
             "omega": np.zeros((2, 3)), "f": np.zeros((2, 3))}
    parts = spheres(atoms)
    assert parts["id"].tolist() == [3, 1] and parts["radius"].tolist() == [1e-4, 2e-4]
    assert parts["orientation"].tolist() == [[1, 0, 0, 0]] * 2


def test_aggregate_is_vectorised():
    """10 000 chips (90 000 spheres) in well under the engine's time for one frame."""
    import time

    b = 10_000
    atoms = clump_atoms(CHIP, random_quaternions(b, 7), np.zeros((b, 3)), np.zeros((b, 3)),
                        np.zeros((b, 3)), shuffle=8)
    t0 = time.perf_counter()
    aggregate(atoms, CHIP, 9)
    assert time.perf_counter() - t0 < 1.0


def test_prepared_geometry_from_the_spec(tmp_path):
    """The runner hands the prepare hook's mesh and template inline or as files."""
    from vibrofeed.engine.worker import prepared_geometry

    vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    template = np.column_stack([CHIP, np.full(9, 7.5e-5)])
    track, tpl = prepared_geometry({"prepared": {"track": [vertices, [[0, 1, 2]]],
                                                 "body_template": template.tolist()}})
    assert track[0].shape == (3, 3) and track[1].dtype == np.int32 and np.array_equal(tpl, template)
    np.savez(tmp_path / "track.npz", vertices=np.array(vertices, float), triangles=[[0, 1, 2]])
    np.savetxt(tmp_path / "chip.multisphere", template, header="chip: x y z r [m]")
    track, tpl = prepared_geometry({"prepared": {"track": str(tmp_path / "track.npz"),
                                                 "body_template": str(tmp_path / "chip.multisphere")}})
    assert track[1].tolist() == [[0, 1, 2]]
    assert np.allclose(tpl, template, rtol=0, atol=1e-18)  # m: savetxt's %.18e keeps every digit
    assert prepared_geometry({}) == (None, None)
    assert prepared_geometry({"prepared": {"track": None, "body_template": None}}) == (None, None)


def test_the_fragments_of_a_body_being_deleted_are_no_part():
    # fix multisphere removes a body that lost a sphere: the others get body -1 until
    # they are deleted; a frame in between must neither count them as a part nor
    # call a whole body incomplete
    q = random_quaternions(3, seed=8)
    atoms = clump_atoms(CLUMP, q, np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)))
    keep = np.ones(15, bool)
    keep[10] = False  # body 102 lost its first sphere ...
    atoms["molecule"] = np.where(atoms["molecule"] == 102, -1, atoms["molecule"])  # ... and is removed
    atoms = {k: a[keep] for k, a in atoms.items()}
    parts, incomplete = aggregate(atoms, CLUMP, 5)
    assert parts["id"].tolist() == [100, 101] and incomplete == 0
    assert np.abs(parts["orientation"] - q[:2]).max() < 1e-12


def test_a_frame_of_only_fragments_has_no_parts_with_the_shapes_of_parts():
    # the last body being deleted: every atom left is a fragment (body -1)
    q = random_quaternions(1, seed=9)
    atoms = clump_atoms(CLUMP, q, np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)))
    atoms["molecule"][:] = -1
    parts, incomplete = aggregate(atoms, CLUMP, 5)
    assert incomplete == 0
    assert {k: v.shape for k, v in parts.items()} == {
        "id": (0,), "species": (0,), "radius": (0,), "mass": (0,), "orientation": (0, 4),
        "position": (0, 3), "velocity": (0, 3), "angular_velocity": (0, 3), "force": (0, 3)}


def test_bodies_numbered_against_their_atom_ids():
    # body 2 holds atoms 1-5 and body 1 atoms 6-10: parts come by body id, each with its
    # spheres in atom-id (= template) order, whatever order the ranks hand them over in
    q = random_quaternions(2, seed=10)
    centres = np.array([[1e-3, 0, 0], [0, 2e-3, 0]])
    atoms = clump_atoms(CLUMP, q, centres, np.zeros((2, 3)), np.zeros((2, 3)))
    atoms["molecule"] = np.repeat([2, 1], 5).astype(np.int32)
    rng = np.random.default_rng(14)
    for pick in [np.arange(10), np.arange(10)[::-1], *(rng.permutation(10) for _ in range(8))]:
        parts, incomplete = aggregate({k: a[pick] for k, a in atoms.items()}, CLUMP, 5)
        assert incomplete == 0 and parts["id"].tolist() == [1, 2]
        assert np.allclose(parts["position"], centres[::-1], rtol=0, atol=1e-18)
        assert np.abs(parts["orientation"] - q[::-1]).max() < 1e-12


def test_without_a_template_bodies_get_the_identity():
    # no template from the prepare hook and none taken yet: sums and means, no orientation
    q = random_quaternions(2, seed=11)
    centres = np.array([[1e-3, 0, 0], [0, 2e-3, 0]])
    parts, incomplete = aggregate(clump_atoms(CLUMP, q, centres, np.zeros((2, 3)), np.zeros((2, 3))),
                                  None, 5)
    assert incomplete == 0
    assert np.allclose(parts["position"], centres, rtol=0, atol=1e-18)
    assert parts["orientation"].tolist() == [[1, 0, 0, 0]] * 2


def test_a_clump_of_one_sphere_has_no_orientation_to_fit():
    # one sphere fixes no rotation: the identity, not an arbitrary eigenvector
    centres = np.array([[1e-3, 0, 0], [0, 2e-3, 0]])
    atoms = clump_atoms(CLUMP[:1], random_quaternions(2, seed=12), centres, np.zeros((2, 3)),
                        np.zeros((2, 3)))
    parts, incomplete = aggregate(atoms, CLUMP[:1], 1)
    assert incomplete == 0 and parts["id"].tolist() == [100, 101]
    assert parts["orientation"].tolist() == [[1, 0, 0, 0]] * 2


def test_a_two_sphere_clump_gets_its_axis():
    # a dumbbell: the turn about its own axis is undetermined, the axis is not
    dumbbell = np.array([[0, 0, 0], [2e-4, 0, 0]])
    q = random_quaternions(20, seed=13)
    atoms = clump_atoms(dumbbell, q, np.zeros((20, 3)), np.zeros((20, 3)), np.zeros((20, 3)))
    parts, incomplete = aggregate(atoms, dumbbell, 2)
    assert incomplete == 0
    axis = quaternion_matrix(parts["orientation"]) @ (dumbbell[1] - dumbbell[0])
    x = atoms["x"].reshape(20, 2, 3)
    assert np.allclose(axis, x[:, 1] - x[:, 0], rtol=0, atol=1e-16)  # m: 2e-4 m to round-off
