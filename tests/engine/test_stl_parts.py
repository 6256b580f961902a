"""A designer's own part from an STL (shape 4, stl) under LIGGGHTS through `vibrofeed run`: a
feeder description whose [parts] name a 0.6 x 0.4 x 0.3 mm block's STL (written here, in mm)
runs a few parts along a short track with the mass balance exact, the engine given CLUMP's
template and the solid's mass."""

import numpy as np
import trimesh

from helpers import vibrofeed
from vibrofeed.results.reader import Result

DESCRIPTION = """
[feeder]
name = "stl_block"

[parts]
shape = "stl"
file = "block.stl"
unit = "mm"
method = "euclidean"
spheres = 30

[supply]
n_parts = 4
fill_from = 0.5
fill_to = 0.9

[run]
t_settle = 0.01
t_end = 0.03
output_dt = 0.01

[[element]]
kind = "linear"
length = 0.005
width = 2.5e-3
wall_height = 1e-3
drive = { freq = 100, amp_t = 3e-5, amp_n = 5e-5 }
"""


def test_an_stl_part_runs_with_the_mass_balance_exact(tmp_path):
    trimesh.creation.box(extents=(0.6, 0.4, 0.3)).export(tmp_path / "block.stl")
    (tmp_path / "feeder.toml").write_text(DESCRIPTION)
    out = tmp_path / "stl.h5"
    proc = vibrofeed("run", tmp_path / "feeder.toml", "-q", "-o", out)
    assert proc.returncode == 0, proc.stderr
    with Result(out) as r:
        counts = r.mass_balance
        assert np.all(counts["inserted"] == 4) and np.all(counts["lost"] == 0)
        assert np.all(counts["on_track"] + counts["exited"] == counts["inserted"])
        assert r.derived["body_spheres"] == 30 == len(r.body_template)
        # the solid's mass, not the clump's: 0.6 x 0.4 x 0.3 mm of silicon
        assert abs(r.derived["mass"] / (0.6e-3 * 0.4e-3 * 0.3e-3 * 2330) - 1) < 1e-6
        # the sizes the deck placed the parts by are the STL's (single precision: 1e-7)
        assert abs(float(r.parameters["part_size"]) / 6e-4 - 1) < 1e-6
