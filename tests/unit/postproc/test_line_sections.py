"""A feeder line section by section, on synthetic results whose answers are known by
construction (tests/bulk_synthetic.py: parts crossing the joint at given times, conveyed at
known speeds on each section, exiting or falling off at known places): the flux through the
joint, the speed, line density and hold-up of each section, the rejects by tooling, and
whether the bed is steady over the window (single tracks too)."""

import warnings

import numpy as np
import pytest

from bulk_synthetic import JOINT, OUTLET_X, RADIUS, S2_LENGTH, bed, feeder, line_feeder
from helpers import parts, write_bulk_result
from vibrofeed.postproc import FeedRate
from vibrofeed.postproc.feedrate import BOWL_KEYS, LINE_KEYS, SUMMARY_KEYS, period_velocities
from vibrofeed.postproc.line import TOOLING, batch_cuts, bed_pass, drift, drifts, tooling, trend, unsteady
from vibrofeed.results.reader import Result

FREQ = 100.0
# Two frames per period, and an uneven last interval (7.2 ms, not 5) that a chain of
# whole-period intervals (every second frame) reaches.
FRAMES = np.r_[np.arange(0, 0.595 + 1e-9, 0.005), 0.6022]
EDGE = JOINT + S2_LENGTH
D = 2 * RADIUS
V1, V2 = 0.02, 0.04
# Section 2's tooling: a side drop over 0.2 .. 0.6 of it, a wiper at 0.9.
TOOLS = {"s2_width": ("4.2e-4", "m", "", "2e-3"), "s2_drop_from": ("0.2", "-", "", "0"),
         "s2_drop_to": ("0.6", "-", "", "0"), "s2_drop_width": ("2e-4", "m", "", "0"),
         "s2_wiper_height": ("4e-4", "m", "", "0"), "s2_wiper_at": ("0.9", "-", "", "0.5")}
DROP = (JOINT + 0.2 * S2_LENGTH, JOINT + 0.6 * S2_LENGTH)
WIPER = JOINT + 0.9 * S2_LENGTH


def open_line(tmp_path, joint_times, name="line.h5", **kw):
    kw.setdefault("variables", TOOLS)
    return Result(line_feeder(tmp_path / name, FRAMES, joint_times, freq=FREQ, **kw))


def track_x(joint_times, t, v1=V1, v2=V2):
    """Where each part is along the line at t (the generator's closed form)."""
    tj = np.asarray(joint_times)
    return np.where(t < tj, JOINT - v1 * (tj - t), JOINT + v2 * (t - tj))


# -- the flux through the joint --------------------------------------------------------------
def test_the_joint_flux_counts_the_parts_that_cross_it_in_the_window(tmp_path):
    # 300 parts crossing every 5 ms, 2.1 ms after a frame: the first ones were on section 2
    # from the start (first seen beyond the joint: not counted); equal speeds make the
    # interpolated crossing time exact; the track swings 40 um (the track's frame removes it)
    tj = -0.0479 + 0.005 * np.arange(300)
    with open_line(tmp_path, tj, v1=V1, v2=V1, amp=4e-5) as r:
        fr = FeedRate(r, start=0.2, end=0.5).run().results
        times, ids = fr.bed["joint_crossings"][0]
    crossed = (tj > 0.0) & (tj <= FRAMES[-1])      # seen below the joint, then beyond it
    assert ids.tolist() == (np.nonzero(crossed)[0] + 1).tolist()
    assert times == pytest.approx(tj[crossed], abs=1e-12)   # seconds
    inside = ((tj >= 0.2) & (tj < 0.5)).sum()
    assert inside == 60
    s1 = fr.sections[0]
    assert s1["joint_flux"] == pytest.approx(inside / 0.3, rel=1e-12)
    # periodic: six crossings in each batch of three periods (30 ms)
    assert s1["joint_flux_error"] == pytest.approx(0.0, abs=1e-9)
    # the last section's out-flux is the outlet's feed rate
    assert fr.sections[1]["joint_flux"] == fr.parts_per_s
    assert fr.sections[1]["joint_flux_error"] == fr.parts_per_s_err


def test_a_crossing_time_is_interpolated_between_the_two_frames_that_show_it(tmp_path):
    # the speed doubles at the joint: the straight line between the frames before and after
    # (x = J - v1 (tj - t0), J + v2 (t1 - tj)) meets the joint at
    # t0 + v1 (tj - t0) / (v1 (tj - t0) + v2 (t1 - tj)) (t1 - t0)
    tj = 0.1013 + 0.0071 * np.arange(40)
    with open_line(tmp_path, tj) as r:
        fr = FeedRate(r, start=0.1, end=0.4).run().results
    times, ids = fr.bed["joint_crossings"][0]
    k = np.searchsorted(FRAMES, tj, side="right") - 1
    t0, t1 = FRAMES[k], FRAMES[k + 1]
    want = t0 + V1 * (tj - t0) / (V1 * (tj - t0) + V2 * (t1 - tj)) * (t1 - t0)
    assert ids.tolist() == list(range(1, 41))
    assert times == pytest.approx(want, abs=1e-12)
    assert np.abs(times - tj).min() > 1e-5                  # not the crossings themselves


def hand_line(path, rows, times):
    """A line result from per-frame rows {id: track x}: parts on a still track."""
    frames = []
    for k, (t, row) in enumerate(zip(times, rows)):
        ids = sorted(row)
        frames.append((k, t, parts(ids, [[row[i], 0.0, RADIUS] for i in ids], radius=RADIUS)))
    variables = {"freq": ("100", "Hz", "f", "100"), "track_length": (repr(JOINT), "m", "l", "0.02"),
                 "sections": ("2", "-", "s", "1"), "s2_length": (repr(S2_LENGTH), "m", "l", "0.01"),
                 "part_size": (repr(D), "m", "d", "3e-4")}
    return Result(write_bulk_result(path, frames, variables=variables,
                                    outlet={"outlet_x": EDGE, "catch_z": -3e-4, "method": "synthetic"}))


MM = 1e-3
FLICKER_TIMES = [0.0, 0.01, 0.02, 0.03, 0.045]                # the last interval uneven
FLICKER_ROWS = [
    {1: 5.9 * MM, 2: 5.9 * MM, 3: 6.1 * MM},
    {1: 6.1 * MM, 2: 6.1 * MM, 3: 6.2 * MM, 4: 5.98 * MM},   # 4 inserted between frames
    {1: 5.95 * MM, 2: 5.8 * MM, 3: 6.3 * MM, 4: 6.02 * MM},
    {1: 6.2 * MM, 2: 5.7 * MM, 4: 6.1 * MM, 5: 5.99 * MM},   # 3 removed, 5 inserted
    {1: 6.3 * MM, 2: 5.6 * MM, 4: 6.2 * MM},                 # 5 removed before crossing
]


def test_a_part_counts_once_at_its_last_crossing_if_it_stays_beyond_the_joint(tmp_path):
    with hand_line(tmp_path / "flicker.h5", FLICKER_ROWS, FLICKER_TIMES) as r:
        crossings, counts = bed_pass(r, np.arange(5), [JOINT], EDGE)
    times_1, ids_1 = crossings[0]
    # 1 crosses, comes back, crosses again: counted once, at the second crossing (between
    # 0.02 and 0.03 s: 5.95 -> 6.2 mm passes 6 mm a fifth of the way); 2 crosses and comes
    # back: not counted; 3 is first seen beyond: not counted; 4 crosses between 0.01 and
    # 0.02 s halfway; 5 never crosses
    assert ids_1.tolist() == [4, 1]
    assert times_1 == pytest.approx([0.015, 0.022], abs=1e-12)
    # parts over each section per frame: x < 6 mm on section 1, 6 .. 11 mm on section 2
    assert counts.tolist() == [[2, 1], [1, 3], [2, 2], [2, 2], [1, 2]]


@pytest.mark.parametrize("per_block", [2, 3])
def test_the_pass_in_blocks_of_a_few_frames_gives_the_same_answer(tmp_path, monkeypatch, per_block):
    # a long run is read in blocks of frames overlapping by one: every pair is seen once
    from vibrofeed.postproc import line as pl

    with hand_line(tmp_path / "flicker.h5", FLICKER_ROWS, FLICKER_TIMES) as r:
        (times, ids), = bed_pass(r, np.arange(5), [JOINT], EDGE)[0]
        counts = bed_pass(r, np.arange(5), [JOINT], EDGE)[1]
        monkeypatch.setattr(pl, "_BLOCK_VALUES", 4 * r.n_slots * per_block)
        (times_b, ids_b), = bed_pass(r, np.arange(5), [JOINT], EDGE)[0]
        counts_b = bed_pass(r, np.arange(5), [JOINT], EDGE)[1]
    assert ids.tolist() == [4, 1] and ids_b.tolist() == ids.tolist()
    assert times_b.tolist() == times.tolist() and counts_b.tolist() == counts.tolist()


def test_a_part_below_the_catch_plane_crosses_nothing(tmp_path):
    # part 2 falls off section 1 just before the joint (a reject at 0.008 s) and is seen
    # falling on beyond it at the next frame (it would have crossed at 0.01 s); part 1
    # crosses on the track
    mm = 1e-3
    rows = [{1: 5.9 * mm, 2: 5.95 * mm}, {1: 6.1 * mm, 2: 6.05 * mm}]
    with hand_line(tmp_path / "fall.h5", rows, [0.0, 0.02]) as r:
        crossings, counts = bed_pass(r, [0, 1], [JOINT], EDGE, gone_ids=[2], gone_times=[0.008])
    assert crossings[0][1].tolist() == [1]
    assert crossings[0][0] == pytest.approx([0.01], abs=1e-12)
    assert counts.tolist() == [[2, 0], [0, 1]]   # gone by the second frame: on no section


# -- continuity, speeds, density, hold-up ---------------------------------------------------
def steady_line(tmp_path, name="steady.h5", seen=True):
    """A part across the joint every 4 ms from -0.199 s (never at a frame); every fourth
    falls off the side drop (at its middle), every seventh of the rest upstream of the wiper."""
    tj = -0.199 + 0.004 * np.arange(220)
    reject_at = np.full(len(tj), np.nan)
    reject_at[::4] = 0.5 * (DROP[0] + DROP[1])
    sevenths = np.nonzero(np.isnan(reject_at))[0][::7]
    reject_at[sevenths] = WIPER - 2 * D
    return open_line(tmp_path, tj, name=name, reject_at=reject_at, amp=3e-5, reject_seen=seen), tj, reject_at


@pytest.mark.parametrize("seen", [True, False])   # rejects seen falling, or gone between frames
def test_in_steady_feeding_the_joint_flux_is_the_outlet_flux_plus_the_rejects(tmp_path, seen):
    lr, tj, reject_at = steady_line(tmp_path, seen=seen)
    with lr as r:
        fr = FeedRate(r, start=0.1, end=0.5).run().results
    w = 0.4
    s1, s2 = fr.sections
    exits = np.where(np.isnan(reject_at), tj + S2_LENGTH / V2, np.inf)
    falls = tj + (reject_at - JOINT) / V2                     # NaN compares False
    count = lambda t: int(((t >= 0.1) & (t < 0.5)).sum())   # noqa: E731
    # the window's ends are frames: an interpolated crossing stays between the frames of the
    # true one, on the same side of either end
    assert s1["joint_flux"] == pytest.approx(count(tj) / w, rel=1e-12)
    assert s2["joint_flux"] == pytest.approx(count(exits) / w, rel=1e-12)
    assert s2["reject_rate"] == pytest.approx(count(falls) / w, rel=1e-12)
    assert s2["rejects_in_window"] == count(falls)
    assert s1["reject_rate"] == 0.0
    # continuity, to the one part a window's ends can cut at either flux
    assert abs(s1["joint_flux"] - s2["joint_flux"] - s2["reject_rate"]) <= 2 / w
    assert s1["joint_flux"] == pytest.approx(250.0, abs=1 / w)


def test_each_section_has_its_speed_hold_up_and_line_density(tmp_path):
    lr, tj, reject_at = steady_line(tmp_path)
    with lr as r:
        fr = FeedRate(r, start=0.1, end=0.5).run().results
        ids = [r.read("id", frames=k) for k in range(len(FRAMES))]
    s1, s2 = fr.sections
    assert (s1["x_from"], s1["x_to"], s2["x_from"], s2["x_to"]) == (0.0, JOINT, JOINT, EDGE)
    assert s1["along"] == s2["along"] == "x"  # a line of straight sections: the deck's x
    # whole periods on one section at both ends: its own speed (the track swings 30 um)
    assert s1["speed"] == pytest.approx(V1, rel=1e-9) and s2["speed"] == pytest.approx(V2, rel=1e-9)
    assert s1["speed_error"] < 1e-9 * V1 and s2["speed_error"] < 1e-9 * V2
    # hold-up: the parts over each section at the window's frames, the fallen ones left out
    leave = np.where(np.isnan(reject_at), tj + S2_LENGTH / V2, tj + (reject_at - JOINT) / V2)
    window = FRAMES[(FRAMES >= 0.1 - 1e-12) & (FRAMES <= 0.5 + 1e-12)]
    on1 = [int(((track_x(tj, t) < JOINT) & (track_x(tj, t) >= 0)).sum()) for t in window]
    on2 = [int(((track_x(tj, t) >= JOINT) & (leave > t)).sum()) for t in window]
    assert s1["hold_up"] == pytest.approx(np.mean(on1), rel=1e-12)
    assert s2["hold_up"] == pytest.approx(np.mean(on2), rel=1e-12)
    assert s1["line_density"] == pytest.approx(np.mean(on1) / JOINT, rel=1e-12)
    assert s2["line_density"] == pytest.approx(np.mean(on2) / S2_LENGTH, rel=1e-12)
    # the rejects are still in the frames that report them (falling): left out all the same
    fallen = np.isfinite(reject_at) & (leave <= 0.5)
    assert any(np.isin(np.nonzero(fallen & (leave <= t))[0] + 1, i).any()
               for t, i in zip(FRAMES, ids) if 0.1 <= t <= 0.5)
    # every part conveyed: no drift
    assert fr.unsteady is None and fr.reason is None


def test_the_uneven_last_interval_is_left_out_of_the_speeds(tmp_path):
    # frames two per period and a last one 7.2 ms after: over that interval the track's 50 um
    # swing would alias into the speed; only whole-period intervals are kept
    amp, v = 5e-5, 0.02
    exits = 0.05 + np.arange(300) / 300.0
    with Result(feeder(tmp_path / "uneven.h5", FRAMES, exits, speed=v, amp=amp, freq=FREQ)) as r:
        x, vel, interval, (m, alias) = period_velocities(r, np.arange(len(FRAMES)), 0, OUTLET_X)
        fr = FeedRate(r).run().results
    assert m == 2 and alias == 0.0
    assert interval.max() == len(FRAMES[::2]) - 3                # the chain's last interval is out
    assert vel == pytest.approx(np.full(len(vel), v), rel=1e-9)
    assert fr.mean_velocity == pytest.approx(v, rel=1e-9)
    w = 2 * np.pi * FREQ
    last = (amp * (np.sin(w * FRAMES[-1]) - np.sin(w * FRAMES[-3]))) / (FRAMES[-1] - FRAMES[-3])
    assert abs(last) > 0.05 * v                                  # what it would have added


# -- rejects by tooling -----------------------------------------------------------------------
def test_rejects_are_sorted_by_the_tooling_where_they_fell(tmp_path):
    from vibrofeed.feeders import Feeder

    # x of each reject: inside the drop; a part size before it and after it (slack); beyond
    # the slack; upstream of the wiper within three part sizes; farther upstream
    mm = 1e-3
    at = [0.5 * (DROP[0] + DROP[1]), DROP[0] - 0.9 * D, DROP[1] + 0.9 * D, DROP[1] + 1.1 * D,
          WIPER - 2.9 * D, WIPER + 0.5 * D, WIPER - 3.1 * D, 3 * mm]
    want = ["side_drop", "side_drop", "side_drop", "other", "wiper", "wiper", "other", "other"]
    tj = 0.1 + 0.02 * np.arange(len(at))
    with open_line(tmp_path, tj, reject_at=at) as r:
        params = dict(r.parameters)
        fr = FeedRate(r, start=0.1, end=0.3).run().results
        section = r.rejects["section"]
    names = np.array(TOOLING)
    got = names[tooling(np.array(at), section, Feeder.from_values(params).stations, D)]
    assert got.tolist() == want
    assert section.tolist() == [2, 2, 2, 2, 2, 2, 2, 1]           # 3 mm: off section 1
    # reached at tj + (x - J) / v2 on section 2, tj - (J - x) / v1 on section 1
    fell = np.where(np.array(at) < JOINT, tj - (JOINT - np.array(at)) / V1, tj + (np.array(at) - JOINT) / V2)
    by = fr.rejects_by_tooling
    for name in ("side_drop", "wiper", "other"):  # (no jet on this line: no entry)
        mine = np.array(want) == name
        inside = mine & (fell >= 0.1) & (fell < 0.3)
        assert by[name]["in_window"] == inside.sum()
        assert by[name]["total"] == mine.sum()
        assert by[name]["per_s"] == pytest.approx(inside.sum() / 0.2, rel=1e-12)
    assert fr.sections[0]["reject_rate"] == pytest.approx(((fell >= 0.1) & (fell < 0.3) &
                                                           (section == 1)).sum() / 0.2, rel=1e-12)


def test_a_line_without_tooling_lists_none_for_it(tmp_path):
    tj = 0.1 + 0.01 * np.arange(30)
    with open_line(tmp_path, tj, variables={}) as r:
        fr = FeedRate(r, start=0.1, end=0.4).run().results
    assert fr.rejects_by_tooling["side_drop"] is None and fr.rejects_by_tooling["wiper"] is None
    assert fr.rejects_by_tooling["other"]["total"] == 0


# -- the summary and the table ------------------------------------------------------------------
def test_a_lines_summary_and_table_hold_the_sections(tmp_path):
    from vibrofeed.cli.feedrate import table

    lr, _, _ = steady_line(tmp_path)
    with lr as r:
        fa = FeedRate(r, start=0.1, end=0.5, model=False).run()
    s = fa.summary()
    assert list(s) == [k for k in SUMMARY_KEYS if k not in ("model_velocity", "model_note", "velocity_ratio",
                                                                 "shape", "returned")
                       + tuple(k for k in BOWL_KEYS if k not in LINE_KEYS)]  # (sections: both)
    assert [sec["section"] for sec in s["sections"]] == [1, 2]
    assert set(s["rejects_by_tooling"]) == {"side_drop", "wiper", "other"}
    text = table(s)
    assert "sections" in text and "continuity     joint 1: 250 /s in" in text
    assert "outlet" in text and "side drop" in text
    # a reason (e.g. a drift) puts n/a where the rates were
    s["reason"] = "not steady: something"
    text = table(s)
    assert "feed rate      not steady: something" in text
    assert "continuity" not in text and "joint n/a" in text


def test_a_single_track_has_no_sections_in_its_summary_or_table(tmp_path):
    from vibrofeed.cli.feedrate import table

    exits = 0.1 + np.arange(200) / 250.0
    with Result(feeder(tmp_path / "one.h5", FRAMES, exits, freq=FREQ, amp=3e-5)) as r:
        fa = FeedRate(r).run()
    s = fa.summary()
    assert list(s) == [k for k in SUMMARY_KEYS if k not in LINE_KEYS + BOWL_KEYS]
    assert s["unsteady"] is None and "sections" not in table(s)
    # section 1 is the whole track: its speed is the track's
    assert [t["quantity"] for t in s["bed_trends"]] == ["conveying speed"]   # a store: no hold-up
    assert s["bed_trends"][0]["first"] == pytest.approx(0.02, rel=1e-9)


# -- steadiness from the bed -------------------------------------------------------------------
def test_drift_compares_the_thirds_with_the_scatter_about_a_line():
    # y = 2 + x/2 + d e, e orthogonal to 1 and x: the fit is exact, the residuals d e,
    # scatter sqrt(4 d^2 / (6 - 2)) = d, the thirds' means 2.25 and 4.25, error d sqrt(2/2)
    e = np.array([1.0, -1, 0, 0, -1, 1])
    x = np.arange(6.0)
    for d in (0.6, 0.7):
        first, last, error = drift(2 + 0.5 * x + d * e)
        assert (first, last) == pytest.approx((2.25, 4.25), abs=1e-12)
        assert error == pytest.approx(d, rel=1e-12)
    assert drifts(2.25, 4.25, 0.6) and not drifts(2.25, 4.25, 0.7)    # 2 vs 3 x 0.6, 3 x 0.7
    assert drift(np.r_[np.arange(5.0), np.nan]) is None                # five batches: too few
    assert not drifts(0.02, 0.02 * (1 + 1e-15), 0.0)                   # equal up to round-off


def test_drifts_error_is_the_scatter_times_the_root_of_two_over_a_third():
    # nine batches, thirds of three: y = 2 + x/2 + d e with e (1, -1, 0, 0, 0, 0, 0, -1, 1)
    # orthogonal to 1 and x: residuals d e, scatter sqrt(4 d^2 / 7), thirds' means 2.5, 5.5
    e = np.array([1.0, -1, 0, 0, 0, 0, 0, -1, 1])
    first, last, error = drift(2 + 0.5 * np.arange(9.0) + 0.7 * e)
    assert (first, last) == pytest.approx((2.5, 5.5), abs=1e-12)
    assert error == pytest.approx(2 * 0.7 / np.sqrt(7) * np.sqrt(2 / 3), rel=1e-12)


def test_drift_takes_the_means_of_the_thirds_not_their_medians():
    first, last, _ = drift([1.0, 1.0, 4.0, 2.0, 2.0, 2.0, 3.0, 3.0, 6.0])  # medians 1 and 3
    assert (first, last) == pytest.approx((2.0, 4.0), abs=1e-12)


def test_a_draining_bed_conveyed_at_a_steady_speed_is_steady(tmp_path):
    # the demo's case: a pre-filled bed, no inlet, every part at the same speed: the
    # hold-up falls as the bed drains, which is no drift (a store without inflow)
    exits = 0.1 + np.arange(150) / 300.0
    with Result(feeder(tmp_path / "drain.h5", FRAMES, exits, freq=FREQ, amp=4e-5)) as r:
        fr = FeedRate(r).run().results
        held = fr.bed["hold_up"][0]
    assert held[0] > held[-1] + 10                 # draining
    assert fr.unsteady is None and fr.reason is None
    assert fr.parts_per_s == pytest.approx(300, abs=1 / (fr.steady_to - fr.steady_from))


def accelerating(path, v0, g, n=200, spacing=1e-4, inlet_rate=0.0):
    """A single track on which every part moves at v0 + g t (one speed at a time for all):
    part k starts at x = OUTLET - k spacing, exits when it reaches the edge."""
    x0 = OUTLET_X - spacing * (np.arange(n) + 1)
    reach = OUTLET_X - x0
    leave = (-v0 + np.sqrt(v0 ** 2 + 2 * g * reach)) / g if g else reach / v0
    variables = {"inlet_rate": (repr(inlet_rate), "1/s", "inlet", "0")}
    return bed(path, FRAMES, lambda t: x0 + v0 * t + 0.5 * g * t ** 2, np.full(n, -np.inf), leave,
               amp=3e-5, freq=FREQ, variables=variables, lanes=np.arange(n) % 5 * 1e-3)


def test_a_bed_speeding_up_is_not_steady(tmp_path):
    v0, g = 0.012, 0.02          # 12 mm/s at 0, 20 mm/s at 0.4 s
    with Result(accelerating(tmp_path / "fast.h5", v0, g)) as r:
        fr = FeedRate(r, start=0.1, end=0.4).run().results
    # a whole-period speed is v at the interval's middle: the first third's batches hold
    # middles within [0.1, 0.2], the last third's within [0.3, 0.4]
    t = fr.bed_trends[0]
    assert (t["section"], t["quantity"], t["drifts"]) == (1, "conveying speed", True)
    assert v0 + g * 0.1 <= t["first"] <= v0 + g * 0.2
    assert v0 + g * 0.3 <= t["last"] <= v0 + g * 0.4
    assert fr.unsteady.startswith("not steady: the bed's conveying speed on section 1 rises "
                                  f"{t['first'] * 1e3:.1f} -> {t['last'] * 1e3:.1f} mm/s over the window")
    assert fr.reason == fr.unsteady                 # enough exits: the drift is the reason
    with Result(accelerating(tmp_path / "even.h5", 0.016, 0.0)) as r:
        even = FeedRate(r, start=0.1, end=0.4).run().results
    assert even.unsteady is None and even.bed_trends[0]["first"] == pytest.approx(0.016, rel=1e-9)


def test_a_fed_track_whose_bed_drains_is_not_steady(tmp_path):
    # the same steady speed, but the deck feeds the track (inlet_rate > 0): its hold-up must
    # hold, and it falls
    with Result(accelerating(tmp_path / "fed.h5", 0.016, 0.0, inlet_rate=50.0)) as r:
        fr = FeedRate(r, start=0.1, end=0.4).run().results
    quantities = {t["quantity"]: t for t in fr.bed_trends}
    assert not quantities["conveying speed"]["drifts"] and quantities["hold-up"]["drifts"]
    assert "the hold-up on section 1 falls" in fr.unsteady and "parts over the window" in fr.unsteady


def test_a_line_whose_second_section_fills_is_not_steady(tmp_path):
    # section 2 conveys at 5 mm/s: nobody reaches the outlet in the window, section 2 fills
    tj = 0.05 + 0.005 * np.arange(100)
    with open_line(tmp_path, tj, v2=0.005) as r:
        fr = FeedRate(r, start=0.1, end=0.5).run().results
    held = {t["section"]: t for t in fr.bed_trends if t["quantity"] == "hold-up"}
    assert list(held) == [2]                        # section 1 is a store (no inlet)
    assert held[2]["drifts"] and held[2]["last"] > held[2]["first"] + 20
    assert "the hold-up on section 2 rises" in fr.unsteady
    assert fr.reason.startswith("too few exits")    # no exit at all: that reason first


def test_unsteady_says_every_drift():
    trends = [{"section": 1, "quantity": "conveying speed", "first": 0.012, "last": 0.0201,
               "error": 0.001, "drifts": True},
              {"section": 2, "quantity": "hold-up", "first": 4.0, "last": 4.1, "error": 0.2,
               "drifts": False},
              {"section": 2, "quantity": "hold-up", "first": 6.0, "last": 2.5, "error": 0.2,
               "drifts": True}]
    assert unsteady(trends) == (
        "not steady: the bed's conveying speed on section 1 rises 12.0 -> 20.1 mm/s over the window "
        "(more than 3 standard errors: 3 mm/s); the hold-up on section 2 falls 6.0 -> 2.5 parts over "
        "the window (more than 3 standard errors: 0.6 parts)")
    assert unsteady(trends[1:2]) is None and unsteady([]) is None


def test_unsteady_names_a_bowls_sections_as_its_table_does():
    # a bowl with an exit line: its third section is the exit line's element 2, s2
    said = [{"section": k, "name": name, "quantity": "hold-up", "first": 6.0, "last": 2.5,
             "error": 0.2, "drifts": True} for k, name in ((1, "helix"), (2, "chute"), (3, "s2"))]
    text = unsteady(said)
    assert "the hold-up on the helix falls" in text and "on the chute falls" in text
    assert "the hold-up on s2 falls" in text and "section" not in text
    assert [t["name"] for t in trend(3, "hold-up", [1.0, 1.0, 2.0, 2.0, 3.0, 3.0], "s2")] == ["s2"]
    assert "name" not in trend(3, "hold-up", [1.0, 1.0, 2.0, 2.0, 3.0, 3.0])[0]  # a line's: numbered


def test_a_window_shorter_than_two_periods_is_one_batch():
    assert batch_cuts(0.0, 0.01, 100.0, 10).tolist() == [0.0, 0.01]  # one period at 100 Hz
    assert len(batch_cuts(0.0, 0.1, 100.0, 4)) == 5  # ten periods: four batches


# -- the pieces at their limits -----------------------------------------------------------------
def test_section_bounds_of_a_single_track_a_line_and_which_section_a_part_is_over():
    from vibrofeed.postproc.line import section_bounds, section_index

    assert section_bounds({"sections": "1"}, 0.02) == [(0.0, 0.02)]
    assert section_bounds({"sections": "2", "track_length": "0.006"}, 0.011) == [(0.0, 0.006),
                                                                             (0.006, 0.011)]
    # x < joint: section 1; joint <= x <= edge: section 2; beyond the edge (falling) or no
    # part: -1; without an edge nothing is beyond it
    x = [0.001, JOINT, EDGE, EDGE + 1e-6, np.nan]
    assert section_index(x, [JOINT], EDGE).tolist() == [0, 1, 1, -1, -1]
    assert section_index(x, [JOINT], np.inf).tolist() == [0, 1, 1, 1, -1]


def test_a_part_first_seen_exactly_at_the_joint_is_over_section_2_and_does_not_cross_it(tmp_path):
    # part 1 sits at x = joint at the first frame (over section 2 already) and moves on:
    # first seen beyond the joint, no crossing; part 2 crosses between the frames
    rows = [{1: JOINT, 2: 5.9 * MM}, {1: 6.1 * MM, 2: 6.1 * MM}]
    with hand_line(tmp_path / "at_joint.h5", rows, [0.0, 0.01]) as r:
        crossings, counts = bed_pass(r, [0, 1], [JOINT], EDGE)
    assert crossings[0][1].tolist() == [2]
    assert crossings[0][0] == pytest.approx([0.005], abs=1e-12)
    assert counts.tolist() == [[1, 1], [0, 2]]


def test_a_part_that_crosses_rests_on_the_joint_and_goes_back_does_not_count(tmp_path):
    # part 1 crosses up (5.9 -> 6 mm: x >= joint), then from x = joint back below it: its
    # last crossing is back, it did not stay; part 2 crosses and stays
    rows = [{1: 5.9 * MM, 2: 5.9 * MM}, {1: JOINT, 2: 6.1 * MM}, {1: 5.9 * MM, 2: 6.2 * MM}]
    with hand_line(tmp_path / "back.h5", rows, [0.0, 0.01, 0.02]) as r:
        crossings, counts = bed_pass(r, [0, 1, 2], [JOINT], EDGE)
    assert crossings[0][1].tolist() == [2]
    assert counts.tolist() == [[2, 0], [0, 2], [1, 1]]


def test_parts_gone_at_or_before_a_frame_are_on_no_section(tmp_path):
    # three parts gone, given out of id order: 3 (on section 2) exactly at the second frame's
    # time, 2 (on section 1) before it, 1 after it; 4 never
    rows = [{1: 5.0 * MM, 2: 5.5 * MM, 3: 6.5 * MM, 4: 7.0 * MM},
            {1: 5.1 * MM, 2: 5.6 * MM, 3: 6.6 * MM, 4: 7.1 * MM}]
    with hand_line(tmp_path / "gone.h5", rows, [0.0, 0.02]) as r:
        _, counts = bed_pass(r, [0, 1], [JOINT], EDGE, gone_ids=[3, 2, 1],
                             gone_times=[0.02, 0.015, 0.03])
    assert counts.tolist() == [[2, 2], [1, 1]]


def test_a_pass_over_a_single_frame_counts_its_parts(tmp_path):
    # no pair of frames, so no crossing, but the frame's hold-up all the same
    with hand_line(tmp_path / "one.h5", FLICKER_ROWS[:1], FLICKER_TIMES[:1]) as r:
        crossings, counts = bed_pass(r, [0], [JOINT], EDGE)
    assert counts.tolist() == [[2, 1]]
    assert crossings[0][1].tolist() == [] and crossings[0][0].tolist() == []


def test_line_tooling_at_the_exact_ends_of_each_stretch():
    # the bounds are inclusive: a reject exactly at the side drop's widened ends or at the
    # wiper's reach and bar end belongs to that tool
    from vibrofeed.feeders import Feeder
    from vibrofeed.feeders.feeder import section_from

    values = {"sections": 2, "track_length": JOINT, "s2_length": S2_LENGTH, "s2_width": 4.2e-4,
              "s2_drop_from": 0.2, "s2_drop_to": 0.6, "s2_drop_width": 2e-4,
              "s2_wiper_height": 4e-4, "s2_wiper_at": 0.9, "part_size": D}
    s = section_from(values)
    (d0, d1), (w0, w1) = s.drop_x, s.wiper_x
    names = np.array(TOOLING)
    at = np.array([d0 - D, d1 + D, w0 - 3.0 * D, w1, d0 - D])
    got = names[tooling(at, [2, 2, 2, 2, 1], Feeder.from_values(values).stations, D)]
    assert got.tolist() == ["side_drop", "side_drop", "wiper", "wiper", "other"]


def test_bowl_tooling_at_the_exact_ends_of_each_stretch():
    from vibrofeed.feeders import Feeder
    from vibrofeed.postproc.line import TOOLING

    size = 3e-4
    feeder = Feeder.from_values({
        "bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "turns": 1.5,
        "wall_height": 1e-3, "cone_angle": 3.0, "cross_tilt": 3.0, "lip_height": 0.0,
        "chute_length": 8e-3, "part_size": size, "drop_from": 0.5, "drop_to": 0.7,
        "drop_width": 4e-4, "wiper_height": 4.5e-4, "wiper_at": 0.2})
    b = feeder.elements[0].bowl
    d0, d1 = (float(b.arc_length(t)) for t in b.drop)
    w0, w1 = (float(b.arc_length(t)) for t in b.wiper)
    where = np.array([d0 - size, d1 + size, w0 - 3.0 * size, w1])
    assert [TOOLING[k] for k in tooling(where, 1, feeder.stations, size)] == [
        "side_drop", "side_drop", "wiper", "wiper"]


def test_batch_cuts_without_a_frequency_at_a_slow_one_and_under_half_a_period():
    # no frequency: 200 equal units, ten batches of 20
    assert batch_cuts(0.0, 1.0, 0.0, 10) == pytest.approx(np.arange(11) / 10, abs=1e-15)
    # 0.5 Hz over 20 s: ten whole periods in four batches of 3, 3, 2, 2 periods (2 s each)
    assert batch_cuts(0.0, 20.0, 0.5, 4) == pytest.approx([0.0, 6.0, 12.0, 16.0, 20.0], abs=1e-12)
    # 0.4 of a period: still one batch over the whole window
    assert batch_cuts(1.0, 1.004, 100.0, 10) == pytest.approx([1.0, 1.004], abs=1e-15)


def test_batch_means_put_each_time_in_its_batch_the_last_one_closed():
    from vibrofeed.postproc.line import batch_means

    cuts = np.array([0.0, 1.0, 2.0, 3.0])
    # at each inner cut a value starts the next batch; at the last cut it ends the last one;
    # before the first cut or after the last: left out; batch 2 holds one value alone
    times = [-0.5, 0.0, 0.5, 1.0, 2.0, 2.5, 3.0, 3.5]
    values = [100.0, 1.0, 3.0, 7.0, 10.0, 20.0, 60.0, 100.0]
    assert batch_means(times, values, cuts) == pytest.approx([2.0, 7.0, 30.0], abs=1e-12)
    with warnings.catch_warnings():   # an empty batch is NaN without a 0/0 warning
        warnings.simplefilter("error")
        got = batch_means([0.5], [4.0], cuts)
    assert got[0] == 4.0 and np.isnan(got[1:]).all()


def test_a_change_of_exactly_three_errors_is_no_drift():
    assert not drifts(1.0, 4.0, 1.0) and drifts(1.0, 4.0 + 1e-9, 1.0)   # 3 x 1.0 exactly
    # without scatter, a change of exactly 1e-9 of the values is still taken for round-off
    assert not drifts(999999999.0, 1e9, 0.0) and drifts(999999998.0, 1e9, 0.0)


def test_unsteady_tells_speeds_in_millimetres_per_second():
    # 0.5 m/s is 500.0 mm/s exactly (a scale off by 0.1 % shows in the first decimal)
    t = {"section": 2, "quantity": "conveying speed", "first": 0.5, "last": 0.25, "error": 0.01,
         "drifts": True}
    assert unsteady([t]) == ("not steady: the bed's conveying speed on section 2 falls 500.0 -> "
                             "250.0 mm/s over the window (more than 3 standard errors: 30 mm/s)")


def test_a_reject_a_jet_fired_at_is_the_jets_wherever_it_fell():
    from vibrofeed.postproc.line import JET_FALL, fired_at

    # part 7 fired at on section 2 over [0.10, 0.115] s; part 8 on section 2 long before; part 9
    # on section 3 (a jet of another section)
    firings = {"id": np.array([7, 8, 9]), "section": np.array([2, 2, 3]),
               "start": np.array([0.10, 0.01, 0.10]), "end": np.array([0.115, 0.025, 0.115])}
    ids = np.array([7, 7, 8, 9, 10, 7])
    times = np.array([0.12, 0.115 + JET_FALL + 1e-6, 0.3, 0.12, 0.12, 0.09])
    sections = np.array([2, 2, 2, 2, 2, 2])
    got = fired_at(ids, times, sections, firings)
    # in its window's reach; too long after; fell long after; another section's; never fired
    # at; fell before the window opened
    assert got.tolist() == [True, False, False, False, False, False]
    assert not fired_at(ids, times, sections, {"id": np.array([], dtype=np.int64)}).any()


def test_fired_at_is_its_definition_on_many_rejects_and_firings():
    """The sorted lookups give what the definition says, reject by reject (a firing of the same
    part on the same section whose window started by the fall and ended at most JET_FALL
    before it), on 2000 rejects against 3000 firings with repeated and overlapping windows."""
    from vibrofeed.postproc.line import JET_FALL, fired_at

    rng = np.random.default_rng(5)
    start = rng.uniform(0, 2, 3000)
    firings = {"id": rng.integers(0, 300, 3000), "section": rng.integers(2, 5, 3000),
               "start": start, "end": start + rng.uniform(0, 0.05, 3000)}
    ids, sections = rng.integers(0, 320, 2000), rng.integers(2, 5, 2000)
    times = rng.uniform(0, 2.1, 2000)
    times[:200] = firings["end"][:200] + JET_FALL  # at the reach's edge, exactly
    ids[:200], sections[:200] = firings["id"][:200], firings["section"][:200]
    want = [bool(np.any((firings["id"] == i) & (firings["section"] == s) & (firings["start"] <= t)
                        & (t <= firings["end"] + JET_FALL))) for i, s, t in zip(ids, sections, times)]
    got = fired_at(ids, times, sections, firings)
    assert got.tolist() == want and 200 <= sum(want) < 2000
