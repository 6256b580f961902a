"""A short two-section feeder line through the driver, on 1 and 2 ranks: a bed of spheres
near section 1's end crosses the joint onto a faster section 2 whose side drop (a ledge
narrower than the bed, open on one side) throws off every part not against its wall. By
construction some parts fall off the drop and some leave over the outlet edge; the mass
balance is exact at every frame (inserted = on_track + exited + rejected, nothing lost),
each reject fell off the drop's open side, and the result stores both sections' meshes and
both sections' motion: section 2's is its own sine drive at every frame, where its mesh is."""

import math
import subprocess

import numpy as np
import pytest

from helpers import DECKS, vibrofeed
from vibrofeed.feeders.feeder import section_from
from vibrofeed.line import section_mesh
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result

LINE = {"sections": 2, "n_parts": 30, "track_length": 0.004, "track_width": 1.2e-3,
        "fill_from": 0.5, "fill_to": 0.97, "s2_length": 0.003, "s2_width": 1.2e-3,
        "s2_amp_t": 1e-4, "s2_phase": -30, "s2_drop_from": 0.1, "s2_drop_to": 0.9,
        "s2_drop_width": 4e-4, "t_end": 0.2, "output_dt": 0.004, "part_size": 3e-4}
# (frames 0.4 periods apart: the drives are sampled at every phase, not stroboscopically)


@pytest.mark.parametrize("ranks", [1, 2])
def test_two_sections_mass_balance_is_exact(tmp_path, ranks):
    out = tmp_path / f"line{ranks}.h5"
    args = [a for k, v in LINE.items() for a in ("-p", f"{k}={v}")]
    vibrofeed("run", "bulk_feeder", "-q", "-o", out, "-n", ranks, *args, check=True)
    report = check_file(out)
    assert report.ok, [str(p) for p in report.problems]
    with Result(out) as r:
        mb, ev, rej, plane = r.mass_balance, r.outlet, r.rejects, r.outlet_plane
        assert (mb["lost"] == 0).all()
        assert (mb["inserted"] == mb["on_track"] + mb["exited"] + mb["rejected"]).all()
        assert mb["inserted"][-1] == 30
        assert len(ev["id"]) == mb["exited"][-1] > 0 and len(rej["id"]) == mb["rejected"][-1] > 0
        assert not set(ev["id"]) & set(rej["id"])  # a part leaves once, one way
        assert plane["outlet_x"] == pytest.approx(0.007, abs=1e-12)  # the outlet is section 2's end
        # every reject fell off section 2 over the drop's open side (+y, past the ledge), a
        # part's size around the stretch at most (it is timed where it crossed the catch plane)
        s = section_from({k: str(v) for k, v in LINE.items()} | {"s2_wall_height": "1e-3",
                                                                    "s2_step": "5e-5"})
        a, b = s.drop_x
        assert (rej["section"] == 2).all()
        assert (rej["position"][:, 0] > a - 3e-4).all() and (rej["position"][:, 0] < b + 3e-4).all()
        assert (rej["position"][:, 1] > -s.width / 2 + s.drop_width).all()
        assert np.abs(rej["position"][:, 2] - plane["catch_z"]).max() < 1e-12
        # both sections' meshes, at rest: section 2 below section 1 and reaching the outlet
        v, _ = r.track_mesh
        assert v[:, 0].max() == pytest.approx(0.007, abs=1e-12)
        assert v[:, 2].min() == pytest.approx(-5e-5, abs=1e-12)  # no cross tilt: the step
        # which vertex is whose: section 2's are its mesh exactly, section 1's end at the joint
        split = r.track_sections
        np.testing.assert_array_equal(v[split == 2], section_mesh(s)[0])
        assert (v[split == 1][:, 0] <= 0.004 + 1e-12).all() and (split == 1).sum() > 0
        assert_section_2_follows_its_drive(r)


def mover_sum(amp, w, phi, dt, n_max):
    """Displacement after n = 0..n_max steps of a LIGGGHTS sine mover (wiggle, viblin), summed
    step by step as it moves the mesh: v(t_j) dt at steps j = 1..n, v = amp w cos(w t + phi),
    from amp sin(phi) at t = 0."""
    j = np.arange(1, n_max + 1)
    return amp * math.sin(phi) + np.concatenate([[0.0], np.cumsum(amp * w * dt * np.cos(w * j * dt + phi))])


def assert_section_2_follows_its_drive(r):
    """At every frame, section 2's recorded motion is its sine drive (s2_* of LINE and the
    deck's defaults: s2_freq 100 Hz, s2_amp_n 50 um): the position the movers' step-by-step
    sum to float rounding (1e-9 of the amplitude), which departs from the continuous sine by
    at most amplitude x w dt (1 + w dt / 24) (the sum's bound; reached where cos(w t) = -1);
    the velocity the sine's derivative to 1e-9 of its peak."""
    assert r.n_sections == 2
    p2, v2 = r.section_surface(2)
    p1, _ = r.section_surface(1)
    step, t, dt = r.step, r.time, r.derived["dt_used"]
    a_t, a_n, w, phi = 1e-4, 5e-5, 2 * math.pi * 100.0, math.radians(-30)
    amp = max(a_t, a_n)
    np.testing.assert_allclose(t, step * dt, rtol=1e-12, atol=0)  # time is step x dt
    x = mover_sum(a_t, w, 0.0, dt, int(step[-1]))[step]
    z = mover_sum(a_n, w, phi, dt, int(step[-1]))[step]
    assert np.abs(p2[:, 0] - x).max() <= 1e-9 * amp
    assert np.abs(p2[:, 2] - z).max() <= 1e-9 * amp
    assert (p2[:, 1] == 0).all() and (v2[:, 1] == 0).all()
    # the continuous closed form, x = a_t sin(w t), z = a_n sin(w t + phi), within a w dt
    th = w * dt
    assert np.abs(p2[:, 0] - a_t * np.sin(w * t)).max() <= a_t * th * (1 + th / 24)
    assert np.abs(p2[:, 2] - a_n * np.sin(w * t + phi)).max() <= a_n * th * (1 + th / 24)
    assert np.abs(v2[:, 0] - a_t * w * np.cos(w * t)).max() <= 1e-9 * amp * w
    assert np.abs(v2[:, 2] - a_n * w * np.cos(w * t + phi)).max() <= 1e-9 * amp * w
    # sampled over the whole period, not only where the sines vanish
    assert np.abs(p2[:, 0]).max() > 0.9 * a_t and np.abs(v2[:, 0]).max() > 0.9 * a_t * w
    # a drive of its own: section 1 (amp_t 50 um, phase 0) moves otherwise
    assert np.abs(p2[:, 0] - p1[:, 0]).max() > 0.4 * (a_t - 5e-5)
    assert np.abs(p2[:, 2] - p1[:, 2]).max() > 0.4 * a_n * math.sin(math.radians(30))


def read_stl_ascii(path):
    return np.array([[float(v) for v in line.split()[1:4]]
                     for line in open(path) if line.strip().startswith("vertex")])


def read_stl_binary(path):
    data = open(path, "rb").read()
    n = int(np.frombuffer(data[80:84], np.uint32)[0])
    rows = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    return np.frombuffer(data[84:84 + 50 * n], rows)["v"].reshape(-1, 3).astype(float)


def test_section_2s_mesh_is_where_its_motion_is_recorded(tmp_path):
    """By hand, with a mesh dump of section 2 and a print of its recorded s2_surface_*: at every
    dump, each vertex sits at its rest position (track_s2.stl) + the recorded displacement. A
    second frequency and phase make the test tell section 2's drive from section 1's."""
    params = {"sections": 2, "n_parts": 4, "track_length": 0.004, "track_width": 1.2e-3,
              "fill_from": 0.5, "fill_to": 0.97, "s2_length": 0.003, "s2_width": 1.2e-3,
              "s2_freq": 130, "s2_amp_t": 8e-5, "s2_amp_n": 3e-5, "s2_phase": -30, "s2_step": 1e-4,
              "t_end": 0.004, "output_dt": 5e-4, "part_size": 3e-4}
    meshes = tmp_path / "meshes"
    vibrofeed("prepare", "bulk_feeder", "-o", meshes,
              *[a for k, v in params.items() for a in ("-p", f"{k}={v}")], check=True)
    text = (DECKS / "bulk_feeder.liggghts").read_text()
    marker = "# ------------------------------------------------------------------ run"
    extra = ("dump s2 all mesh/stl ${output_every} mesh_*.stl track_s2\n"
             "variable rec_step equal step\n"
             'fix rec all print ${output_every} "${rec_step} ${s2_surface_x} ${s2_surface_y} '
             '${s2_surface_z} ${surface_x} ${dt_used}" file surface.txt screen no\n')
    assert text.count(marker) == 1
    (tmp_path / "deck.liggghts").write_text(text.replace(marker, extra + marker))
    args = ["liggghts", "-in", "deck.liggghts", "-var", "deck_dir", str(DECKS), "-var", "mesh_dir",
            str(meshes), "-log", "log", "-nocite"]
    for k, v in params.items():
        args += ["-var", k, str(v)]
    subprocess.run(args, cwd=tmp_path, check=True, capture_output=True, timeout=300)
    rest = read_stl_binary(meshes / "track_s2.stl")  # what LIGGGHTS read (float32)
    recorded = np.loadtxt(tmp_path / "surface.txt", ndmin=2)
    assert len(recorded) >= 6
    for step, sx, sy, sz, _, _ in recorded:
        moved = read_stl_ascii(tmp_path / f"mesh_{int(step)}.stl") - rest
        # the dump prints 6 significant digits: +-5e-9 m on x (up to 7e-3 m), +-5e-10 m on y and
        # z (up to 1e-3 m, the wall tops): twice that is below the drive's O(w dt) departure from
        # the sine (3.5e-8 m on x) and 1e-4 of the amplitudes (8e-5, 3e-5 m)
        assert np.abs(moved[:, 0] - sx).max() <= 1e-8
        assert np.abs(moved[:, 1] - sy).max() <= 1e-9 and sy == 0
        assert np.abs(moved[:, 2] - sz).max() <= 1e-9
    assert np.abs(recorded[:, 1] - recorded[:, 4]).max() > 1e-5  # not section 1's motion
    assert np.abs(recorded[:, 1]).max() > 0.5 * 8e-5  # it does move
    # and the recorded motion is the drive's (130 Hz, phase -30 deg): the movers' step-by-step
    # sum to 1e-9 of the amplitude (fix print writes 15 significant digits)
    steps, dt = recorded[:, 0].astype(int), recorded[0, 5]
    w = 2 * math.pi * 130
    x = mover_sum(8e-5, w, 0.0, dt, int(steps[-1]))[steps]
    z = mover_sum(3e-5, w, math.radians(-30), dt, int(steps[-1]))[steps]
    assert np.abs(recorded[:, 1] - x).max() <= 1e-9 * 8e-5
    assert np.abs(recorded[:, 3] - z).max() <= 1e-9 * 8e-5


@pytest.mark.parametrize("ranks", [1, 2])
def test_recirculated_rejects_come_back_at_the_inlet(tmp_path, ranks):
    """recirculate=1: each reject is dropped into the inlet block again return_delay after it
    crossed the catch plane, at the first frame at or after that time (inserted in the next
    step, so counted from the frame after): ``returned`` at frame k is exactly the rejects
    with crossing + delay <= t(k-1); each returned part is a new one that appears at the track
    start; and the balance, now with the returns in ``inserted``, is exact at every frame."""
    out, delay = tmp_path / "returns.h5", 0.02
    params = {**LINE, "recirculate": 1, "return_delay": delay, "t_end": 0.22}
    vibrofeed("run", "bulk_feeder", "-q", "-o", out, "-n", ranks,
              *[a for k, v in params.items() for a in ("-p", f"{k}={v}")], check=True)
    report = check_file(out)
    assert report.ok, [str(p) for p in report.problems]
    with Result(out) as r:
        mb, rej, t = r.mass_balance, r.rejects, r.time
        assert (mb["lost"] == 0).all() and mb["rejected"][-1] >= 10  # the drop throws many off
        assert (mb["inserted"] == 30 + mb["returned"]).all()
        assert (mb["inserted"] == mb["on_track"] + mb["exited"] + mb["rejected"]).all()
        due = np.array([0] + [int(np.sum(rej["time"] + delay <= tk)) for tk in t[:-1]])
        np.testing.assert_array_equal(mb["returned"], due)
        assert mb["returned"][-1] >= 10
        # the new parts, frame by frame: as many as were returned, new ids, in or just below
        # the inlet block (x from r_ext to r_ext + 3 part sizes, r_ext 150 um; at rest there
        # a frame (4 ms) before, they have fallen or slid far less than a part since)
        seen = set()
        for frame in r.iter_frames():
            new = np.isin(frame.ids, list(seen), invert=True)
            if frame.index:
                k = frame.index
                assert new.sum() == mb["returned"][k] - mb["returned"][k - 1]
                assert (frame.ids[new] > 30).all()
                x = frame["position"][new]
                assert ((x[:, 0] > 1.5e-4) & (x[:, 0] < 1.5e-4 + 3 * 3e-4)).all()
            seen |= set(frame.ids.tolist())
