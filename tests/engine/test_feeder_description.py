"""A feeder description of three linear sections through the driver, on 1 and 2 ranks, and by
hand: a bed of spheres pre-filled near section 1's end crosses both joints; the mass balance
is exact at every frame (inserted = on_track + exited + rejected, nothing lost), the outlet is
the third section's end, each section's mesh is stored with its vertices told apart, and the
third section's recorded motion is its own sine drive at every frame. By hand, the deck
`vibrofeed prepare` writes runs under plain LIGGGHTS, and refuses a value other than the one
its geometry was checked for."""

import math
import os
import shlex
import subprocess

import numpy as np
import pytest

from helpers import vibrofeed
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result

THREE = """
[feeder]
name = "three"
[parts]
size = 3e-4
[supply]
n_parts = 30
fill_from = 0.5
fill_to = 0.97
[run]
t_end = 0.2
output_dt = 0.004

[[element]]
kind = "linear"
length = 0.004
width = 1.2e-3
drive = { freq = 100, amp_t = 5e-5, amp_n = 5e-5 }

[[element]]
kind = "linear"
length = 0.002
width = 1.2e-3
wall_height = 1e-3
step = 5e-5
drive = { freq = 100, amp_t = 1e-4, amp_n = 5e-5 }

[[element]]
kind = "linear"
length = 0.002
width = 1.2e-3
wall_height = 1e-3
step = 5e-5
drive = { freq = 100, amp_t = 1.5e-4, amp_n = 5e-5, phase = -20 }
"""
A_T, A_N, W, PHI = 1.5e-4, 5e-5, 2 * math.pi * 100.0, math.radians(-20)  # section 3's drive


@pytest.fixture
def feeder(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    path = tmp_path / "three.toml"
    path.write_text(THREE)
    return path


@pytest.mark.parametrize("ranks", [1, 2])
def test_three_sections_mass_balance_is_exact(tmp_path, feeder, ranks):
    out = tmp_path / f"three{ranks}.h5"
    vibrofeed("run", feeder, "-q", "-o", out, "-n", ranks, check=True)
    report = check_file(out)
    assert report.ok, [str(p) for p in report.problems]
    with Result(out) as r:
        assert r.description == THREE  # the description, verbatim: the result says what feeder it is
        mb, ev, plane = r.mass_balance, r.outlet, r.outlet_plane
        assert (mb["lost"] == 0).all()
        assert (mb["inserted"] == mb["on_track"] + mb["exited"] + mb["rejected"]).all()
        assert mb["inserted"][-1] == 30 and len(ev["id"]) == mb["exited"][-1] > 0
        assert plane["outlet_x"] == pytest.approx(0.008, abs=1e-12)  # the third section's end
        v, _ = r.track_mesh
        split = r.track_sections
        assert sorted(set(split.tolist())) == [1, 2, 3]
        # each section's vertices lie over its own stretch, each floor a step below the last
        for k, (a, b, floor) in enumerate([(0, 4e-3, 0.0), (4e-3, 6e-3, -5e-5), (6e-3, 8e-3, -1e-4)], 1):
            mine = v[split == k]
            assert mine[:, 0].min() == pytest.approx(a, abs=1e-12)
            assert mine[:, 0].max() == pytest.approx(b, abs=1e-12)
            assert mine[:, 2].min() == pytest.approx(floor, abs=1e-12)
        assert r.n_sections == 3
        p3, v3 = r.section_surface(3)
        t = r.time
        # the sine's velocity to 1e-9 of its peak; the position the continuous sine within w dt
        assert np.abs(v3[:, 0] - A_T * W * np.cos(W * t)).max() <= 1e-9 * A_T * W
        assert np.abs(v3[:, 2] - A_N * W * np.cos(W * t + PHI)).max() <= 1e-9 * A_T * W
        th = W * r.derived["dt_used"]
        assert np.abs(p3[:, 0] - A_T * np.sin(W * t)).max() <= A_T * th * (1 + th / 24)
        assert np.abs(p3[:, 2] - A_N * np.sin(W * t + PHI)).max() <= A_N * th * (1 + th / 24)
        assert np.abs(v3[:, 0]).max() > 0.9 * A_T * W  # sampled over the whole period
    # parts crossed both joints: some left over the third section's end
    assert (ev["position"][:, 0] > 0.008).all()


def test_the_prepared_deck_runs_by_hand_and_holds_to_its_values(tmp_path, feeder):
    folder = tmp_path / "byhand"
    proc = vibrofeed("prepare", feeder, "-o", folder, "-p", "run.t_end=0.02", check=True)
    line = proc.stdout.strip().splitlines()[-1]
    words = shlex.split(line)
    assert words[:3] == ["liggghts", "-in", str((folder / "three.liggghts").resolve())]
    env = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
    ran = subprocess.run(words, cwd=folder, capture_output=True, text=True, env=env, timeout=300)
    assert ran.returncode == 0 and "ERROR" not in ran.stdout, ran.stdout[-2000:]
    assert (folder / "outlet.txt").is_file() and (folder / "bulk_feeder.dump").is_file()
    # the same line with section 3's stroke changed: the geometry was checked for another
    other = words + ["-var", "s3_amp_t", "1e-4"]
    refused = subprocess.run(other, cwd=folder, capture_output=True, text=True, env=env, timeout=300)
    assert "Invalid s3_amp_t: mesh_dir was checked and written for s3_amp_t=0.00015" \
        in refused.stdout


CHUTE = """
[feeder]
name = "chute"
[parts]
size = 3e-4
[supply]
n_parts = 20
fill_from = 0.5
fill_to = 0.97
[run]
t_end = 0.2
output_dt = 0.004

[[element]]
kind = "linear"
length = 0.003
width = 1.2e-3
drive = { freq = 100, amp_t = 5e-5, amp_n = 5e-5 }

[[element]]
kind = "chute"
length = 0.002
width = 1.2e-3
wall_height = 1e-3
step = 8e-5
slope = 10

[[element]]
kind = "linear"
length = 0.002
width = 1.2e-3
wall_height = 1e-3
step = 5e-5
drive = { freq = 100, amp_t = 1e-4, amp_n = 2e-5 }
"""


@pytest.mark.parametrize("ranks", [1, 2])
def test_a_line_through_a_chute_conserves_its_parts_and_the_chute_stands_still(tmp_path, monkeypatch,
                                                                                ranks):
    """The element kind added as one module (vibrofeed/feeders/chute.py) runs like the others:
    parts slide down the chute onto the last section and leave over its end; the mass
    balance is exact at every frame; `check` verifies that the chute did not move."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    path = tmp_path / "chute.toml"
    path.write_text(CHUTE)
    out = tmp_path / f"chute{ranks}.h5"
    vibrofeed("run", path, "-q", "-o", out, "-n", ranks, check=True)
    report = check_file(out)
    assert report.ok, [str(p) for p in report.problems]
    with Result(out) as r:
        mb, ev = r.mass_balance, r.outlet
        assert (mb["lost"] == 0).all()
        assert (mb["inserted"] == mb["on_track"] + mb["exited"] + mb["rejected"]).all()
        assert mb["inserted"][-1] == 20 and mb["exited"][-1] > 0
        assert r.outlet_plane["outlet_x"] == pytest.approx(0.007, abs=1e-12)
        assert (ev["position"][:, 0] > 0.007).all()
        p2, v2 = r.section_surface(2)
        assert not p2.any() and not v2.any()  # the chute: exactly still
        v, _ = r.track_mesh
        chute = v[r.track_sections == 2]
        # its floor's lowest point: its end, 80 um + 2 mm tan 10 below section 1's floor
        assert chute[:, 2].min() == pytest.approx(-8e-5 - 2e-3 * math.tan(math.radians(10)), abs=1e-12)
