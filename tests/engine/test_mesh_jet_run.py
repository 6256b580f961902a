"""An air jet on a track from CAD (a mesh element), through the driver, by construction: one box
placed on the channel's first leg, face down or face up (LIGGGHTS commands after the deck: the
pre-fill removed, the deck's own box inserted turned as asked), conveyed round the bend onto
the diagonal leg, where the camera senses it by its path coordinate.

The line: a 3 mm linear section, then a channel from CAD in millimetres, 1.2 mm wide with walls
1 mm high, whose floor's centre line runs (0,0) -> (4,0) -> (8,-3) -> (12,-3) mm; the camera at
0.4 of its 13 mm of path: 1.2 mm down the diagonal leg (4, -3)/5, where the deck's x (7.96 mm)
falls 0.24 mm short of the path coordinate (8.2 mm), and a box lengthwise along the path lies
37 degrees off x. The jet keeps "up" (ideal mode: only the
sensed box), 2e-5 N (about five weights) for 10 ms, 60 degrees up and across to the path's
left, (3, 4)/5 there: over the wall, away from the channel's next leg (the jet blows over the
wall a designer leaves open for it; blown over the inner wall of a bend, a box lands on the
channel's next leg).

(a) a box face down is sensed there once, in state down, fired at, blown over the left wall and
    caught below: one reject, the jet's (it was fired at); on 1 and 2 ranks;
(b) a box face up crosses the camera unfired and is still on the channel past it at the end
    (lengthwise along the path there: its long axis 37 degrees off x).

Each run's mass balance is exact at every frame (inserted = on track + exited + rejected)."""

import math

import numpy as np
import pytest

from helpers import BOX_PARTS, channel, one_body_balanced, place_one_body
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import run_deck
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.description import read
from vibrofeed.mesh import write_stl
from vibrofeed.orientation import STATES
from vibrofeed.parts import Box, box_template
from vibrofeed.poses import matrix_quaternion, pose_matrix
from vibrofeed.results.reader import Result

PLAN = [(0, 0, 0), (4, 0, 0), (8, -3, 0), (12, -3, 0)]  # mm: a bend to the right
STEP, AMP_N, PHASE = 5e-5, 2e-5, -30.0
LINE = f"""
{BOX_PARTS}[supply]
n_parts = 1
fill_from = 0.05
fill_to = 0.45
[run]
t_end = 0.3
t_settle = 0.002
output_dt = 0.0025

[[element]]
kind = "linear"
length = 0.003
width = 1.4e-3
wall_height = 1.5e-3
drive = {{ freq = 100, amp_t = 6e-5, amp_n = {AMP_N}, phase = {PHASE} }}
gate = {{ width = 9e-4, at = 0.8 }}

[[element]]
kind = "mesh"
file = "channel.stl"
unit = "mm"
path = {[list(p) for p in PLAN]}
width = 1.2e-3
step = {STEP}
drive = {{ freq = 100, amp_t = 1.8e-4, amp_n = {AMP_N}, phase = {PHASE} }}
jet = {{ force = 2e-5, at = 0.4, keep = "up", duration = 0.01, angle = 60, mode = "ideal" }}
"""
SEED = 15485863
GAP = 2e-5  # between the placed box and the floor


def run(folder, face_down: bool, ranks: int = 1):
    write_stl(*channel(PLAN, 1.2, 1.0), folder / "channel.stl", "channel")
    (folder / "line.toml").write_text(LINE)
    deck = Deck.find(folder / "line.toml")
    feeder = Feeder.from_values(read(folder / "line.toml").values)
    rows = box_template(Box.of(feeder.part))
    R = pose_matrix(0, 0)
    if face_down:
        R = np.diag([1.0, -1.0, -1.0]) @ R  # turned over about its long axis
    placed, r = rows[:, :3] @ R.T, rows[:, 3]
    floor = -STEP + AMP_N * math.sin(math.radians(PHASE))  # the channel's floor at t = 0
    at = np.array([3e-3 + 3e-3, 0.0, floor + GAP - (placed[:, 2] - r).min()])  # 3 mm down its first leg
    out = folder / f"{'down' if face_down else 'up'}{ranks}.h5"
    run_deck(deck, {}, out, ranks=ranks, before_run=place_one_body(at, matrix_quaternion(R), SEED))
    with Result(out) as res:
        ids, x = res.read("id")[:, 0], res.read("position")[:, 0, :]
        found = {"mb": res.mass_balance, "out": res.outlet["id"].tolist(),
                 "rejects": res.rejects, "fired": res.jet_firings}
    on = ids >= 0
    found["path"] = feeder.line_coordinate(x[on])  # along the path while on the line
    found["sensing"] = feeder.elements[1].sensing
    return found


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("mesh_jet")


@pytest.mark.parametrize("ranks", [1, 2])
def test_a_box_face_down_is_sensed_along_the_path_and_blown_off(folder, ranks):
    found = run(folder, face_down=True, ranks=ranks)
    one_body_balanced(found["mb"])
    fired, rejects = found["fired"], found["rejects"]
    assert len(fired["id"]) == 1 and STATES[int(fired["state"][0])] == "down"  # sensed once, face down
    assert int(fired["section"][0]) == 2
    # sensed as its path coordinate crossed the camera's (8.2 mm)
    crossed = found["path"]
    assert np.nanmax(crossed) >= found["sensing"] and np.nanmin(crossed) < found["sensing"]
    # blown over the wall: rejected from the channel after it was fired at, not delivered
    assert rejects["id"].tolist() == fired["id"].tolist() and rejects["section"].tolist() == [2]
    assert rejects["time"][0] > fired["start"][0] and not found["out"]
    assert found["mb"]["rejected"][-1] == 1


def test_a_box_face_up_passes_the_camera_unfired(folder):
    found = run(folder, face_down=False)
    one_body_balanced(found["mb"])
    assert len(found["fired"]["id"]) == 0 and len(found["rejects"]["id"]) == 0
    assert np.nanmax(found["path"]) > found["sensing"] + 1e-4  # past the camera ...
    assert found["mb"]["on_track"][-1] == 1  # ... and still on the channel
