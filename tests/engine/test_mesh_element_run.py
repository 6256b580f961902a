"""A line whose last element is a track from CAD (a mesh element), and one with a detour from CAD
between two linear sections, through the driver, on 1 and 2 ranks.

The first: a short S-bend channel in millimetres after a 4 mm section; the mass balance is
exact at every frame (inserted = on_track + exited + rejected, nothing lost), the outlet is the
path's end along x (4 + 4.6 mm), the mesh is stored placed after section 1 with its vertices
told apart, its recorded motion is its own sine drive, and the parts over it have their path
coordinate along the bend (the legs of 1.5, 2 and 1.5 mm: 5 mm of path from the joint).

The second: the detour (8.5 mm of path for 7.7 mm along x) with a wiper and a gate, then a 2 mm
section; the outlet is past the third element, its tools are in its stored mesh, and over the
third element the path coordinate is x plus the detour's 0.8 mm."""

import math

import numpy as np
import pytest

from helpers import channel, vibrofeed
from vibrofeed.mesh import write_stl
from vibrofeed.postproc.path import along, path_end
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result

PATH = [(0, 0, 0), (1.5, 0, 0), (3.1, 1.2, 0), (4.6, 1.2, 0)]  # mm: legs 1.5, 2 (1.6, 1.2), 1.5
BEND = f"""
[feeder]
name = "bend"
[parts]
size = 3e-4
[supply]
n_parts = 16
fill_from = 0.6
fill_to = 0.97
[run]
t_end = 0.12
output_dt = 0.004

[[element]]
kind = "linear"
length = 0.004
width = 1.2e-3
drive = {{ freq = 100, amp_t = 1e-4, amp_n = 5e-5 }}

[[element]]
kind = "mesh"
file = "bend.stl"
unit = "mm"
path = {[list(p) for p in PATH]}
width = 1.2e-3
step = 5e-5
drive = {{ freq = 100, amp_t = 1.5e-4, amp_n = 5e-5, phase = -20 }}
"""
A_T, A_N, W, PHI = 1.5e-4, 5e-5, 2 * math.pi * 100.0, math.radians(-20)


def run_checked(tmp_path, monkeypatch, name: str, path, description: str, ranks: int):
    """Write the channel along ``path`` as ``name``.stl and run ``description`` on ``ranks``:
    the result, checked as any result is, with every part accounted for at every frame (16
    inserted, none lost)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    write_stl(*channel(path, 1.2, 1.0), tmp_path / f"{name}.stl", name)
    (tmp_path / f"{name}.toml").write_text(description)
    out = tmp_path / f"{name}{ranks}.h5"
    vibrofeed("run", tmp_path / f"{name}.toml", "-q", "-o", out, "-n", ranks, check=True)
    report = check_file(out)
    assert report.ok, [str(p) for p in report.problems]
    with Result(out) as r:
        mb = r.mass_balance
        assert (mb["lost"] == 0).all() and mb["inserted"][-1] == 16
        assert (mb["inserted"] == mb["on_track"] + mb["exited"] + mb["rejected"]).all()
    return out


@pytest.mark.parametrize("ranks", [1, 2])
def test_a_cad_track_conveys_with_an_exact_mass_balance(tmp_path, monkeypatch, ranks):
    out = run_checked(tmp_path, monkeypatch, "bend", PATH, BEND, ranks)
    with Result(out) as r:
        mb, ev, plane = r.mass_balance, r.outlet, r.outlet_plane
        assert len(ev["id"]) == mb["exited"][-1] > 0  # some left over the bend's end
        assert (ev["position"][:, 0] > 8.6e-3).all()  # past the path's end along x
        assert plane["outlet_x"] == pytest.approx(8.6e-3, abs=1e-12)
        v, _ = r.track_mesh
        mine = v[r.track_sections == 2]
        assert mine[:, 0].min() == pytest.approx(4e-3, abs=1e-8)
        assert mine[:, 0].max() == pytest.approx(8.6e-3, abs=1e-8)
        assert mine[:, 1].max() == pytest.approx(1.8e-3, abs=1e-8)  # the last leg's wall: 1.2 + 0.6 mm
        assert mine[:, 2].min() == pytest.approx(-5e-5, abs=1e-8)
        p2, v2 = r.section_surface(2)
        t = r.time
        assert np.abs(v2[:, 0] - A_T * W * np.cos(W * t)).max() <= 1e-9 * A_T * W
        assert np.abs(v2[:, 2] - A_N * W * np.cos(W * t + PHI)).max() <= 1e-9 * A_T * W
        # the path coordinate: 4 mm of section 1, then 5 mm along the bend
        assert path_end(r) == pytest.approx(9e-3, abs=1e-12)
        frames = np.arange(r.n_frames)
        s, _ = along(r, frames)
        x = r.read("position", frames=frames)[..., 0]
        on_mesh = np.isfinite(s) & (x > 4.2e-3)
        assert on_mesh.any()  # parts crossed the joint onto the bend
        over, past = on_mesh & (s <= 9e-3), on_mesh & (s > 9e-3)
        assert over.any() and (s[over] > 4e-3).all()
        # the path runs 0.4 mm more than x (its diagonal leg 2 mm for 1.6); across that leg a part
        # 0.6 mm off the path at most is 0.6 x 0.6 mm off along x; on the last leg s - x is 0.4 mm
        assert (s[over] - x[over] >= -0.36e-3 - 1e-12).all() and (s[over] - x[over] <= 0.76e-3).all()
        last = over & (s >= 7.7e-3)
        assert last.any() and np.abs(s[last] - x[last] - 0.4e-3).max() <= 1e-12
        # past the path's end, on along its last leg (along +x): as far past it as past 8.6 mm
        assert np.abs((s[past] - 9e-3) - (x[past] - 8.6e-3)).max(initial=0) <= 1e-12


# A detour from CAD between two linear sections: legs 1.5, 2 (1.6, 1.2), 1.5, 2 (1.6, -1.2), 1.5 mm,
# 8.5 mm of path for 7.7 mm along x, back on the centre line; a wiper and a gate on it; then 2 mm.
DETOUR_PATH = [(0, 0, 0), (1.5, 0, 0), (3.1, 1.2, 0), (4.6, 1.2, 0), (6.2, 0, 0), (7.7, 0, 0)]
DETOUR = BEND.replace('name = "bend"', 'name = "detour"').replace("t_end = 0.12", "t_end = 0.3").replace(
    'file = "bend.stl"', 'file = "detour.stl"').replace(
    f"path = {[list(p) for p in PATH]}", f"path = {[list(p) for p in DETOUR_PATH]}") + """
wiper = { height = 4.5e-4, at = 0.3 }
gate = { width = 9e-4, at = 0.8 }

[[element]]
kind = "linear"
length = 0.002
width = 1.2e-3
step = 5e-5
drive = { freq = 100, amp_t = 1.5e-4, amp_n = 5e-5, phase = -20 }
"""


@pytest.mark.parametrize("ranks", [1, 2])
def test_a_cad_detour_between_two_sections_hands_its_parts_on(tmp_path, monkeypatch, ranks):
    out = run_checked(tmp_path, monkeypatch, "detour", DETOUR_PATH, DETOUR, ranks)
    with Result(out) as r:
        mb, ev, plane = r.mass_balance, r.outlet, r.outlet_plane
        # the outlet: 4 mm, the detour's 7.7 mm along x, 2 mm; along the path 4 + 8.5 + 2 mm
        assert plane["outlet_x"] == pytest.approx(13.7e-3, abs=1e-12)
        assert path_end(r) == pytest.approx(14.5e-3, abs=1e-12)
        assert len(ev["id"]) == mb["exited"][-1] > 0 and (ev["position"][:, 0] > 13.7e-3).all()
        v, _ = r.track_mesh
        mine, third = v[r.track_sections == 2], v[r.track_sections == 3]
        # its tools are in its mesh: the wiper's underside 0.45 mm above its floor
        assert np.isclose(mine[:, 2], -5e-5 + 4.5e-4, rtol=0, atol=1e-8).sum() >= 4
        assert third[:, 0].min() == pytest.approx(11.7e-3, abs=1e-8)
        frames = np.arange(r.n_frames)
        s, _ = along(r, frames)
        x = r.read("position", frames=frames)[..., 0]
        # over the third section the path coordinate is x plus the detour's 0.8 mm
        on_third = np.isfinite(s) & (x > 11.7e-3 + 3e-4) & (x <= 13.7e-3)
        assert on_third.any() and np.abs(s[on_third] - x[on_third] - 0.8e-3).max() <= 1e-12
        on_detour = np.isfinite(s) & (x > 4.3e-3) & (x < 11.7e-3 - 3e-4)
        assert on_detour.any() and (s[on_detour] > 4e-3).all() and (s[on_detour] < 12.5e-3).all()
