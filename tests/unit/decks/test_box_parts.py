"""Rectangular parts (shape 3, vibrofeed.parts): the solid's closed-form mass properties
against textbook formulas, the clump template's outline and frame, its fidelity figures,
the one-line refusals, and what prepare writes for the decks."""

import math

import numpy as np
import pytest

from vibrofeed.decks import Deck
from vibrofeed.errors import ParameterError
from vibrofeed.feeders.records import Part, shape_code
from vibrofeed.geometry import prepare_bulk_feeder
from vibrofeed.parameters import resolve
from vibrofeed.parts import (
    CLUMP_SPACING,
    Box,
    _moments,
    box_template,
    box_template_box_frame,
    cap_integrals,
    check_box,
    clump_fidelity,
    engine_inertia,
    mass_properties,
    principal_axes,
    solid_inside,
    voxel_grid,
)
from vibrofeed.postproc.singulation import thin_axis

RHO = 2330.0
BIG = Box(1.0e-3, 0.5e-3, 0.35e-3)
SMALL = Box(0.6e-3, 0.3e-3, 0.3e-3)
BUMP = dict(bump_height=0.05e-3, bump_diameter=0.2e-3, bump_at=0.5)
BIG_BUMP = Box(1.0e-3, 0.5e-3, 0.35e-3, **BUMP)
SMALL_BUMP = Box(0.6e-3, 0.3e-3, 0.3e-3, **BUMP)


def test_a_plain_box_has_the_textbook_mass_and_inertia():
    L, W, T = BIG.length, BIG.width, BIG.thickness
    props = mass_properties(BIG, RHO)
    m = RHO * L * W * T
    assert props.mass == pytest.approx(m, rel=1e-12)
    assert np.allclose(props.com, 0.0, atol=1e-18)
    expected = np.diag([m * (W * W + T * T) / 12, m * (L * L + T * T) / 12, m * (L * L + W * W) / 12])
    assert np.allclose(props.inertia, expected, rtol=1e-12, atol=1e-12 * expected.max())
    assert props.tilt == 0.0


@pytest.mark.parametrize("h", [0.02e-3, 0.1e-3, 0.15e-3, 0.2e-3])
def test_the_cap_has_the_textbook_volume_and_centroid(h):
    r = 0.1e-3
    volume, first, _, _ = cap_integrals(r, h)
    assert volume == pytest.approx(math.pi * h * h * (3 * r - h) / 3, rel=1e-10)
    # the cap's centroid from the sphere's centre: 3 (2r - h)^2 / (4 (3r - h))
    assert first / volume == pytest.approx(3 * (2 * r - h) ** 2 / (4 * (3 * r - h)), rel=1e-9)


def test_the_whole_sphere_as_a_cap_has_the_ball_s_moments():
    r = 0.1e-3
    volume, first, zz, xx = cap_integrals(r, 2 * r)
    assert volume == pytest.approx(4 / 3 * math.pi * r ** 3, rel=1e-12)
    assert abs(first) < 1e-12 * r ** 4
    # sum z^2 dV over a ball = 4 pi r^5 / 15, the same along x
    assert zz == pytest.approx(4 * math.pi * r ** 5 / 15, rel=1e-10)
    assert xx == pytest.approx(4 * math.pi * r ** 5 / 15, rel=1e-10)


def test_a_bump_shifts_the_centre_of_mass_and_gives_the_xz_product():
    b = BIG_BUMP
    L, W, T = b.length, b.width, b.thickness
    r, h = b.bump_diameter / 2, b.bump_height
    v_cap = math.pi * h * h * (3 * r - h) / 3
    m_box, m_cap = RHO * L * W * T, RHO * v_cap
    # the cap's centroid: on the face plus its own offset above the plane (hand: from the
    # sphere centre T/2 + h - r, 3 (2r - h)^2 / (4 (3r - h)) up)
    x_cap = b.bump_at * L / 2
    z_cap = T / 2 + h - r + 3 * (2 * r - h) ** 2 / (4 * (3 * r - h))
    props = mass_properties(b, RHO)
    assert props.mass == pytest.approx(m_box + m_cap, rel=1e-12)
    com = np.array([m_cap * x_cap, 0.0, m_cap * z_cap]) / (m_box + m_cap)
    assert np.allclose(props.com, com, rtol=1e-9, atol=1e-15)
    # xz product about the COM: the box's (its centre at -com) plus the cap's (its own xz
    # product 0 by symmetry about its axis), each m x z with the parallel axis theorem
    cx, cz = com[0], com[2]
    ixz = -(m_box * (0 - cx) * (0 - cz) + m_cap * (x_cap - cx) * (z_cap - cz))
    assert props.inertia[0, 2] == pytest.approx(ixz, rel=1e-9)
    assert props.inertia[0, 2] < 0 and props.inertia[0, 1] == 0 and props.inertia[1, 2] == 0
    # I_yy about the COM by the parallel-axis theorem from the box's and the cap's own
    _, first, zz, xx = cap_integrals(r, h)
    zc_sphere = T / 2 + h - r
    cap_yy_about_sphere = RHO * (xx + zz)  # sum (x^2 + z^2) dm about the sphere's centre
    cap_yy_origin = (cap_yy_about_sphere + 2 * RHO * first * zc_sphere
                     + m_cap * (zc_sphere ** 2 + x_cap ** 2))
    box_yy = m_box * (L * L + T * T) / 12
    iyy = box_yy + cap_yy_origin - (m_box + m_cap) * (cx * cx + cz * cz)
    assert props.inertia[1, 1] == pytest.approx(iyy, rel=1e-10)


@pytest.mark.parametrize("box", [BIG, BIG_BUMP, SMALL_BUMP])
def test_the_solid_on_a_voxel_grid_matches_the_closed_forms(box):
    """The voxel integrator the fidelity figures use, checked on the solid itself."""
    grid, cell = voxel_grid(box, 40)
    volume, com, inertia = _moments(solid_inside(box, grid), grid, cell)
    exact = mass_properties(box, 1.0)
    assert volume == pytest.approx(exact.mass, rel=2e-3)
    assert np.linalg.norm(com - exact.com) < 2e-3 * box.thickness
    assert np.allclose(np.diag(inertia), np.diag(exact.inertia), rtol=5e-3, atol=0)
    assert inertia[0, 2] == pytest.approx(exact.inertia[0, 2], rel=0.05, abs=1e-3 * exact.inertia.max())


def _lattice_counts(box):
    d = box.thickness / 2
    return [max(2, math.ceil((e - d) / (CLUMP_SPACING * d) - 1e-9) + 1)
            for e in (box.length, box.width, box.thickness)]


@pytest.mark.parametrize("box, counts, spheres", [(BIG, (8, 4, 3), 84), (SMALL, (5, 3, 3), 42)])
def test_the_template_is_a_shell_whose_outline_is_the_box(box, counts, spheres):
    # hand: d = T/2; 1.0 mm: spans 0.825, 0.325, 0.175 mm at <= 0.13125 mm -> 8, 4, 3 rows
    assert tuple(_lattice_counts(box)) == counts
    nx, ny, nz = counts
    assert spheres == nx * ny * nz - (nx - 2) * (ny - 2) * (nz - 2)
    rows = box_template_box_frame(box)
    assert len(rows) == spheres
    d = box.thickness / 2
    assert np.all(rows[:, 3] == d / 2)
    half = np.array([box.length, box.width, box.thickness]) / 2
    assert np.allclose(rows[:, :3].max(axis=0) + d / 2, half, rtol=0, atol=1e-15)  # m
    assert np.allclose(rows[:, :3].min(axis=0) - d / 2, -half, rtol=0, atol=1e-15)  # m
    for k in range(3):  # spacing along each edge
        steps = np.diff(np.unique(np.round(rows[:, k], 15)))
        assert steps.max() <= CLUMP_SPACING * d * (1 + 1e-9)
    # every face has at least two rows across it
    assert min(counts) >= 2
    # no bump: the body frame is the box frame, the COM its centre
    assert np.array_equal(box_template(box), rows)


def test_the_bumped_template_is_about_the_com_in_the_principal_frame():
    b = BIG_BUMP
    rows, box_rows = box_template(b), box_template_box_frame(b)
    bump = box_rows[-1]
    assert bump[3] == b.bump_diameter / 2
    assert bump[2] + bump[3] == pytest.approx(b.thickness / 2 + b.bump_height, rel=1e-12)  # its top
    assert bump[0] == pytest.approx(b.bump_at * b.length / 2, rel=1e-12) and bump[1] == 0
    props = mass_properties(b, RHO)
    axes = principal_axes(b)
    assert np.allclose(axes.T @ axes, np.eye(3), atol=1e-12) and np.linalg.det(axes) > 0
    # the box's centre lies at -com in the body frame; rotating back gives the box frame
    assert np.allclose(rows[:, :3] @ axes.T + props.com, box_rows[:, :3], atol=1e-15)
    # the engine's tensor: diagonal, the closed form's eigenvalues (the template's frame)
    mass, six = engine_inertia(b, RHO)
    assert mass == props.mass and six[1] == six[2] == six[4] == 0
    assert np.allclose(sorted([six[0], six[3], six[5]]), np.linalg.eigvalsh(props.inertia), rtol=1e-12,
                       atol=0)
    assert np.allclose(axes.T @ props.inertia @ axes, np.diag([six[0], six[3], six[5]]),
                       atol=1e-12 * six[5])
    # the tilt about y: tan 2a = 2 I_xz / (I_zz - I_xx)
    ixx, izz, ixz = props.inertia[0, 0], props.inertia[2, 2], props.inertia[0, 2]
    assert props.tilt == pytest.approx(math.degrees(0.5 * math.atan2(-2 * ixz, izz - ixx)), rel=1e-6)


@pytest.mark.parametrize("box", [BIG, SMALL, BIG_BUMP, SMALL_BUMP])
def test_the_fidelity_figures(box):
    f = clump_fidelity(box)
    d = box.thickness / 2
    assert f["sphere_diameter"] == d and f["edge_radius"] == d / 2
    # the clump lies inside the solid: its volume and moments are less; its spheres'
    # rounding and the dimples between them take at most a quarter of it
    assert -0.25 < f["volume_error"] < 0
    assert np.all((f["inertia_errors"] > -0.4) & (f["inertia_errors"] < 0))
    assert f["com_error"] < (1e-12 if box.bump_height == 0 else 0.005)
    # the pivot half-width: half the span of the sphere centres across the face
    assert f["pivot_half_width"]["z/x"] == pytest.approx((box.length - d) / 2, rel=1e-12)
    assert f["pivot_half_width"]["x/z"] == pytest.approx((box.thickness - d) / 2, rel=1e-12)
    assert f["pivot_half_width"]["y/x"] == pytest.approx((box.length - d) / 2, rel=1e-12)
    assert f["face_half_width"]["z/y"] == box.width / 2


def test_a_box_part_s_sizes():
    part = Part.from_values({"shape": "box", "part_size": "1e-3", "part_width": "5e-4",
                             "part_thickness": "3.5e-4"})
    assert part.shape == 3 and part.widest == 1e-3 and part.tallest == 3.5e-4
    d = 3.5e-4 / 2
    corner = math.sqrt((1e-3 - d) ** 2 + (5e-4 - d) ** 2 + (3.5e-4 - d) ** 2) / 2 + d / 2
    assert part.reach == pytest.approx(corner, rel=1e-12)
    bumped = Part.from_values({"shape": "3", "part_size": "1e-3", "part_width": "5e-4",
                               "part_thickness": "3.5e-4", "bump_height": "5e-5",
                               "bump_diameter": "2e-4"})
    assert bumped.tallest == pytest.approx(4e-4, rel=1e-12) and bumped.reach > part.reach
    assert shape_code("box") == 3 and shape_code(3.0) == 3


@pytest.mark.parametrize("box, says", [
    (Box(1e-3, 5e-4, 6e-4), "part_size >= part_width >= part_thickness"),
    (Box(4e-4, 5e-4, 3e-4), "part_size >= part_width >= part_thickness"),
    (Box(1e-3, -5e-4, 3e-4), "part_width=-0.0005 m must be > 0"),
    (Box(1e-3, 5e-4, 3.5e-4, 5e-5, 6e-4), "wider than the face"),
    (Box(1e-3, 5e-4, 3.5e-4, 5e-5, 2e-4, 0.9), "reaches past the face's end"),
    (Box(1e-3, 5e-4, 3.5e-4, 3e-4, 2e-4), "exceeds bump_diameter"),
    (Box(1e-3, 5e-4, 3.5e-4, -5e-5, 2e-4), "must be >= 0"),
    (Box(1e-3, 5e-4, 3.5e-4, 5e-5, 4.5e-4), "through the bottom face"),
])
def test_a_bad_box_is_refused_in_one_line(box, says):
    with pytest.raises(ParameterError, match=says) as err:
        check_box(box)
    assert "\n" not in str(err.value)


def test_the_bulk_deck_refuses_a_bad_box_and_a_box_with_surface_forces():
    deck = Deck.find("bulk_feeder")
    base = {"shape": "box", "part_size": "1e-3", "part_width": "5e-4", "part_thickness": "3.5e-4",
            "track_width": "3e-3", "n_parts": "10"}
    resolve(deck, {**base, "bump_height": "5e-5", "bump_diameter": "2e-4"})  # accepted
    with pytest.raises(ParameterError, match="bump_diameter=0.0006 m is wider"):
        resolve(deck, {**base, "bump_height": "5e-5", "bump_diameter": "6e-4"})
    with pytest.raises(ParameterError, match="hamaker and air_viscosity"):
        resolve(deck, {**base, "hamaker": "1e-19"})


def test_thin_axis_finds_a_box_s_body_z():
    assert np.allclose(thin_axis(box_template(BIG)), [0, 0, 1], rtol=0, atol=1e-12)
    # W = T: the tie goes to z
    assert np.allclose(thin_axis(box_template(SMALL)), [0, 0, 1], rtol=0, atol=1e-12)
    normal = principal_axes(SMALL_BUMP).T @ [0, 0, 1]  # the marked face's normal, body frame
    assert np.allclose(thin_axis(box_template(SMALL_BUMP)), normal, atol=1e-9)


def test_prepare_writes_the_box_template_and_its_mass(tmp_path):
    values = {"shape": "3", "part_size": "1e-3", "part_width": "5e-4", "part_thickness": "3.5e-4",
              "bump_height": "5e-5", "bump_diameter": "2e-4", "bump_at": "0.5", "density": "2330",
              "track_length": "0.006", "track_width": "3e-3", "wall_height": "1e-3",
              "gate_width": "0", "gate_at": "0.7"}
    prepared = prepare_bulk_feeder(values, tmp_path)
    written = np.loadtxt(tmp_path / "box.multisphere")
    assert np.allclose(written, prepared.body_template, rtol=1e-15, atol=0) and len(written) == 85
    text = (tmp_path / "prepared.in").read_text()
    numbers = dict(line.split()[1::2] for line in text.splitlines() if line.startswith("variable"))
    v_cap = math.pi * 5e-5 ** 2 * (3e-4 - 5e-5) / 3
    assert float(numbers["m_box"]) == pytest.approx(2330 * (1e-3 * 5e-4 * 3.5e-4 + v_cap), rel=1e-12)
    assert float(numbers["n_sph_box"]) == 85 and float(numbers["I_box_xz"]) == 0
    assert "Invalid bump_at" in text  # a run by hand is held to the box it was built for


def test_clump_spacing_sets_the_lattice():
    """spacing 1.0: spheres touching along each edge; 1.0 x 0.5 x 0.35 mm, d = 0.175 mm: centres
    span 0.825, 0.325 and 0.175 mm, so 6 x 3 x 2 positions, all on the surface: 36 spheres."""
    from vibrofeed.parts import Box, box_template_box_frame, check_box

    rows = box_template_box_frame(Box(1e-3, 5e-4, 3.5e-4, spacing=1.0))
    assert len(rows) == 6 * 3 * 2
    xs = np.unique(np.round(rows[:, 0], 12))
    assert np.diff(xs).max() <= 1.75e-4 * (1 + 1e-9)  # at most one diameter apart
    for bad in (0.4, 1.2):
        with pytest.raises(ParameterError, match=rf"^clump_spacing={bad:g} must be in \[0.5, 1\]"):
            check_box(Box(1e-3, 5e-4, 3.5e-4, spacing=bad))
