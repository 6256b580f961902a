"""The bulk analyses at their edges: the pieces of the feed rate checked on hand-computed
series (bins, batch means, lags), and results that lack what the usual path reads (an outlet
edge, the part at the frame after its exit, arrivals, frames in the window)."""

import math
import warnings

import numpy as np
import pytest

from bulk_synthetic import RADIUS, feeder
from helpers import parts, write_bulk_result
from vibrofeed.errors import InputError
from vibrofeed.postproc import FeedRate, Singulation
from vibrofeed.postproc.feedrate import (
    BOWL_KEYS,
    LINE_KEYS,
    SUMMARY_KEYS,
    _mean_and_batch_error,
    batch_rate,
    bin_width,
    mser,
    outlet_x,
    period_lag,
    period_velocities,
)
from vibrofeed.postproc.singulation import SUMMARY_KEYS as SINGULATION_KEYS
from vibrofeed.results.reader import Result

FREQ = 100.0
FRAMES = np.arange(0, 1.0 + 1e-9, 0.01)


# -- the pieces, on hand-computed series --------------------------------------------------
def test_bins_hold_about_ten_events_in_whole_periods():
    # 100 periods in 1 s: 1000 events -> 100 bins of one period, 500 -> 50 bins of two
    # (widths in s, rates per s: hand-computed, equal up to rounding)
    assert bin_width(0.0, 1.0, 100.0, 1000) == pytest.approx(0.01, rel=1e-12)
    assert bin_width(0.0, 1.0, 100.0, 500) == pytest.approx(0.02, rel=1e-12)
    assert bin_width(0.0, 1.0, 100.0, 0) == pytest.approx(0.1, rel=1e-12)  # at least 10 bins
    assert bin_width(0.0, 1.0, 100.0, 10 ** 6) == pytest.approx(0.01, rel=1e-12)  # never below a period
    assert bin_width(0.0, 6.0, 100.0, 10 ** 6) == pytest.approx(0.03, rel=1e-12)  # at most 200 bins: 600/200
    assert bin_width(0.0, 0.005, 100.0, 50) == pytest.approx(0.005, rel=1e-12)  # less than a period: the span
    # without vibration: the span in 10 .. 200 equal bins
    assert bin_width(0.0, 1.0, 0.0, 55) == pytest.approx(0.1, rel=1e-12)
    assert bin_width(0.0, 1.0, 0.0, 1000) == pytest.approx(0.01, rel=1e-12)
    assert bin_width(0.0, 2.0, 0.0, 10 ** 5) == pytest.approx(0.01, rel=1e-12)
    # only the span counts, not where it starts
    assert bin_width(0.5, 1.5, 100.0, 1000) == pytest.approx(0.01, rel=1e-12)
    assert bin_width(0.5, 1.5, 0.0, 55) == pytest.approx(0.1, rel=1e-12)


@pytest.mark.parametrize("freq", [4.0, 0.0])  # four one-period batches, or 200 units in 4 batches
def test_batch_means_of_a_known_pattern(freq):
    # 1, 3, 1, 3 events in the quarters of [0, 1): rates 4, 12, 4, 12 per s
    times = np.array([0.1, 0.3, 0.4, 0.45, 0.6, 0.8, 0.9, 0.95])
    rate, err = batch_rate(times, np.ones(8), 0.0, 1.0, freq, 4)
    assert rate == pytest.approx(8.0, rel=1e-12)
    # std (ddof 1) of the rates / sqrt(4)
    assert err == pytest.approx(math.sqrt(4 * 4 ** 2 / 3) / 2, rel=1e-12)
    # weights: mass per second; events at t_b are not in [t_a, t_b)
    rate, _ = batch_rate(np.r_[times, 1.0], np.r_[np.full(8, 2.0), 100.0], 0.0, 1.0, freq, 4)
    assert rate == pytest.approx(16.0, rel=1e-12)
    rate, _ = batch_rate(np.r_[0.0, times], np.r_[5.0, np.ones(8)], 0.0, 1.0, freq, 4)
    assert rate == pytest.approx(13.0, rel=1e-12)  # t_a is inside


def test_batch_means_need_two_periods():
    rate, err = batch_rate(np.array([0.001, 0.004]), np.ones(2), 0.0, 0.01, 100.0, 10)
    assert rate == pytest.approx(200.0, rel=1e-12) and math.isnan(err)          # one period: one batch
    _, err = batch_rate(np.array([0.001, 0.014]), np.ones(2), 0.0, 0.02, 100.0, 10)
    assert err == pytest.approx(0.0, abs=1e-12)  # two periods, one event each


def test_mean_and_batch_error_of_grouped_values():
    mean, err = _mean_and_batch_error(np.array([1.0, 2, 3, 4]), np.array([0, 0, 1, 1]), 10)
    assert mean == 2.5 and err == pytest.approx(1.0, rel=1e-12)  # batch means 1.5, 3.5: std sqrt(2) / sqrt(2)
    mean, err = _mean_and_batch_error(np.arange(1.0, 7.0), np.arange(6), 2)
    # batches {1,2,3}, {4,5,6}: 3 / sqrt(2) / sqrt(2)
    assert mean == 3.5 and err == pytest.approx(1.5, rel=1e-12)
    mean, err = _mean_and_batch_error(np.array([1.0, 5.0]), np.array([3, 3]), 10)
    assert mean == 3.0 and math.isnan(err)             # one interval: no spread to measure
    mean, err = _mean_and_batch_error(np.empty(0), np.empty(0, dtype=int), 10)
    assert math.isnan(mean) and math.isnan(err)


def test_period_lag_of_too_few_frames():
    assert period_lag(np.array([0.0]), 100.0)[0] == 1 and math.isnan(period_lag(np.array([0.0]), 100.0)[1])
    assert period_lag(np.array([0.0, 0.01]), 100.0) == (1, 0.0)
    assert period_lag(np.array([0.0, 0.005, 0.01]), 100.0) == (2, 0.0)


# -- results lacking the usual pieces -----------------------------------------------------
def hand_made(path, frames, events, outlet=None, variables=None):
    variables = variables or {"freq": ("100", "Hz", "f", "100")}
    outlet = outlet or {"outlet_x": 0.02, "catch_z": -3e-4, "method": "synthetic"}
    return Result(write_bulk_result(path, frames, events=events, outlet=outlet, variables=variables))


def events_of(times, ids):
    n = len(ids)
    return {"time": np.asarray(times, float), "id": np.asarray(ids), "position": np.zeros((n, 3)),
            "velocity": np.zeros((n, 3)), "orientation": np.tile([1.0, 0, 0, 0], (n, 1))}


def test_the_outlet_edge_falls_back_on_the_track_length(tmp_path):
    frames = [(k, 0.01 * k, parts([1], [[0.001 * k, 0, RADIUS]])) for k in range(5)]
    variables = {"freq": ("100", "Hz", "f", "100"), "track_length": ("0.015", "m", "l", "0.02")}
    with hand_made(tmp_path / "a.h5", frames, events_of([], []), outlet={"method": "m"},
                   variables=variables) as r:
        assert outlet_x(r) == 0.015
    with hand_made(tmp_path / "b.h5", frames, events_of([], [])) as r:
        assert outlet_x(r) == 0.02


def test_an_event_mass_comes_from_the_frame_before_when_the_part_is_gone(tmp_path):
    # part 1 leaves at 0.025 s and is not in the next frame; part 2 leaves at 0.045 s and
    # is in no frame at all (its mass is unknown): the mass rate is then unknown too
    m1, m2 = 2e-7, 5e-7

    def frame(k):
        ids = [i for i, gone in ((1, 0.025), (3, 9.0)) if 0.01 * k < gone]
        p = parts(ids, [[0.001 * i, 0, RADIUS] for i in ids], mass=m1)
        p["mass"] = np.where(np.array(ids) == 1, m1, m2)
        return (k, 0.01 * k, p)

    frames = [frame(k) for k in range(8)]
    with hand_made(tmp_path / "m.h5", frames, events_of([0.025], [1])) as r:
        fr = FeedRate(r).run().results
        assert fr.event_mass.tolist() == [m1]
        # over a window that holds the event (the detected one would not: 0 = 0 proves nothing)
        fr = FeedRate(r, start=0.0, end=0.07).run().results
        assert fr.parts_per_s > 0
        assert fr.mass_per_s == pytest.approx(fr.parts_per_s * m1, rel=1e-12, abs=1e-20)  # kg/s
    with hand_made(tmp_path / "n.h5", frames, events_of([0.025, 0.045], [1, 2])) as r:
        fr = FeedRate(r).run().results
        assert fr.event_mass[0] == m1 and math.isnan(fr.event_mass[1])
        assert math.isnan(fr.mass_per_s) and math.isnan(fr.mass_per_s_err)
        assert fr.parts_per_s > 0


def test_feed_rate_summary_holds_the_contract_keys_json_ready(tmp_path):
    exits = 0.1 + np.arange(200) / 250.0
    with Result(feeder(tmp_path / "s.h5", FRAMES, exits, freq=FREQ)) as r:
        fa = FeedRate(r)
        assert repr(fa).endswith("not run>")
        fa.run()
        assert repr(fa).endswith(f"{len(FRAMES)} frames>")
        assert len(fa.results.profile_count) == 20      # the profile's bins by default
        with pytest.raises(InputError, match="bins must be at least 1"):
            FeedRate(r, bins=0)
        one = FeedRate(r, bins=1).run().results   # the whole track in one bin
        assert one.profile_count.tolist() == [fa.results.profile_count.sum()]
        assert one.profile_velocity[0] == pytest.approx(fa.results.mean_velocity, rel=1e-12)
    summary = fa.summary()
    # LINE_KEYS: feeder lines only; BOWL_KEYS: bowls only (sections: both)
    assert list(summary) == [k for k in SUMMARY_KEYS if k not in LINE_KEYS + BOWL_KEYS]
    assert LINE_KEYS == ("rejected", "returned", "sections", "rejects_by_tooling")
    assert BOWL_KEYS == ("sections", "rejects_by_tooling", "fell", "fell_per_s", "fell_per_s_err")
    assert summary["parts_per_s"] == fa.results.parts_per_s
    assert isinstance(summary["profile_x"], list) and summary["n_events"] == 200


def test_a_window_of_one_frame_has_no_speed(tmp_path):
    exits = 0.1 + np.arange(40) / 50.0
    with Result(feeder(tmp_path / "w.h5", FRAMES, exits, freq=FREQ, speed=0.05)) as r:
        with warnings.catch_warnings():
            warnings.simplefilter("error")   # no spacing of a single frame is asked for
            x, v, k, (m, alias) = period_velocities(r, [20])
        assert (len(x), len(v), len(k), m) == (0, 0, 0, 1) and math.isnan(alias)
        fr = FeedRate(r, start=0.511, end=0.525).run().results   # holds frame 52 only
    assert math.isnan(fr.mean_velocity) and math.isnan(fr.mean_velocity_err)
    assert fr.profile_count.sum() == 0 and np.isnan(fr.profile_velocity).all()
    assert fr.parts_per_s == pytest.approx(1 / 0.014, rel=1e-12)  # one arrival inside: at 0.52 s


def test_singulation_without_an_outlet_edge_has_no_speed_and_counts_every_part(tmp_path):
    # two parts touching, one alone; no outlet_x and no track_length: no edge to measure at
    pos = [[0.0, 0, RADIUS], [2 * RADIUS, 0, RADIUS], [0.01, 0, RADIUS]]
    frames = [(k, 0.01 * k, parts([1, 2, 3], pos, radius=RADIUS)) for k in range(6)]
    with hand_made(tmp_path / "e.h5", frames, events_of([0.012, 0.031], [1, 3]),
                   outlet={"method": "m"}) as r:
        sg = Singulation(r, start=0.0, end=0.05).run().results
    assert math.isnan(sg.edge_velocity) and np.isnan(sg.gaps).all() and math.isnan(sg.mean_gap)
    assert sg.cluster_sizes == {1: 1.0, 2: 1.0}
    assert sg.n_arrivals == 2 and sg.n_doubles == 0


def test_singulation_tolerance_from_the_parts_on_the_track_when_none_arrives(tmp_path):
    exits = np.array([5.0, 5.01, 5.02])          # after the run: nobody arrives
    with Result(feeder(tmp_path / "t.h5", FRAMES, exits, freq=FREQ, speed=0.001, radius=RADIUS)) as r:
        sg = Singulation(r).run().results
    assert sg.n_arrivals == 0 and sg.tolerance == pytest.approx(0.01 * 2 * RADIUS, rel=1e-12, abs=0)
    assert math.isnan(sg.cv_interarrival) and math.isnan(sg.mean_interarrival)
    assert math.isnan(sg.doubles_rate) and math.isnan(sg.singulated_fraction)
    # no part at all: no size to take a tolerance from
    frames = [(k, 0.01 * k, parts([], np.zeros((0, 3)))) for k in range(4)]
    with hand_made(tmp_path / "none.h5", frames, events_of([], [])) as r:
        sg = Singulation(r).run().results
    assert sg.tolerance == 0.0 and sg.cluster_sizes == {}
    assert math.isnan(sg.track_singulated_fraction)


def test_singulation_between_two_frames_samples_clusters_from_all_frames(tmp_path):
    exits = 0.1 + np.arange(40) / 50.0
    with Result(feeder(tmp_path / "b.h5", FRAMES, exits, freq=FREQ, speed=0.05)) as r:
        sg = Singulation(r, start=0.503, end=0.507, cluster_frames=4).run()
        with pytest.raises(InputError, match="two frames"):
            Singulation(r).run(stop=1)
        two = Singulation(r, start=0.5, end=0.53).run(frames=[50, 53]).results   # two are enough
    assert two.n_arrivals == 1 and two.arrival_times == pytest.approx([0.52], abs=1e-12)   # s
    assert sg.results.cluster_frames == 4               # the window holds no frame
    summary = sg.summary()
    assert list(summary) == [k for k in SINGULATION_KEYS if k in sg.results]
    assert summary["face_up_fraction"] is None and summary["steady_from"] == 0.503


def test_period_lag_of_frames_shorter_than_a_period_weighs_the_alias_per_period():
    # lags of 0.17, 0.34, 0.51 periods: aliases 0.17, 0.34, 0.49, per period 1, 1, 0.96
    m, alias = period_lag(np.arange(4) * 0.0017, 100.0)
    assert m == 3 and alias == pytest.approx(0.49, rel=1e-12)


def test_a_given_start_cuts_only_the_end_by_mser_over_the_bins_after_it():
    # a burst in the first bin, steady bins, then the run-out: with the start given, the end
    # cut is MSER's over the bins from that start on, the burst included
    from vibrofeed.postproc.feedrate import mser, steady_window

    rng = np.random.default_rng(1)
    times = np.r_[rng.uniform(0.0, 0.01, 60), rng.uniform(0.01, 0.7, 700)]
    t_a, t_b, width, counts = steady_window(times, 0.0, 1.0, FREQ, start=0.0)
    assert width == pytest.approx(0.01, rel=1e-12) and counts[0] == 60
    d, e = mser(counts, cut_start=False, cut_end=True)
    assert d == 0 and mser(counts[1:], cut_start=False, cut_end=True)[1] != e   # the burst matters
    assert t_a == 0.0 and t_b == pytest.approx(1.0 - e * width, rel=1e-12)
    assert len(counts) == 100 and counts.sum() == len(times)   # whole bins over the span, no more


def test_feed_rate_profile_without_an_outlet_edge_spans_the_parts(tmp_path):
    pos = [[0.0, 0, RADIUS], [2 * RADIUS, 0, RADIUS], [0.01, 0, RADIUS]]
    frames = [(k, 0.01 * k, parts([1, 2, 3], pos, radius=RADIUS)) for k in range(6)]
    with hand_made(tmp_path / "p.h5", frames, events_of([0.012, 0.031], [1, 3]),
                   outlet={"method": "m"}) as r:
        fr = FeedRate(r, bins=10).run().results
    assert fr.profile_edges == pytest.approx(np.linspace(0.0, 0.01, 11), abs=1e-15)  # 0 .. the farthest part
    assert fr.profile_x == pytest.approx((np.arange(10) + 0.5) * 1e-3, abs=1e-15)  # the bins' middles
    assert fr.profile_count.sum() == 3 * 5 and fr.mean_velocity == 0.0


def test_a_window_of_two_frames_has_one_whole_period_interval(tmp_path):
    exits = 0.1 + np.arange(40) / 50.0
    with Result(feeder(tmp_path / "two.h5", FRAMES, exits, freq=FREQ, speed=0.05, amp=2e-5)) as r:
        fr = FeedRate(r, start=0.505, end=0.525).run().results   # frames at 0.51 and 0.52 s
    assert fr.velocity_lag == 1 and fr.mean_velocity == pytest.approx(0.05, rel=1e-9)
    assert math.isnan(fr.mean_velocity_err)                       # one interval: no batches


def test_singulation_counts_only_the_arrivals_in_its_window(tmp_path):
    exits = 0.05 + np.arange(90) / 100.0
    with Result(feeder(tmp_path / "win.h5", FRAMES, exits, freq=FREQ, speed=0.3)) as r:
        sg = Singulation(r, start=0.3, end=0.6).run().results
    inside = exits[(exits >= 0.3) & (exits < 0.6)]
    assert sg.n_arrivals == len(inside) == 30
    assert sg.arrival_times == pytest.approx(inside, rel=1e-12)
    with Result(tmp_path / "win.h5") as r:   # every pair 10 ms apart is a double by a 20 ms gap
        crowded = Singulation(r, gap=0.02, start=0.3, end=0.6).run().results
    assert crowded.n_doubles == 29 and crowded.doubles_per_s == pytest.approx(29 / 0.3, rel=1e-12)


def test_a_feed_rate_of_two_frames(tmp_path):
    exits = 0.1 + np.arange(40) / 50.0
    with Result(feeder(tmp_path / "f2.h5", FRAMES, exits, freq=FREQ, speed=0.05, amp=2e-5)) as r:
        fr = FeedRate(r).run(frames=[50, 51]).results
    assert fr.mean_velocity == pytest.approx(0.05, rel=1e-9)
    assert fr.n_events == ((exits > 0.5) & (exits <= 0.51)).sum()


def test_outlet_events_are_those_after_the_first_time_up_to_the_last():
    from vibrofeed.postproc.feedrate import outlet_events

    class Fake:
        outlet_plane = {"outlet_x": 0.02}
        outlet = {"time": np.array([0.3, 0.1, 0.2, 0.4]), "id": np.array([3, 1, 2, 4])}

    ev = outlet_events(Fake(), 0.1, 0.3)
    assert ev["time"].tolist() == [0.2, 0.3] and ev["id"].tolist() == [2, 3]   # sorted by time
    assert outlet_events(Fake())["id"].tolist() == [1, 2, 3, 4]   # by default, all of them


def test_mser_may_cut_half_the_series_at_its_end():
    assert mser(np.r_[np.full(10, 5.0), np.zeros(10)]) == (0, 10)
    assert mser(np.r_[np.arange(10.0), np.full(10, 5.0)]) == (10, 0)   # and half at its start


def test_the_edge_speed_is_measured_within_the_window_only(tmp_path):
    # parts leaving before 0.5 s ran at 0.05 m/s, the later ones at 0.1 m/s (side by side
    # lanes, so nobody overtakes anybody in the same lane); over [0.5, 1] only the fast ones
    # are near the edge
    exits = 0.05 + np.arange(90) / 100.0
    speeds = np.where(exits < 0.5, 0.05, 0.1)
    lanes = np.where(exits < 0.5, 0.0, 2e-3)
    with Result(feeder(tmp_path / "edge.h5", FRAMES, exits, freq=FREQ, speed=speeds, lanes=lanes)) as r:
        sg = Singulation(r, start=0.5, end=1.0).run().results
    assert sg.edge_velocity == pytest.approx(0.1, rel=1e-9)


def test_simultaneous_arrivals_have_no_cv_and_no_warning(tmp_path):
    import warnings

    frames = [(k, 0.01 * k, parts([1, 2], [[0, 0, RADIUS], [0, 1e-3, RADIUS]])) for k in range(6)]
    with hand_made(tmp_path / "sim.h5", frames, events_of([0.02, 0.02, 0.02], [1, 2, 3])) as r:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            sg = Singulation(r, start=0.0, end=0.05).run().results
    assert sg.n_arrivals == 3 and math.isnan(sg.cv_interarrival) and sg.mean_interarrival == 0.0


def test_a_fed_run_keeps_its_end_a_draining_one_may_lose_it():
    from vibrofeed.postproc.feedrate import steady_window

    # 100 exits/s from 0.2 s, halved over the last fifth: a run-out for a drained bed,
    # noise to be kept for a fed line (it does not run out)
    times = np.r_[np.arange(0.2, 0.8, 0.01), np.arange(0.8, 1.0, 0.02)]
    _, t_b, _, _ = steady_window(times, 0.0, 1.0, 100.0)
    assert t_b < 0.85
    t_a, t_b, _, _ = steady_window(times, 0.0, 1.0, 100.0, fed=True)
    assert t_b == pytest.approx(1.0, abs=1e-12) and t_a == pytest.approx(0.2, abs=0.05)


def test_a_whole_period_speeds_mid_point_is_halfway_between_its_two_frames(tmp_path):
    # one part at 0.05 m/s, on the track from 0.105 s, over the edge at 0.505 s: at frame k
    # (0.01 k s) it is at x = 0.02 - 0.05 (0.505 - 0.01 k); frames 11 .. 50 see it on the track
    with Result(feeder(tmp_path / "mid.h5", FRAMES, [0.505], freq=FREQ, speed=0.05)) as r:
        x_mid, v, k, (m, _) = period_velocities(r, np.arange(len(FRAMES)), 0, 0.02)
    assert m == 1 and k.tolist() == list(range(11, 50))
    assert x_mid == pytest.approx(0.02 - 0.05 * (0.5 - 0.01 * k), abs=1e-15)   # m
    assert v == pytest.approx(np.full(len(k), 0.05), rel=1e-9)


def test_without_an_edge_or_any_speed_the_profile_spans_a_nominal_metre(tmp_path):
    pos = [[0.0, 0, RADIUS], [0.01, 0, RADIUS]]
    frames = [(k, 0.01 * k, parts([1, 2], pos, radius=RADIUS)) for k in range(6)]
    with hand_made(tmp_path / "n.h5", frames, events_of([], []), outlet={"method": "m"}) as r:
        fr = FeedRate(r, start=0.015, end=0.025, bins=4, model=False).run().results  # frame 2 only
    assert fr.profile_count.sum() == 0
    assert fr.profile_edges == pytest.approx([0.0, 0.25, 0.5, 0.75, 1.0], abs=1e-15)  # m
    assert fr.profile_x == pytest.approx([0.125, 0.375, 0.625, 0.875], abs=1e-15)


def test_section_1_takes_the_parts_upstream_of_x_0_too(tmp_path):
    # a part behind x = 0 (from -4 mm at 1 mm/s) and one on the track (from 5 mm at 3 mm/s),
    # both there all the run: the bed's speed over section 1 is their mean in every batch
    with Result(feeder(tmp_path / "up.h5", FRAMES, [24.0, 5.0], freq=FREQ, speed=[0.001, 0.003],
                       insert_x=-0.01)) as r:
        fr = FeedRate(r, start=0.0, end=1.0, model=False).run().results
    assert fr.bed["speed"][0] == pytest.approx(np.full(10, 0.002), rel=1e-9)   # m/s
    assert fr.mean_velocity == pytest.approx(0.002, rel=1e-9)


def test_a_line_without_an_outlet_edge_has_a_second_section_of_no_length_and_no_density(tmp_path):
    # the edge falls back on track_length, the joint: section 2 is 6 .. 6 mm
    variables = {"freq": ("100", "Hz", "f", "100"), "track_length": ("0.006", "m", "l", "0.02"),
                 "sections": ("2", "-", "s", "1"), "s2_length": ("0.005", "m", "l2", "0.01")}
    frames = [(k, 0.01 * k, parts([1, 2], [[0.002 + 0.001 * k, 0, RADIUS], [0.003, 1e-3, RADIUS]]))
              for k in range(6)]
    with hand_made(tmp_path / "l.h5", frames, events_of([], []), outlet={"method": "m"},
                   variables=variables) as r:
        fr = FeedRate(r, start=0.0, end=0.03, model=False).run().results
    one, two = fr.sections
    assert (two["x_from"], two["x_to"]) == (0.006, 0.006) and math.isnan(two["line_density"])
    # over frames 0..3 of the window section 1 holds both parts (part 1 reaches the joint at
    # frame 4, after it): 2 parts over 6 mm
    assert one["hold_up"] == 2.0 and one["line_density"] == pytest.approx(2 / 0.006, rel=1e-12)  # 1/m


def test_the_longest_lag_searched_is_a_thousand_frames():
    # frames 1.001 periods apart: lag k is 0.001 k off whole periods, until 1000 frames span
    # 1001 periods exactly
    assert period_lag(np.arange(1001) * 0.01001, FREQ) == (1000, 0.0)
    # 1 + 1/1001 periods apart: only 1001 frames span whole periods, beyond the search; within
    # it the least alias per period is lag 1000's, 1 - 1000/1001 of a period
    m, alias = period_lag(np.arange(1002) * (1 + 1 / 1001) / FREQ, FREQ)
    assert m == 1000 and alias == pytest.approx(1 / 1001, abs=1e-9)   # periods (rounding of 1001 periods)


def test_a_given_end_finds_the_start_from_the_bins_before_it():
    from vibrofeed.postproc.feedrate import steady_window

    # 97 exits: 10 bins of 0.1 s; per bin 0, 0, 10, 11, 10, 11, then a burst of 40 after the end
    per_bin = [0, 0, 10, 11, 10, 11, 40, 5, 5, 5]
    times = np.concatenate([0.1 * (b + (np.arange(c) + 0.5) / c) for b, c in enumerate(per_bin)])
    t_a, t_b, width, counts = steady_window(times, 0.0, 1.0, FREQ, end=0.6)
    assert width == pytest.approx(0.1, rel=1e-12) and counts.tolist() == per_bin
    # over bins 0..5: SSD / m^2 = 1 / 4^2 from bin 2, (2/3) / 3^2 from bin 3 (at most half cut);
    # with the burst's bin it would be best to cut nothing
    assert t_a == pytest.approx(0.2, abs=1e-12) and t_b == 0.6


def test_a_reject_at_the_window_start_is_in_the_window(tmp_path):
    from bulk_synthetic import line_feeder
    from vibrofeed.postproc.line import drift

    # a line's parts cross the joint (6 mm) every 20 ms from 0.3 s, two of them fall off
    # section 2 at 8 mm, 50 ms after crossing; the window starts at the first fall
    tj = 0.3 + 0.02 * np.arange(20)
    reject_at = np.where(np.isin(np.arange(20), [2, 5]), 0.008, np.nan)
    with Result(line_feeder(tmp_path / "rej.h5", FRAMES, tj, reject_at=reject_at, freq=FREQ)) as r:
        first = float(r.rejects["time"].min())
        fr = FeedRate(r, start=first, end=1.0, model=False).run().results
    assert first == pytest.approx(tj[2] + 0.05, abs=1e-12)
    assert [s["rejects_in_window"] for s in fr.sections] == [0, 2]
    assert fr.rejects_by_tooling["other"]["in_window"] == 2
    # the hold-up judged is section 2's (section 1, no inlet, is a store), from its own batches
    held = [t for t in fr.bed_trends if t["quantity"] == "hold-up"]
    assert [t["section"] for t in held] == [2]
    own, first = drift(fr.bed["hold_up"][1])[:2], drift(fr.bed["hold_up"][0])[:2]
    assert (held[0]["first"], held[0]["last"]) == own != first


def test_mser_of_an_even_series_warns_nothing():
    # d = e = n/2 keeps nothing: that cell is out of bounds, never a division by zero. Kept
    # 5, 6, 5, 6: SSD / m^2 = 1 / 16, below the 0.67 / 9 of 5, 6, 5 or 6, 5, 6
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert mser([0.0, 5.0, 6.0, 5.0, 6.0, 0.0]) == (1, 1)


def test_a_slow_vibration_has_whole_periods_too():
    # 0.5 Hz, a frame a second: two frames span a period
    assert period_lag(np.arange(10.0), 0.5) == (2, 0.0)


def test_the_frame_spacing_is_the_usual_one_not_the_mean():
    # frames every half period and an uneven last one (7.2 ms, a run whose end is not a whole
    # number of intervals): two frames span a period; the mean spacing (4.87 ms) would not
    assert period_lag(np.r_[np.arange(21) * 0.005, 0.1022], FREQ) == (2, 0.0)


def test_a_reject_at_the_last_frame_is_in_the_run(tmp_path):
    from bulk_synthetic import JOINT, line_feeder

    # two parts fall off section 2 at 8 mm, 50 ms after crossing the joint; the run's last frame
    # is the second fall's time
    tj = 0.3 + 0.02 * np.arange(20)
    reject_at = np.where(np.isin(np.arange(20), [2, 5]), 0.008, np.nan)
    last = tj[5] + (0.008 - JOINT) / 0.04          # as line_feeder times it
    frames = np.r_[FRAMES[FRAMES < last - 1e-6], last]
    with Result(line_feeder(tmp_path / "last.h5", frames, tj, reject_at=reject_at, freq=FREQ)) as r:
        assert r.rejects["time"].max() == last == r.time[-1]
        fr = FeedRate(r, start=0.3, end=last, model=False).run().results
    other = fr.rejects_by_tooling["other"]
    assert other["total"] == 2 and other["in_window"] == 1     # the window is [0.3, last)
