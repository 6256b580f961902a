"""The declining chute (vibrofeed.feeders.chute), the element kind added as one module: its floor,
mesh, joints and refusals against geometry computed by hand, and its commands in the deck."""

import math
from collections import Counter

import numpy as np
import pytest

from helpers import REPO
from vibrofeed.decks import Deck
from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.chute import Chute
from vibrofeed.feeders.deck import line_files
from vibrofeed.parameters import resolve

TAN = {deg: math.tan(math.radians(deg)) for deg in (5, 10)}
# a level 4 mm section (50 um normal stroke), then a 3 mm chute 5 deg down, 80 um below it
LINE = {"sections": 2, "part_size": 3e-4, "track_length": 4e-3, "track_width": 1.2e-3,
        "wall_height": 1e-3, "freq": 100, "amp_t": 3.5e-5, "amp_n": 5e-5,
        "s2_kind": 1, "s2_length": 3e-3, "s2_width": 1.2e-3, "s2_wall_height": 1e-3,
        "s2_step": 8e-5, "s2_slope": 5, "s2_cross_tilt": 10}


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


def test_the_chute_descends_from_its_step_by_its_slope():
    f = Feeder.from_values(LINE)
    c = f.elements[1]
    assert isinstance(c, Chute) and f.further_elements == (c,) and f.sections == 2
    assert (c.x0, c.x1) == (4e-3, pytest.approx(7e-3, abs=1e-15))
    # high edge (y = +0.6 mm): 80 um below at its start, 80 um + 3 mm tan 5 at its end
    assert c.entry_z(6e-4) == pytest.approx(-8e-5, abs=1e-18)
    assert c.exit_z(6e-4) == pytest.approx(-8e-5 - 3e-3 * TAN[5], rel=1e-12)
    assert c.exit_level == pytest.approx(8e-5 + 3e-3 * TAN[5], rel=1e-12)
    # its lowest point: the end, at the reference wall, 1.2 mm tan 10 lower again
    assert c.lowest == pytest.approx(-8e-5 - 3e-3 * TAN[5] - 1.2e-3 * TAN[10], rel=1e-12)


def test_a_section_after_the_chute_starts_below_its_end():
    f = Feeder.from_values({**LINE, "sections": 3, "s3_length": 2e-3, "s3_width": 1.2e-3,
                            "s3_wall_height": 6e-4, "s3_step": 5e-5, "s3_cross_tilt": 10,
                            "s3_freq": 100, "s3_amp_t": 1e-4, "s3_amp_n": 2e-5})
    s3 = f.elements[2]
    assert s3.x0 == pytest.approx(7e-3, abs=1e-15)
    assert s3.level == pytest.approx(8e-5 + 3e-3 * TAN[5] + 5e-5, rel=1e-12)
    # the joint from the chute: the step across its exit is 50 um (both tilted alike)
    assert f.joints[1].steps == (pytest.approx(5e-5, rel=1e-9), pytest.approx(5e-5, rel=1e-9))
    # the chute stands still: the joint opens by the next section's own strokes
    assert f.joints[1].motion == (pytest.approx(2e-5, rel=1e-12), pytest.approx(1e-4, rel=1e-12))
    f.check()


def test_the_joint_onto_a_chute_must_clear_the_section_strokes():
    # the chute does not move: the floors part by section 1's whole 50 um normal stroke
    assert Feeder.from_values(LINE).joints[0].motion == (pytest.approx(5e-5, rel=1e-12),
                                                          pytest.approx(3.5e-5, rel=1e-12))
    with pytest.raises(ParameterError, match=r"^s2_step=4e-05 m: the joint must step down by more than "
                                             r"the floors move apart normal to them \(5e-05 m"):
        Feeder.from_values({**LINE, "s2_step": 4e-5, "s2_cross_tilt": 0}).check()


def test_the_chutes_mesh_is_its_floor_and_two_walls_open_at_both_ends():
    c = Feeder.from_values(LINE).elements[1]
    v, t = c.mesh()
    # every floor vertex on the plane z(x, y); wall tops wall_height above the high edge
    # (the mesh keeps vertices to 1e-12 m)
    on_floor = np.isclose(v[:, 2], c.floor_z(v[:, 0], v[:, 1]), rtol=0, atol=1e-12)
    tops = np.isclose(v[:, 2], c.floor_z(v[:, 0], 6e-4) + 1e-3, rtol=0, atol=1e-12)
    assert (on_floor | tops).all() and on_floor.sum() > 4 and tops.sum() > 2
    assert v[:, 0].min() == pytest.approx(4e-3, abs=1e-15) and v[:, 0].max() == pytest.approx(7e-3, abs=1e-15)
    # open edges only at the joint, the end and the wall tops: no open edge inside
    e = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    open_edges = [edge for edge, n in Counter(map(tuple, e)).items() if n == 1]
    for a, b in open_edges:
        pa, pb = v[a], v[b]
        at_end = any(np.isclose([pa[0], pb[0]], x, atol=1e-12).all() for x in (4e-3, 7e-3))
        at_top = tops[a] and tops[b]
        assert at_end or at_top, (pa, pb)


@pytest.mark.parametrize("change, words", [
    ({"s2_slope": 0}, "s2_slope=0 deg must be in (0, 60]: a chute descends"),
    ({"s2_slope": 61}, "s2_slope=61 deg must be in (0, 60]"),
    ({"s2_width": 2e-4}, "s2_width=0.0002 m is narrower than a part"),
    ({"s2_wall_height": 1e-4}, "s2_wall_height=0.0001 m is no higher than a part's centre"),
    ({"s2_kind": 3}, "s2_kind=3 must be 0 (a linear section), 1 (a chute) or 2 (a mesh)"),
])
def test_a_chute_that_does_not_work_is_refused_in_one_line(change, words):
    with pytest.raises(ParameterError) as err:
        Feeder.from_values({**LINE, **change}).check()
    assert words in str(err.value) and "\n" not in str(err.value)


def test_the_chutes_commands_stand_still_and_take_the_free_fall_speed():
    files = line_files(Feeder.from_values(LINE))
    assert "fix track_s2 all mesh/surface file ${mesh_dir}/track_s2.stl type 2\n" in files["line_meshes.in"]
    assert "variable s2_peak equal sqrt(2*v_g*v_s2_length*tan(v_s2_slope*PI/180))" in files["line_derived.in"]
    assert "s2_shake" not in files["line_motion.in"]
    for axis in ("x", "y", "z", "vx", "vy", "vz"):
        assert f"variable s2_surface_{axis} equal 0" in files["line_motion.in"]


def test_the_example_line_with_a_chute_resolves_and_names_its_keys():
    deck = Deck.find(REPO / "feeders" / "chute_line.toml")
    values = resolve(deck, {"element.2.slope": "8"})
    assert values["s2_kind"] == "1" and values["s2_slope"] == "8"
    assert "s2_amp_t" not in deck.tunables  # a chute has no drive
    assert deck.aliases["element.2.slope"] == "s2_slope"
    f = Feeder.from_values(values)
    assert [e.kind for e in f.elements] == ["linear", "chute", "linear"]
    assert f.section_values(2) is None  # undriven: no vibration model


def test_a_chute_cannot_come_first(tmp_path):
    from vibrofeed.feeders.description import read

    path = tmp_path / "c.toml"
    path.write_text('[parts]\nsize = 3e-4\n[[element]]\nkind = "chute"\nlength = 0.003\nwidth = 1e-3\n'
                    'slope = 5\n')
    with pytest.raises(ParameterError, match='element 1: kind = "chute": the first element is a linear '
                                             'section'):
        read(path)
