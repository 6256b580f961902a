"""A bowl with an exit line through the driver, on 1 and 2 ranks: dies placed along the bowl's
track and chute cross onto the exit section; the mass balance is exact at every frame
(inserted = on_track + exited + rejected, nothing lost), the outlet is the exit section's end,
its mesh lies after the chute's end in the bowl's frame with its vertices told apart from the
bowl's, it is recorded moving by its own sine while the bowl turns, and the path coordinate
runs on from the bowl's along it."""

import math

import numpy as np
import pytest

from helpers import vibrofeed
from vibrofeed.feeders import Feeder
from vibrofeed.postproc.path import along
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result

BOWL_LINE = """
[feeder]
name = "bowl_exit"
[parts]
shape = "chip"
size = 5e-4
thickness = 2.5e-4
youngs = 2e7
[supply]
n_parts = 0
n_track = 12
[run]
t_end = 0.08
output_dt = 0.004

[[element]]
kind = "bowl"
diameter = 0.02
width = 1.2e-3
turns = 0.25
helix_angle = 3
chute_length = 5.5e-3
drive = { freq = 75, amp_t = 2e-4, amp_n = 4e-5, phase = -60 }

[[element]]
kind = "linear"
length = 3e-3
width = 1.5e-3
wall_height = 1e-3
step = 5e-5
cross_tilt = 10
drive = { freq = 75, amp_t = 4e-4, amp_n = 4e-5, phase = -60 }
"""
A_T, A_N, W, PHI = 4e-4, 4e-5, 2 * math.pi * 75.0, math.radians(-60)  # the exit section's drive
OUTLET_X = 5.5e-3 * math.cos(math.radians(3)) + 3e-3  # the chute's end along x, then the section


@pytest.fixture
def feeder(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    path = tmp_path / "bowl_exit.toml"
    path.write_text(BOWL_LINE)
    return path


@pytest.mark.parametrize("ranks", [1, 2])
def test_a_bowl_hands_its_dies_to_its_exit_line_with_the_mass_balance_exact(tmp_path, feeder, ranks):
    out = tmp_path / f"bowl_exit{ranks}.h5"
    vibrofeed("run", feeder, "-q", "-o", out, "-n", ranks, check=True)
    report = check_file(out)
    assert report.ok, [str(p) for p in report.problems]
    with Result(out) as r:
        mb = r.mass_balance
        assert (mb["lost"] == 0).all()
        assert (mb["inserted"] == mb["on_track"] + mb["exited"] + mb["rejected"]).all()
        assert mb["inserted"][-1] == 12
        assert r.outlet_plane["outlet_x"] == pytest.approx(OUTLET_X, rel=1e-12)
        assert r.holds("surface_angle") and r.n_sections == 2
        f = Feeder.from_values(r.parameters)
        v, _ = r.track_mesh
        split = r.track_sections
        line = v[split == 2]
        assert line[:, 0].min() == pytest.approx(OUTLET_X - 3e-3, rel=1e-12)
        assert line[:, 0].max() == pytest.approx(OUTLET_X, rel=1e-12)
        assert line[:, 1].min() == pytest.approx(f.line_origin[1] - 7.5e-4, rel=1e-12)
        # its own sine, while the bowl turns (recorded apart, FORMAT.md)
        p2, v2 = r.section_surface(2)
        t = r.time
        assert np.abs(v2[:, 0] - A_T * W * np.cos(W * t)).max() <= 1e-9 * A_T * W
        assert np.abs(v2[:, 2] - A_N * W * np.cos(W * t + PHI)).max() <= 1e-9 * A_T * W
        th = W * r.derived["dt_used"]
        assert np.abs(p2[:, 0] - A_T * np.sin(W * t)).max() <= A_T * th * (1 + th / 24)
        assert np.abs(r.read("surface_angle")[:, 2]).max() > 0.9 * 2e-4 / f.bowl.r_mid
        # dies reached the exit section: their path coordinate runs on past the chute's end
        s, _ = along(r, np.arange(r.n_frames))
        chute_end = f.bowl.length + f.bowl.chute_length
        assert np.nanmax(s) > chute_end + 1e-3
        assert np.nanmax(s) <= f.path_end + 1e-3  # (a part beyond the edge is falling: NaN)
