"""An orienting station's scheduling without the engine (vibrofeed.engine.jets), and what a
jet refuses (vibrofeed.feeders.linear)."""

import math
import warnings

import numpy as np
import pytest

from vibrofeed.engine.jets import (
    Jets,
    Station,
    atom_expression,
    atom_ranges,
    crossings,
    merged,
    window_expression,
)
from vibrofeed.errors import ParameterError
from vibrofeed.feeders.feeder import Feeder
from vibrofeed.orientation import parse_correct

UP = (1.0, 0.0, 0.0, 0.0)  # the body frame as the simulation's: marked face (+z) up
DOWN = (0.0, 1.0, 0.0, 0.0)  # turned 180 degrees about x: face down
LINE = {"part_size": "3e-4", "part_thickness": "1.5e-4", "shape": "1", "track_length": "2e-3",
        "track_width": "2e-3", "gate_width": "4.5e-4", "wall_height": "1e-3", "sections": "2",
        "s2_length": "3e-3", "s2_width": "4.5e-4", "s2_wall_height": "6e-4", "s2_step": "5e-5",
        "s2_freq": "100", "s2_amp_t": "6e-5", "s2_amp_n": "2e-5", "s2_jet_force": "1.5e-6",
        "s2_jet_at": "0.3", "s2_jet_keep": "up,any-direction"}


def frame(ids, x, q):
    n = len(ids)
    return {"id": np.asarray(ids), "position": np.column_stack([x, np.zeros(n), np.zeros(n)]),
            "orientation": np.asarray(q, dtype=float).reshape(n, 4)}


def test_a_crossing_is_timed_between_the_frames_and_only_parts_seen_at_both_count():
    # part 1 crosses x = 1 a quarter of the way; part 2 was already past; part 3 is new; part 4
    # goes back
    hit, t, first = crossings(1.0, 0.0, [4, 1, 2], [1.5, 0.9, 1.1], 0.1,
                              [1, 2, 3, 4], [1.3, 1.4, 2.0, 0.5])
    assert hit.tolist() == [0] and t == pytest.approx([0.025], rel=0, abs=1e-12) and first.tolist() == [True]


def test_windows_merge_where_they_overlap_and_the_formula_is_zero_or_one():
    assert merged([(0.3, 0.4), (0.1, 0.2), (0.15, 0.25), (0.25, 0.26), (0.5, 0.5)]) == \
        [(0.1, 0.26), (0.3, 0.4)]
    assert window_expression([]) == "0"
    assert window_expression([(0.2, 0.3), (0.1, 0.25)]) == "(time>=0.1)*(time<0.3)"
    formula = window_expression([(0.1, 0.2), (0.3, 0.4)])
    assert formula == "(time>=0.1)*(time<0.2)+(time>=0.3)*(time<0.4)"
    for time in (0.05, 0.15, 0.25, 0.35, 0.45):  # evaluated as LIGGGHTS would (booleans 0/1)
        assert eval(formula, {"time": time}) == (0.1 <= time < 0.2 or 0.3 <= time < 0.4)
    assert atom_expression([(10, 18, [(0.1, 0.2)]), (19, 27, [])]) == \
        "(id>=10)*(id<=18)*((time>=0.1)*(time<0.2))"


def station(**kw):
    return Station(**{"section": 2, "x_sense": 1.0, "keep": parse_correct("up, any-direction"),
                      "delay": 0.02, "duration": 0.01, "mode": "region", **kw})


def test_a_part_in_a_wrong_state_is_fired_at_after_the_delay_once_and_windows_are_pruned():
    s = station()
    prev = frame([1, 2], [0.9, 0.8], [DOWN, UP])
    now = frame([1, 2], [1.1, 1.2], [DOWN, UP])  # both cross; only the face-down one is fired at
    (f,) = s.sense(0.0, prev, 0.01, now)
    assert f[:4] == (pytest.approx(0.005, rel=0, abs=1e-12), 1, 2, 1)
    assert f[4:6] == pytest.approx((0.025, 0.035), rel=0, abs=1e-12)
    assert f[6] is False
    assert s.commands(0.01) == ["variable s2_jet_on equal (time>=0.025)*(time<0.035)"]
    assert s.sense(0.01, frame([1], [0.95], [DOWN]), 0.02, frame([1], [1.05], [DOWN])) == []  # once
    assert s.commands(0.04) == ["variable s2_jet_on equal 0"]  # over: pruned


def test_a_window_due_before_the_frame_that_saw_the_crossing_starts_then_and_is_late():
    s = station(delay=0.002)
    (f,) = s.sense(0.0, frame([7], [0.5], [DOWN]), 0.01, frame([7], [1.5], [DOWN]))
    assert f[4:] == (0.01, pytest.approx(0.02, rel=0, abs=1e-12), True)


def test_the_state_is_read_at_the_frame_nearer_the_crossing():
    s = station()
    # crosses at 90 % of the interval, turned face down by then: fired at
    assert s.sense(0.0, frame([1], [0.1], [UP]), 0.01, frame([1], [1.01], [DOWN]))
    # crosses at 10 %, face up then (flipped later): not
    assert not station().sense(0.0, frame([1], [0.99], [UP]), 0.01, frame([1], [1.9], [DOWN]))


def test_the_state_is_read_in_the_templates_body_frame_as_the_analyses_read_it():
    # a template laid out with its length along y, its width along z and its thickness along
    # x: recorded unturned, the part stands on a long side (its width upright), not face up
    grid = np.array([[x, y, z] for x in (-1, 1) for y in (-4, -2, 0, 2, 4) for z in (-2, 2)], float)
    template = np.column_stack([grid * 1e-4, np.full(len(grid), 5e-5)])
    line = Jets(Feeder.from_values(LINE), template)
    s = line.stations[0]
    assert s.axes_q != (1.0, 0.0, 0.0, 0.0)
    x = s.x_sense
    (f,) = s.sense(0.0, frame([1], [x - 1e-4], [UP]), 0.01, frame([1], [x + 1e-4], [UP]))
    assert f[3] == 2  # side (index of STATES): the analyses' part_states says the same
    from vibrofeed.orientation import STATES, part_states
    assert STATES[part_states(np.array([UP]), template).state[0]] == "side"


def test_the_ideal_jet_holds_the_sensed_bodys_atoms_only():
    atoms = {"molecule": np.array([5, 5, 5, 6, 6, 6, -1]), "id": np.array([3, 1, 2, 4, 6, 5, 9])}
    ranges = atom_ranges(atoms)
    assert ranges == {5: (1, 3), 6: (4, 6)}
    s = station(mode="ideal")
    s.sense(0.0, frame([5, 6], [0.9, 0.2], [DOWN, DOWN]), 0.01, frame([5, 6], [1.1, 0.3], [DOWN, DOWN]),
            ranges)
    assert s.commands(0.01) == ["variable s2_jet_on atom (id>=1)*(id<=3)*((time>=0.025)*(time<0.035))"]


def test_the_ideal_jets_fix_acts_on_the_pending_bodies_atoms_only():
    # the fix's group holds the atoms of the bodies with a window pending, redefined (fix removed
    # first: LIGGGHTS deletes no group a fix uses) with every new window; once all are over,
    # the fix is removed and the group left as it was
    fix = "fix s2_jet s2_jet_parts addforce 0 v_s2_jet_fy v_s2_jet_fz region s2_jet"
    s = station(mode="ideal", fix=fix)
    assert s.idle() == ["unfix s2_jet"] and not s.placed  # the deck's, at the first frame
    ranges = {5: (1, 3), 6: (4, 6)}
    s.sense(0.0, frame([5], [0.9], [DOWN]), 0.01, frame([5], [1.1], [DOWN]), ranges)
    assert s.commands(0.01) == [
        "group s2_jet_parts delete", "group s2_jet_parts id 1:3",
        "variable s2_jet_on atom (id>=1)*(id<=3)*((time>=0.025)*(time<0.035))", fix]
    s.sense(0.01, frame([6], [0.9], [DOWN]), 0.02, frame([6], [1.1], [DOWN]), ranges)
    assert s.commands(0.02) == [
        "unfix s2_jet", "group s2_jet_parts delete", "group s2_jet_parts id 1:3 4:6",
        "variable s2_jet_on atom (id>=1)*(id<=3)*((time>=0.025)*(time<0.035))"
        "+(id>=4)*(id<=6)*((time>=0.035)*(time<0.045))", fix]
    assert s.commands(0.05) == ["unfix s2_jet"] and not s.placed


def test_a_headway_fires_at_a_kept_part_sensed_too_soon_after_the_last_one_passed():
    # four face-up parts cross x = 1 at 1, 3, 6 and 9 ms (between frames at 0 and 10 ms, given
    # out of order), headway 4 ms: the first passes, the second (2 ms after it) is fired at,
    # the third (5 ms after the first passed) passes, the fourth (3 ms after it) is fired at
    s = station(headway=0.004)
    x0 = np.array([0.99, 0.97, 0.94, 0.91])  # ids 1 to 4
    x1 = x0 + 0.1  # each moves 0.1 in the 10 ms: crosses when x0 + 10 t = 1
    prev, now = frame([4, 3, 2, 1], x0[::-1], [UP] * 4), frame([4, 3, 2, 1], x1[::-1], [UP] * 4)
    fired = s.sense(0.0, prev, 0.01, now)
    assert [f[1] for f in fired] == [2, 4] and [f[3] for f in fired] == [0, 0]  # ids, state up
    assert [f[0] for f in fired] == pytest.approx([0.003, 0.009], rel=0, abs=1e-12)
    assert s.passed == pytest.approx(0.006, rel=0, abs=1e-12)
    # a wrong part does not count as passed: a face-up one 12 ms after the last passed passes
    later = s.sense(0.01, frame([5, 6], [0.95, 0.9], [DOWN, UP]), 0.02,
                    frame([5, 6], [1.05, 1.02], [DOWN, UP]))
    assert [f[1] for f in later] == [5] and s.passed == pytest.approx(0.01 + 0.01 * 0.1 / 0.12, abs=1e-12)


def test_without_a_headway_parts_in_the_kept_state_pass_however_close():
    s = station()
    close = frame([1, 2], [1.01, 1.0], [UP, UP])  # 1 ms apart
    assert s.sense(0.0, frame([1, 2], [0.99, 0.98], [UP, UP]), 0.01, close) == []


class OneRank:
    size = 1


def test_the_line_s_jets_give_commands_only_when_a_firing_is_new_and_place_the_fix_only_then():
    feeder = Feeder.from_values(LINE)
    jets = Jets(feeder)
    (s,) = jets.stations
    assert s.x_sense == pytest.approx(2e-3 + 0.3 * 3e-3, rel=0, abs=1e-15) and s.section == 2
    # the deck's own fix line, which the driver removes while no window is pending
    fix = next(line for line in feeder.elements[1].jet_commands(feeder.part) if line.startswith("fix "))
    assert s.fix == fix == "fix s2_jet all addforce 0 v_s2_jet_fy v_s2_jet_fz region s2_jet"
    x = s.x_sense
    assert jets.step(OneRank(), 0.0, frame([1], [x - 1e-4], [DOWN])) == (["unfix s2_jet"], None)
    commands, table = jets.step(OneRank(), 0.005, frame([1], [x + 1e-4], [DOWN]))
    # crossed at 2.5 ms, due at once (delay 0): late, it fires from the frame that saw it
    assert commands == ["variable s2_jet_on equal (time>=0.005)*(time<0.015)", fix]
    assert table["id"].tolist() == [1] and table["state"].tolist() == [1] and table["late"].tolist() == [1]
    assert jets.step(OneRank(), 0.01, frame([1], [x + 2e-4], [DOWN])) == ([], None)  # still firing
    # its window over at 15 ms: removed at the frame that sees it so, once
    assert jets.step(OneRank(), 0.015, frame([1], [x + 3e-4], [DOWN])) == (["unfix s2_jet"], None)
    assert jets.step(OneRank(), 0.02, frame([1], [x + 4e-4], [DOWN])) == ([], None)


def jet(**kw):
    return Feeder.from_values({**LINE, **{f"s2_jet_{k}": str(v) for k, v in kw.items()}})


@pytest.mark.parametrize("change, names", [
    ({"keep": "up|down|side|end,any-direction"}, "s2_jet_keep"),
    ({"keep": "upside"}, "s2_jet_keep"),
    ({"mode": "gentle"}, "s2_jet_mode"),
    ({"delay": -0.01}, "s2_jet_delay"),
    ({"duration": 0}, "s2_jet_duration"),
    ({"force": -1e-6}, "s2_jet_force"),
    ({"offset": 3e-3}, "s2_jet_offset"),
    ({"at": 1.2}, "s2_jet_at"),
    ({"angle": 120}, "s2_jet_angle"),
    ({"headway": -0.001}, "s2_jet_headway"),
])
def test_bad_jets_are_refused_in_one_line_naming_the_key(change, names):
    with pytest.raises(ParameterError) as info:
        jet(**change).check()
    assert names in str(info.value) and "\n" not in str(info.value)


def test_a_jet_that_keeps_every_state_is_one_that_spaces_the_stream():
    f = jet(keep="up|down|side|end,any-direction", headway=0.005)
    f.check()
    assert f.elements[1].jet.headway == 0.005 and Jets(f).stations[0].headway == 0.005
    with pytest.raises(ParameterError, match="s2_jet_headway"):  # without: the refusal says so
        jet(keep="up|down|side|end,any-direction").check()


def test_a_jet_on_spheres_is_refused():
    with pytest.raises(ParameterError, match="s2_jet_force.*spheres"):
        Feeder.from_values({**LINE, "shape": "0"}).check()


def test_a_delay_that_fires_past_the_section_warns():
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        jet(delay=0.5).check()
    assert any("s2_jet_delay" in str(w.message) for w in said)
    speed = 2 * math.pi * 100 * 6e-5
    assert speed * 0.5 > 3e-3 * 0.7  # (the case is past the end)


def test_the_jet_is_a_station_spanning_its_block():
    (st,) = [s for s in jet(length=4e-4, offset=1e-4).stations if s.kind == "jet"]
    assert (st.section, st.start, st.end) == (2, pytest.approx(2.8e-3, rel=0, abs=1e-15),
                                             pytest.approx(3.2e-3, rel=0, abs=1e-15))
