"""`vibrofeed demo`'s report on synthetic results (tests/bulk_synthetic.py): parts with an
orientation state (box-like clumps) add the orientation report, the table `vibrofeed
orientation` prints, and a picture coloured by state; spheres keep the feed rate and
singulation alone and a picture coloured by speed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bulk_synthetic import feeder
from vibrofeed.cli.demo import report

FRAMES = np.arange(0, 1.0 + 1e-9, 0.01)
BOX = np.array([[x, y, 0.0, 5e-5] for x in (-2e-4, -1e-4, 0.0, 1e-4, 2e-4) for y in (-5e-5, 5e-5)])
BOX_VARIABLES = {"shape": ("3", "", "part shape", "0"), "part_size": ("5e-4", "m", "length", "5e-4"),
                 "part_width": ("2e-4", "m", "width", "2e-4"),
                 "part_thickness": ("1e-4", "m", "thickness", "1e-4")}
# 20 parts leaving one every 40 ms, in separate lanes: every fourth face down, the rest face up
EXITS = 0.1 + 0.04 * np.arange(20)
LANES = np.arange(20) % 5 * 1e-3
DOWN = np.array([0.0, 1.0, 0.0, 0.0])   # 180 deg about x


def boxes(path):
    q = np.array([DOWN if k % 4 == 3 else [1.0, 0, 0, 0] for k in range(len(EXITS))])
    return feeder(path, FRAMES, EXITS, speed=0.05, orientations=q, body_template=BOX,
                  variables=BOX_VARIABLES, lanes=LANES, clumps=True)


def spheres(path):
    return feeder(path, FRAMES, EXITS, speed=0.05, lanes=LANES)


def test_boxes_get_the_orientation_report(tmp_path):
    from vibrofeed.cli import orientation as O
    from vibrofeed.postproc.orientation import Orientation
    from vibrofeed.results.reader import Result

    path = boxes(tmp_path / "boxes.h5")
    text, reason = report(path)
    assert reason is None
    assert "\nFeed rate\n" in text and "\nSingulation\n" in text
    head, orientation = text.split("\nOrientation\n")
    assert "\nSingulation\n" in head   # after the feed rate and the singulation
    # the table `vibrofeed orientation` prints, over the feed rate's window
    with Result(path) as r:
        alone = Orientation(r).run().summary()
    assert orientation == O.table(alone)
    assert "at the outlet  up 75.0 %, down 25.0 %, side 0.0 %, end 0.0 %" in orientation
    assert math.isclose(alone["correct_fraction"], 0.75, rel_tol=0, abs_tol=1e-12)


def test_spheres_keep_their_report(tmp_path):
    text, reason = report(spheres(tmp_path / "spheres.h5"))
    assert reason is None and "\nSingulation\n" in text
    assert "Orientation" not in text and "oriented rate" not in text


@pytest.mark.parametrize("make, color", [(boxes, "state"), (spheres, "speed")])
def test_the_picture_is_coloured_by_state_when_the_parts_have_one(tmp_path, monkeypatch, make, color):
    pytest.importorskip("pyvista")
    import vibrofeed.pictures.render as R

    drawn = []
    real = R.render

    def small(result, output, **kw):   # the demo's call, drawn small
        drawn.append(kw["color"])
        return real(result, output, **{**kw, "size": (160, 96)})

    monkeypatch.setattr(R, "render", small)
    path = make(tmp_path / "run.h5")
    text, _ = report(path, tmp_path / "out")
    assert drawn == [color]
    assert f"figure: {tmp_path / 'out' / 'run.png'}" in text
