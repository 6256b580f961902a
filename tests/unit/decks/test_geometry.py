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
    assert names == ["catch.stl", "chip.multisphere", "disc.multisphere", "prepared.in", "track.stl"]
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
