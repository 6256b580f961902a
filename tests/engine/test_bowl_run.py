"""A short bowl feeder run through the driver, on 1 and 2 ranks: parts placed along the
helix and the chute, the ones near the chute's end leave over it. The mass balance is exact
at every frame (inserted = on_track + exited, nothing lost), every exit left past the
outlet edge beside the bowl, `vibrofeed check` passes, and the bowl's recorded motion is its
drive's closed form: turned by (amp_t / r_mid) sin(w t), lifted by amp_n sin(w t + phase),
where the engine's movers put it (their Riemann sums)."""

import math

import numpy as np
import pytest

from helpers import vibrofeed
from vibrofeed.bowl import bowl_from, bowl_mesh
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result

BOWL = {"shape": 0, "n_parts": 6, "n_track": 80, "turns": 0.5, "youngs": 2e7, "t_settle": 0.002,
        "t_end": 0.1, "output_dt": 0.0037, "amp_t": 1e-4, "phase": -30, "rolling_friction": 0.3}
# (frames 0.37 periods apart: the drive is sampled at every phase, not stroboscopically; half a
# turn, the softest contact the bulk feeder is validated for and a stroke that conveys the
# chute's last parts over its end keep the run short; the rolling friction keeps spheres from
# rolling back down the helix)


def riemann(amplitude: float, omega: float, dt: float, steps: np.ndarray, phi: float = 0.0):
    """sum_{j=1..k} amplitude omega dt cos(omega j dt + phi): where a mover that adds
    v(t_j) dt at step j has moved the mesh after k steps."""
    j = np.arange(1, int(steps.max()) + 1)
    terms = amplitude * omega * dt * np.cos(omega * j * dt + phi)
    return np.concatenate([[0.0], np.cumsum(terms)])[steps]


@pytest.mark.parametrize("ranks", [1, 2])
def test_a_short_bowl_run_keeps_every_part_and_records_the_bowls_motion(tmp_path, ranks):
    out = tmp_path / f"bowl{ranks}.h5"
    args = [a for k, v in BOWL.items() for a in ("-p", f"{k}={v}")]
    vibrofeed("run", "bowl_feeder", "-q", "-o", out, "-n", ranks, *args, check=True)
    report = check_file(out)
    assert report.ok, [str(p) for p in report.problems]
    with Result(out) as r:
        p = r.parameters
        mb, ev, plane = r.mass_balance, r.outlet, r.outlet_plane
        assert (mb["lost"] == 0).all()
        assert (mb["inserted"] == mb["on_track"] + mb["exited"]).all()
        assert mb["inserted"][-1] > 70  # the pile and the track's parts
        assert len(ev["id"]) == mb["exited"][-1] > 0  # the chute's last parts left
        b = bowl_from(p)
        assert plane["outlet_x"] == pytest.approx(b.outlet_x, rel=1e-12, abs=0)
        # each exit left over the chute's end, beside the bowl: past the outlet edge, within
        # the chute's width (and what a part's flight adds) of its centre line
        assert (ev["position"][:, 0] > b.outlet_x).all()
        assert (np.abs(ev["position"][:, 1] + b.r_mid) < b.track_width).all()
        # the result stores the bowl at rest, as the prepare hook made it
        v, t = r.track_mesh
        want_v, want_t = bowl_mesh(b)
        np.testing.assert_array_equal(v, want_v)
        np.testing.assert_array_equal(t, want_t)
        # the bowl's motion: the closed form of the movers' sums at each frame's step
        assert r.holds("surface_angle")
        dt = float(r.derived["dt_used"])
        w = 2 * math.pi * p["freq"]
        phi = math.radians(p["phase"])
        steps = r.read("step").astype(np.int64)
        time = r.read("time")
        theta_amp = p["amp_t"] / b.r_mid
        angle = r.read("surface_angle")
        rate = r.read("surface_angular_velocity")
        lift = r.read("surface_position")
        vz = r.read("surface_velocity")
        assert np.allclose(angle[:, :2], 0, rtol=0, atol=0) and np.allclose(rate[:, :2], 0, rtol=0, atol=0)
        assert np.allclose(lift[:, :2], 0, rtol=0, atol=0) and np.allclose(vz[:, :2], 0, rtol=0, atol=0)
        # [rad]: 1e-9 of the amplitude (the deck's closed form and this sum agree to rounding)
        assert np.allclose(angle[:, 2], riemann(theta_amp, w, dt, steps), rtol=0, atol=1e-9 * theta_amp)
        assert np.allclose(rate[:, 2], theta_amp * w * np.cos(w * time), rtol=0, atol=1e-9 * theta_amp * w)
        z_want = p["amp_n"] * math.sin(phi) + riemann(p["amp_n"], w, dt, steps, phi)
        assert np.allclose(lift[:, 2], z_want, rtol=0, atol=1e-9 * p["amp_n"])  # [m]
        assert np.allclose(vz[:, 2], p["amp_n"] * w * np.cos(w * time + phi), rtol=0,
                           atol=1e-9 * p["amp_n"] * w)
        # and that sum is the continuous drive to within omega dt of its amplitude
        assert np.abs(angle[:, 2] - theta_amp * np.sin(w * time)).max() <= 2 * w * dt * theta_amp
        assert angle[:, 2].max() > 0.5 * theta_amp  # the frames sample the drive's phases


def test_by_hand_after_prepare_with_a_long_launch(tmp_path):
    """The deck by hand, as its header says: prepare, then the line it prints. A strong drive
    (75 Hz, 1.5e-4 m of stroke) launches parts far beyond the chute's end, so the catch face
    under it (as wide as the launch's reach) reaches past the bowl's side: the box must hold it
    (LIGGGHTS stops when a mesh leaves the domain). With a side drop over the first turn and a
    wiper: the narrowed floor, the riser's end faces and the bar are a mesh LIGGGHTS accepts."""
    import re
    import shlex
    import subprocess

    given = {"n_parts": 4, "n_track": 10, "turns": 0.5, "youngs": 2e7, "t_settle": 0.002,
             "t_end": 0.002, "output_dt": 0.001, "freq": 75, "amp_t": 1.5e-4, "amp_n": 4e-5,
             "phase": -60, "drop_from": 0.5, "drop_to": 0.8, "drop_width": 4e-4,
             "wiper_height": 4.5e-4, "wiper_at": 0.3}
    args = [a for k, v in given.items() for a in ("-p", f"{k}={v}")]
    proc = vibrofeed("prepare", "bowl_feeder", *args, "-o", tmp_path / "m", check=True)
    line = proc.stdout.strip().splitlines()[-1]
    assert line.startswith("liggghts -in ") and "-var freq 75" in line
    done = subprocess.run(shlex.split(line) + ["-log", "log", "-nocite"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600)
    log = (tmp_path / "log").read_text()
    assert done.returncode == 0 and "ERROR" not in log, log[-2000:]
    assert len(re.findall(r"Loop time of .* for \d+ steps", log)) == 2  # settle, then vibration
    assert (tmp_path / "outlet.txt").exists() and (tmp_path / "bowl_feeder.dump").exists()
