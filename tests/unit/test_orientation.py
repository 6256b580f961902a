"""Orientation states of bodies turned by hand (vibrofeed.orientation): every face up, both
ends leading, the long axis's angle, the boundaries between states, what counts as correct."""

import math

import numpy as np
import pytest

from vibrofeed.errors import ParameterError
from vibrofeed.orientation import FACES, STATES, Correct, classify, parse_correct


def quat(axis, deg):
    """The quaternion (w, x, y, z) of a turn by ``deg`` about ``axis``."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    h = math.radians(deg) / 2
    return np.array([math.cos(h), *(math.sin(h) * a)])


def compose(*qs):
    """The quaternion of turning by qs[0] first, then qs[1], ..."""
    out = np.array([1.0, 0, 0, 0])
    for q in qs:
        w1, x1, y1, z1 = q
        w2, x2, y2, z2 = out
        out = np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])
    return out


# Each face up, by a turn that brings its outward normal to +z.
FACE_TURNS = {
    "+z": quat([1, 0, 0], 0), "-z": quat([1, 0, 0], 180),
    "+y": quat([1, 0, 0], 90), "-y": quat([1, 0, 0], -90),
    "+x": quat([0, 1, 0], -90), "-x": quat([0, 1, 0], 90),
}


def test_every_face_up_and_its_state():
    s = classify(np.array(list(FACE_TURNS.values())))
    assert [FACES[k] for k in s.face] == list(FACE_TURNS)
    assert s.names() == ["up", "down", "side", "side", "end", "end"]


def test_the_boundary_between_up_and_side_is_at_45_degrees():
    # tilted about the long axis: +z up until the +y or -y face is nearer up
    s = classify(np.array([quat([1, 0, 0], a) for a in (44.0, 46.0, -44.0, -46.0)]))
    assert s.names() == ["up", "side", "up", "side"]
    s = classify(np.array([quat([0, 1, 0], a) for a in (44.0, 46.0, 134.0, 136.0)]))
    assert s.names() == ["up", "end", "end", "down"]


def test_leading_end_and_angle_to_the_path():
    # lying flat, marked face up, turned about z by yaw: the +x end leads for |yaw| < 90
    yaws = np.array([0.0, 15.0, -30.0, 89.0, 91.0, 180.0, -150.0])
    s = classify(np.array([quat([0, 0, 1], y) for y in yaws]))
    assert s.lead.tolist() == [1, 1, 1, 1, -1, -1, -1]
    folded = np.abs((yaws + 90) % 180 - 90)  # the axis's angle, whichever end leads
    np.testing.assert_allclose(s.angle, folded, atol=1e-9)  # degrees, of angles up to 90
    assert s.lengthwise(20.0).tolist() == [True, True, False, False, False, True, False]


def test_marked_face_down_keeps_the_ends_and_the_angle():
    q = compose(quat([1, 0, 0], 180), quat([0, 0, 1], 30))  # flipped about x, then yawed 30
    s = classify(q[None])
    assert s.names() == ["down"] and s.lead[0] == 1
    assert s.angle[0] == pytest.approx(30.0, abs=1e-9)


def test_a_part_on_its_end_has_no_direction():
    s = classify(np.array([FACE_TURNS["+x"], compose(FACE_TURNS["-x"], quat([0, 0, 1], 40))]))
    assert np.isnan(s.angle).all() and not s.lengthwise().any()


def test_the_path_turns_per_part():
    # a bowl: the path's tangent is where each part is; a part square to its own tangent
    q = np.array([quat([0, 0, 1], 90), quat([0, 0, 1], 90)])
    s = classify(q, tangent=np.array([[0.0, 1, 0], [1.0, 0, 0]]))
    assert s.angle == pytest.approx([0.0, 90.0], abs=1e-9)
    assert s.lead.tolist() == [1, 1]  # +x end along +y for the first; at 90 deg, counted +x


def test_a_tilted_floor_sets_up():
    # a track tilted 10 deg across: a part lying flat on it is tilted too, still "up"
    tilt = quat([1, 0, 0], 50)
    up = np.array([0.0, -math.sin(math.radians(50)), math.cos(math.radians(50))])
    assert classify(tilt[None]).names() == ["side"]
    assert classify(tilt[None], up=up).names() == ["up"]


def test_correct_states():
    q = np.array([FACE_TURNS["+z"], compose(FACE_TURNS["+z"], quat([0, 0, 1], 180)),
                  compose(FACE_TURNS["+z"], quat([0, 0, 1], 60)), FACE_TURNS["-z"], FACE_TURNS["+y"]])
    s = classify(q)
    assert Correct().of(s).tolist() == [True, True, False, False, False]
    assert parse_correct("up, lengthwise, lead +x").of(s).tolist() == [True, False, False, False, False]
    assert parse_correct("up|down, any-direction").of(s).tolist() == [True, True, True, True, False]
    assert parse_correct("side").of(s).tolist() == [False, False, False, False, True]
    assert str(parse_correct(" Up , lead -x")) == "up, lengthwise, lead -x"


@pytest.mark.parametrize("text, said", [
    ("upside", "no state named 'upside'"), ("", "is empty"), ("up, sideways", "'sideways' is not"),
    ("end, lengthwise", "has no direction on the floor"),
])
def test_bad_names_are_one_line_errors(text, said):
    with pytest.raises(ParameterError, match=said) as e:
        parse_correct(text, name="s2_jet_keep")
    assert "\n" not in str(e.value) and "s2_jet_keep" in str(e.value)


def test_end_alone_counts_any_direction():
    assert parse_correct("end").lengthwise is False
    assert STATES == ("up", "down", "side", "end")
