"""A feeder line's result stores every section's motion (FORMAT.md, "Feeder lines").

Synthetic two-section line files are written through the writer with section 2's motion
computed here, independently of the package, as LIGGGHTS' sine movers produce it: the sum of
v(t_j) dt over the steps j = 1..n (an explicit cumulative sum, not the closed form that
``vibrofeed check`` evaluates). The reader must give back what was written, ``vibrofeed check``
must pass such a file and fail one whose section 2 moved off its drive by 1 % of the
amplitude, or that lacks section 2's motion.
"""

from __future__ import annotations

import hashlib
import math

import h5py
import numpy as np
import pytest

from helpers import parts
from vibrofeed.errors import ResultError
from vibrofeed.results import layout as L
from vibrofeed.results.check import DRIVE_RTOL, check_file
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import Recording, ResultWriter

DT = 2e-6             # s, the run's step
EVERY = 500           # steps between frames
N_FRAMES = 21         # 0 .. 0.02 s: more than two periods of either drive
S1 = {"freq": 100.0, "amp_t": 5e-5, "amp_n": 5e-5, "phase": 0.0}
S2 = {"s2_freq": 130.0, "s2_amp_t": 8e-5, "s2_amp_n": 3e-5, "s2_phase": -30.0}
JOINT = 0.004         # track_length: section 2 starts here
S2_AMP = max(S2["s2_amp_t"], S2["s2_amp_n"])
S2_OMEGA = 2 * math.pi * S2["s2_freq"]


def mover_sum(amp, freq, phase_deg, steps):
    """(n, position, velocity) of one axis of a sine mover, by summing v(t_j) dt step by step
    (LIGGGHTS' wiggle and viblin): position after step n from the start's amp sin(phase)."""
    w, phi = 2 * math.pi * freq, math.radians(phase_deg)
    j = np.arange(1, steps + 1)
    x = np.concatenate([[0.0], np.cumsum(amp * w * np.cos(w * j * DT + phi) * DT)])
    n = np.arange(steps + 1)
    return amp * math.sin(phi) + x, amp * w * np.cos(w * n * DT + phi)


def section2_motion(cross=None):
    """(steps (F,), times (F,), position (F, 3), velocity (F, 3)) of section 2 at the frames;
    ``cross`` ({"s2_amp_c": .., "s2_phase_c": ..}): it also moves across (a third mover, y)."""
    steps = np.arange(N_FRAMES) * EVERY
    x, vx = mover_sum(S2["s2_amp_t"], S2["s2_freq"], 0.0, int(steps[-1]))
    z, vz = mover_sum(S2["s2_amp_n"], S2["s2_freq"], S2["s2_phase"], int(steps[-1]))
    y = vy = np.zeros(int(steps[-1]) + 1)
    if cross:
        y, vy = mover_sum(cross["s2_amp_c"], S2["s2_freq"], cross["s2_phase_c"], int(steps[-1]))
    return (steps, steps * DT, np.column_stack([x[steps], y[steps], z[steps]]),
            np.column_stack([vx[steps], vy[steps], vz[steps]]))


def two_sections():
    """Section 1's floor (x 0..JOINT) and section 2's (JOINT..JOINT+3 mm, 50 um lower), each
    with its own 4 vertices, and each vertex's section."""
    v1 = np.array([[0, -6e-4, 0], [JOINT, -6e-4, 0], [JOINT, 6e-4, 0], [0, 6e-4, 0]], float)
    v2 = v1 + [JOINT, 0, -5e-5]
    t = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
    return (np.vstack([v1, v2]), np.vstack([t, t + 4])), np.repeat([1, 2], 4)


def write_line(path, shift=None, sections=2, track_sections=True, derived=None, frames=N_FRAMES,
               cross=None, cross_recorded=True):
    """A complete two-section line result; ``shift(position, velocity)`` may alter section 2's
    recorded motion in place before it is written. ``sections=1`` records section 1 only;
    ``derived`` replaces the derived values ({"dt_used": DT}); ``frames``: the first ones only;
    ``cross``: section 2 also moves across (section2_motion), its parameters recorded unless
    ``cross_recorded`` is false."""
    steps, times, s2_pos, s2_vel = section2_motion(cross)
    derived = {"dt_used": DT} if derived is None else derived
    if shift is not None:
        shift(s2_pos, s2_vel)
    w1 = 2 * math.pi * S1["freq"]
    variables = {name: (repr(value), "", name, repr(value))
                 for name, value in {**S1, **S2, **(cross if cross and cross_recorded else {}),
                                     "sections": 2, "track_length": JOINT}.items()}
    track, split = two_sections()
    w = ResultWriter(path, deck_name="synthetic_line", deck_path="synthetic_line.liggghts",
                     deck_text="# synthetic line\n", variables=variables, derived=derived,
                     engine_version="LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)", seed=1,
                     run_id=hashlib.sha256(str(path).encode()).hexdigest(),
                     recording=Recording(sections=sections, rejects=True),
                     outlet={"outlet_x": JOINT + 3e-3, "catch_z": -5e-4, "method": "synthetic"},
                     track=track, track_sections=split if track_sections else None)
    for k, (step, t) in enumerate(zip(steps[:frames], times[:frames])):
        s1 = [S1["amp_t"] * math.sin(w1 * t), 0, S1["amp_n"] * math.sin(w1 * t)]
        v1 = [S1["amp_t"] * w1 * math.cos(w1 * t), 0, S1["amp_n"] * w1 * math.cos(w1 * t)]
        # one part on each section, resting on its floor
        p = parts([1, 2], [[2e-3 + s1[0], 0, 1.5e-4 + s1[2]],
                           [5e-3 + s2_pos[k, 0], 0, 1e-4 + s2_pos[k, 2]]], radius=1.5e-4,
                  velocity=[v1, s2_vel[k]])
        counts = {"inserted": 2, "on_track": 2, "exited": 0, "rejected": 0, "lost": 0}
        w.write_frame(int(step), float(t), p, s1, v1, counts=counts,
                      section_surfaces=[(s2_pos[k], s2_vel[k])] if sections == 2 else ())
    w.finish("complete")
    return path


def errors(path):
    return [str(p) for p in check_file(path).problems if p.level == "error"]


@pytest.fixture
def line(tmp_path):
    return write_line(tmp_path / "line.h5")


# -- writer and reader ------------------------------------------------------------------------
def test_each_sections_motion_reads_back_as_written(line):
    steps, times, s2_pos, s2_vel = section2_motion()
    w1 = 2 * math.pi * S1["freq"]
    with Result(line) as r:
        assert r.n_sections == 2
        p2, v2 = r.section_surface(2)
        np.testing.assert_array_equal(p2, s2_pos)  # stored float64: the same numbers
        np.testing.assert_array_equal(v2, s2_vel)
        # section 1 is the single track's surface, unchanged
        p1, v1 = r.section_surface(1)
        np.testing.assert_array_equal(p1, r.surface_position)
        np.testing.assert_array_equal(v1, r.surface_velocity)
        np.testing.assert_allclose(p1[:, 0], S1["amp_t"] * np.sin(w1 * times), rtol=0, atol=1e-20)
        # the two sections move differently (section 2 is not section 1 written twice)
        assert np.abs(p2 - p1).max() > 0.5 * S2["s2_amp_t"]
        # windows, as for surface_position
        np.testing.assert_array_equal(r.read("surface_s2_position", frames=-1), s2_pos[-1])
        np.testing.assert_array_equal(r.section_surface(2, frames=[3, 1])[1], s2_vel[[3, 1]])
        f = r.frame(4, fields=("surface_s2_velocity",))
        np.testing.assert_array_equal(f["surface_s2_velocity"], s2_vel[4])
        np.testing.assert_array_equal(r.track_sections, np.repeat([1, 2], 4))
        with pytest.raises(IndexError, match="section 3 out of range"):
            r.section_surface(3)
        with pytest.raises(IndexError):
            r.section_surface(0)


def test_section_motion_is_an_h5md_time_series_of_the_parts_frames(line):
    with h5py.File(line, "r") as f:
        assert L.surface_path(2) == "observables/surface_s2"
        for name, unit in (("position", "m"), ("velocity", "m s-1")):
            g = f[f"observables/surface_s2/{name}"]
            assert set(g) == {"step", "time", "value"}
            assert g["value"].shape == (N_FRAMES, 3)
            assert g["value"].attrs["unit"] == unit and g["time"].attrs["unit"] == "s"
            info = h5py.check_string_dtype(g["value"].attrs.get_id("unit").dtype)
            assert info.length is None and info.encoding == "ascii"  # the units module's vlen ASCII
            # the same frames as the parts: step and time hard-linked (H5MD shares them so)
            assert g["step"] == f[f"{L.PARTS}/position/step"] and g["time"] == f[f"{L.PARTS}/position/time"]
        assert f[L.TRACK_SECTION].dtype == np.int32
        assert f[L.PARAMETERS].attrs["format_version"].tolist() == list(L.FORMAT_VERSION)
        assert tuple(L.FORMAT_VERSION) >= L.SECTIONS_SINCE == (1, 4)


def test_a_single_track_has_one_section(tmp_path):
    from helpers import write_result

    path = write_result(tmp_path / "one.h5", [(0, 0.0, parts([1], [[0, 0, 1e-4]])),
                                               (1, 1e-3, parts([1], [[0, 0, 1e-4]]))],
                        surface=[([1e-6, 0, 0], [0, 0, 0]), ([2e-6, 0, 0], [0, 0, 0])])
    with Result(path) as r, h5py.File(path, "r") as f:
        assert r.n_sections == 1 and r.track_sections is None
        np.testing.assert_array_equal(r.section_surface(1)[0][:, 0], [1e-6, 2e-6])
        with pytest.raises(IndexError, match="section 2 out of range"):
            r.section_surface(2)
        with pytest.raises(ResultError, match=r"records no motion of section 2 \(it has 1 section\)$"):
            r.read("surface_s2_position")
        assert set(f["observables"]) == {"surface"}  # nothing new in a single track's file


def test_writer_refuses_a_frame_without_every_sections_motion(tmp_path):
    track, split = two_sections()
    w = ResultWriter(tmp_path / "w.h5", deck_name="d", deck_path="d", deck_text="d", variables={},
                     derived={}, engine_version="LIGGGHTS", seed=1, recording=Recording(sections=2),
                     track=track, track_sections=split)
    with pytest.raises(ValueError, match="1 further section"):
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), np.zeros(3), np.zeros(3))
    assert w.frames == 0  # refused before anything was taken
    w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), np.zeros(3), np.zeros(3),
                  section_surfaces=[(np.ones(3), np.zeros(3))])
    w.finish()
    with pytest.raises(ValueError, match="track_sections must lie in 1..2"):
        ResultWriter(tmp_path / "b.h5", deck_name="d", deck_path="d", deck_text="d", variables={},
                     derived={}, engine_version="LIGGGHTS", seed=1, recording=Recording(sections=2),
                     track=track, track_sections=split + 1)


def test_a_line_of_format_1_3_still_reads(line, tmp_path):
    old = tmp_path / "old.h5"
    old.write_bytes(line.read_bytes())
    with h5py.File(old, "r+") as f:  # as format 1.3 wrote a line: section 1's motion only
        del f["observables/surface_s2"], f[L.TRACK_SECTION]
        f[L.PARAMETERS].attrs["format_version"] = np.array([1, 3], dtype="i4")
    with Result(old) as r, Result(line) as new:
        assert r.n_sections == 2 and r.format_version == (1, 3) and r.track_sections is None
        np.testing.assert_array_equal(r.surface_position, new.surface_position)
        with pytest.raises(ResultError, match="records no motion of section 2"):
            r.section_surface(2)
    report = check_file(old)
    assert report.ok, [str(p) for p in report.problems]  # a warning, not an error
    assert any("surface_s2" in str(p) and p.level == "warning" for p in report.problems)


def test_reading_a_section_beyond_the_lines_names_its_sections(line):
    with Result(line) as r:
        with pytest.raises(ResultError, match=r"records no motion of section 3 \(it has 2 sections\)$"):
            r.read("surface_s3_velocity")


# -- vibrofeed check ---------------------------------------------------------------------------
def test_a_good_line_file_passes_check(line):
    report = check_file(line)
    assert report.ok, [str(p) for p in report.problems]
    assert not report.problems


@pytest.mark.parametrize("element, axis", [("position", 0), ("position", 2), ("velocity", 0),
                                           ("velocity", 2)])
def test_section_2_one_percent_off_its_drive_fails(tmp_path, element, axis):
    """1 % of the amplitude (of the peak speed for the velocity), at one frame on one axis."""
    scale = S2_AMP * (S2_OMEGA if element == "velocity" else 1.0)

    def shift(pos, vel):
        (pos if element == "position" else vel)[7, axis] += 0.01 * scale

    found = errors(write_line(tmp_path / "off.h5", shift))
    assert any(f"/observables/surface_s2/{element}/value" in e and "at frame 7" in e for e in found), found


CROSS = {"s2_amp_c": 4e-5, "s2_phase_c": 60.0}


def test_a_section_moving_across_its_track_passes_check(tmp_path):
    path = write_line(tmp_path / "cross.h5", cross=CROSS)
    assert errors(path) == []
    with Result(path) as r:
        p2, _ = r.section_surface(2)
    # it did move across: its sway spans most of twice the amplitude over two periods
    assert np.ptp(p2[:, 1]) > CROSS["s2_amp_c"]


def test_a_cross_stroke_one_percent_off_fails(tmp_path):
    def shift(pos, vel):
        pos[5:, 1] += 0.01 * CROSS["s2_amp_c"]

    assert any("section 2's position" in e for e in errors(write_line(tmp_path / "c.h5", shift, cross=CROSS)))


def test_a_cross_motion_without_its_drive_among_the_parameters_fails(tmp_path):
    # (a file before cross strokes: no s2_amp_c, taken as 0: a section that swayed is off its drive)
    path = write_line(tmp_path / "c.h5", cross=CROSS, cross_recorded=False)
    assert any("section 2's position" in e for e in errors(path))


def test_check_tolerance_is_a_millionth_of_the_amplitude(tmp_path):
    """Off by half the tolerance passes (the recorded values are the movers' closed form to
    float rounding), off by twice the tolerance fails."""
    assert DRIVE_RTOL == 1e-6

    def by(fraction):
        def shift(pos, vel):
            pos[:, 0] += fraction * DRIVE_RTOL * S2_AMP
        return shift

    assert not errors(write_line(tmp_path / "near.h5", by(0.5)))
    assert any("surface_s2/position" in e for e in errors(write_line(tmp_path / "far.h5", by(2.0))))


def test_a_line_without_section_2s_motion_fails(tmp_path):
    found = errors(write_line(tmp_path / "no_s2.h5", sections=1, track_sections=False))
    assert any("/observables/surface_s2: missing" in e for e in found), found
    found = errors(write_line(tmp_path / "no_split.h5", track_sections=False))
    assert any(f"/{L.TRACK_SECTION}: missing" in e for e in found), found


def test_section_2s_motion_is_checked_as_section_1s(line, tmp_path):
    """Non-finite values and frames other than the parts' fail, as for observables/surface."""
    bad = tmp_path / "nan.h5"
    bad.write_bytes(line.read_bytes())
    with h5py.File(bad, "r+") as f:
        f["observables/surface_s2/velocity/value"][3, 1] = np.nan
    assert any("surface_s2/velocity/value: non-finite values" in e for e in errors(bad))
    short = tmp_path / "short.h5"
    short.write_bytes(line.read_bytes())
    with h5py.File(short, "r+") as f:
        g = f["observables/surface_s2/position"]
        data = g["value"][:-1]
        del g["value"], g["step"], g["time"]
        g["value"] = data
        g["value"].attrs["unit"] = "m"
        g["step"], g["time"] = np.arange(N_FRAMES - 1), np.arange(N_FRAMES - 1) * EVERY * DT
        g["time"].attrs["unit"] = "s"
    assert any(f"{N_FRAMES - 1} frames, particles have {N_FRAMES}" in e for e in errors(short))
    extra = tmp_path / "extra.h5"
    extra.write_bytes(line.read_bytes())
    with h5py.File(extra, "r+") as f:
        f.copy("observables/surface_s2", "observables/surface_s3")
    assert any("surface_s3: the motion of a section the run does not have" in e for e in errors(extra))


def test_check_needs_section_2s_drive_among_the_parameters(line, tmp_path):
    bad = tmp_path / "nodrive.h5"
    bad.write_bytes(line.read_bytes())
    with h5py.File(bad, "r+") as f:
        del f[f"{L.VARIABLES}/s2_phase"]
    assert any("s2_phase" in e and "cannot be verified" in e for e in errors(bad))


def test_speed_limit_counts_the_fastest_section(tmp_path):
    """A part at 1.5 m/s: beyond the 1 m/s floor of the limit, within 100 x section 2's peak
    speed (about 7 cm/s x 100): only section 2's drive admits it."""
    path = write_line(tmp_path / "fast.h5")
    with h5py.File(path, "r+") as f:
        v = f[f"{L.PARTS}/velocity/value"]
        ids = f[f"{L.PARTS}/id/value"][5]
        data = v[5]
        data[np.nonzero(ids == 2)[0][0]] = [1.5, 0, 0]
        v[5] = data
        # section 1's drive and recorded speed alone: 2 pi 100 Hz * 7.1e-5 m = 4.4 cm/s -> 4.4 m/s
        # limit; make section 1 slow so that only section 2's peak (6.5 cm/s) admits the part
        for name in ("amp_t", "amp_n"):
            del f[f"{L.VARIABLES}/{name}"]
            f[f"{L.VARIABLES}/{name}"] = 1e-7
            f[f"{L.VARIABLES}/{name}"].attrs["unit"] = "m"
        f["observables/surface/velocity/value"][...] *= 2e-3
    assert not any("moves at" in e for e in errors(path))
    with h5py.File(path, "r+") as f:  # without section 2 (s2 amplitudes 0 and at rest) it fails
        for name in ("s2_amp_t", "s2_amp_n"):
            del f[f"{L.VARIABLES}/{name}"]
            f[f"{L.VARIABLES}/{name}"] = 0.0
            f[f"{L.VARIABLES}/{name}"].attrs["unit"] = "m"
        for element in ("position", "velocity"):
            f[f"observables/surface_s2/{element}/value"][...] = 0.0
    assert any("moves at 1.5 m/s" in e for e in errors(path))


# -- the H5MD-MD export ------------------------------------------------------------------------
def test_md_export_carries_section_2s_motion(line, tmp_path):
    from vibrofeed.results.md_export import export_md

    with Result(line) as r:
        out = export_md(r, tmp_path / "line.h5md")
        p2, v2 = r.section_surface(2)
    with h5py.File(out, "r") as f:
        g = f["observables/surface_s2"]
        assert g["position/value"].attrs["unit"] == "nm" and g["velocity/value"].attrs["unit"] == "m s-1"
        np.testing.assert_allclose(g["position/value"][()], p2 * 1e9, rtol=1e-12, atol=0)
        np.testing.assert_allclose(g["velocity/value"][()], v2, rtol=0, atol=0)
    mda = pytest.importorskip("MDAnalysis")
    u = mda.Universe(str(out))
    for k, ts in enumerate(u.trajectory):
        np.testing.assert_allclose(ts.data["surface_s2/position"], p2[k] * 1e9, rtol=1e-12, atol=1e-9)


def test_pyh5md_reads_section_2s_motion(line):
    pyh5md = pytest.importorskip("pyh5md")
    with pyh5md.File(str(line), "r") as f, Result(line) as r:
        position = pyh5md.element(f["observables"], "surface_s2/position")
        assert position.element_type == "TimeElement"
        np.testing.assert_array_equal(position.value[()], r.section_surface(2)[0])
        np.testing.assert_array_equal(position.step[()], r.step)


def test_a_section_the_run_does_not_have_is_reported_once_as_such(line, tmp_path):
    """Not also as a section whose drive (s3_*) is missing: the run has no section 3."""
    extra = tmp_path / "extra.h5"
    extra.write_bytes(line.read_bytes())
    with h5py.File(extra, "r+") as f:
        f.copy("observables/surface_s2", "observables/surface_s3")
    assert errors(extra) == ["error: /observables/surface_s3: the motion of a section the run does "
                             "not have (sections = 2)"]


@pytest.mark.parametrize("elements", [("angle",), ("angle", "angular_velocity")])
def test_only_the_first_sections_surface_may_rotate(line, tmp_path, elements):
    bad = tmp_path / "turning.h5"
    bad.write_bytes(line.read_bytes())
    with h5py.File(bad, "r+") as f:
        for name in elements:   # a rotation's series: any (frames, 3) one will do
            f.copy("observables/surface_s2/position", f"observables/surface_s2/{name}")
    found = errors(bad)
    assert found == ["error: /observables/surface_s2/angle: only the first section's surface may "
                     "rotate"], found


def test_the_drive_is_checked_at_the_recorded_step_else_at_time_over_step(tmp_path):
    """derived/dt_used is the movers' step (a step 1 % longer moves section 2 elsewhere); a run
    that did not record it is checked at time / step, the same step here."""
    assert not errors(write_line(tmp_path / "no_dt.h5", derived={}))
    found = errors(write_line(tmp_path / "other_dt.h5", derived={"dt_used": 1.01 * DT}))
    assert any("/observables/surface_s2/position/value: section 2's position at frame" in e
               for e in found), found


def test_a_line_without_any_time_step_cannot_be_verified(tmp_path):
    """One frame, at step 0, and no dt_used: no step to compute the drive with."""
    found = errors(write_line(tmp_path / "first.h5", derived={}, frames=1))
    assert found == ["error: /observables/surface_s2: no time step recorded (derived/dt_used): section "
                     "2's motion cannot be verified"], found
