"""What the rest of vibrofeed asks a feeder instead of its kind (vibrofeed.feeders.Feeder): how
many elements it has, whether it turns, has rejects, returns them, carries an air jet, reports
by section; the parameter rules' questions of a set that may be partial; a bowl's turn. Four
feeders built by hand: a single track, a two-section line, a bowl alone, a bowl with an exit
line."""

import math

import pytest
from feeder_values import BOWL, BOWL_LINE, LINE, TRACK

from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.bowl import TURN_NAMES, Turn
from vibrofeed.feeders.feeder import inserts_between_walls, side_tools_unprefixed, starts_with_bowl


@pytest.mark.parametrize("values, elements, several, rotates, rejects, path_is_x", [
    (TRACK, 1, False, False, False, True),
    (LINE, 2, True, False, True, True),
    (BOWL, 1, True, True, False, False),        # its path: the helix, then the chute
    (BOWL_LINE, 2, True, True, True, False),
])
def test_each_feeder_says_what_it_has(values, elements, several, rotates, rejects, path_is_x):
    f = Feeder.from_values(values)
    assert f.path_is_x is path_is_x
    assert f.n_elements == elements and f.further_elements == f.elements[1:]
    assert len(f.further_elements) == elements - 1
    assert f.several_sections is several
    assert f.rotates is rotates
    assert f.has_rejects is rejects
    assert f.returns_rejects is False and f.has_jets is False


def test_only_a_feeder_with_rejects_returns_them():
    assert Feeder.from_values({**LINE, "recirculate": 1}).returns_rejects is True
    assert Feeder.from_values({**BOWL_LINE, "recirculate": 1}).returns_rejects is True
    # a single track has none to return (its check refuses recirculate=1: not asked here)
    assert Feeder.from_values({**TRACK, "recirculate": 1}).returns_rejects is False


def test_an_air_jet_on_a_further_section_is_seen():
    jet = {**LINE, "s2_drop_to": 0, "s2_jet_force": 1e-6, "s2_jet_at": 0.25}
    assert Feeder.from_values(jet).has_jets is True
    assert Feeder.from_values({**jet, "s2_jet_force": 0}).has_jets is False


@pytest.mark.parametrize("values, bowl", [(TRACK, False), (LINE, False), (BOWL, True), (BOWL_LINE, True),
                                          ({"bowl_diameter": 0.02}, True), ({"freq": 50}, False)])
def test_the_parameter_rules_questions_of_a_partial_set(values, bowl):
    """Asked of any set, a partial one too (no Feeder is made of it)."""
    assert starts_with_bowl(values) is bowl
    assert inserts_between_walls(values) is not bowl      # a bowl drops its parts into itself
    assert side_tools_unprefixed(values) is bowl          # drop_from, wiper_height: the bowl's helix
    if len(values) > 2:  # a whole feeder decides its kind by the same test
        assert Feeder.from_values(values).rotates is bowl


def test_check_values_checks_a_whole_line_and_only_the_return_of_the_rest():
    Feeder.check_values(LINE)
    too_narrow = {**LINE, "s2_width": 2e-4}   # narrower than a part: section 2's own check
    with pytest.raises(ParameterError, match="s2_width"):
        Feeder.check_values(too_narrow)
    # a partial set and a bowl: their rejects' return only
    Feeder.check_values({"freq": 50})
    Feeder.check_values({**BOWL_LINE, "s2_width": 2e-4})   # (checked with its geometry instead)
    for values in ({"recirculate": 2}, {**BOWL, "recirculate": 0.5}):
        with pytest.raises(ParameterError, match=r"recirculate=.* must be 0 \(rejects removed\) or 1"):
            Feeder.check_values(values)
    with pytest.raises(ParameterError, match=r"return_delay=-0.1 s must be >= 0"):
        Feeder.check_values({**BOWL, "return_delay": -0.1})
    with pytest.raises(ParameterError, match=r"return_delay=-0.1 s must be >= 0"):
        Feeder.check_values({**LINE, "return_delay": -0.1})


def test_a_bowls_turn_is_its_stroke_over_its_centre_lines_radius():
    # r_mid = 10 mm - 0.6 mm = 9.4 mm: 200 um along it turns the bowl by 21.3 mrad
    turn = Turn.from_values(BOWL)
    assert turn.angle == pytest.approx(2e-4 / 9.4e-3, rel=1e-12)
    assert (turn.freq, turn.lift, turn.phase) == (75.0, pytest.approx(4e-5, rel=1e-12), -60.0)
    # its parameters alone make it (a file may record no more of the bowl), strings as well
    alone = Turn.from_values({name: repr(float(BOWL[name])) for name in TURN_NAMES})
    assert alone.angle == pytest.approx(turn.angle, rel=1e-12)
    # the bowl element's own geometry agrees: the same centre line
    assert Feeder.from_values(BOWL).bowl.r_mid == pytest.approx(9.4e-3, rel=1e-12)
    assert math.isclose(2e-4 / Feeder.from_values(BOWL).bowl.r_mid, turn.angle, rel_tol=1e-12)
    with pytest.raises(ParameterError, match="track_width"):
        Turn.from_values({k: v for k, v in BOWL.items() if k != "track_width"})


def test_the_element_count_is_read_from_the_parameters_alone():
    """A result's recorded surface motions: its sections, at least 1; 1 where the parameter is
    absent or no number (a result stays readable), and the built feeder's own count."""
    from vibrofeed.feeders.feeder import element_count

    for values, n in (({}, 1), ({"sections": "3"}, 3), ({"sections": 2.0}, 2), ({"sections": "abc"}, 1),
                      ({"sections": float("nan")}, 1), ({"sections": "0"}, 1)):
        assert element_count(values) == n, values
