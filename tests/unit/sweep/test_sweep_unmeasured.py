"""The summary's metric columns (vibrofeed.sweep.metrics), each specified here by a value
computed independently: by hand or a closed form from a synthetic result whose answer is known
by construction (tests/bulk_synthetic.py), or the single-part model called directly.

What a sweep could not measure stays unmeasured (issue 19): a job whose feed rate the
analysis cannot give (too few exits, a bed still drifting) records no rate and says why,
the report shows it as unmeasured and never names it best, the maps leave it uncoloured;
a feeder line's per-section figures and the chips' orientation yield are columns too. The
whole row of a job (its parameters, status, error, file, run id, wall time and metrics), as
the summary stores and reads it back, is the last section."""

from __future__ import annotations

import io
import math
import re

import numpy as np
import pytest

from bulk_synthetic import JOINT, OUTLET_X, RADIUS, S2_LENGTH, feeder, line_feeder
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
    # the arrivals' statistics: the same words, of the arrivals in the window
    assert row["singulation_reason"] == "too few exits to measure (3 in the window; need ≥ 10)"
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
    # aligned: along the track whichever face is up (turned over about x, a chip keeps its
    # yaw), so the face-down chips are aligned and the turned ones are not
    assert row["aligned_fraction"] == pytest.approx((inside & (np.arange(n) % 3 != 1)).sum()
                                                    / inside.sum(), abs=1e-12)


def test_spheres_have_no_orientation_yield(tmp_path):
    row = metrics(feeder(tmp_path / "s.h5", FRAMES, 0.02 + 0.15 * np.arange(40) / 40, freq=100.0))
    assert row["orientation_yield"] is None
    assert row["oriented_rate"] is None and row["correct_fraction"] is None


def test_the_rate_of_correctly_oriented_single_parts_is_a_column(tmp_path):
    # box-like parts (5 x 2 spheres, long along x), one in three crosswise: the others are
    # correct (up, lengthwise), all single (1.9 mm apart along the track, in lanes 1 mm apart)
    box = np.array([[x, y, 0.0, 5e-5] for x in (-2e-4, -1e-4, 0, 1e-4, 2e-4) for y in (-5e-5, 5e-5)])
    n = 40
    quats = np.array([_q_axis([0, 0, 1], math.pi / 2 if k % 3 == 0 else 0.0) for k in range(n)])
    exits = 0.02 + 0.15 * np.arange(n) / n
    path = feeder(tmp_path / "boxes.h5", FRAMES, exits, speed=0.5, orientations=quats,
                  body_template=box, lanes=np.arange(n) * 1e-3, freq=100.0)
    row = metrics(path)
    inside = (exits >= row["steady_from"]) & (exits < row["steady_to"])
    right = inside & (np.arange(n) % 3 != 0)
    span = row["steady_to"] - row["steady_from"]
    assert row["singulated_fraction"] == 1.0
    assert row["correct_fraction"] == pytest.approx(right.sum() / inside.sum(), abs=1e-12)
    assert row["oriented_rate"] == pytest.approx(right.sum() / span, rel=1e-12)
    assert row["correct_rate"] == pytest.approx(right.sum() / span, rel=1e-12)
    assert row["oriented_rate_err"] is not None and row["recirculation_per_s"] == 0.0


def test_the_new_columns_round_trip_through_the_summary(tmp_path):
    rows = [{"job": 0, "status": S.DONE, "parts_per_s": None, "feedrate_reason": "too few exits",
             "joint_flux_1": None, "speed_1": 0.02},
            {"job": 1, "status": S.DONE, "parts_per_s": 12.5, "feedrate_reason": None,
             "joint_flux_1": 13.0, "speed_1": 0.021}]
    S.write(tmp_path, rows, [], {})
    back, _ = S.read(tmp_path)
    assert back[0]["feedrate_reason"] == "too few exits" and back[1]["feedrate_reason"] is None
    assert back[0]["parts_per_s"] is None and back[1]["joint_flux_1"] == 13.0


# ------------------------------------------------------------------ every column of a bulk result
# A steady stream after an empty start, at 100 Hz with one frame per period: parts leave every
# 4 ms from 81.3 ms on (never on a frame, nor on an edge of the count bins), but eight of
# them are each followed by a partner 1 ms later, 1 mm aside (a double: 0.1 mm apart along the
# track, less than a diameter; never touching), the next one 7 ms after. Every part moves at
# 0.1 m/s over the 20 mm track (0.2 s on it), its mass 1, 2 or 3 ng in turn; 140 parts, the
# last 60 still to come at the last frame (0.4 s).
STREAM_FRAMES = np.arange(0, 0.4 + 1e-9, 0.01)
V_STREAM = 0.1
PAIRED = np.arange(4, 80, 10)
STREAM_EXITS = 0.0813 + 0.004 * np.arange(140)
STREAM_EXITS[PAIRED + 1] = STREAM_EXITS[PAIRED] + 1e-3
STREAM_LANES = np.where(np.isin(np.arange(140), PAIRED + 1), 1e-3, 0.0)
STREAM_MASS = 1e-9 * (1 + np.arange(140) % 3)
LOST = 3  # the mass balance's count of lost parts at the last frame, written over the file's 0
# the single-part model's drive: Gamma_t 2.0, Gamma_n 0.8 (sliding only)
SINE_100 = {"amp_t": ("4.97e-5", "m", "", "0"), "amp_n": ("2e-5", "m", "", "0"),
            "phase": ("0", "deg", "", "0"), "mu": ("0.4", "", "", "0.5"),
            "restitution": ("0.2", "", "", "0.3")}


@pytest.fixture(scope="module")
def stream(tmp_path_factory):
    """(path, metrics) of the stream above: analysed once for the tests of its columns."""
    import h5py

    path = feeder(tmp_path_factory.mktemp("stream") / "stream.h5", STREAM_FRAMES, STREAM_EXITS,
                  speed=V_STREAM, amp=2e-5, freq=100.0, mass=STREAM_MASS, lanes=STREAM_LANES,
                  variables=SINE_100)
    with h5py.File(path, "r+") as f:
        f["observables/mass_balance/lost/value"][-1] = LOST
    return path, metrics(path)


def batch_error(times, weights, t_a, t_b, freq=100.0, batches=10):
    """The batch-means error of a rate over [t_a, t_b): ``batches`` batches of whole periods
    (lengths differing by one at most), the standard deviation of their rates over sqrt(batches)."""
    periods = round((t_b - t_a) * freq)
    sizes = [len(c) for c in np.array_split(np.arange(periods), batches)]
    cuts = t_a + (t_b - t_a) * np.r_[0, np.cumsum(sizes)] / periods
    rates = np.histogram(times, bins=cuts, weights=weights)[0] / np.diff(cuts)
    return rates.std(ddof=1) / math.sqrt(batches)


def test_the_window_rates_and_mass_balance_columns_of_a_stream_after_an_empty_start(stream):
    _, row = stream
    # The count bins: 80 exits over 40 periods make 10 bins of 4 periods (40 ms). The first two
    # are empty, the other eight hold 10 exits each: MSER cuts exactly the two (a smaller cut
    # keeps the transient, and of the equal-variance cuts the smallest wins), nothing at the end.
    assert row["steady_from"] == pytest.approx(0.08, abs=1e-12)   # s
    assert row["steady_to"] == pytest.approx(0.4, abs=1e-12)
    exits = STREAM_EXITS[STREAM_EXITS <= 0.4]
    assert row["n_events"] == 80 and len(exits) == 80
    assert row["parts_per_s"] == pytest.approx(80 / 0.32, rel=1e-12)     # 250 parts/s
    assert row["parts_per_s_err"] == pytest.approx(batch_error(exits, np.ones(80), 0.08, 0.4), rel=1e-9)
    assert 1.0 < row["parts_per_s_err"] < 20.0                            # parts/s: 7 or 8 per 3 periods
    mass = STREAM_MASS[:80]
    assert row["mass_per_s"] == pytest.approx(mass.sum() / 0.32, rel=1e-12, abs=0)   # kg/s, ~5e-7
    assert row["mass_per_s_err"] == pytest.approx(batch_error(exits, mass, 0.08, 0.4), rel=1e-9, abs=0)
    assert row["mass_per_s_err"] > 1e-9
    # every part at 0.1 m/s: over whole periods the track's vibration cancels
    assert row["mean_velocity"] == pytest.approx(V_STREAM, rel=1e-9)
    assert row["mean_velocity_err"] == pytest.approx(0.0, abs=1e-12)      # m/s: one speed
    # the mass balance at the last frame: a part is inserted 0.2 s before it leaves
    assert row["inserted"] == int((STREAM_EXITS <= 0.4 + 0.2).sum()) == 130
    assert (row["exited"], row["on_track"], row["lost"]) == (80, 50, LOST)
    assert row["feedrate_reason"] is None
    for key in ("n_events", "inserted", "exited", "on_track", "lost"):
        assert type(row[key]) is int, key


def test_the_arrival_columns_of_a_stream_with_planted_doubles(stream):
    _, row = stream
    arrivals = STREAM_EXITS[(STREAM_EXITS >= 0.08) & (STREAM_EXITS < 0.4)]
    dt = np.diff(arrivals)
    assert row["n_arrivals"] == 80 and type(row["n_arrivals"]) is int
    assert sorted(set(np.round(dt * 1e3, 9))) == [1.0, 4.0, 7.0]           # ms
    assert row["mean_interarrival"] == pytest.approx(0.316 / 79, rel=1e-12, abs=0)   # first to last over 79
    assert row["cv_interarrival"] == pytest.approx(dt.std(ddof=1) / dt.mean(), rel=1e-9)
    # a double: less than a diameter of clear track (0.3 mm) between consecutive parts; 1 ms
    # at 0.1 m/s is 0.1 mm, 4 ms is 0.4 mm
    assert row["doubles_rate"] == pytest.approx(8 / 79, rel=1e-12, abs=0)          # of the 79 pairs
    assert row["singulated_fraction"] == pytest.approx(64 / 80, rel=1e-12, abs=0)  # 16 parts in a double
    assert row["doubles_per_s"] == pytest.approx(8 / 0.32, rel=1e-12)
    assert row["edge_velocity"] == pytest.approx(V_STREAM, rel=1e-9)
    assert row["mean_gap"] == pytest.approx(dt.mean() * V_STREAM - 2 * RADIUS, rel=1e-9, abs=0)   # 0.1 mm
    assert row["track_singulated_fraction"] == pytest.approx(1.0, abs=1e-12)  # no two touch on the track
    assert row["singulation_reason"] is None
    # spheres: no orientation
    assert row["face_up_fraction"] is None and row["aligned_fraction"] is None
    assert row["orientation_yield"] is None


def test_the_model_velocity_is_the_single_part_model_and_the_ratio_is_measured_over_it(stream):
    from vibrofeed.models.constants import G
    from vibrofeed.models.part_on_surface import PartParams, mean_velocity
    from vibrofeed.models.surface import SineWaveform

    _, row = stream
    model = mean_velocity(SineWaveform(100.0, 4.97e-5, 2e-5, 0.0), PartParams(0.4, 0.4, 0.2), 0.0, G).velocity
    assert model > 1e-3                                                     # m/s: it conveys
    assert row["model_velocity"] == pytest.approx(model, rel=1e-12, abs=0)
    assert row["velocity_ratio"] == pytest.approx(V_STREAM / model, rel=1e-9)  # the dilute-limit ratio


def test_a_bulk_rows_columns_are_the_documented_ones_in_their_order(stream):
    _, row = stream
    assert list(row) == [
        "parts_per_s", "parts_per_s_err", "mass_per_s", "mass_per_s_err", "mean_velocity",
        "mean_velocity_err", "steady_from", "steady_to", "n_events", "inserted", "exited", "on_track",
        "lost", "feedrate_reason", "cv_interarrival", "doubles_rate", "singulated_fraction", "mean_gap",
        "n_arrivals", "doubles_per_s", "mean_interarrival", "edge_velocity", "track_singulated_fraction",
        "face_up_fraction", "aligned_fraction", "orientation_yield", "singulation_reason",
        "correct_fraction", "lengthwise_fraction", "correct_rate", "correct_rate_err", "oriented_rate",
        "oriented_rate_err", "recirculation_per_s", "model_velocity", "velocity_ratio"]


def test_the_velocity_error_and_the_edge_speed_of_parts_at_their_own_speeds(tmp_path):
    # 280 parts leaving every 2.5 ms, each at its own speed (80 .. 120 mm/s), in four lanes
    # (they overtake one another freely); the stream lasts beyond the run
    n = 280
    exits = 0.0013 + 0.0025 * np.arange(n)
    speeds = np.random.default_rng(7).uniform(0.08, 0.12, n)
    row = metrics(feeder(tmp_path / "speeds.h5", STREAM_FRAMES, exits, speed=speeds, amp=2e-5, freq=100.0,
                         lanes=np.arange(n) % 4 * 1e-3))
    # 8 exits in every bin of 2 periods: no cut
    assert row["steady_from"] == pytest.approx(0.0, abs=1e-12)            # s
    assert row["steady_to"] == pytest.approx(0.4, abs=1e-12)
    assert row["feedrate_reason"] is None
    # one frame per period: each frame interval is a whole period; a part counts in it when it
    # is on the track (entered, not yet left) at both of its frames, at its own speed
    samples, mids = [], []
    for t0, t1 in zip(STREAM_FRAMES[:-1], STREAM_FRAMES[1:]):
        on = [(exits > t) & (OUTLET_X - speeds * (exits - t) >= 0) for t in (t0, t1)]
        both = on[0] & on[1]
        samples.append(speeds[both])
        mids.append(OUTLET_X - speeds[both] * (exits[both] - 0.5 * (t0 + t1)))
    v = np.concatenate(samples)
    assert row["mean_velocity"] == pytest.approx(v.mean(), rel=1e-9)
    # its error: 10 batches of consecutive intervals, the scatter of their means over sqrt(10)
    batches = [np.concatenate([samples[k] for k in part]) for part in np.array_split(np.arange(40), 10)]
    assert row["mean_velocity_err"] == pytest.approx(np.std([b.mean() for b in batches], ddof=1)
                                                     / math.sqrt(10), rel=1e-6)
    assert row["mean_velocity_err"] > 1e-5                                  # m/s: the speeds differ
    # the edge speed: of the intervals whose middle is within 5 diameters of the edge
    edge = v[np.concatenate(mids) >= OUTLET_X - 10 * RADIUS].mean()
    assert row["edge_velocity"] == pytest.approx(edge, rel=1e-9)
    assert abs(row["edge_velocity"] - row["mean_velocity"]) > 1e-4        # not the mean of all
    arrivals = exits[exits < 0.4]
    gaps = np.diff(arrivals) * edge - 2 * RADIUS
    assert row["mean_gap"] == pytest.approx(gaps.mean(), rel=1e-9, abs=0)


def test_the_track_singulated_fraction_counts_the_parts_alone_on_the_track(tmp_path):
    # groups of three abreast every 4 ms: one part alone (lane 0) and a touching pair (lanes
    # 1 mm and 1 mm + one diameter); groups 0.4 mm apart along the track (more than a
    # diameter): whenever a frame holds parts, a third of them are alone
    n = 150
    exits = np.repeat(0.0013 + 0.004 * np.arange(n), 3)
    lanes = np.tile([0.0, 1e-3, 1e-3 + 2 * RADIUS], n)
    row = metrics(feeder(tmp_path / "pairs.h5", STREAM_FRAMES, exits, speed=V_STREAM, freq=100.0,
                         lanes=lanes))
    assert row["track_singulated_fraction"] == pytest.approx(1 / 3, rel=1e-12, abs=0)
    # each group arrives at once: every part is in a double, at most 4 ms x 0.1 m/s clear track
    assert row["singulated_fraction"] == pytest.approx(0.0, abs=1e-12)


def test_a_bed_speeding_up_records_why_and_no_rate_but_its_other_figures(tmp_path):
    from bulk_synthetic import bed

    # 200 parts 0.1 mm apart on a pre-filled track, all at v0 + g t (12 mm/s at 0, 32 at 1 s)
    v0, g, n = 0.012, 0.02, 200
    x0 = OUTLET_X - 1e-4 * (np.arange(n) + 1)
    leave = (-v0 + np.sqrt(v0 ** 2 + 2 * g * (OUTLET_X - x0))) / g
    frames = np.arange(0, 1.0 + 1e-9, 0.01)
    row = metrics(bed(tmp_path / "faster.h5", frames, lambda t: x0 + v0 * t + 0.5 * g * t ** 2,
                      np.full(n, -np.inf), leave, amp=3e-5, freq=100.0, lanes=np.arange(n) % 5 * 1e-3))
    reason = row["feedrate_reason"]
    found = re.fullmatch(r"not steady: the bed's conveying speed on section 1 rises ([\d.]+) -> ([\d.]+) "
                         r"mm/s over the window \(more than 3 standard errors: .* mm/s\)", reason)
    assert found, reason
    t_a, t_b = row["steady_from"], row["steady_to"]
    third = (t_b - t_a) / 3
    first, last = (float(x) * 1e-3 for x in found.groups())                 # m/s, as printed (0.1 mm/s)
    # the means of the first and last thirds of the window: the speed at a time within each
    assert v0 + g * t_a - 1e-4 <= first <= v0 + g * (t_a + third) + 1e-4
    assert v0 + g * (t_b - third) - 1e-4 <= last <= v0 + g * t_b + 1e-4
    for key in ("parts_per_s", "parts_per_s_err", "mass_per_s", "mass_per_s_err"):
        assert row[key] is None, key                                        # no rate of a drifting bed
    # what is no steady rate is still measured: the exits counted, the speed, the arrivals
    assert row["n_events"] == n
    assert row["n_arrivals"] == int(((leave >= t_a) & (leave < t_b)).sum()) >= 10
    assert row["singulation_reason"] is None and row["doubles_rate"] is not None
    assert v0 + g * t_a <= row["mean_velocity"] <= v0 + g * t_b
    # no mu, no restitution in the result: no model, no ratio
    assert row["model_velocity"] is None and row["velocity_ratio"] is None


# a deck without an outlet: three parts at 10, 20, 30 mm/s for the whole run, one gone after
# frame 5, one arriving at frame 14; the track vibrates along x at 50 Hz
SPEEDS = np.array([0.01, 0.02, 0.03, 0.05, 0.07])
LIFE = [(0, 20), (0, 20), (0, 20), (0, 5), (14, 20)]
SINE_50 = {"freq": ("50", "Hz", "", "50"), "amp_t": ("1e-4", "m", "", "0"), "amp_n": ("2e-5", "m", "", "0"),
           "phase": ("0", "deg", "", "0"), "mu": ("0.4", "", "", "0.5"),
           "restitution": ("0.2", "", "", "0.3")}


def conveyor(path, times, variables=SINE_50, life=LIFE):
    from helpers import parts, write_result

    frames = []
    for j, t in enumerate(times):
        alive = np.array([k for k, (a, b) in enumerate(life) if a <= j <= b], dtype=int)
        x = alive * 1e-3 + SPEEDS[alive] * t + 3e-5 * np.sin(2 * np.pi * 50.0 * t)
        frames.append((j, float(t), parts(alive + 1, np.column_stack([x, alive * 1e-3,
                                                                      np.full(len(alive), 5e-4)]))))
    return write_result(path, frames, variables=variables)


def model_50():
    """The single-part model of SINE_50, called directly: Gamma_t 1.0, Gamma_n 0.2."""
    from vibrofeed.models.constants import G
    from vibrofeed.models.part_on_surface import PartParams, mean_velocity
    from vibrofeed.models.surface import SineWaveform

    return mean_velocity(SineWaveform(50.0, 1e-4, 2e-5, 0.0), PartParams(0.4, 0.4, 0.2), 0.0, G).velocity


def test_a_deck_without_an_outlet_has_its_part_count_speed_and_model(tmp_path):
    row = metrics(conveyor(tmp_path / "one.h5", np.arange(21) * 0.005))
    assert list(row) == ["n_parts", "mean_velocity", "model_velocity", "velocity_ratio"]
    assert row["n_parts"] == 5 and type(row["n_parts"]) is int   # every part the run saw
    # the whole periods ending at the last frame from its middle on (2 periods: 0.06 .. 0.1 s),
    # over the parts present at both ends: the three that stay
    assert row["mean_velocity"] == pytest.approx(0.02, rel=1e-9)
    model = model_50()
    assert model > 1e-3                                           # m/s: it conveys
    assert row["model_velocity"] == pytest.approx(model, rel=1e-12, abs=0)
    assert row["velocity_ratio"] == pytest.approx(0.02 / model, rel=1e-9)


def test_three_frames_give_a_speed_two_do_not_and_no_model_no_ratio(tmp_path):
    only_freq = {"freq": ("50", "Hz", "", "50")}
    three = metrics(conveyor(tmp_path / "three.h5", [0.0, 0.02, 0.04], variables=only_freq))
    assert three["n_parts"] == 4                          # parts 1 .. 4 (the fifth comes at frame 14)
    # one period, 0.02 .. 0.04 s, over the four parts present at both ends
    assert three["mean_velocity"] == pytest.approx(np.mean(SPEEDS[:4]), rel=1e-9)
    assert three["model_velocity"] is None and three["velocity_ratio"] is None   # no mu, no restitution
    two = metrics(conveyor(tmp_path / "two.h5", [0.0, 0.02]))
    assert two["n_parts"] == 4 and two["mean_velocity"] is None and two["velocity_ratio"] is None
    assert two["model_velocity"] == pytest.approx(model_50(), rel=1e-12, abs=0)   # the model needs no frames


def test_a_lines_sections_become_columns_by_number_the_rates_voided_with_the_feed_rate():
    from vibrofeed.sweep.metrics import section_columns

    sections = [
        {"section": 1, "joint_flux": 10.0, "joint_flux_error": 0.5, "speed": 0.02, "hold_up": 5.0,
         "reject_rate": 99.0},
        {"section": 2, "joint_flux": 8.0, "joint_flux_error": math.nan, "speed": np.float64(0.03),
         "hold_up": np.int64(4), "reject_rate": 2.0},
        {"section": 3, "joint_flux": 6.0, "joint_flux_error": 0.1, "speed": "n/a", "hold_up": True,
         "reject_rate": 1.0},
    ]
    measured = section_columns(sections, True)
    # no joint flux after the last section (the outlet's is parts_per_s), no rejects off the first
    assert measured == {"joint_flux_1": 10.0, "joint_flux_1_err": 0.5, "speed_1": 0.02, "hold_up_1": 5.0,
                        "joint_flux_2": 8.0, "joint_flux_2_err": None, "speed_2": 0.03, "hold_up_2": 4,
                        "reject_rate_2": 2.0, "speed_3": None, "hold_up_3": 1, "reject_rate_3": 1.0}
    assert type(measured["speed_2"]) is float and type(measured["hold_up_2"]) is int
    assert type(measured["hold_up_3"]) is int                      # a flag as 0/1, not True
    unmeasured = section_columns(sections, False)
    assert unmeasured == {**measured, "joint_flux_1": None, "joint_flux_1_err": None, "joint_flux_2": None,
                          "reject_rate_2": None, "reject_rate_3": None}
    assert section_columns([], True) == {}


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


# ------------------------------------------------------------------ the whole row of a job
SWEEP = ('deck = "bulk_feeder"\nreplicates = 2\n[fixed]\nseed = 40\nn_parts = 300\n'
         '[grid]\namp_n = [5e-5, 1e-4]\n')


class Clock:
    """Stands for the time module in run_job: time.monotonic() gives these readings in turn."""

    def __init__(self, *readings):
        self.readings = list(readings)

    def monotonic(self):
        return self.readings.pop(0)


def one_job(tmp_path, monkeypatch, run, clock):
    """(job, deck, parameters, (row, computed)) of run_job for job 3 of SWEEP (amp_n = 1e-4,
    replicate 1), ``run`` standing for run_deck."""
    from vibrofeed.sweep import execute as E
    from vibrofeed.sweep import plan as P
    from vibrofeed.sweep.spec import parse

    spec = parse(SWEEP, tmp_path / "s.toml")
    deck = P.find_deck(spec)
    job = P.plan(spec, deck)[3]
    (tmp_path / "jobs").mkdir(exist_ok=True)
    monkeypatch.setattr(E, "run_deck", run)
    monkeypatch.setattr(E, "time", clock)
    parameters = [p for p in spec.parameters if p != "seed"]
    return job, deck, parameters, E.run_job(job, tmp_path, deck, 1, parameters)


def summary_csv(folder):
    import csv

    with open(folder / S.CSV_NAME, newline="") as f:
        return list(csv.DictReader(f))


def test_a_done_jobs_row_holds_its_setting_state_and_metrics_as_the_summary_stores_them(
        tmp_path, monkeypatch, stream):
    import shutil
    from types import SimpleNamespace

    from vibrofeed.engine.runner import run_id

    source, figures = stream
    given = []

    def run(deck, params, output, **kw):
        given.append(dict(params))
        shutil.copy(source, output)
        return SimpleNamespace(wall=99.0, reused=False)

    job, deck, parameters, (row, computed) = one_job(tmp_path, monkeypatch, run, Clock(100.0, 103.25))
    # job 3: the second amp_n, its second replicate: seed 40 + 1
    assert given == [{"seed": "41", "n_parts": "300", "amp_n": "0.0001"}] and computed
    S.write(tmp_path, [row], parameters, {})
    (back,), meta = S.read(tmp_path)
    head = {"job": 3, "replicate": 1, "seed": 41, "n_parts": 300, "amp_n": 1e-4, "status": S.DONE,
            "error": None, "file": "jobs/job-0003.h5", "run_id": run_id(deck, job.values), "wall_s": 3.25}
    assert meta["columns"] == list(head) + list(figures)
    assert meta["parameters"] == ["n_parts", "amp_n"] and meta["metrics"] == list(figures)
    assert {c: back[c] for c in head} == head
    assert {c: type(back[c]) for c in ("job", "replicate", "seed", "n_parts")} == dict.fromkeys(
        ("job", "replicate", "seed", "n_parts"), int)
    assert type(back["amp_n"]) is float and type(back["wall_s"]) is float
    # the figures of the job's result (specified above), stored and read back unchanged
    assert {c: back[c] for c in figures} == figures
    (text,) = summary_csv(tmp_path)
    assert {c: text[c] for c in head} == {"job": "3", "replicate": "1", "seed": "41", "n_parts": "300",
                                          "amp_n": "0.0001", "status": "done", "error": "",
                                          "file": "jobs/job-0003.h5", "run_id": head["run_id"],
                                          "wall_s": "3.25"}
    assert (text["parts_per_s"], text["n_events"], text["feedrate_reason"]) == ("250.0", "80", "")


def test_a_reused_result_keeps_the_wall_time_of_the_run_that_made_it(tmp_path, monkeypatch, stream):
    import shutil
    from types import SimpleNamespace

    def run(deck, params, output, **kw):
        shutil.copy(stream[0], output)
        return SimpleNamespace(wall=42.5, reused=True)

    _, _, _, (row, computed) = one_job(tmp_path, monkeypatch, run, Clock(100.0))
    assert not computed and row["status"] == S.DONE and row["wall_s"] == 42.5
    assert row["error"] == "" and row["file"] == "jobs/job-0003.h5"


def test_a_failed_runs_row_says_why_on_one_line_and_names_what_it_left(tmp_path, monkeypatch):
    from pathlib import Path

    from vibrofeed.errors import RunError

    def crashed(deck, params, output, **kw):
        exc = RunError("LIGGGHTS stopped:\n  Lost atoms:  original 300   current 298\n")
        exc.partial = (Path(str(output) + ".part"), 12)  # it wrote 12 frames
        raise exc

    def broken(deck, params, output, **kw):
        raise ZeroDivisionError("division by zero")

    _, _, parameters, (row, computed) = one_job(tmp_path, monkeypatch, crashed, Clock(10.0, 17.5))
    assert computed
    assert {c: row[c] for c in ("job", "replicate", "seed", "status", "error", "file", "wall_s")} == {
        "job": 3, "replicate": 1, "seed": 41, "status": S.FAILED,
        "error": "LIGGGHTS stopped: Lost atoms: original 300 current 298",
        "file": "jobs/job-0003.h5.part", "wall_s": 7.5}
    assert "parts_per_s" not in row                   # nothing measured
    _, _, _, (bug, _) = one_job(tmp_path, monkeypatch, broken, Clock(10.0, 11.0))
    assert (bug["status"], bug["error"], bug["file"], bug["wall_s"]) == (
        S.FAILED, "ZeroDivisionError: division by zero", "", 1.0)
    # in the summary beside a done row: its metrics empty, never 0
    done = {**row, "job": 0, "status": S.DONE, "error": "", "file": "jobs/job-0000.h5", "parts_per_s": 250.0,
            "n_events": 80}
    S.write(tmp_path, [row, done], parameters, {})
    back = S.read(tmp_path)[0]
    assert (back[1]["parts_per_s"], back[1]["n_events"], back[1]["error"]) == (
        None, None, "LIGGGHTS stopped: Lost atoms: original 300 current 298")
    assert back[0]["n_events"] == 80.0 and back[0]["error"] is None
    failed_text = summary_csv(tmp_path)[1]
    assert (failed_text["parts_per_s"], failed_text["n_events"], failed_text["status"]) == ("", "", "failed")


def test_a_run_whose_analysis_fails_is_a_failed_row_that_keeps_its_file(tmp_path, monkeypatch, stream):
    import shutil
    from types import SimpleNamespace

    from vibrofeed.sweep import execute as E

    def run(deck, params, output, **kw):
        shutil.copy(stream[0], output)
        return SimpleNamespace(wall=1.0, reused=False)

    def no_analysis(path):
        raise ValueError("no outlet table")

    monkeypatch.setattr(E, "metrics", no_analysis)
    _, _, _, (row, computed) = one_job(tmp_path, monkeypatch, run, Clock(5.0, 6.5))
    assert computed and (row["status"], row["error"], row["file"], row["wall_s"]) == (
        S.FAILED, "analysis failed: ValueError: no outlet table", "jobs/job-0003.h5", 1.5)
