"""A bowl with an exit line (vibrofeed.feeders.bowl and Feeder): the exit line's frame at the
chute's end, the joint's sway, the path running on from the chute, the meshes, stations and
the section models, against geometry computed by hand from the bowl's own numbers."""

import math

import numpy as np
import pytest

from helpers import REPO
from vibrofeed.decks import Deck
from vibrofeed.errors import ParameterError
from vibrofeed.feeders import BowlElement, Feeder, LinearSection
from vibrofeed.feeders.deck import line_files
from vibrofeed.parameters import resolve

R, W, HELIX, TURNS, CHUTE, TILT = 0.01, 1.2e-3, 3.0, 0.5, 6e-3, 3.0
AMP_T, AMP_N = 2e-4, 4e-5
# the demo's bowl of dies with a 10 mm exit section, twice its stroke, tilted 10 deg
BOWL_LINE = {"bowl_diameter": 2 * R, "track_width": W, "helix_angle": HELIX, "turns": TURNS,
             "wall_height": 1e-3, "cross_tilt": TILT, "chute_length": CHUTE, "shape": 1,
             "part_size": 5e-4, "part_thickness": 2.5e-4, "freq": 75, "amp_t": AMP_T,
             "amp_n": AMP_N, "phase": -60, "sections": 2, "s2_length": 0.01, "s2_width": 1.5e-3,
             "s2_wall_height": 1e-3, "s2_step": 5e-5, "s2_cross_tilt": 10, "s2_freq": 75,
             "s2_amp_t": 4e-4, "s2_amp_n": 4e-5, "s2_phase": -60, "s2_drop_from": 0.2,
             "s2_drop_to": 0.5, "s2_drop_width": 5.5e-4, "s2_wiper_height": 4e-4, "s2_wiper_at": 0.7}
R_MID = R - W / 2
COS, SIN = math.cos(math.radians(HELIX)), math.sin(math.radians(HELIX))
OUTLET_X = CHUTE * COS  # the chute's end, the exit line's start
HELIX_LENGTH = 2 * math.pi * TURNS * R_MID / COS


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


def test_the_exit_line_starts_at_the_chutes_end_on_its_centre_line():
    f = Feeder.from_values(BOWL_LINE)
    bowl, line = f.elements
    assert isinstance(bowl, BowlElement) and isinstance(line, LinearSection) and f.further_elements == (line,)
    assert line.x0 == pytest.approx(OUTLET_X, rel=1e-12) and f.bowl is bowl.bowl
    # the chute's floor at its end, high (inner) edge: the helix's end height, the chute's rise,
    # half the width's cross tilt up from the centre line
    end_z = bowl.bowl.end_z
    ox, oy, oz = f.line_origin
    assert (ox, oy) == (0.0, pytest.approx(-R_MID, rel=1e-12))
    assert oz == pytest.approx(end_z + CHUTE * SIN + W / 2 * math.tan(math.radians(TILT)), rel=1e-12)
    # along the path: the helix, the chute, then the line, shifted on from the chute's end
    (h0, h1), (c0, c1), (l0, l1) = f.bounds
    assert (h0, h1, c0) == (0.0, pytest.approx(HELIX_LENGTH, rel=1e-12), h1)
    assert c1 == pytest.approx(HELIX_LENGTH + CHUTE, rel=1e-12) and l0 == pytest.approx(c1, rel=1e-12)
    assert l1 == pytest.approx(c1 + 0.01, rel=1e-12) and f.path_end == l1
    assert f.path_shift == pytest.approx(HELIX_LENGTH + CHUTE - OUTLET_X, rel=1e-12)
    # the catch plane sorts rejects by the deck's x: the helix anywhere, the chute from the slot
    assert f.catch_x == [-math.inf, 0.0, pytest.approx(OUTLET_X, rel=1e-12)]
    assert list(f.element_at_x([-R, 0.5 * OUTLET_X, OUTLET_X + 1e-3, 1.0])) == [0, 0, 1, 1]


def test_the_outlets_band_is_the_exit_sections_walls_about_the_chutes_centre_line_and_a_die():
    # the exit section 1.5 mm wide on the chute's centre line y = -r_mid, widened by a die's edge
    assert Feeder.from_values(BOWL_LINE).exit_band == pytest.approx(
        (-R_MID - 0.75e-3 - 5e-4, -R_MID + 0.75e-3 + 5e-4), rel=0, abs=1e-15)
    # a bowl alone: its chute's walls
    alone = {k: v for k, v in BOWL_LINE.items() if not k.startswith("s2_") and k != "sections"}
    assert Feeder.from_values(alone).exit_band == pytest.approx(
        (-R_MID - W / 2 - 5e-4, -R_MID + W / 2 + 5e-4), rel=0, abs=1e-15)


def test_a_jet_on_the_exit_line_records_its_firings_on_the_path_section_its_rejects_have():
    # helix 1, chute 2, the exit section 3 (its element is 2, its deck names s2_jet_*)
    from vibrofeed.engine.jets import Jets

    f = Feeder.from_values({**BOWL_LINE, "s2_jet_force": 4e-6, "s2_jet_at": 0.6,
                            "s2_jet_keep": "up,any-direction", "s2_jet_mode": "ideal"})
    (st,) = Jets(f).stations
    assert (st.section, st.path_section) == (2, 3)
    assert [s.section for s in f.stations if s.kind == "jet"] == [3]


def test_the_chutes_end_is_an_exit_with_its_tilt_stroke_and_sway():
    bowl = Feeder.from_values(BOWL_LINE).elements[0]
    tan = math.tan(math.radians(TILT))
    assert bowl.exit_width == W and bowl.exit_z(W / 2) == 0.0
    assert bowl.exit_z(-W / 2) == pytest.approx(-W * tan, rel=1e-12)
    # the torsion: amp_t / r_mid of a turn, times the end's distance from the axis along x
    assert bowl.sway == pytest.approx(AMP_T / R_MID * OUTLET_X, rel=1e-12)
    assert (bowl.drive.amp_t, bowl.drive.amp_n, bowl.drive.phase) == (AMP_T, AMP_N, -60)
    np.testing.assert_allclose(bowl.exit_direction, (COS, 0.0, SIN), rtol=0, atol=1e-15)


def test_the_joint_wants_the_chute_and_its_sway_either_way():
    need = W + 2 * AMP_T / R_MID * OUTLET_X  # 1.2 mm + 2 x 0.127 mm
    Feeder.from_values({**BOWL_LINE, "s2_width": need * 1.001}).check()
    with pytest.raises(ParameterError, match=r"^s2_width=0.00145 m is narrower than the bowl's chute "
                                             r"\(0.0012 m, swaying 0.000127 m either way"):
        Feeder.from_values({**BOWL_LINE, "s2_width": 1.45e-3}).check()
    # the step at its least (the inner edge, y = +0.6 mm: the chute's floor there is the origin,
    # the line's 50 um + 0.15 mm tan 10 lower) against the floors' relative lift: 40 um at
    # -60 deg against 40 um at +120 deg move apart by 80 um; at +30 deg by 40 sqrt(2) = 56.6 um
    least = 5e-5 + 1.5e-4 * math.tan(math.radians(10))
    assert Feeder.from_values(BOWL_LINE).joints[0].steps[0] == pytest.approx(least, rel=1e-12)
    Feeder.from_values({**BOWL_LINE, "s2_phase": 30}).check()
    with pytest.raises(ParameterError, match=r"^s2_step=5e-05 m: the joint must step down by more "
                                             r"than the floors move apart normal to them \(8e-05 m.*"
                                             r"a step of 7.64e-05 m at its least"):
        Feeder.from_values({**BOWL_LINE, "s2_phase": 120}).check()
    with pytest.raises(ParameterError, match="recirculate=1: a bowl returns its rejects itself"):
        Feeder.from_values({**BOWL_LINE, "recirculate": 1}).check()


def test_the_line_mesh_lies_in_the_bowls_frame_after_the_chute():
    f = Feeder.from_values(BOWL_LINE)
    (vertices, _), = f.further_meshes()
    _, oy, oz = f.line_origin
    line = f.elements[1]
    assert vertices[:, 0].min() == pytest.approx(OUTLET_X, rel=1e-12)
    assert vertices[:, 0].max() == pytest.approx(OUTLET_X + 0.01, rel=1e-12)
    assert vertices[:, 1].min() == pytest.approx(oy - 7.5e-4, rel=1e-12)
    assert vertices[:, 1].max() == pytest.approx(oy + 7.5e-4, rel=1e-12)
    # the floor's lowest (the reference wall): the step, then 1.5 mm of 10 deg tilt below the origin
    assert vertices[:, 2].min() == pytest.approx(oz - 5e-5 - 1.5e-3 * math.tan(math.radians(10)),
                                                 rel=1e-12)
    assert line.lowest == pytest.approx(vertices[:, 2].min() - oz, rel=1e-12)


def test_a_part_on_the_exit_line_has_its_path_coordinate_and_one_beside_it_none():
    f = Feeder.from_values(BOWL_LINE)
    _, oy, oz = f.line_origin
    on = [OUTLET_X + 3e-3, oy, oz - 5e-5 + 1.25e-4]        # lying on the floor, 3 mm along
    beside = [OUTLET_X + 3e-3, oy + 2e-3, oz]               # outside its walls
    below = [OUTLET_X + 3e-3, oy, oz - 2e-3]                # fallen off, under it
    before = [0.5 * OUTLET_X, oy, oz]                       # over the chute: the bowl's path
    s = f.line_coordinate([on, beside, below, before])
    assert s[0] == pytest.approx(HELIX_LENGTH + CHUTE + 3e-3, rel=1e-12)
    assert np.isnan(s[1:]).all()
    # the profile in height: the line's centre line floor beyond the chute's end
    h = f.height_at([HELIX_LENGTH + CHUTE + 3e-3])
    assert h[0] == pytest.approx(oz - 5e-5 - 7.5e-4 * math.tan(math.radians(10)), rel=1e-12)


def test_the_exit_lines_tools_are_stations_on_its_path_section():
    f = Feeder.from_values(BOWL_LINE)
    drop, wiper = f.stations
    start = HELIX_LENGTH + CHUTE
    assert (drop.section, drop.kind) == (3, "side_drop") and (wiper.section, wiper.kind) == (3, "wiper")
    assert (drop.start, drop.end) == (pytest.approx(start + 2e-3, rel=1e-12),
                                      pytest.approx(start + 5e-3, rel=1e-12))
    assert (wiper.start, wiper.end) == (pytest.approx(start + 7e-3, rel=1e-12),
                                        pytest.approx(start + 7.5e-3, rel=1e-12))


def test_each_sections_model_takes_its_own_drive_a_lines_level_and_without_the_bowl():
    f = Feeder.from_values(BOWL_LINE)
    assert f.section_values(1) == BOWL_LINE and f.section_values(2) == BOWL_LINE
    three = f.section_values(3)
    assert "bowl_diameter" not in three and three["incline"] == 0.0
    assert (three["amp_t"], three["amp_n"], three["phase"], three["waveform"]) == (4e-4, 4e-5, -60, 0)


def test_the_line_files_name_the_bowl_and_its_outlet():
    files = line_files(Feeder.from_values(BOWL_LINE))
    assert "meshes bowl track_s2" in files["line_meshes.in"]
    assert "variable outlet_x equal v_bowl_outlet_x+v_s2_length" in files["line_derived.in"]
    assert "variable s1_peak equal $(v_v_peak)" in files["line_derived.in"]
    assert "move ${bowl_outlet_x} $(-v_bowl_r_mid) ${catch_z}" in files["line_catch.in"]
    alone = line_files(Feeder.from_values({**BOWL_LINE, "sections": 1}))
    assert alone["line_meshes.in"].splitlines()[1:] == [
        "fix walls all wall/gran ${gran_model} mesh n_meshes 1 meshes bowl &",
        "     tangential_damping ${tdamp} limitForce ${limitf}"]
    assert all(len(text.splitlines()) == 1 for name, text in alone.items() if name != "line_meshes.in")


def test_the_bowl_line_description_becomes_the_bowl_deck_with_its_exit_line():
    deck = Deck.find(REPO / "feeders" / "bowl_line.toml")
    assert deck.description.template == "bowl_feeder" and deck.prepare_target.endswith("prepare_bowl_feeder")
    values = resolve(deck, {})
    assert values["bowl_diameter"] == "0.02" and values["s2_amp_t"] == "0.0004"
    assert resolve(deck, {"element.1.drive.amp_t": "1.5e-4"})["amp_t"] == "1.5e-4"
    f = Feeder.from_values(values)
    assert [e.kind for e in f.elements] == ["bowl", "linear"]


def test_a_bowl_description_with_a_number_its_deck_lacks_is_refused(tmp_path):
    text = (REPO / "feeders" / "bowl_line.toml").read_text().replace(
        "n_track = 40", "n_track = 40\ninlet_rate = 30")
    path = tmp_path / "b.toml"
    path.write_text(text)
    with pytest.raises(ParameterError, match=r"^b.toml: supply.inlet_rate: a feeder whose first element "
                                             r"is a bowl has no such number"):
        Deck.find(path)


def test_the_store_a_pre_fill_drains_is_the_first_elements_sections():
    from vibrofeed.postproc.feedrate import store_sections

    assert store_sections(BOWL_LINE) == 2  # the helix and the chute: the exit line must hold
    assert store_sections({**BOWL_LINE, "sections": 1}) == 2
    line = {"part_size": 3e-4, "track_length": 4e-3, "track_width": 1.2e-3, "wall_height": 1e-3,
            "sections": 2, "s2_length": 4e-3, "s2_width": 1.2e-3, "s2_wall_height": 1e-3, "s2_step": 5e-5}
    assert store_sections(line) == 1 and store_sections({}) == 1  # (no feeder: a single track)


def test_every_number_of_a_linear_section_is_declared_after_a_bowl_as_after_a_section():
    """A bowl's exit section takes the line's tooling: every s2_* number the bulk deck declares
    for a section, bowl_feeder declares too (their gate, cross stroke and slot were once
    missing, and a description's gate on a bowl's exit line was dropped without a word)."""
    from vibrofeed.decks import decks_dir
    from vibrofeed.feeders.linear import deck_names

    bulk, bowl = (Deck(decks_dir() / f"{n}.liggghts").tunables for n in ("bulk_feeder", "bowl_feeder"))
    linear = set(deck_names(2).values())
    assert linear <= set(bulk) and linear <= set(bowl)
    assert {n for n in bulk if n.startswith("s2_")} <= set(bowl)


def test_a_gate_on_a_bowls_exit_section_is_built(tmp_path):
    """The exit section's gate narrows its walls: the mesh's half-width past the taper is the
    gate's, before it the section's."""
    text = (REPO / "feeders" / "bowl_line.toml").read_text()
    drop = "side_drop = { from = 0.4, to = 0.9, width = 6.5e-4 }"
    assert drop in text
    path = tmp_path / "g.toml"
    path.write_text(text.replace(drop, "gate = { width = 6.5e-4, at = 0.2 }"))
    values = resolve(Deck.find(path), {})
    assert (float(values["s2_gate_width"]), float(values["s2_gate_at"])) == (6.5e-4, 0.2)
    line = Feeder.from_values(values).elements[1]
    assert line.gate is not None and line.gate.width == 6.5e-4
    s = line.mesh_section()
    assert s.half_width(s.x0 + 0.1 * s.length) == pytest.approx(1.5e-3 / 2, rel=1e-12)
    assert s.half_width(s.x0 + 0.5 * s.length) == pytest.approx(6.5e-4 / 2, rel=1e-12)


def test_a_further_number_its_deck_does_not_declare_is_refused_not_dropped(tmp_path):
    from vibrofeed.decks import decks_dir
    from vibrofeed.feeders.description import deck_text, read

    template = (decks_dir() / "bowl_feeder.liggghts").read_text()
    lacking = "\n".join(line for line in template.splitlines() if not line.startswith("variable s2_gate"))
    text = (REPO / "feeders" / "bowl_line.toml").read_text().replace(
        "side_drop = { from = 0.4, to = 0.9, width = 6.5e-4 }", "gate = { width = 6.5e-4, at = 0.2 }")
    path = tmp_path / "g.toml"
    path.write_text(text)
    described = read(path)
    with pytest.raises(ParameterError, match=r"^g.toml: element.2.gate.width: a feeder whose first element "
                                             r"is a bowl has no such number in this version"):
        deck_text(described, lacking, Deck.parse_variables(lacking))


def test_a_cad_detour_after_the_bowl_runs_on_along_its_path_then_on_along_x(tmp_path):
    """The bowl's exit line a detour from CAD (legs of 2, 2.5, 2, 2.5 and 2 mm: 11 mm of path for
    10 mm along x, 1.5 mm wide, 0.1 mm below the chute's end), then a 4 mm section 50 um below
    it: the path, the floor's height along it and the rejects' places run on over both."""
    from helpers import channel
    from vibrofeed.feeders.mesh_element import path_text
    from vibrofeed.mesh import write_stl

    plan = [(0, 0, 0), (2, 0, 0), (4, 1.5, 0), (6, 1.5, 0), (8, 0, 0), (10, 0, 0)]
    write_stl(*channel(plan, 1.5, 1.0), tmp_path / "detour.stl", "detour")
    values = {k: v for k, v in BOWL_LINE.items() if not k.startswith("s2_")}
    values.update({"sections": 3, "s2_kind": 2, "s2_file": str(tmp_path / "detour.stl"), "s2_unit": 1e-3,
                   "s2_path": path_text(plan), "s2_width": 1.5e-3, "s2_step": 1e-4, "s2_freq": 75,
                   "s2_amp_t": 4e-4, "s2_amp_n": 4e-5, "s2_phase": -60, "s3_length": 4e-3,
                   "s3_width": 1.5e-3, "s3_wall_height": 1e-3, "s3_step": 5e-5, "s3_freq": 75,
                   "s3_amp_t": 4e-4, "s3_amp_n": 4e-5, "s3_phase": -60})
    f = Feeder.from_values(values)
    f.check()
    c1 = HELIX_LENGTH + CHUTE
    want = [c1, c1 + 11e-3, c1 + 15e-3]
    assert np.abs(np.array([b for _, b in f.bounds[1:]]) - want).max() <= 1e-12
    # the floor on the centre line, from the exit line's frame (the chute's end, high edge):
    # 0.1 mm down over the detour, 0.15 mm down over the section after it
    oz = f.line_origin[2]
    h = f.height_at([c1 + 5e-3, c1 + 13e-3])
    assert np.abs(h - [oz - 1e-4, oz - 1.5e-4]).max() <= 1e-12
    # a reject that fell at the deck's x 1 mm past the detour's end: 1 mm into the section after it
    assert f.path_at_x([OUTLET_X + 11e-3])[0] == pytest.approx(c1 + 12e-3, abs=1e-12)
