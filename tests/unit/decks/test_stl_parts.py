"""A designer's own part from an STL (shape 4, vibrofeed.stl_part): a box's STL gives the box's
closed-form mass, centre of mass and principal moments, in the box frame; CLUMP's clump of it
lies about the centre of mass with its fidelity within stated bounds; bad inputs are one line
each; the description's [parts] keys and prepare's files and variables."""

import math

import numpy as np
import pytest
import trimesh

from vibrofeed.errors import ParameterError
from vibrofeed.feeders.description import read
from vibrofeed.geometry import prepare_bulk_feeder
from vibrofeed.stl_part import StlPart, engine_inertia, fidelity, fidelity_line, sizes, solid, template

L, W, T = 1.0, 0.5, 0.35  # mm
SHIFT = (3.0, -2.0, 1.5)  # mm: the STL's frame is not the part's


@pytest.fixture(scope="module")
def box_stl(tmp_path_factory):
    """A 1.0 x 0.5 x 0.35 mm box, turned 30 degrees about z and moved off the origin."""
    mesh = trimesh.creation.box(extents=(L, W, T))
    mesh.apply_transform(trimesh.transformations.rotation_matrix(math.radians(30), (0, 0, 1)))
    mesh.apply_translation(SHIFT)
    path = tmp_path_factory.mktemp("stl") / "box.stl"
    mesh.export(path)
    return str(path)


def test_a_box_stl_gives_the_box_closed_forms_in_the_box_frame(box_stl):
    s = solid(StlPart(box_stl, 1e-3))
    Lm, Wm, Tm = L * 1e-3, W * 1e-3, T * 1e-3
    volume = Lm * Wm * Tm
    # the STL holds single-precision coordinates: 1e-7 relative, far above float64's rounding
    assert s.volume == pytest.approx(volume, rel=1e-6)
    assert np.allclose(s.com, np.array(SHIFT) * 1e-3, rtol=0, atol=1e-6 * Lm)
    exact = volume / 12 * np.array([Wm**2 + Tm**2, Lm**2 + Tm**2, Lm**2 + Wm**2])  # per unit density
    assert np.allclose(s.moments, exact, rtol=1e-5, atol=0)  # ascending: x along L, z across T
    c, h = math.cos(math.radians(30)), math.sin(math.radians(30))
    assert np.allclose(s.axes, [[c, -h, 0], [h, c, 0], [0, 0, 1]], atol=1e-5)  # the box's turn
    assert np.allclose(s.extents, [Lm, Wm, Tm], rtol=1e-5, atol=0)
    assert sizes(StlPart(box_stl, 1e-3)) == pytest.approx((Lm, Wm, Tm), rel=1e-5)
    mass, inertia = engine_inertia(StlPart(box_stl, 1e-3), 2330.0)
    assert mass == pytest.approx(2330.0 * volume, rel=1e-6)
    assert inertia[1] == inertia[2] == inertia[4] == 0.0
    assert np.allclose(np.array(inertia)[[0, 3, 5]], 2330.0 * exact, rtol=1e-5, atol=0)


@pytest.mark.parametrize("method, spheres, bounds", [
    # (volume error, COM offset / L, the principal moments' errors, surface mean / L, max / L):
    # the figures measured for this box (docs/parts.md) with a margin, so that a clump moved off
    # the centre of mass, out of the principal frame, or scaled by the unit twice fails
    (0, 60, (0.08, 0.02, 0.15, 0.02, 0.12)),
    (2, 60, (0.35, 0.02, 0.50, 0.04, 0.15)),
])
def test_the_clump_lies_on_the_solid_within_its_stated_fidelity(box_stl, method, spheres, bounds):
    part = StlPart(box_stl, 1e-3, method=method, spheres=spheres)
    rows = template(part)
    assert rows.shape[1] == 4 and len(rows) <= spheres and np.all(rows[:, 3] > 0)
    f = fidelity(part)
    volume, com, inertia, mean, most = bounds
    Lm = L * 1e-3
    assert abs(f["volume_error"]) < volume, f
    assert f["com_offset"] < com * Lm, f
    assert np.all(np.abs(f["inertia_errors"]) < inertia), f
    assert f["surface_mean"] < mean * Lm and f["surface_max"] < most * Lm, f
    # every sphere's centre inside the solid (the body frame, about its centre of mass)
    assert np.all(np.abs(rows[:, :3]) <= np.array([L, W, T]) * 1e-3 / 2 + 1e-9)
    assert "spheres" in fidelity_line(part, f)


def test_the_euclidean_clump_is_the_boxs_whatever_its_place_in_the_stl(box_stl, tmp_path):
    """The same box at the STL's origin, unturned: the same clump (to the voxels' registration)."""
    trimesh.creation.box(extents=(L, W, T)).export(tmp_path / "plain.stl")
    a = template(StlPart(box_stl, 1e-3, spheres=20))
    b = template(StlPart(str(tmp_path / "plain.stl"), 1e-3, spheres=20))
    assert len(a) == len(b)
    assert np.allclose(np.sort(a[:, 3]), np.sort(b[:, 3]), rtol=0, atol=0.05 * T * 1e-3)


def test_bad_stls_are_one_line_each(tmp_path, box_stl):
    open_box = trimesh.creation.box(extents=(L, W, T))
    open_box.update_faces(np.arange(len(open_box.faces)) > 0)  # one triangle missing: a hole
    open_box.export(tmp_path / "open.stl")
    flipped = trimesh.creation.box(extents=(L, W, T))
    flipped.faces[0] = flipped.faces[0][::-1]  # one triangle wound the other way
    flipped.export(tmp_path / "flipped.stl")
    cases = {
        str(tmp_path / "open.stl"): (1e-3, "open.stl is not watertight"),
        str(tmp_path / "flipped.stl"): (1e-3, "flipped.stl: its triangles are not wound alike"),
        box_stl: (1.0, "is the unit mm?"),  # a 1 m box: millimetres read as metres
        str(tmp_path / "missing.stl"): (1e-3, "missing.stl: cannot read it"),
    }
    for file, (unit, said) in cases.items():
        with pytest.raises(ParameterError) as err:
            solid(StlPart(file, unit))
        message = str(err.value)
        assert said in message and "\n" not in message, message


def description(tmp_path, parts: str) -> str:
    path = tmp_path / "feeder.toml"
    path.write_text(f"[parts]\n{parts}\n[[element]]\nkind = \"linear\"\nlength = 0.005\nwidth = 2e-3\n")
    return path


def test_the_descriptions_parts_keys(tmp_path, box_stl):
    (tmp_path / "box.stl").write_bytes(open(box_stl, "rb").read())
    d = read(description(tmp_path, 'shape = "stl"\nfile = "box.stl"\nunit = "mm"\nmethod = "favier"\n'
                                   "spheres = 8\nresolution = 30\n"))
    v = d.values
    assert v["shape"] == "4" and v["part_file"] == str((tmp_path / "box.stl").resolve())
    assert float(v["part_unit"]) == 1e-3 and v["clump_method"] == "1"
    assert v["clump_spheres"] == "8" and v["clump_resolution"] == "30"
    refusals = {
        'shape = "stl"\nfile = "nowhere.stl"': 'parts.file = "nowhere.stl": no such file',
        'shape = "stl"\nfile = "box.stl"\nunit = "inch"': 'parts.unit = "inch"',
        'shape = "stl"\nfile = "box.stl"\nmethod = "octree"': 'parts.method = "octree"',
        'shape = "stl"\nfile = "box.stl"\nsize = 1e-3': "parts.size: an stl part's sizes are its STL's",
        'shape = "stl"': "needs parts.file",
        'shape = "box"\nfile = "box.stl"': "parts.file shapes an stl part",
    }
    for parts, said in refusals.items():
        with pytest.raises(ParameterError) as err:
            read(description(tmp_path, parts))
        assert said in str(err.value) and "\n" not in str(err.value), str(err.value)


def test_prepare_writes_the_template_and_the_variables_the_decks_read(tmp_path, box_stl):
    from vibrofeed.decks import Deck
    from vibrofeed.parameters import resolve

    deck = Deck.find("bulk_feeder")
    values = resolve(deck, {"shape": "stl", "part_file": box_stl, "clump_spheres": "20",
                            "track_width": "3e-3", "n_parts": "4"})
    assert float(values["part_size"]) == pytest.approx(1e-3, rel=1e-5)  # the STL's, derived
    assert float(values["part_thickness"]) == pytest.approx(3.5e-4, rel=1e-5)
    with pytest.raises(ParameterError, match="an stl part's sizes are its STL's"):
        resolve(deck, {"shape": "stl", "part_file": box_stl, "part_size": "2e-3", "track_width": "3e-3"})
    prepared = prepare_bulk_feeder(values, tmp_path)
    rows = np.loadtxt(tmp_path / "stl.multisphere")
    assert np.allclose(rows, prepared.body_template, rtol=0, atol=1e-15) and len(rows) == 20
    text = (tmp_path / "prepared.in").read_text()
    got = {line.split()[1]: float(line.split()[3]) for line in text.splitlines()
           if line.startswith("variable") and "_stl" in line}
    assert got["n_sph_stl"] == 20
    assert got["m_stl"] == pytest.approx(2330 * L * W * T * 1e-9, rel=1e-6)
    assert got["r_min_stl"] == pytest.approx(rows[:, 3].min(), rel=1e-12)
    assert got["r_ext_stl"] == \
        pytest.approx(np.max(np.linalg.norm(rows[:, :3], axis=1) + rows[:, 3]), rel=1e-12)
    assert got["I_stl_xy"] == got["I_stl_xz"] == got["I_stl_yz"] == 0
    assert got["I_stl_xx"] < got["I_stl_yy"] < got["I_stl_zz"]
    assert "clump_spheres} != 20.0" in text  # a run by hand is held to the clump it was made for
