"""The bulk feeder's geometry (vibrofeed.geometry): the track mesh is one connected
surface open only at the outlet and along the wall tops, has the asked dimensions and gate,
and the clump templates have the part's outline and thickness."""

import json
import math
from collections import Counter

import numpy as np
import pytest

from vibrofeed.errors import ParameterError
from vibrofeed.geometry import (
    CLUMP_SPACING,
    Prepared,
    catch_face,
    chip_template,
    disc_template,
    insertion_seeds,
    prepare_bowl_feeder,
    prepare_bulk_feeder,
    shape_code,
    track_mesh,
    wall_stations,
)
from vibrofeed.mesh import write_stl

L, W, H = 0.02, 2e-3, 1e-3
PM = 1e-12  # m: the meshes and templates keep their lengths (1e-4..2e-2 m) to 1 pm (float64 rounding)


def same(a, b):
    """Lengths (m) equal to the mesh's precision PM, with no relative part: numpy's defaults
    (atol=1e-8 m, rtol=1e-5: 0.2 um at 2 cm) would take a micro-part's gap for a coincidence."""
    return np.isclose(a, b, rtol=0, atol=PM)


def all_same(a, b):
    """:func:`same` everywhere."""
    return np.allclose(a, b, rtol=0, atol=PM)


def edge_counts(triangles):
    """How many triangles hold each (sorted) edge."""
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    return Counter(map(tuple, np.sort(edges, axis=1)))


def open_edges(vertices, triangles):
    return [vertices[list(e)] for e, n in edge_counts(triangles).items() if n == 1]


@pytest.mark.parametrize("gate", [0.0, 8e-4])
def test_track_dimensions(gate):
    v, t = track_mesh(L, W, H, gate_width=gate, gate_x=0.7 * L)
    assert v.dtype == np.float64 and t.dtype == np.int32 and v.shape[1] == t.shape[1] == 3
    assert all_same(v.min(axis=0), [0, -W / 2, 0]) and all_same(v.max(axis=0), [L, W / 2, H])
    floor = v[same(v[:, 2], 0)]
    assert same(floor[:, 0].max(), L)  # the floor reaches the outlet edge


@pytest.mark.parametrize("gate", [0.0, 8e-4])
def test_floor_and_walls_share_whole_edges(gate):
    v, t = track_mesh(L, W, H, gate_width=gate, gate_x=0.7 * L)
    counts = edge_counts(t)
    assert set(counts.values()) <= {1, 2}  # no edge of three faces, none doubled
    # no T-junction: no vertex lies inside an edge it is not an end of
    for (a, b) in counts:
        d = v[b] - v[a]
        rel = (v - v[a]) @ d / (d @ d)
        off = np.linalg.norm(v - v[a] - np.outer(rel, d), axis=1)
        assert not np.any((rel > 1e-9) & (rel < 1 - 1e-9) & (off < 1e-12))
    # open edges: the outlet (floor edge and the walls' ends at x = L) and the wall tops
    for p, q in open_edges(v, t):
        at_outlet = same(p[0], L) and same(q[0], L)
        on_top = same(p[2], H) and same(q[2], H)
        assert at_outlet or on_top, (p, q)
    outlet = [e for e in open_edges(v, t) if same(e[0][2], 0) and same(e[1][2], 0)]
    assert len(outlet) == 1 and all_same(outlet[0][:, 0], L)  # the floor's one open edge


def test_track_is_consistently_wound_with_normals_into_the_track():
    trimesh = pytest.importorskip("trimesh")
    v, t = track_mesh(L, W, H)
    m = trimesh.Trimesh(v, t, process=False)
    assert m.is_winding_consistent
    centre = m.triangles_center
    n = m.face_normals
    floor = same(centre[:, 2], 0)
    assert np.allclose(n[floor], [0, 0, 1], rtol=0, atol=1e-12)  # unit normals: rounding
    back = same(centre[:, 0], 0) & ~floor
    assert np.allclose(n[back], [1, 0, 0], rtol=0, atol=1e-12)
    side = ~floor & ~back
    assert np.all(n[side, 1] * centre[side, 1] < 0)  # the side walls face the centre line


def test_gate_width_and_taper():
    gate, gate_x = 6e-4, 0.7 * L
    v, t = track_mesh(L, W, H, gate_width=gate, gate_x=gate_x)
    at = lambda x: np.abs(v[same(v[:, 0], x) & same(v[:, 2], 0), 1]).max()  # noqa: E731
    assert same(at(L), gate / 2)
    assert same(at(gate_x), W / 2)
    taper_end = gate_x + (W - gate) / 2  # 45 degrees
    assert same(at(taper_end), gate / 2)
    # no gate when it is as wide as the track
    v0, _ = track_mesh(L, W, H, gate_width=W)
    assert all_same(np.abs(v0[:, 1]), W / 2)


def test_a_gate_that_does_not_fit_is_refused():
    with pytest.raises(ParameterError, match="gate"):
        track_mesh(L, W, H, gate_width=2e-4, gate_x=L - 1e-4)


def test_wall_stations_are_at_most_the_spacing_apart_and_a_taper_may_end_at_the_outlet():
    # default spacing: the track width, at most 1 mm; the stations end exactly at the outlet
    for length, width in ((0.02, 2e-3), (0.0105, 4e-4)):
        xs, _ = wall_stations(length, width)
        assert xs[0] == 0.0 and xs[-1] == length
        assert np.diff(xs).max() <= min(width, 1e-3) * (1 + 1e-12)
    # a taper ending exactly at the outlet edge fits (binary fractions: exact sums)
    xs, half = wall_stations(1.0, 0.5, gate_width=0.25, gate_x=0.875)
    assert xs[-1] == 1.0 and half[-1] == 0.125


def test_catch_face_is_a_unit_rectangle_facing_down(tmp_path):
    v, t = catch_face()
    assert np.allclose(v.min(axis=0), [0, -0.5, 0], rtol=0, atol=1e-15)  # unit lengths: rounding
    assert np.allclose(v.max(axis=0), [1, 0.5, 0], rtol=0, atol=1e-15)
    normals = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    assert np.all(normals[:, 2] < 0)


def test_stl_round_trip(tmp_path):
    from stl import mesh as stl_mesh

    v, t = track_mesh(L, W, H, gate_width=8e-4)
    path = write_stl(v, t, tmp_path / "track.stl")
    m = stl_mesh.Mesh.from_file(str(path))
    assert np.allclose(m.vectors, v[t], rtol=0, atol=1e-9)  # float32: half an ulp is 0.93 nm below 3.1 cm
    expected = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    assert np.all(np.einsum("ij,ij->i", m.normals, expected) > 0)


def liggghts_first_line(data: bytes) -> bytes:
    """What LIGGGHTS reads of an STL before it decides the file is binary: its first line, up
    to the first newline byte (src/input_mesh_tri.cpp: fgets, then the input parser, which
    refuses unbalanced quotes)."""
    end = data.find(b"\n")
    return data if end < 0 else data[:end]


@pytest.mark.parametrize("n", [1, 34, 39, 295, 551, 10 + 256 * 10])  # 34 '"', 39 "'", 10 newline
def test_liggghts_reads_the_stls_first_line_as_its_header_whatever_the_triangles(tmp_path, n):
    """A binary STL's first line is its header, text without quotes that does not open with
    "solid": the triangle count's bytes (a count of 39 starts with a quote) and the coordinates'
    never reach the line LIGGGHTS parses. A bowl of 551 triangles stopped a run before."""
    from stl import mesh as stl_mesh

    rng = np.random.default_rng(n)
    v = rng.normal(scale=1e-2, size=(n + 2, 3))
    v[0] = np.frombuffer(b"'\"\n'" * 3, dtype="<f4").astype(np.float64)  # quote and newline bytes
    t = np.column_stack([np.zeros(n, dtype=int), np.arange(1, n + 1), np.arange(2, n + 2)])
    path = write_stl(v, t, tmp_path / "m.stl", name="bowl 'x\"")
    data = path.read_bytes()
    line = liggghts_first_line(data)
    assert len(line) < 80 and line == line.strip() and line.decode("ascii").isprintable()
    assert b"'" not in line and b'"' not in line and not line.startswith(b"solid")
    assert len(data) == 84 + 50 * n and int.from_bytes(data[80:84], "little") == n
    m = stl_mesh.Mesh.from_file(str(path))  # another reader takes it as the mesh written
    assert np.array_equal(m.vectors, v[t].astype(np.float32))


@pytest.mark.parametrize("edge, thickness, n", [(3e-4, 1.5e-4, 9), (3e-4, 1e-4, 16), (1e-3, 1e-4, 169)])
def test_chip_outline_is_the_die(edge, thickness, n):
    rows = chip_template(edge, thickness)
    assert rows.shape == (n, 4)
    x, y, z, r = rows.T
    assert all_same(r, thickness / 2)
    assert same((x - r).min(), -edge / 2) and same((x + r).max(), edge / 2)
    assert same((y - r).min(), -edge / 2) and same((y + r).max(), edge / 2)
    assert same((z + r).max() - (z - r).min(), thickness)  # the die's thickness
    assert np.allclose(rows[:, :3].mean(axis=0), 0, atol=1e-18)  # centred: body frame
    spacing = np.diff(np.unique(np.round(x, 15)))
    assert all_same(spacing, spacing[0]) and spacing[0] <= CLUMP_SPACING * thickness + 1e-15


def test_disc_outline_and_thickness():
    d, t = 5e-4, 1e-4
    rows = disc_template(d, t)
    x, y, z, r = rows.T
    rho = np.hypot(x, y)
    assert same((rho + r).max(), d / 2)
    assert all_same(z, 0) and all_same(r, t / 2)
    assert np.allclose(rows[:, :3].mean(axis=0), 0, atol=1e-18)
    # neighbours on the outer ring are no further apart than the spacing rule
    outer = np.sort(np.arctan2(y, x)[same(rho, rho.max())])
    chord = 2 * rho.max() * np.sin(np.diff(outer).max() / 2)
    assert chord <= CLUMP_SPACING * t + 1e-12


def test_shape_codes():
    assert [shape_code(s) for s in ("sphere", "chip", "disc", "0", "1", "2.0")] == [0, 1, 2, 0, 1, 2]
    with pytest.raises(ParameterError, match="shape"):
        shape_code("cube")


def test_insertion_seeds_are_distinct_primes_liggghts_accepts():
    for seed in (1, 5489, 199_999, 10**9):
        seeds = insertion_seeds(seed, 6)
        assert len(set(seeds)) == 6
        assert all(10_000 < p < 2**31 for p in seeds)
        assert all(all(p % d for d in range(2, int(p**0.5) + 1)) for p in seeds)
    assert insertion_seeds(1, 6) != insertion_seeds(2, 6)


VALUES = {"track_length": "0.02", "track_width": "0.002", "wall_height": "0.001",
          "gate_width": "0", "gate_at": "0.7", "part_size": "3e-4", "part_thickness": "1.5e-4",
          "shape": "1", "seed": "5489"}


def test_prepare_writes_the_files_and_describes_them(tmp_path):
    p = prepare_bulk_feeder(VALUES, tmp_path / "m")
    assert isinstance(p, Prepared)
    names = sorted(f.name for f in (tmp_path / "m").iterdir())
    assert names == ["catch.stl", "chip.multisphere", "disc.multisphere", "line_catch.in",
                     "line_derived.in", "line_meshes.in", "line_motion.in", "prepared.in", "track.stl"]
    assert p.variables == {"mesh_dir": str((tmp_path / "m").resolve())}
    text = (tmp_path / "m" / "prepared.in").read_text()
    assert "variable n_sph_chip equal 9" in text and "variable seed_6 equal" in text
    assert all_same(p.body_template, chip_template(3e-4, 1.5e-4))
    assert all_same(np.loadtxt(tmp_path / "m" / "chip.multisphere"), p.body_template)
    spec = json.loads(json.dumps(p.to_spec()))  # what the runner hands the worker
    assert all_same(np.array(spec["track"][0]), p.track[0])
    assert spec["variables"]["mesh_dir"] == p.variables["mesh_dir"]
    sphere = prepare_bulk_feeder({**VALUES, "shape": "0"}, tmp_path / "s")
    assert sphere.body_template is None and sphere.to_spec()["body_template"] is None


@pytest.mark.parametrize("gate", [0.0, 8e-4])
def test_cross_tilt_makes_the_floor_a_plane_down_towards_the_minus_y_wall(gate):
    tilt = 12.0
    v, t = track_mesh(L, W, H, gate_width=gate, gate_x=0.7 * L, cross_tilt=tilt)
    slope = math.tan(math.radians(tilt))
    walls_top = np.isclose(v[:, 2], H, rtol=0, atol=1e-15)
    floor = v[~walls_top]
    # every floor vertex on the plane z = -(W/2 - y) tan(tilt), whatever the gate's width there
    assert np.abs(floor[:, 2] + (W / 2 - floor[:, 1]) * slope).max() < 1e-12  # the mesh keeps 1 pm
    # the reference wall's foot, to the mesh's 1 pm (vertices are rounded to 12 decimals: 3.4e-13 m off
    # here, which rel=1e-12 alone, 4e-16 m, would refuse)
    assert v[:, 2].min() == pytest.approx(-W * slope, rel=0, abs=PM)
    # still one surface: no edge of three faces, and the only floor edge left open is the outlet's
    counts = edge_counts(t)
    assert set(counts.values()) <= {1, 2}
    open_floor = [(p, q) for p, q in open_edges(v, t) if not (same(p[2], H) and same(q[2], H))]
    assert all(same(p[0], L) and same(q[0], L) for p, q in open_floor)  # to 1 pm
    # the floor's normals lean towards -y by the tilt: downhill, where the parts go
    tri = v[t]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    is_floor = np.all(~same(tri[:, :, 2], H), axis=1) & (np.abs(n[:, 2]) > 0.5)
    assert np.allclose(n[is_floor], [0, -math.sin(math.radians(tilt)), math.cos(math.radians(tilt))],
                       rtol=0, atol=1e-7)  # unit vectors from vertices kept to 1 pm over 0.1 mm


def test_no_cross_tilt_is_the_level_track_bit_for_bit():
    a = track_mesh(L, W, H, gate_width=8e-4, gate_x=0.7 * L)
    b = track_mesh(L, W, H, gate_width=8e-4, gate_x=0.7 * L, cross_tilt=0.0)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


# ------------------------------------------------------------------ wall stations, by hand
def test_stations_are_the_fewest_uniform_ones_within_the_spacing():
    # a length that is a whole number of spacings: exactly that many steps, no extra station
    # (binary fractions: exact)
    xs, half = wall_stations(1.0, 0.5, spacing=0.25)
    assert xs.tolist() == [0.0, 0.25, 0.5, 0.75, 1.0] and half.tolist() == [0.25] * 5
    # default spacing 1 mm: 2 cm in 20 steps of 1 mm (20 spacings up to rounding)
    xs, _ = wall_stations(0.02, 2e-3)
    assert len(xs) == 21 and all_same(np.diff(xs), 1e-3)
    # one step more than a whole number: ceil
    xs, _ = wall_stations(1.0, 0.5, spacing=0.3)
    assert len(xs) == 5 and all_same(np.diff(xs), 0.25)


@pytest.mark.parametrize("length, spacing", [(5e-4, None), (1.0, 2e9)])
def test_a_track_shorter_than_a_spacing_is_one_step(length, spacing):
    # the default spacing is 1 mm; a spacing 2e9 times the length (below the ceil's 1e-9 slack)
    # still leaves a first and a last station
    xs, half = wall_stations(length, 2e-3, spacing=spacing)
    assert xs.tolist() == [0.0, length] and half.tolist() == [1e-3, 1e-3]


def hand_half(x, width, gate_width, gate_x):
    """The walls' half width by hand: full up to the gate, a 45 degree taper, then the gate."""
    taper_end = gate_x + (width - gate_width) / 2
    return np.where(x <= gate_x, width / 2,
                    np.where(x >= taper_end, gate_width / 2, width / 2 - (x - gate_x)))


@pytest.mark.parametrize("gate_x", [0.0, 0.25, 0.875])
def test_gate_walls_full_width_up_to_the_gate_then_a_45_degree_taper(gate_x):
    # binary fractions: the stations and half widths are exact
    xs, half = wall_stations(1.0, 0.5, gate_width=0.25, gate_x=gate_x, spacing=0.125)
    assert gate_x in xs and gate_x + 0.125 in xs  # both kinks are stations
    assert np.array_equal(half, hand_half(xs, 0.5, 0.25, gate_x))
    assert xs[0] == 0.0 and xs[-1] == 1.0 and np.all(np.diff(xs) > 0)


@pytest.mark.parametrize("gate_x", [-0.5, -1e-9])
def test_a_gate_before_the_back_wall_is_refused(gate_x):
    with pytest.raises(ParameterError, match="gate does not fit"):
        wall_stations(1.0, 0.5, gate_width=0.25, gate_x=gate_x)


def test_a_gate_whose_taper_rounds_to_no_length_is_refused():
    # 2**-53 narrower than the track: half of it added to gate_x = 0.5 rounds away, so the
    # taper would run from 0.5 to 0.5; the check asks gate_x < taper_end strictly
    narrow = np.nextafter(1.0, 0.0)
    assert 0.5 + (1.0 - narrow) / 2 == 0.5
    with pytest.raises(ParameterError, match="gate does not fit"):
        wall_stations(2.0, 1.0, gate_width=narrow, gate_x=0.5)


def test_the_gate_kinks_are_kept_to_a_picometre_and_merge_with_a_station_as_close():
    # the kinks keep their position to the mesh's 1 pm, wherever they fall
    gate_x = 0.014 + 3.7e-12
    xs, _ = wall_stations(L, W, gate_width=8e-4, gate_x=gate_x)
    taper_end = gate_x + (W - 8e-4) / 2
    assert np.abs(xs - gate_x).min() <= PM and np.abs(xs - taper_end).min() <= PM
    # a kink within 1 pm of a uniform station (0.014 m) is that station: no sliver face
    xs, _ = wall_stations(L, W, gate_width=8e-4, gate_x=0.014 + 3e-13)
    assert np.diff(xs).min() > PM
    assert len(xs) == 21 + 1  # the uniform 21 and the taper's end (0.0146 m)


def test_no_gate_by_default_even_on_a_track_wider_than_a_metre():
    xs, half = wall_stations(4.0, 2.0, spacing=0.5)
    assert half.tolist() == [1.0] * 9
    v, _ = track_mesh(4.0, 2.0, 1.0, spacing=0.5)
    assert np.all(np.abs(v[:, 1]) == 1.0)  # straight walls: every vertex on one of them


def test_a_gate_at_the_back_wall_keeps_the_back_wall_full_width():
    v, t = track_mesh(L, W, H, gate_width=8e-4, gate_x=0.0)
    back = v[same(v[:, 0], 0)]
    assert all_same([back[:, 1].min(), back[:, 1].max()], [-W / 2, W / 2])
    for p, q in open_edges(v, t):  # still closed but at the outlet and along the wall tops
        assert (same(p[0], L) and same(q[0], L)) or (same(p[2], H) and same(q[2], H)), (p, q)


# ------------------------------------------------------------------ catch face, clumps
def test_catch_face_covers_its_rectangle():
    v, t = catch_face(length=2.0, width=0.5, z=0.25)
    assert {tuple(p) for p in v[t].reshape(-1, 3).tolist()} == {
        (0.0, -0.25, 0.25), (0.0, 0.25, 0.25), (2.0, 0.25, 0.25), (2.0, -0.25, 0.25)}
    cross = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    assert np.all(cross[:, 2] < 0)  # every triangle a real one, facing down
    assert np.abs(cross[:, 2]).sum() / 2 == pytest.approx(1.0, rel=1e-15)  # area 2 x 0.5: no gap


def test_a_chip_of_an_edge_up_to_a_spacing_beyond_its_thickness_is_two_by_two():
    t = 1e-4
    rows = chip_template(1.5 * t, t)  # centres span 0.5 t <= 0.75 t: two a side are enough
    assert rows.shape == (4, 4)
    assert all_same(np.sort(np.unique(np.round(rows[:, 0], 15))), [-t / 4, t / 4])


@pytest.mark.parametrize("edge", [1e-4, 8e-5])
def test_a_chip_no_wider_than_thick_is_one_sphere(edge):
    # (a sphere run writes the chip template too, whatever part_size and part_thickness are)
    rows = chip_template(edge, 1e-4)
    assert rows.tolist() == [[0.0, 0.0, 0.0, 5e-5]]  # at the body frame's origin


@pytest.mark.parametrize("diameter", [1e-4, 8e-5])
def test_a_disc_no_wider_than_thick_is_one_sphere(diameter):
    rows = disc_template(diameter, 1e-4)
    assert rows.tolist() == [[0.0, 0.0, 0.0, 5e-5]]


def rings(rows):
    """The clump's rings about the centre sphere: [(radius, sphere count, angles)]."""
    rho = np.hypot(rows[:, 0], rows[:, 1])
    out = []
    for r in np.unique(np.round(rho[1:], 15)):
        on = np.abs(rho - r) <= PM
        out.append((r, int(on.sum()), np.sort(np.mod(np.arctan2(rows[on, 1], rows[on, 0]), 2 * np.pi))))
    return out


T = 1e-4
RING_12 = 12 * CLUMP_SPACING * T / (2 * math.pi)  # a ring of exactly 12 spacings round


@pytest.mark.parametrize("diameter, counts", [
    (5e-4, [6, 12, 17]),  # outer 2e-4 = 2.67 spacings: 3 rings; ceil(2 pi k (2/3) / 0.75) = 5.6, 11.2, 16.8
    (4e-4, [7, 13]),  # outer 1.5e-4, exactly 2 spacings: 2 rings; ceil(2 pi) = 7, ceil(4 pi) = 13
    (T + 2 * RING_12, [6, 12]),  # rings of exactly 6 and 12 spacings round: 6 and 12 spheres
    (1.8e-4, [6]),  # outer 0.4e-4: one ring, 3.4 spacings round, but 6 spheres at least
])
def test_disc_rings_are_the_fewest_that_keep_the_spacing(diameter, counts):
    rows = disc_template(diameter, T)
    assert len(rows) == 1 + sum(counts) and rows[0].tolist() == [0.0, 0.0, 0.0, T / 2]
    outer = (diameter - T) / 2
    got = rings(rows)
    assert [n for _, n, _ in got] == counts
    # rings equally spaced out to the rim, radially within the spacing
    n = len(counts)
    assert all_same([r for r, _, _ in got], [outer * k / n for k in range(1, n + 1)])
    assert outer / n <= CLUMP_SPACING * T * (1 + 1e-12)
    for _, m, angles in got:  # each ring equally spaced from angle 0
        assert np.allclose(angles, 2 * np.pi * np.arange(m) / m, rtol=0, atol=1e-12)  # rad: rounding


# ------------------------------------------------------------------ seeds
def test_is_prime_against_a_sieve():
    from vibrofeed.geometry import _is_prime

    limit = 2000
    sieve = np.ones(limit, dtype=bool)
    sieve[:2] = False
    for d in range(2, int(limit**0.5) + 1):
        sieve[d * d::d] = False
    assert [_is_prime(n) for n in range(-3, limit)] == [False] * 3 + sieve.tolist()
    assert not _is_prime(7159**2) and _is_prime(2**31 - 1)


@pytest.mark.parametrize("seed", [5138, 20101, 66397])
def test_seeds_are_primes_where_the_scan_meets_a_primes_square(seed):
    # these seeds' scans pass 7159**2, 14159**2, 25733**2 before any prime: a divisor test
    # stopping short of the square root would take the square for a prime
    for p in insertion_seeds(seed, 6):
        assert all(p % d for d in range(2, math.isqrt(p) + 1)), p


# ------------------------------------------------------------------ the prepare hooks
def seed_lines(text):
    return [line for line in text.splitlines() if line.startswith("variable seed_")]


def test_prepare_writes_the_six_insertion_seeds_of_the_seed_and_of_the_decks_default(tmp_path):
    def want(seed):
        return [f"variable seed_{k} equal {p}" for k, p in zip(range(1, 7), insertion_seeds(seed, 6))]

    prepare_bulk_feeder({**VALUES, "seed": "1"}, tmp_path / "a")
    assert seed_lines((tmp_path / "a" / "prepared.in").read_text()) == want(1)
    # no seed: the deck's default, 5489 (decks/bulk_feeder.liggghts: variable seed index 5489)
    values = {k: v for k, v in VALUES.items() if k != "seed"}
    prepare_bulk_feeder(values, tmp_path / "b")
    assert seed_lines((tmp_path / "b" / "prepared.in").read_text()) == want(5489)


def test_prepare_makes_its_folder_with_the_parents_and_a_disc_template(tmp_path):
    folder = tmp_path / "runs" / "r1" / "mesh"
    p = prepare_bulk_feeder({**VALUES, "shape": "disc"}, folder)
    assert (folder / "prepared.in").is_file()
    assert all_same(p.body_template, disc_template(3e-4, 1.5e-4))
    text = (folder / "prepared.in").read_text()
    assert f"variable n_sph_disc equal {len(disc_template(3e-4, 1.5e-4))}\n" in text
    spec = p.to_spec()
    assert np.array_equal(np.array(spec["track"][1]), p.track[1])  # the triangles, as indices


def test_prepare_track_is_level_without_cross_tilt_and_tilted_with_it(tmp_path):
    args = (0.02, 0.002, 0.001, 0.0, 0.7 * 0.02)
    level = prepare_bulk_feeder(VALUES, tmp_path / "l").track
    want = track_mesh(*args)
    assert np.array_equal(level[0], want[0]) and np.array_equal(level[1], want[1])
    tilted = prepare_bulk_feeder({**VALUES, "cross_tilt": "5"}, tmp_path / "t").track
    assert np.array_equal(tilted[0], track_mesh(*args, cross_tilt=5.0)[0])


@pytest.mark.parametrize("change, words", [
    ({"track_width": None}, "needs the parameter track_width"),
    ({"part_size": "big"}, "part_size=big is not a number"),
])
def test_prepare_refuses_a_missing_or_unreadable_number_in_one_line(tmp_path, change, words):
    values = {k: v for k, v in {**VALUES, **change}.items() if v is not None}
    with pytest.raises(ParameterError, match=words):
        prepare_bulk_feeder(values, tmp_path)


BOWL_VALUES = {"bowl_diameter": "0.02", "track_width": "0.0012", "helix_angle": "3", "turns": "1.5",
               "wall_height": "0.001", "cone_angle": "3", "cross_tilt": "3", "lip_height": "0",
               "chute_length": "0.008", "drop_from": "0", "drop_to": "0", "drop_width": "0",
               "wiper_height": "0", "wiper_at": "0.5", "part_size": "3e-4", "part_thickness": "1.5e-4",
               "shape": "chip", "size_spread": "0", "seed": "7"}


def test_prepare_bowl_feeder_writes_its_files_again_and_again_into_a_new_folder(tmp_path):
    from vibrofeed.bowl import bowl_from, bowl_mesh

    folder = tmp_path / "runs" / "bowl"
    for _ in range(2):  # a new folder with its parents, then the same folder again (a rerun)
        p = prepare_bowl_feeder(BOWL_VALUES, folder)
    names = sorted(f.name for f in folder.iterdir())
    assert names == ["bowl.stl", "catch.stl", "chip.multisphere", "disc.multisphere", "line_catch.in",
                     "line_derived.in", "line_meshes.in", "line_motion.in", "prepared.in"]
    text = (folder / "prepared.in").read_text()
    assert text.startswith("# written by vibrofeed.geometry.prepare_bowl_feeder for one run\n")
    assert seed_lines(text) == [f"variable seed_{k} equal {s}" for k, s in
                                zip(range(1, 7), insertion_seeds(7, 6))]
    assert "variable bowl_pitch equal " in text
    assert all_same(p.body_template, chip_template(3e-4, 1.5e-4))
    want = bowl_mesh(bowl_from({k: float(v) for k, v in BOWL_VALUES.items() if k != "shape"}))
    assert np.array_equal(p.track[0], want[0]) and np.array_equal(p.track[1], want[1])
    assert p.variables == {"mesh_dir": str(folder.resolve())}
