"""Rectangular parts (shape 3, box) under LIGGGHTS through `vibrofeed run`: a few 1.0 x 0.5 x
0.35 mm boxes with a bump convey along a short track with the mass balance exact, and a box
dropped on the still floor comes to rest with its centre half its vertical extent above it."""

import numpy as np

from helpers import vibrofeed
from vibrofeed.results.reader import Result
from vibrofeed.rotations import quaternion_matrices

BOX = {"shape": "box", "part_size": "1e-3", "part_width": "5e-4", "part_thickness": "3.5e-4",
       "track_width": "3e-3", "track_length": "0.006"}


def params(values):
    return [a for k, v in values.items() for a in ("-p", f"{k}={v}")]


def test_boxes_with_a_bump_convey_with_the_mass_balance_exact(tmp_path):
    given = {**BOX, "bump_height": "5e-5", "bump_diameter": "2e-4", "bump_at": "0.5", "n_parts": "6",
             "fill_from": "0.6", "fill_to": "0.95", "t_settle": "0.01", "t_end": "0.06",
             "output_dt": "0.01"}
    out = tmp_path / "box.h5"
    proc = vibrofeed("run", "bulk_feeder", *params(given), "-q", "-o", out)
    assert proc.returncode == 0, proc.stderr
    with Result(out) as r:
        counts = r.mass_balance
        assert np.all(counts["inserted"] == 6) and np.all(counts["lost"] == 0)
        assert np.all(counts["on_track"] + counts["exited"] == counts["inserted"])
        assert r.derived["body_spheres"] == 85  # 84 on the shell and the bump
        assert len(r.body_template) == 85
        x = r.read("position")[:, :, 0]
        on = ~np.isnan(x[0]) & ~np.isnan(x[-2])
        # Gamma_n 2 at 100 Hz carries them forward: more than a millimetre in 0.05 s on average
        assert np.mean(x[-2, on] - x[0, on]) > 1e-3 or counts["exited"][-1] > 0


def test_a_dropped_box_rests_half_its_vertical_extent_above_the_floor(tmp_path):
    given = {**BOX, "n_parts": "1", "fill_from": "0.4", "fill_to": "0.6", "t_settle": "0.03",
             "t_end": "0.005", "output_dt": "0.005", "amp_t": "0", "amp_n": "0"}
    out = tmp_path / "drop.h5"
    proc = vibrofeed("run", "bulk_feeder", *params(given), "-q", "-o", out)
    assert proc.returncode == 0, proc.stderr
    with Result(out) as r:
        position, q = r.read("position", -1), r.read("orientation", -1)
        here = ~np.isnan(position[:, 0])
        (z,), rot = position[here, 2], quaternion_matrices(q[here])[0]
        assert np.all(np.abs(r.read("velocity", -1)[here]) < 1e-3)  # at rest
    # the body axis nearest the vertical and the box's half extent along it (no bump: the
    # body frame is the box frame, the COM its centre): T/2 lying flat, W/2 on a long side,
    # L/2 on an end; the contact's overlap under its own weight is well below a micrometre,
    # the tolerance 2 % of T (7 um) is the part's scale
    axis = int(np.argmax(np.abs(rot[2, :])))
    assert abs(rot[2, axis]) > 0.999  # resting on a face, not on an edge
    half = {0: 5e-4, 1: 2.5e-4, 2: 1.75e-4}[axis]
    assert abs(z - half) < 0.02 * 3.5e-4
