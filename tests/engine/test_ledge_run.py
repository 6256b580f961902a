"""A side drop is a ledge for boxes, by construction: a box lying crosswise falls off it when
its centre of mass lies past the edge, and on a floor tilted tau towards the wall that centre
leans (T/2) tan(tau) nearer the wall than its footprint's (the closed form behind
SideDropWarning; docs/orientation.md, "A ledge instead of a gate").

One 1.0 x 0.5 x 0.35 mm box (the orient demo's) placed lying flat, marked face up, against the
reference wall of a section 2 tilted 15 degrees towards it, over its side drop (LIGGGHTS
commands after the deck: the pre-fill removed, the deck's own box inserted turned as asked),
then a short sliding run (the orient demo's section 2 drive). A crosswise box's centre of mass
lies L/2 - (T/2) tan(15 deg) = 0.453 mm out, a lengthwise one's 0.203 mm:

(a) crosswise on a ledge 0.40 mm wide: it falls off, the one reject, of section 2;
(b) crosswise on a ledge 0.48 mm wide, narrower than the footprint's half (0.5 mm) but wider
    than the leaning centre of mass: it stays on and leaves over the outlet edge;
(c) lengthwise on the 0.40 mm ledge: it stays on (it rides slower against the wall: still on
    the section at the run's end).

Each run's mass balance is exact at every frame (inserted = on track + exited + rejected).
"""

import math
import warnings

import numpy as np
import pytest

from helpers import deck_values, one_body_balanced, place_one_body
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import run_deck
from vibrofeed.feeders.feeder import section_from
from vibrofeed.feeders.records import Part
from vibrofeed.parts import Box, box_template
from vibrofeed.poses import matrix_quaternion, pose_matrix
from vibrofeed.results.reader import Result

L_, W_, T_ = 1e-3, 5e-4, 3.5e-4
TILT = 15.0
LINE = {"n_parts": 1, "shape": 3, "part_size": L_, "part_width": W_, "part_thickness": T_,
        "clump_spacing": 1.0, "youngs": 2e7, "mu": 0.5, "restitution": 0.3,
        "track_length": 3e-3, "track_width": 1.4e-3, "cross_tilt": TILT, "gate_width": 0,
        "fill_from": 0.05, "fill_to": 0.45, "amp_n": 2e-5, "amp_t": 6e-5, "phase": -30,
        "sections": 2, "s2_length": 4e-3, "s2_width": 1.4e-3, "s2_step": 1.6e-4, "s2_cross_tilt": TILT,
        "s2_amp_t": 2.6e-4, "s2_amp_n": 2e-5, "s2_phase": -30, "s2_wall_height": 1e-3,
        "s2_drop_from": 0.1, "s2_drop_to": 0.9, "t_end": 0.12, "t_settle": 0.002, "output_dt": 0.0025}
SEED = 32452843
GAP = 2e-5  # between the placed box and the wall, and the floor


def turn(axis, degrees):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    if axis == "x":
        return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def run(path, ledge, crosswise):
    params = {**LINE, "s2_drop_width": ledge}
    section = section_from(deck_values(params))
    rows = box_template(Box.of(Part.from_values(params)))
    # lying flat (a quarter turn about z: crosswise), then tilted with the floor about x
    R = turn("x", TILT) @ turn("z", 90.0 if crosswise else 0.0) @ pose_matrix(0, 0)
    placed, r = rows[:, :3] @ R.T, rows[:, 3]
    shift = LINE["s2_amp_n"] * math.sin(math.radians(LINE["s2_phase"]))  # the floor's at t = 0
    y = -section.width / 2 + GAP - (placed[:, 1] - r).min()
    # each sphere GAP (or more) above the tilted floor under it
    z = GAP + max(section.floor_z(y + placed[:, 1]) + shift + r - placed[:, 2])
    at = np.array([LINE["track_length"] + 0.3 * LINE["s2_length"], y, z])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (b) is the side drop warned of: it keeps crosswise boxes
        run_deck(Deck.find("bulk_feeder"), deck_values(params), path,
                 before_run=place_one_body(at, matrix_quaternion(R), SEED))
    with Result(path) as res:
        return res.mass_balance, res.outlet, res.rejects


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ledge")
    cases = {"crosswise, 0.40 mm": (4.0e-4, True), "crosswise, 0.48 mm": (4.8e-4, True),
             "lengthwise, 0.40 mm": (4.0e-4, False)}
    return {name: run(folder / f"{k}.h5", *case) for k, (name, case) in enumerate(cases.items())}


def test_the_ledges_by_hand():
    lean = T_ / 2 * math.tan(math.radians(TILT))
    assert 4.0e-4 < L_ / 2 - lean < 4.8e-4 < L_ / 2  # (a) falls, (b) stays though inside L/2
    assert W_ / 2 - lean < 4.0e-4  # (c) stays


def test_a_crosswise_box_falls_off_a_ledge_narrower_than_its_leaning_centre(runs):
    mb, out, rejects = runs["crosswise, 0.40 mm"]
    one_body_balanced(mb)
    assert mb["rejected"][-1] == 1 and mb["exited"][-1] == 0 and len(out["id"]) == 0
    assert rejects["section"].tolist() == [2]


def test_a_crosswise_box_whose_centre_lies_over_a_wider_ledge_stays_on_and_leaves(runs):
    mb, out, _ = runs["crosswise, 0.48 mm"]
    one_body_balanced(mb)
    assert (mb["rejected"] == 0).all() and mb["exited"][-1] == 1 and len(out["id"]) == 1


def test_a_lengthwise_box_stays_on_the_narrow_ledge(runs):
    mb, _, _ = runs["lengthwise, 0.40 mm"]
    one_body_balanced(mb)
    assert (mb["rejected"] == 0).all() and mb["on_track"][-1] + mb["exited"][-1] == 1
