"""What a sweep could not measure stays unmeasured (issue 19): a job whose feed rate the
analysis cannot give (too few exits, a bed still drifting) records no rate and says why,
the report shows it as unmeasured and never names it best, the maps leave it uncoloured;
a feeder line's per-section figures and the chips' orientation yield are columns, each
checked here against its closed form on synthetic results (tests/bulk_synthetic.py)."""

from __future__ import annotations

import io
import math
import re

import numpy as np
import pytest

from bulk_synthetic import JOINT, S2_LENGTH, feeder, line_feeder
from vibrofeed.sweep import report as R
from vibrofeed.sweep import summary as S
from vibrofeed.sweep.metrics import metrics

FRAMES = np.arange(0, 0.2 + 1e-9, 0.01)


# ------------------------------------------------------------------ metrics of one job
def test_too_few_exits_record_no_rate_and_the_reason(tmp_path):
    path = feeder(tmp_path / "few.h5", FRAMES, np.array([0.05, 0.12, 0.15]), freq=100.0)
    row = metrics(path)
    assert row["feedrate_reason"] == "too few exits to measure (3 in the window; need ≥ 10)"
    for key in ("parts_per_s", "parts_per_s_err", "mass_per_s", "mass_per_s_err"):
        assert row[key] is None, key                   # not 0 +- 0
    assert row["n_events"] == 3                        # what was counted stays
    assert row["singulation_reason"].startswith("too few exits")
    for key in ("cv_interarrival", "doubles_rate", "singulated_fraction", "mean_gap",
                "doubles_per_s", "mean_interarrival"):
        assert row[key] is None, key
    assert row["n_arrivals"] == 3


def test_a_measured_rate_has_no_reason(tmp_path):
    exits = 0.02 + 0.15 * np.arange(40) / 40
    row = metrics(feeder(tmp_path / "many.h5", FRAMES, exits, freq=100.0))
    assert row["feedrate_reason"] is None and row["singulation_reason"] is None
    inside = ((exits >= row["steady_from"]) & (exits < row["steady_to"])).sum()
    assert row["parts_per_s"] == pytest.approx(inside / (row["steady_to"] - row["steady_from"]),
                                               rel=1e-12)
    assert "joint_flux_1" not in row and "speed_1" not in row  # a single track has no sections


# A line: parts cross the joint every 5 ms, 2.1 ms after a frame (none on a frame), but for
# every seventh missing (batches of periods count unequal numbers); conveyed at 20 mm/s over
# both sections; every fourth falls off section 2 at 40 % of it.
LINE_FRAMES = np.r_[np.arange(0, 0.595 + 1e-9, 0.005), 0.6022]
V = 0.02
REJECT_X = JOINT + 0.4 * S2_LENGTH
# section 2's drive, as a line's result records it (the track itself stands still here)
DRIVE_2 = {name: (value, unit, "", value) for name, value, unit in (
    ("s2_freq", "100", "Hz"), ("s2_amp_t", "0", "m"), ("s2_amp_n", "0", "m"), ("s2_phase", "0", "deg"))}


def test_a_lines_sections_are_columns_each_as_its_closed_form(tmp_path):
    tj = -0.0479 + 0.005 * np.array([k for k in range(350) if k % 7 != 3])
    reject = np.where(np.arange(len(tj)) % 4 == 3, REJECT_X, np.nan)
    path = line_feeder(tmp_path / "line.h5", LINE_FRAMES, tj, v1=V, v2=V, reject_at=reject, freq=100.0,
                       variables=DRIVE_2)
    row = metrics(path)
    assert row["feedrate_reason"] is None, row["feedrate_reason"]
    t_a, t_b = row["steady_from"], row["steady_to"]
    span = t_b - t_a

    def rate(times):
        return ((times >= t_a) & (times < t_b)).sum() / span

    rejected = np.isfinite(reject)
    leave = np.where(rejected, tj + (REJECT_X - JOINT) / V, tj + S2_LENGTH / V)
    # through the joint: every part (equal speeds make the interpolated crossing exact)
    assert row["joint_flux_1"] == pytest.approx(rate(tj), rel=1e-12)
    # its error: the scatter of the rates of 10 batches of whole periods (100 Hz) over sqrt(10)
    periods = round(span * 100)
    sizes = [len(c) for c in np.array_split(np.arange(periods), min(10, periods))]
    cuts = t_a + span * np.r_[0, np.cumsum(sizes)] / periods
    rates = np.histogram(tj[(tj >= t_a) & (tj < t_b)], bins=cuts)[0] / np.diff(cuts)
    assert row["joint_flux_1_err"] == pytest.approx(rates.std(ddof=1) / math.sqrt(len(rates)), rel=1e-9)
    assert row["joint_flux_1_err"] > 1.0  # parts/s: the gaps show
    # the last section's flux is the feed rate (no joint_flux_2); its rejects per second
    assert "joint_flux_2" not in row and "reject_rate_1" not in row
    assert row["parts_per_s"] == pytest.approx(rate(leave[~rejected]), rel=1e-12)
    assert row["reject_rate_2"] == pytest.approx(rate(leave[rejected]), rel=1e-12)
    assert row["reject_rate_2"] == pytest.approx(200 * 6 / 7 / 4, abs=5.0)  # a quarter of the parts
    # conveying speed: 20 mm/s on both
    assert row["speed_1"] == pytest.approx(V, rel=1e-9)
    assert row["speed_2"] == pytest.approx(V, rel=1e-9)
    # hold-up: the parts over each section at the window's frames, averaged
    frames = LINE_FRAMES[(LINE_FRAMES >= t_a - 1e-12) & (LINE_FRAMES <= t_b + 1e-12)]
    on_1 = [((tj - JOINT / V <= t) & (t < tj)).sum() for t in frames]
    on_2 = [((tj <= t) & (t < leave)).sum() for t in frames]
    assert row["hold_up_1"] == pytest.approx(np.mean(on_1), abs=1e-9)  # parts
    assert row["hold_up_2"] == pytest.approx(np.mean(on_2), abs=1e-9)
    assert row["hold_up_1"] == pytest.approx(60 * 6 / 7, abs=1.0)  # 0.3 s on it at 171 parts/s


def test_an_unmeasured_lines_rates_are_missing_with_its_feed_rate(tmp_path):
    tj = 0.1 + 0.05 * np.arange(3)  # three parts: too few exits
    row = metrics(line_feeder(tmp_path / "few.h5", LINE_FRAMES, tj, v1=V, v2=V, freq=100.0,
                              variables=DRIVE_2))
    assert row["feedrate_reason"].startswith("too few exits")
    assert row["joint_flux_1"] is None and row["joint_flux_1_err"] is None
    assert row["reject_rate_2"] is None
    assert row["speed_1"] == pytest.approx(V, rel=1e-9)  # not a rate of the window: kept


def _q_axis(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.r_[np.cos(angle / 2), np.sin(angle / 2) * axis]


def test_the_orientation_yield_of_chips_is_a_column(tmp_path):
    # chips lying face up along the track, face up turned 30 degrees, face down: in turn
    chip = np.array([[x, y, 0.0, 75e-6] for x in (-1e-4, 0, 1e-4) for y in (-1e-4, 0, 1e-4)])
    kinds = [_q_axis([0, 0, 1], 0.0), _q_axis([0, 0, 1], math.radians(30)), _q_axis([1, 0, 0], math.pi)]
    n = 40
    quats = np.array([kinds[k % 3] for k in range(n)])
    exits = 0.02 + 0.15 * np.arange(n) / n
    path = feeder(tmp_path / "chips.h5", FRAMES, exits, speed=0.05, orientations=quats,
                  body_template=chip, lanes=np.arange(n) * 1e-3, freq=100.0)
    row = metrics(path)
    inside = (exits >= row["steady_from"]) & (exits < row["steady_to"])
    want = (inside & (np.arange(n) % 3 == 0)).sum() / inside.sum()
    assert row["orientation_yield"] == pytest.approx(want, abs=1e-12)
    assert row["face_up_fraction"] == pytest.approx((inside & (np.arange(n) % 3 != 2)).sum()
                                                    / inside.sum(), abs=1e-12)


def test_spheres_have_no_orientation_yield(tmp_path):
    row = metrics(feeder(tmp_path / "s.h5", FRAMES, 0.02 + 0.15 * np.arange(40) / 40, freq=100.0))
    assert row["orientation_yield"] is None


def test_the_new_columns_round_trip_through_the_summary(tmp_path):
    rows = [{"job": 0, "status": S.DONE, "parts_per_s": None, "feedrate_reason": "too few exits",
             "joint_flux_1": None, "speed_1": 0.02},
            {"job": 1, "status": S.DONE, "parts_per_s": 12.5, "feedrate_reason": None,
             "joint_flux_1": 13.0, "speed_1": 0.021}]
    S.write(tmp_path, rows, [], {})
    back, _ = S.read(tmp_path)
    assert back[0]["feedrate_reason"] == "too few exits" and back[1]["feedrate_reason"] is None
    assert back[0]["parts_per_s"] is None and back[1]["joint_flux_1"] == 13.0


# ------------------------------------------------------------------ the report
def _row(job, a, rate, reason=None, singulated=0.5, velocity=0.01):
    return {"job": job, "status": S.DONE, "a": a, "parts_per_s": rate,
            "parts_per_s_err": None if rate is None else 1.0, "feedrate_reason": reason,
            "n_events": 3 if reason else 100, "singulated_fraction": singulated,
            "mean_velocity": velocity, "mean_velocity_err": 1e-4}


FEW = "too few exits to measure (3 in the window; need ≥ 10)"


def test_a_setting_with_an_unmeasured_replicate_is_unmeasured_and_never_best():
    rows = [_row(0, 1.0, 500.0), _row(1, 1.0, None, FEW),       # a high rate, and one unmeasured
            _row(2, 2.0, 100.0), _row(3, 2.0, 104.0)]
    one, two = R.settings(rows, ["a"], "parts_per_s")
    assert one["merit"] is None and one["parts_per_s"] is None   # not the mean of the 500 alone
    assert one["merit_unmeasured"] == f"1 of 2 runs: {FEW}"
    assert two["merit"] == pytest.approx(102.0, rel=1e-12) and two["merit_unmeasured"] is None
    assert R.best([one, two]) is two


def test_every_setting_unmeasured_names_no_best_and_keeps_the_feed_rate_as_merit(tmp_path):
    rows = [_row(0, 1.0, None, FEW, velocity=0.05), _row(1, 2.0, None, FEW, velocity=0.01)]
    S.write(tmp_path, rows, ["a"], {"varied": '["a"]', "n_jobs": 2, "deck": "bulk_feeder"})
    rep = R.report(tmp_path)
    # the conveying speed is no stand-in for an unmeasured feed rate
    assert rep["merit"] == "parts_per_s" and rep["best"] is None
    text = R.text(rep)
    assert "best: none (no setting has a measured feed rate)" in text
    assert not re.search(r"(?<![\d.])0 ± 0(?![\d.])", text) and text.count("unmeasured") >= 4
    assert f"unmeasured: a=1: feed rate: {FEW}" in text


def test_an_unmeasured_setting_reads_unmeasured_in_the_table(tmp_path):
    rows = [_row(0, 1.0, None, FEW), _row(1, 2.0, 80.0)]
    S.write(tmp_path, rows, ["a"], {"varied": '["a"]', "n_jobs": 2, "deck": "bulk_feeder"})
    rep = R.report(tmp_path)
    lines = R.text(rep).splitlines()
    row_1 = next(line for line in lines if line.startswith("1 "))
    assert "unmeasured" in row_1 and "n/a" not in row_1
    assert rep["best"]["parameters"] == {"a": 2.0}


def test_the_maps_leave_an_unmeasured_setting_uncoloured(tmp_path, monkeypatch):
    from vibrofeed.pictures import sweep_maps

    drawn = []
    monkeypatch.setattr(sweep_maps, "save", lambda fig, path: drawn.append(fig) or path)
    entries = []
    for a in (1.0, 2.0):
        for b in (10.0, 20.0):
            unmeasured = (a, b) == (2.0, 20.0)
            entries.append({"parameters": {"a": a, "b": b}, "merit": None if unmeasured else a * b,
                            "merit_err": None if unmeasured else 1.0,
                            "merit_unmeasured": FEW if unmeasured else None,
                            "parts_per_s": None if unmeasured else a * b,
                            "parts_per_s_err": None if unmeasured else 1.0,
                            "parts_per_s_unmeasured": FEW if unmeasured else None})
    sweep_maps.heat_map(entries, "a", "b", "feed rate", 1.0, str, None, tmp_path / "m.png", "t")
    ax = drawn[0].axes[0]
    grid = ax.images[0].get_array()
    assert np.ma.is_masked(grid[1, 1]) or not np.isfinite(grid[1, 1])   # b = 20 (row), a = 2 (col)
    said = {(t.get_position(), t.get_text()) for t in ax.texts}
    assert ((1, 1), "unmeasured") in said and ((0, 0), "10") in said
    sweep_maps.trends(entries, "a", "b", [("parts_per_s", "feed rate", 1.0)], str,
                      tmp_path / "t.png", "t")
    crosses = [line for line in drawn[1].axes[0].lines if line.get_marker() == "x"]
    assert len(crosses) == 1 and list(crosses[0].get_xdata()) == [2.0]


# ------------------------------------------------------------------ progress
def test_a_reused_job_says_reused_not_done(tmp_path):
    from vibrofeed.sweep import plan as P
    from vibrofeed.sweep.progress import SweepProgress
    from vibrofeed.sweep.spec import parse

    jobs = P.plan(parse('deck = "bulk_feeder"\n[grid]\nt_end = [1.0, 2.0]\n', "s.toml"))
    out = io.StringIO()
    p = SweepProgress(jobs, 1, stream=out)
    p.started(jobs[0])
    p.finished(jobs[0], {"status": S.DONE}, computed=False)
    p.started(jobs[1])
    p.finished(jobs[1], {"status": S.DONE}, computed=True)
    first, second = out.getvalue().splitlines()
    assert first.startswith("sweep: job 0: reused (an earlier complete result, analysed in ")
    assert "done" not in first.split("|")[0]
    assert second.startswith("sweep: job 1: done (")
