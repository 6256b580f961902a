"""`vibrofeed render --color state`: each part in its orientation state's colour, the correctly
oriented ones in their own, a legend that names them and counts them.

Boxes in known states (quaternions turned by hand, tests/bulk_synthetic.py's clumps resting on
a straight track): the picture holds the colour of every category present and none of an
absent one (the top faces, lit square on, show the colour as it is); along a bowl's helix the
state is read against the helix, not +x; spheres are refused in one line.
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from bulk_synthetic import feeder
from helpers import parts, vibrofeed
from vibrofeed.errors import UsageError
from vibrofeed.pictures import scene
from vibrofeed.results.reader import Result

# A box-like clump: 5 x 2 spheres spanning 0.5 x 0.2 mm in the body's xy plane (long along x,
# thin along z); drawn as the deck's box of part_size x part_width x part_thickness.
BOX = np.array([[x, y, 0.0, 5e-5] for x in (-2e-4, -1e-4, 0.0, 1e-4, 2e-4) for y in (-5e-5, 5e-5)])
BOX_VARIABLES = {"shape": ("3", "", "part shape", "0"), "part_size": ("5e-4", "m", "length", "5e-4"),
                 "part_width": ("2e-4", "m", "width", "2e-4"),
                 "part_thickness": ("1e-4", "m", "thickness", "1e-4")}
LENGTH, WIDTH, WALL = 0.01, 0.002, 0.001
SIZE = (480, 270)
FRAMES = np.array([0.0, 0.01, 0.02])
# A pixel is a category's colour (as lit) within this much on each channel (0-255).
TOLERANCE = 20


def quat(axis, deg):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    h = math.radians(deg) / 2
    return np.array([math.cos(h), *(math.sin(h) * a)])


UP = quat([0, 0, 1], 0)          # marked face up, lengthwise: correct by default
CROSS = quat([0, 0, 1], 90)      # marked face up, crosswise: "up", not correct
DOWN = quat([1, 0, 0], 180)      # marked face down
SIDE = quat([1, 0, 0], 90)       # on a long side
END = quat([0, 1, 0], 90)        # standing on an end


def track():
    h = WIDTH / 2
    v = np.array([[0, -h, 0], [LENGTH, -h, 0], [LENGTH, h, 0], [0, h, 0],
                  [0, h, WALL], [LENGTH, h, WALL], [0, -h, WALL], [LENGTH, -h, WALL]], float)
    t = np.array([[0, 1, 2], [0, 2, 3], [3, 2, 5], [3, 5, 4], [1, 0, 6], [1, 6, 7]], np.int32)
    return v, t


def boxes(path, orientations, speed=0.01):
    """Boxes in ``orientations``, 1.4 mm apart on the track's centre line at the last frame,
    resting on the floor; none reaches the outlet edge over the three frames."""
    q = np.asarray(orientations, dtype=float)
    x_last = 0.0015 + 1.4e-3 * np.arange(len(q))
    exits = FRAMES[-1] + (LENGTH - x_last) / speed
    return feeder(path, FRAMES, exits, speed=speed, orientations=q, body_template=BOX,
                  variables=BOX_VARIABLES, track=track(), clumps=True, outlet_x=LENGTH)


def pixels(image, color):
    """How many pixels of the scene (left of the legend) are ``color`` (#rrggbb) as lit: the
    colour times a brightness between a half and one (a face turned from the light), within
    :data:`TOLERANCE` on each channel."""
    from vibrofeed.pictures.render import SCENE_WIDTH

    rgb = np.array([int(color[k:k + 2], 16) for k in (1, 3, 5)], dtype=float)
    scene_part = image[:, : int(SCENE_WIDTH * image.shape[1])].astype(float)
    lit = scene_part @ rgb / (rgb @ rgb)
    near = np.abs(scene_part - lit[..., None] * rgb).max(axis=-1) <= TOLERANCE
    return int((near & (lit >= 0.5) & (lit <= 1.05)).sum())


@pytest.fixture
def painter():
    pytest.importorskip("pyvista")
    from vibrofeed.pictures.render import _Painter

    made = []

    def make(result, frames, correct=None, size=SIZE):
        made.append(_Painter(result, "state", size, np.asarray(frames), None, correct))
        return made[-1]

    yield make
    for p in made:
        p.close()


def picture(painter, path, correct=None, frame=-1):
    with Result(path) as r:
        p = painter(r, [frame % r.n_frames], correct)
        p.draw(scene.read_frame(r, frame))
        return p.image(), p.legend_labels(), p


@pytest.mark.parametrize("orientations, correct, present", [
    # default "up, lengthwise": the crosswise one is "up", not correct; no part on an end
    ([UP, CROSS, DOWN, SIDE, UP], None, {"correct": 2, "up": 1, "down": 1, "side": 1, "end": 0}),
    # face up or down, any direction, is correct: no "up" or "down" colour left
    ([END, CROSS, DOWN, UP], "up|down, any-direction",
     {"correct": 3, "up": 0, "down": 0, "side": 0, "end": 1}),
])
def test_each_state_has_its_colour_and_the_correct_parts_theirs(tmp_path, painter, orientations,
                                                                correct, present):
    from vibrofeed.pictures.render import CORRECT_COLOR, STATE_COLORS

    image, labels, _ = picture(painter, boxes(tmp_path / "b.h5", orientations), correct)
    colors = {"correct": CORRECT_COLOR, **STATE_COLORS}
    counts = {name: pixels(image, c) for name, c in colors.items()}
    for name, n in present.items():
        if n:
            assert counts[name] > 10 * n, counts
        else:
            assert counts[name] == 0, counts
    # the legend names every category, counting the parts of the frame in each
    assert labels == [f"{name}  {n}" for name, n in present.items()]


def test_the_palette_tells_the_categories_apart():
    """Five Okabe-Ito colours, far apart: no pixel of one falls within another's tolerance."""
    from vibrofeed.pictures.render import state_palette

    rgb = np.array([[int(c[k:k + 2], 16) for k in (1, 3, 5)] for _, c in state_palette()])
    gap = np.abs(rgb[:, None] - rgb[None]).max(axis=-1)
    assert [label for label, _ in state_palette()] == ["correct", "up", "down", "side", "end"]
    assert gap[~np.eye(len(rgb), dtype=bool)].min() > 2 * TOLERANCE


def test_the_legend_says_what_counts_as_correct(tmp_path, painter):
    _, labels, p = picture(painter, boxes(tmp_path / "b.h5", [UP]), "up|down, lengthwise, lead +x")
    rule = p.plotter.actors["correct"].GetInput()
    assert rule == "correct:\nup or down,\nlengthwise,\nlead +x"
    assert p.legend.GetNumberOfEntries() == 5 and labels[0] == "correct  1"
    assert "state" not in p.plotter.scalar_bars.keys()   # the legend, not a colour bar


def test_a_movie_keeps_the_legend_and_counts_each_frame(tmp_path, painter):
    """A part turned from crosswise to lengthwise between frames 0 and 1 (a station turning it
    at 3.85 mm): the legend's counts follow the frame drawn."""
    q = np.array([CROSS, UP])
    # 0.1 mm a frame: part 1 at 3.8, 3.9, 4.0 mm; part 2 at 5.8 mm and on, lengthwise throughout
    path = feeder(tmp_path / "m.h5", FRAMES, FRAMES[-1] + np.array([0.6, 0.4]), speed=0.01,
                  orientations=q, turn=(3.85e-3, np.array([UP, UP])), body_template=BOX,
                  variables=BOX_VARIABLES, track=track(), clumps=True, outlet_x=LENGTH)
    with Result(path) as r:
        p = painter(r, np.arange(3))
        seen = []
        for k in range(3):
            p.draw(scene.read_frame(r, k))
            seen.append(p.legend_labels()[:2])
        assert p.legend.GetNumberOfEntries() == 5   # one legend, its counts changed
    assert seen == [["correct  1", "up  1"], ["correct  2", "up  0"], ["correct  2", "up  0"]]


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="MP4 needs ffmpeg (apt-get install ffmpeg)")
def test_a_movie_coloured_by_state(tmp_path):
    pytest.importorskip("pyvista")
    from vibrofeed.pictures.render import render

    out = tmp_path / "m.mp4"
    with Result(boxes(tmp_path / "b.h5", [UP, DOWN])) as r:
        done = render(r, out, color="state", size=(160, 96), correct="down")
    assert done.frames == 3 and out.stat().st_size > 0


def test_along_a_bowls_helix_the_state_is_read_against_the_helix(tmp_path):
    """Where the helix runs along +y (polar angle -2 pi), a box lying along y is lengthwise
    (correct) and one along x crosswise, as the orientation analysis reads them
    (postproc.orientation.path_directions), not as along a line's +x."""
    from vibrofeed.bowl import bowl_from
    from vibrofeed.pictures.render import PartStates
    from vibrofeed.results.writer import Recording, ResultWriter

    bowl = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "turns": 1.5,
            "wall_height": 1e-3, "cone_angle": 3.0, "cross_tilt": 3.0, "lip_height": 0.0,
            "chute_length": 8e-3, "freq": 100.0, "amp_t": 5e-5, "amp_n": 3e-5, "phase": -20.0,
            "mu": 0.5, "restitution": 0.3, "shape": 3, "part_size": 5e-4, "density": 2330.0}
    b = bowl_from(bowl)
    points = np.repeat(b.helix_point(np.array([-2 * math.pi])) + [0, 0, 1e-4], 2, axis=0)
    points[1, 2] += 2e-4  # (not on top of each other: one a little higher up the same turn)
    q = np.array([quat([0, 0, 1], 90), UP])   # long axis along y, along x
    w = ResultWriter(tmp_path / "bowl.h5", deck_name="bowl_feeder", deck_path="bowl_feeder.liggghts",
                     deck_text="#\n", variables={k: (repr(v), "", k, repr(v)) for k, v in bowl.items()},
                     derived={"dt_used": 1e-6}, engine_version="LIGGGHTS (synthetic)", seed=1,
                     run_id="b" * 64, recording=Recording(rotating=True), body_template=BOX)
    p = parts([1, 2], points, radius=2.7e-4)
    p["orientation"] = q
    w.write_frame(0, 0.0, p, [0, 0, 0], [0, 0, 0], surface_rotation=([0, 0, 0], [0, 0, 0]))
    w.finish("complete")
    with Result(tmp_path / "bowl.h5") as r:
        states, correct = PartStates(r).of(scene.read_frame(r, 0))
    assert states.names() == ["up", "up"] and list(correct) == [True, False]
    assert states.angle == pytest.approx([0.0, 90.0], abs=1e-6)   # degrees


def test_the_demos_picture_is_the_last_frame_with_the_most_correct_parts(tmp_path):
    """Two boxes up and lengthwise; the first turns face down at x = 1.45 mm, which it passes
    between frames 1 and 2: 2, 2 and 1 correct parts, so frame 1 (the last of the most), not
    the last frame; with both face down, none."""
    from vibrofeed.pictures.render import most_correct_frame

    x_last = 0.0015 + 1.4e-3 * np.arange(2)
    exits = FRAMES[-1] + (LENGTH - x_last) / 0.01
    for name, q, turned, want in (("turns.h5", [UP, UP], [DOWN, UP], 1),
                                  ("down.h5", [DOWN, DOWN], [DOWN, DOWN], None)):
        path = feeder(tmp_path / name, FRAMES, exits, speed=0.01, orientations=np.array(q),
                      body_template=BOX, variables=BOX_VARIABLES, track=track(), clumps=True,
                      outlet_x=LENGTH, turn=(1.45e-3, np.array(turned)))
        with Result(path) as r:
            assert most_correct_frame(r, [0, 1, 2]) == want
            if want is not None:
                assert most_correct_frame(r, [0, 2]) == 0 and most_correct_frame(r, [2]) == 2


def test_spheres_are_refused_in_one_line(tmp_path, capsys):
    from vibrofeed.cli import main
    from vibrofeed.pictures.render import render_frame

    path = feeder(tmp_path / "spheres.h5", FRAMES, [0.3, 0.4], track=track(), outlet_x=LENGTH)
    with Result(path) as r, pytest.raises(UsageError) as err:
        render_frame(r, -1, color="state", size=SIZE)
    assert str(err.value) == "spheres have no orientation state: use --color speed or cluster"
    capsys.readouterr()
    out = tmp_path / "s.png"
    assert main(["render", str(path), "--color", "state", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "spheres have no orientation state" in err, err
    assert not out.exists()


def test_command_line(tmp_path, capsys):
    from vibrofeed.cli import main

    path = boxes(tmp_path / "b.h5", [UP, END])
    out = tmp_path / "pic.png"
    proc = vibrofeed("render", path, "-o", out, "--size", "240x160", "--color", "state",
                     "--correct", "end", check=True)
    assert "wrote" in proc.stdout and out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    capsys.readouterr()
    # a state that does not exist: one line, before anything is drawn
    assert main(["render", str(path), "--color", "state", "--correct", "upside", "-o",
                 str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--correct: no state named 'upside'" in err, err
    # --correct without --color state: said to have no effect, the picture drawn all the same
    assert main(["render", str(path), "--correct", "up", "-o", str(tmp_path / "y.png"),
                 "--size", "160x96"]) == 0
    assert "warning: --correct has no effect" in capsys.readouterr().err
