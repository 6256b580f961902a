"""A skewed wiper, the tipping rail, turns a box off its long side onto a broad face, by
construction: one box placed on a level section 2 upstream of the rail, against the reference
wall, in a given pose (LIGGGHTS commands after the deck: the pre-fill removed, the deck's own box
inserted turned as asked), then a short sliding run (Gamma_n 0.8, the orient demo's section 2
drive) that conveys it against the rail and on over the outlet edge.

Boxes 1.0 x 0.5 x 0.35 mm (L x W x T, the orient demo's), a rail 0.42 mm above the floor
(T < 0.42 mm < W) turned 60 degrees from straight across, its upstream face from the reference
wall at 2 mm to the far wall at 3.7 mm of a 6 mm section 1 mm wide:

(a) a box on its long side is pushed across by the rail's face and tips over away from the wall
    onto a broad face: the face that looked at the wall then looks up (a quarter turn about the
    track's direction, its top towards +y), so a box whose marked face looked at the wall ends
    up, one whose marked face looked away ends face down; either way it leaves flat over the
    outlet edge;
(b) a box lying flat, marked face up, passes under the rail unturned and leaves up.

Each run's mass balance is exact at every frame (inserted = on track + exited + rejected).
Measured first with the same placements (2026-12-05): on a floor tilted 15 degrees towards the
wall the box on its side is held at the rail instead (the tilt adds to what it must be lifted
against); the rail is a tool for a level floor (docs/orientation.md, "The tipping rail").
"""

import math

import numpy as np
import pytest

from helpers import deck_values, one_body_balanced, place_one_body
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import run_deck
from vibrofeed.feeders.feeder import section_from
from vibrofeed.feeders.records import Part
from vibrofeed.orientation import STATES, part_states
from vibrofeed.parts import Box, box_template
from vibrofeed.poses import matrix_quaternion, pose_matrix
from vibrofeed.results.reader import Result

L_, W_, T_ = 1e-3, 5e-4, 3.5e-4
LINE = {"n_parts": 1, "shape": 3, "part_size": L_, "part_width": W_, "part_thickness": T_,
        "clump_spacing": 1.0, "youngs": 2e7, "mu": 0.5, "restitution": 0.3,
        "track_length": 3e-3, "track_width": 1.4e-3, "gate_width": 9e-4, "gate_at": 0.8,
        "fill_from": 0.05, "fill_to": 0.45, "amp_n": 2e-5, "amp_t": 6e-5, "phase": -30,
        "sections": 2, "s2_length": 6e-3, "s2_width": 1e-3, "s2_step": 5e-5, "s2_amp_t": 1.8e-4,
        "s2_amp_n": 2e-5, "s2_phase": -30, "s2_wall_height": 1e-3, "s2_wiper_height": 4.2e-4,
        "s2_wiper_at": 2.0 / 6, "s2_wiper_skew": 60.0, "t_end": 0.22, "t_settle": 0.002,
        "output_dt": 0.0025}
SEED = 15485863
GAP = 2e-5  # between the placed box and the wall, and the floor


def rx(degrees):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


# the box frame's turn after vibrofeed.poses' flat pose (L along the track, marked face +z up)
POSES = {"side, marked face to the wall": rx(90),  # its +z towards -y, the reference wall
         "side, marked face away": rx(-90),
         "flat, marked face up": np.eye(3)}


def run(path, turn):
    section = section_from(deck_values(LINE))
    rows = box_template(Box.of(Part.from_values(LINE)))
    R = turn @ pose_matrix(0, 0)
    placed, r = rows[:, :3] @ R.T, rows[:, 3]
    floor = -section.step + LINE["s2_amp_n"] * math.sin(math.radians(LINE["s2_phase"]))  # at t = 0
    # 0.7 mm past the joint (its rear clear of section 1), its front 0.6 mm short of the rail
    at = np.array([LINE["track_length"] + 7e-4, -section.width / 2 + GAP - (placed[:, 1] - r).min(),
                   floor + GAP - (placed[:, 2] - r).min()])
    run_deck(Deck.find("bulk_feeder"), deck_values(LINE), path,
             before_run=place_one_body(at, matrix_quaternion(R), SEED))
    with Result(path) as res:
        ids, q, x = res.read("id"), res.read("orientation"), res.read("position")
        mb, out = res.mass_balance, res.outlet
    on = ids[:, 0] >= 0
    states = np.array([STATES[k] for k in part_states(q[on, 0], rows).state])
    return {"mb": mb, "out": out["id"].tolist(), "states": states, "x": x[on, 0, 0],
            "rail": section.wiper_x}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rail")
    return {pose: run(folder / f"{k}.h5", turn) for k, (pose, turn) in enumerate(POSES.items())}


@pytest.mark.parametrize("pose, ends", [("side, marked face to the wall", "up"),
                                        ("side, marked face away", "down")])
def test_a_box_on_its_side_tips_flat_at_the_rail(runs, pose, ends):
    found = runs[pose]
    one_body_balanced(found["mb"])
    assert len(found["out"]) == 1 and found["mb"]["exited"][-1] == 1  # over the outlet edge
    states, x = found["states"], found["x"]
    a, b = found["rail"]
    before = x + L_ / 2 < a  # its front short of the rail's face at the wall
    assert before.sum() >= 2 and (states[before] == "side").all()
    # once past the rail's far end it lies flat, the face that looked at the wall up
    past = (x - L_ / 2 > b) & (x <= LINE["track_length"] + LINE["s2_length"])
    assert past.sum() >= 2 and (states[past] == ends).all()


def test_a_flat_box_passes_under_the_rail_unturned(runs):
    found = runs["flat, marked face up"]
    one_body_balanced(found["mb"])
    assert len(found["out"]) == 1
    x, states = found["x"], found["states"]
    on_section = (x > LINE["track_length"]) & (x <= LINE["track_length"] + LINE["s2_length"])
    a, b = found["rail"]
    assert (x[on_section] > b).any()  # it crossed the rail's whole footprint
    assert (states[on_section] == "up").all()
