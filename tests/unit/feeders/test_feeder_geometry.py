"""The feeder object (vibrofeed.feeders): sections along the path, joints, tooling stations and
checks, against geometry computed by hand here."""

import math

import pytest

from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder

TAN10 = math.tan(math.radians(10.0))

# three sections: 4 mm at 1.2 mm wide with a gate to 0.6 mm, 5 mm at 0.6 mm with a side drop
# and a wiper, 3 mm at 0.8 mm; the first two floors level, the third tilted 10 degrees; steps of
# 60 and 40 um
THREE = {
    "sections": 3, "part_size": 3e-4, "shape": 0,
    "track_length": 4e-3, "track_width": 1.2e-3, "wall_height": 1e-3, "cross_tilt": 0,
    "gate_width": 6e-4, "gate_at": 0.5,
    "freq": 100, "amp_t": 3e-5, "amp_n": 5e-5, "phase": 0,
    "s2_length": 5e-3, "s2_width": 6e-4, "s2_wall_height": 6e-4, "s2_step": 6e-5, "s2_cross_tilt": 0,
    "s2_freq": 100, "s2_amp_t": 1.2e-4, "s2_amp_n": 2e-5, "s2_phase": 0,
    "s2_drop_from": 0.2, "s2_drop_to": 0.6, "s2_drop_width": 3.5e-4,
    "s2_wiper_height": 4.5e-4, "s2_wiper_at": 0.8,
    "s3_length": 3e-3, "s3_width": 8e-4, "s3_wall_height": 6e-4, "s3_step": 4e-5, "s3_cross_tilt": 10,
    "s3_freq": 100, "s3_amp_t": 1e-4, "s3_amp_n": 1e-5, "s3_phase": 0,
}


def test_three_sections_lie_end_to_end_along_the_path():
    f = Feeder.from_values(THREE)
    assert f.sections == 3 and f.n_elements == 3
    assert [c for b in f.bounds for c in b] == pytest.approx([0.0, 4e-3, 4e-3, 9e-3, 9e-3, 12e-3],
                                                             abs=1e-15)
    assert f.path_end == pytest.approx(12e-3, abs=1e-15)
    assert f.joint_positions == pytest.approx([4e-3, 9e-3], abs=1e-15)
    # before the first joint: 0; from it to the next: 1; at the outlet edge: 2; past it or NaN: -1
    got = f.section_at([0.0, 3.999e-3, 4e-3, 9.001e-3, 12e-3 - 1e-9, 12.1e-3, math.nan])
    assert got.tolist() == [0, 0, 1, 2, 2, -1, -1]


def test_each_floor_lies_below_the_last_by_the_summed_steps():
    s1, s2, s3 = Feeder.from_values(THREE).linear_sections
    assert (s1.level, s2.level, s3.level) == (0.0, 6e-5, pytest.approx(1e-4, abs=1e-18))
    assert s1.floor_z(-6e-4) == 0.0 and s2.floor_z(0.0) == pytest.approx(-6e-5, abs=1e-18)
    # at the reference wall (y = -w/2) a tilted floor lies w tan(tilt) below its high edge
    assert s3.floor_z(4e-4) == pytest.approx(-1e-4, rel=1e-12)
    assert s3.lowest == pytest.approx(-1e-4 - 8e-4 * TAN10, rel=1e-12)


def test_a_joints_step_across_the_exit_by_hand():
    one, two = Feeder.from_values(THREE).joints
    # joint 1: section 1's gate (0.6 mm) onto a level section 2 of that width: 60 um everywhere
    assert one.steps == (pytest.approx(6e-5, rel=1e-12), pytest.approx(6e-5, rel=1e-12))
    # joint 2: a level 0.6 mm exit onto a 0.8 mm floor tilted 10 deg, 40 um below at its high
    # edge (+0.4 mm): step 40 um + (0.4 mm - y) tan 10 for y in +-0.3 mm
    lo, hi = two.steps
    assert lo == pytest.approx(4e-5 + 1e-4 * TAN10, rel=1e-12)
    assert hi == pytest.approx(4e-5 + 7e-4 * TAN10, rel=1e-12)


def test_joint_motion_in_closed_form():
    one, two = Feeder.from_values(THREE).joints
    # one frequency, in phase: the amplitudes' differences
    assert one.motion == (pytest.approx(3e-5, rel=1e-12), pytest.approx(9e-5, rel=1e-12))
    assert two.motion == (pytest.approx(1e-5, rel=1e-12), pytest.approx(2e-5, rel=1e-12))
    # two frequencies: the phases drift, the amplitudes add
    f = Feeder.from_values({**THREE, "s3_freq": 120})
    assert f.joints[1].motion == (pytest.approx(3e-5, rel=1e-12), pytest.approx(2.2e-4, rel=1e-12))
    # one frequency, 60 degrees apart: equal amplitudes differ by one amplitude
    f = Feeder.from_values({**THREE, "s2_amp_n": 5e-5, "s2_phase": 60})
    assert f.joints[0].motion[0] == pytest.approx(5e-5, rel=1e-12)


def test_cross_strokes_sway_the_joint_apart_in_closed_form():
    f = Feeder.from_values({**THREE, "s2_amp_c": 3e-5, "s2_phase_c": 90, "s3_amp_c": 4e-5})
    one, two = f.joints
    # from a section without one: its own amplitude; 3 and 4 (x 1e-5) a quarter period apart: 5
    assert f.linear_sections[1].drive.sway_from(f.linear_sections[0].drive) == pytest.approx(3e-5, rel=1e-12)
    assert two.a.drive.sway_from(two.b.drive) == pytest.approx(5e-5, rel=1e-12)
    # (the floors along and normal move as before)
    assert one.motion == (pytest.approx(3e-5, rel=1e-12), pytest.approx(9e-5, rel=1e-12))
    # the peak surface speed counts it: 2 pi 100 Hz |(1e-4, 1e-5, 4e-5)|
    assert two.b.drive.peak_speed == pytest.approx(2 * math.pi * 100 * math.sqrt(1e-8 + 1e-10 + 1.6e-9),
                                                   rel=1e-12)


def test_a_joint_whose_walls_sway_into_the_path_is_refused_naming_the_strokes():
    # section 3 (0.8 mm) swaying against section 2's 0.6 mm exit: up to 0.1 mm either way fits
    Feeder.from_values({**THREE, "s3_amp_c": 0.9e-4}).check()
    with pytest.raises(ParameterError) as err:
        Feeder.from_values({**THREE, "s3_amp_c": 1.2e-4}).check()
    assert ("s3_width=0.0008 m is narrower than section 2's exit (0.0006 m, the two moving 0.00012 m "
            "apart across)") in str(err.value) and "(s3_amp_c)" in str(err.value)


def test_tooling_stations_where_the_numbers_put_them():
    stations = Feeder.from_values(THREE).stations
    assert [(s.section, s.kind) for s in stations] == [(1, "gate"), (2, "side_drop"), (2, "wiper")]
    assert [(s.element, s.name) for s in stations] == [(1, "s1.gate"), (2, "s2.side_drop"), (2, "s2.wiper")]
    gate, drop, wiper = stations
    # the gate at 0.5 of 4 mm, its walls narrowing at 45 degrees from 1.2 to 0.6 mm: 0.3 mm long
    assert (gate.start, gate.end) == (pytest.approx(2e-3, abs=1e-15), pytest.approx(2.3e-3, abs=1e-15))
    # a part passes a station from a part size (part_size) before it to one past it
    size = THREE["part_size"]
    assert (drop.x_in, drop.x_out) == (pytest.approx(5e-3 - size, abs=1e-15),
                                       pytest.approx(7e-3 + size, abs=1e-15))
    # 4 mm + 0.2 .. 0.6 of 5 mm
    assert (drop.start, drop.end) == (pytest.approx(5e-3, abs=1e-15), pytest.approx(7e-3, abs=1e-15))
    assert wiper.start == pytest.approx(8e-3, abs=1e-15)
    assert wiper.end - wiper.start == pytest.approx(3e-4, abs=1e-15)


def test_section_values_give_each_sections_drive_as_the_first_ones_names():
    f = Feeder.from_values(THREE)
    three = f.section_values(3)
    assert (three["freq"], three["amp_t"], three["amp_n"], three["phase"], three["waveform"]) == \
        (100.0, 1e-4, 1e-5, 0.0, 0)
    assert f.section_values(1) == THREE


@pytest.mark.parametrize("change, words", [
    ({"s3_width": 5e-4}, "s3_width=0.0005 m is narrower than section 2's exit (0.0006 m)"),
    ({"s3_step": 9e-6, "s3_cross_tilt": 0}, "s3_step=9e-06 m: the joint must step down by more "
                                             "than the floors move apart normal to them (1e-05 m"),
    ({"s3_step": 2e-4}, "s3_step=0.0002 m is not a small step: keep it below a part's thickness "
                        "(0.0003 m) (with the cross tilts it is 0.000323 m at its most)"),
    ({"s3_amp_t": 1.3e-4, "s3_freq": 120}, "the joint opens by up to 0.00025 m along the track "
                                            "(s2_amp_t, s3_amp_t)"),
    ({"s3_wall_height": 1e-4}, "s3_wall_height=0.0001 m is no higher than a part's centre"),
    ({"s2_wiper_at": 0.99}, "runs past the end of section 2"),
    ({"s2_drop_to": 1.2}, "the side drop lies outside section 2"),
    ({"s3_width": 2e-4, "s2_width": 2e-4, "gate_width": 0, "track_width": 2e-4},
     "s2_width=0.0002 m is narrower than a part"),
])
def test_a_section_or_joint_that_does_not_work_is_refused_in_one_line_naming_it(change, words):
    with pytest.raises(ParameterError) as err:
        Feeder.from_values({**THREE, **change}).check()
    assert words in str(err.value) and "\n" not in str(err.value)


def test_the_three_sections_pass_their_checks():
    Feeder.from_values(THREE).check()


def test_a_bowl_is_its_helix_then_its_chute():
    from vibrofeed.bowl import bowl_from

    values = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "turns": 1.5,
              "wall_height": 1e-3, "chute_length": 8e-3, "part_size": 3e-4}
    f = Feeder.from_values(values)
    b = bowl_from(values)
    # the helix's centre line: 1.5 turns at r_mid = 9.4 mm, 3 degrees up
    helix = 1.5 * 2 * math.pi * 9.4e-3 / math.cos(math.radians(3.0))
    assert b.length == pytest.approx(helix, rel=1e-12)
    assert f.bounds == [(0.0, pytest.approx(helix, rel=1e-12)),
                        (pytest.approx(helix, rel=1e-12), pytest.approx(helix + 8e-3, rel=1e-12))]
    assert not f.further_elements and f.stations == []


def test_sections_out_of_range_are_refused():
    for n in (0, 10, 1.5):
        with pytest.raises(ParameterError, match="must be a whole number from 1 to 9"):
            Feeder.from_values({**THREE, "sections": n})


def test_an_air_jet_is_a_station_spanning_its_block():
    # a jet sensing at 0.25 of section 2 (4 mm from the line's start, 5 mm long): its block,
    # 0.5 mm long, centred 0.2 mm downstream of the sensing point, by hand
    f = Feeder.from_values({**THREE, "shape": 1, "part_thickness": 1e-4, "s2_drop_to": 0,
                            "s2_wiper_height": 0, "s2_jet_force": 1e-6, "s2_jet_at": 0.25,
                            "s2_jet_offset": 2e-4, "s2_jet_length": 5e-4})
    gate, jet = f.stations
    assert (jet.section, jet.element, jet.kind, jet.name) == (2, 2, "jet", "s2.jet")
    centre = 4e-3 + 0.25 * 5e-3 + 2e-4
    assert (jet.start, jet.end) == pytest.approx((centre - 2.5e-4, centre + 2.5e-4), rel=0, abs=1e-15)


BOX_LINE = {"sections": 2, "shape": 3, "part_size": 1e-3, "part_width": 5e-4, "part_thickness": 3.5e-4,
            "track_length": 4e-3, "track_width": 1.4e-3, "wall_height": 1e-3, "gate_width": 6e-4,
            "gate_at": 0.5, "freq": 100, "amp_t": 1e-4, "amp_n": 5e-5,
            "s2_length": 5e-3, "s2_width": 7.5e-4, "s2_wall_height": 1e-3, "s2_step": 1e-4,
            "s2_freq": 100, "s2_amp_t": 1e-4, "s2_amp_n": 5e-5}


def test_a_later_section_needs_room_for_a_box_riding_lengthwise_only():
    # behind a 0.6 mm gate the boxes (1.0 x 0.5 mm) arrive lengthwise: 0.75 mm holds them
    Feeder.from_values(BOX_LINE).check()
    with pytest.raises(ParameterError, match=r"^s2_width=0.00045 m is narrower than a part "
                                             r"\(0.0005 m across riding lengthwise\)$"):
        Feeder.from_values({**BOX_LINE, "s2_width": 4.5e-4, "gate_width": 4.5e-4}).check()
