"""Feed rate on synthetic bulk-feeder results whose answers are known by construction
(tests/bulk_synthetic.py: parts entering at the inlet, leaving over the edge at given times)."""

import math

import numpy as np
import pytest

from bulk_synthetic import OUTLET_X, bed, feeder, poisson_times
from helpers import parts, write_result
from vibrofeed.errors import InputError
from vibrofeed.postproc import FeedRate
from vibrofeed.postproc.feedrate import mser, period_lag, steady_window
from vibrofeed.results.reader import Result

FREQ = 100.0
FRAMES = np.arange(0, 1.0 + 1e-9, 0.01)  # one frame per period


def open_feeder(tmp_path, exit_times, name="feed.h5", frames=FRAMES, **kw):
    return Result(feeder(tmp_path / name, frames, exit_times, freq=FREQ, **kw))


# -- steady window and rate ----------------------------------------------------------
def test_periodic_exits_after_a_start_up_give_the_rate_and_the_start(tmp_path):
    rate, t0 = 250.0, 0.213  # no exit before t0 (the front travels to the edge), then steady
    exits = t0 + np.arange(400) / rate
    with open_feeder(tmp_path, exits, amp=4e-5) as r:
        fr = FeedRate(r).run().results
    width = fr.bin_width
    assert width * FREQ == pytest.approx(round(width * FREQ), abs=1e-12)  # bins of whole periods
    assert t0 - width <= fr.steady_from <= t0 + 2 * width
    assert fr.steady_to == pytest.approx(1.0, rel=1e-12)              # no run-out: to the end
    n_in = ((exits >= fr.steady_from) & (exits < fr.steady_to)).sum()
    assert fr.parts_per_s == pytest.approx(n_in / (fr.steady_to - fr.steady_from), rel=1e-12)
    assert abs(fr.parts_per_s - rate) <= 1.0 / (fr.steady_to - fr.steady_from) + 1e-9
    assert 0 <= fr.parts_per_s_err < 0.02 * rate      # periodic: batches agree to one part
    assert fr.n_events == (exits <= 1.0).sum()
    assert np.all(np.diff(fr.event_times) >= 0)


def test_the_run_out_of_the_fill_ends_the_window(tmp_path):
    rate, t0, t_out = 300.0, 0.15, 0.7  # the pre-fill is exhausted at t_out
    exits = t0 + np.arange(int((t_out - t0) * rate)) / rate
    with open_feeder(tmp_path, exits) as r:
        fr = FeedRate(r).run().results
        forced = FeedRate(r, start=0.3, end=0.6).run().results
    w = fr.bin_width
    assert t0 - w <= fr.steady_from <= t0 + 2 * w
    assert t_out - 2 * w <= fr.steady_to <= t_out + w
    assert fr.parts_per_s == pytest.approx(rate, rel=0.03)
    # a given window is used as it is
    assert (forced.steady_from, forced.steady_to) == (0.3, 0.6)
    assert forced.parts_per_s == pytest.approx(rate, abs=1 / 0.3)


def test_the_error_bar_covers_poisson_feeding_in_most_seeds(tmp_path):
    rate, t0, seeds = 300.0, 0.2, 16
    covered, ratio, starts = 0, [], []
    for seed in range(seeds):
        exits = poisson_times(rate, t0, 1.0, np.random.default_rng(seed))
        with open_feeder(tmp_path, exits, name=f"p{seed}.h5") as r:
            fr = FeedRate(r).run().results
        covered += abs(fr.parts_per_s - rate) <= 2 * fr.parts_per_s_err
        # Poisson's own standard error over the window
        span = fr.steady_to - fr.steady_from
        ratio.append(fr.parts_per_s_err / (math.sqrt(rate * span) / span))
        starts.append(fr.steady_from)
    print(f"2-sigma coverage {covered}/{seeds}, error / Poisson's {np.median(ratio):.2f}")
    assert covered >= 0.65 * seeds                   # ~90 % expected (10 batches, 2 sigma)
    assert 0.6 < np.median(ratio) < 1.4              # not an inflated (useless) error bar
    assert min(starts) >= t0 - 0.05                  # the start-up is never counted
    assert np.median(starts) <= t0 + 0.05


def test_mser_cuts_transients_at_either_end():
    rng = np.random.default_rng(2)
    steady = rng.poisson(12, 80)
    assert mser(np.r_[np.zeros(15), steady]) == (15, 0)
    d, e = mser(np.r_[np.zeros(10), steady, np.zeros(12)])
    assert (d, e) == (10, 12)
    # a steady series keeps (nearly) everything
    d, e = mser(steady)
    assert d + e <= 8
    # never cuts more than half
    d, e = mser(np.r_[np.zeros(60), steady[:40]])
    assert d + e <= 50
    assert mser([1.0, 2.0]) == (0, 0)


def test_steady_window_without_exits_is_the_whole_run():
    t_a, t_b, width, counts = steady_window(np.empty(0), 0.0, 1.0, FREQ)
    assert (t_a, t_b) == (0.0, 1.0) and counts.sum() == 0
    with pytest.raises(InputError, match="no steady window"):
        steady_window(np.empty(0), 0.0, 1.0, FREQ, start=0.6, end=0.5)


def test_mass_per_second_weighs_each_part(tmp_path):
    rate, t0 = 200.0, 0.1
    exits = t0 + np.arange(300) / rate
    masses = np.where(np.arange(300) % 2, 3e-7, 1e-7)  # alternating: mean 2e-7 kg
    with open_feeder(tmp_path, exits, mass=masses) as r:
        fr = FeedRate(r).run().results
    inside = (exits >= fr.steady_from) & (exits < fr.steady_to)
    assert fr.mass_per_s == pytest.approx(masses[inside].sum() / (fr.steady_to - fr.steady_from),
                                          rel=1e-12)
    assert fr.mass_per_s == pytest.approx(2e-7 * fr.parts_per_s, rel=0.02)
    assert np.allclose(fr.event_mass, masses[exits <= 1.0], rtol=0, atol=1e-20)  # kg, ~2e-7: copied
    # (numpy's default atol=1e-8 kg would pass a mass 5 % off)


def test_mass_balance_is_read_at_the_last_frame_analysed(tmp_path):
    exits = 0.1 + np.arange(200) / 200.0
    with open_feeder(tmp_path, exits) as r:
        fr = FeedRate(r).run().results
        half = FeedRate(r).run(stop=51).results  # frames 0..50: t <= 0.5 s
    # every part is on the track from the start (the schedule reaches back beyond t = 0)
    in_at = lambda t: int(((OUTLET_X - 0.02 * (exits - t)) >= 0).sum() + 0)  # noqa: E731
    assert fr.exited == (exits <= 1.0).sum() and fr.lost == 0
    assert fr.inserted == int(((OUTLET_X - 0.02 * (exits - 1.0) >= 0) | (exits <= 1.0)).sum())
    assert fr.on_track == fr.inserted - fr.exited
    assert half.exited == (exits <= 0.5).sum() and half.n_events == half.exited
    assert half.inserted == in_at(0.5)


def filling(path, leave_early=0):
    """A fed track (inlet_rate > 0), a frame every period for 1 s: a stream enters at x = 0
    every 10 ms (5 ms past each frame) at 0.1 m/s and exits 0.2 s later, steadily from 0.205 s;
    from 0.205 s on, 20 more parts come to rest on the track, one every 10 ms. At frame n the
    hold-up is min(n, 40): full at 0.4 s, after the exits are steady. ``leave_early`` of the
    resting parts leave at 0.995 s: the last frame's hold-up is that much lower."""
    stream, resting = 0.005 + 0.01 * np.arange(100), 0.205 + 0.01 * np.arange(20)
    rest_x = 1e-3 + 9e-4 * np.arange(20)
    leave = np.r_[stream + OUTLET_X / 0.1, np.full(20, np.inf)]
    leave[100:100 + leave_early] = 0.995
    return bed(path, FRAMES, lambda t: np.r_[0.1 * (t - stream), rest_x], np.r_[stream, resting], leave,
               variables={"inlet_rate": ("100.0", "1/s", "inlet", "0")},
               lanes=np.r_[np.zeros(100), np.full(20, 1e-3)])


def held_in_bins(last=40.0):
    """The hold-up min(n, 40) at frames n = 0..100 averaged in bins of 5 periods (5 frames;
    the frame at 1 s alone in the last bin), the last frame's value ``last``."""
    held = np.minimum(np.arange(101), 40.0)
    held[-1] = last
    return np.r_[held[:100].reshape(20, 5).mean(axis=1), held[100]]


def test_a_fed_track_is_measured_from_when_its_bed_is_full(tmp_path):
    with Result(filling(tmp_path / "fill.h5")) as r:
        fr = FeedRate(r, model=False).run().results
    # the exits alone are steady from 0.2 s (bins of 10 periods: 0, 0, then 10 each)
    assert steady_window(fr.event_times, 0.0, 1.0, FREQ, fed=True)[0] == pytest.approx(0.2, abs=1e-12)
    # the hold-up in 5-period bins: 2, 7, ..., 37, then 40 from bin 8 (0.4 s) on: MSER (no end
    # cut) drops the filling bins exactly, and the bed is steady after
    assert mser(held_in_bins(), cut_end=False) == (8, 0)
    assert fr.steady_from == pytest.approx(0.4, abs=1e-12) and fr.steady_to == 1.0   # [s]
    assert fr.unsteady is None and fr.reason is None
    assert fr.parts_per_s == pytest.approx(100.0, rel=1e-9)    # 60 exits in 0.6 s


def test_the_filling_of_a_fed_track_is_judged_without_an_end_cut(tmp_path):
    # 10 parts leave at 0.995 s: the last bin's hold-up is 30. Kept (a fed run's end is not a
    # transient), it makes the 37 of bin 7 worth keeping: SSD / m^2 = 96.9 / 14^2 = 0.49 from
    # bin 7, 92.3 / 13^2 = 0.55 from bin 8, 143.6 / 15^2 = 0.64 from bin 6; an end cut would
    # drop the dip and start at bin 8
    held = held_in_bins(last=30.0)
    assert mser(held, cut_end=False)[0] == 7 and mser(held)[0] == 8
    with Result(filling(tmp_path / "dip.h5", leave_early=10)) as r:
        fr = FeedRate(r, model=False).run().results
    assert fr.steady_from == pytest.approx(0.35, abs=1e-12) and fr.unsteady is None   # [s]


def test_a_drifting_bed_moves_the_start_later_by_sixths_while_enough_exits_remain(tmp_path):
    # a stream at 0.1 m/s exits at 0.025 + 0.05 k s: 2 exits in every 0.1 s bin, the exits alone
    # are steady over the whole run (and the stream's share of every batch's speeds the same).
    # But 5 parts in another lane speed up all along (v = 0.01 t m/s): the bed's speed drifts
    # over any window, so the start moves later by sixths of [0, 1], three times: to 0.5 s,
    # where exactly 10 exits (need 10) remain
    exits = 0.025 + 0.05 * np.arange(24)          # (the last 4 after the run: still conveyed)
    x0 = 2e-3 + 1e-3 * np.arange(5)
    with Result(bed(tmp_path / "drift.h5", FRAMES,
                    lambda t: np.r_[OUTLET_X - 0.1 * (exits - t), x0 + 0.005 * t ** 2],
                    np.r_[exits - 0.2, np.full(5, -np.inf)], np.r_[exits, np.full(5, np.inf)],
                    lanes=np.r_[np.zeros(24), np.full(5, 1e-3)])) as r:
        fr = FeedRate(r, model=False).run().results
    assert steady_window(fr.event_times, 0.0, 1.0, FREQ)[:2] == (0.0, 1.0)
    assert fr.steady_from == pytest.approx(3 / 6, abs=1e-12) and fr.steady_to == 1.0   # [s]
    assert ((fr.event_times >= fr.steady_from) & (fr.event_times < 1.0)).sum() == 10
    assert "conveying speed on section 1 rises" in fr.unsteady


def test_too_few_exits_counts_those_before_the_window_end_not_at_it(tmp_path):
    exits = 0.1 + 0.05 * np.arange(12)
    with open_feeder(tmp_path, exits) as r:
        # exits 1..9 inside [exits[1], exits[10]); the one at the end is not: 9 < 10
        short = FeedRate(r, start=exits[1], end=exits[10], model=False).run().results
        enough = FeedRate(r, start=exits[0], end=exits[10], model=False).run().results
    assert short.reason == "too few exits to measure (9 in the window; need ≥ 10)"
    assert enough.reason is None and enough.unsteady is None      # exactly 10: enough


# -- conveying velocity ----------------------------------------------------------------
@pytest.mark.parametrize("spacing, lag", [(0.01, 1), (0.005, 2), (0.013, 10)])
def test_mean_velocity_over_whole_periods_whatever_the_frame_spacing(tmp_path, spacing, lag):
    # 0.013 s frames alias the 10 ms period: only 10 frames (13 periods) apart cancel it
    frames = np.arange(0, 1.0 + 1e-9, spacing)
    v, amp = 0.02, 5e-5
    exits = 0.05 + np.arange(150) / 150.0
    with open_feeder(tmp_path, exits, frames=frames, speed=v, amp=amp) as r:
        fr = FeedRate(r).run().results
    assert fr.velocity_lag == lag and fr.velocity_alias == 0.0
    assert fr.mean_velocity == pytest.approx(v, rel=1e-9)  # parts falling off (2 v) left out
    assert fr.mean_velocity_err < 1e-9
    if lag == 10:  # one frame apart, the track's oscillation would not cancel
        naive = amp * (np.sin(2 * np.pi * FREQ * (frames[1:] - 0)) - np.sin(2 * np.pi * FREQ * frames[:-1]))
        assert np.abs(naive / spacing).max() > 0.1 * v


def test_velocity_profile_of_parts_at_known_speeds(tmp_path):
    # Parts sit in the profile's bins (1 mm wide), 20 um past a bin's start, and move
    # at their bin's speeds, slowly enough to stay inside over the run; nobody leaves.
    # The track swings them 50 um either way: bins are in the track's frame.
    rng = np.random.default_rng(5)
    bins = 20
    edges = np.linspace(0, OUTLET_X, bins + 1)
    which = np.repeat(np.arange(bins), 3)
    speeds = rng.uniform(1e-4, 6e-4, len(which))
    x0 = edges[which] + 2e-5
    exits = (OUTLET_X - x0) / speeds          # when they would reach the edge: after the run
    assert exits.min() > 1.0
    lanes = np.tile([0.0, 1e-3, 2e-3], bins)  # side by side, not in each other's way
    # aliasing spacing, from three quarters of a period: the track is 50 um back at
    # every whole-period frame
    frames = 0.0075 + np.arange(0, 0.6, 0.013)
    with open_feeder(tmp_path, exits, frames=frames, speed=speeds, amp=5e-5, lanes=lanes) as r:
        assert r.surface_position[::10, 0] == pytest.approx(-5e-5, abs=1e-15)  # m
        fr = FeedRate(r, bins=bins).run().results
    expected = np.array([speeds[which == b].mean() for b in range(bins)])
    assert fr.profile_edges == pytest.approx(edges, abs=1e-15)  # m: rounding
    assert fr.profile_velocity == pytest.approx(expected, rel=1e-9)
    chain = len(frames[::10]) - 1
    assert fr.profile_count.tolist() == [3 * chain] * bins
    assert fr.mean_velocity == pytest.approx(speeds.mean(), rel=1e-9)
    assert fr.n_events == 0 and fr.parts_per_s == 0.0


def test_period_lag_finds_whole_periods_or_the_least_alias():
    assert period_lag(np.arange(50) * 0.01, 100.0) == (1, 0.0)
    assert period_lag(np.arange(50) * 0.0025, 100.0) == (4, 0.0)
    assert period_lag(np.arange(50) * 0.013, 100.0) == (10, 0.0)
    assert period_lag(np.arange(50) * 0.01, 0.0) == (1, 0.0)  # no vibration
    # irrational spacing: never whole; the smallest alias per period spanned
    m, alias = period_lag(np.arange(2000) * 0.01 * math.sqrt(2), 100.0)
    assert 0 < alias < 1e-2 and m > 1


# -- windows, not whole datasets ---------------------------------------------------------
def test_many_parts_are_read_by_windows(tmp_path, result_reads):
    rng = np.random.default_rng(11)
    exits = np.sort(rng.uniform(0.05, 3.0, 3000))   # ~1000 parts/s; later ones still on the track
    frames = np.arange(0, 1.0 + 1e-9, 0.01)
    path = feeder(tmp_path / "many.h5", frames, exits, speed=0.05, freq=FREQ, amp=3e-5)
    reads = result_reads
    with Result(path) as r:
        fr = FeedRate(r).run().results
        assert not {"ids", "position", "mass"} & set(vars(r))   # no whole array kept
    assert all(f is not None for name, f in reads if name in ("id", "position", "mass"))
    assert fr.mean_velocity == pytest.approx(0.05, rel=1e-9)
    assert fr.parts_per_s == pytest.approx(1000, rel=0.15)


def test_a_result_without_an_outlet_is_refused(tmp_path):
    path = write_result(tmp_path / "one.h5", [(k, k * 0.01, parts([1], [[0, 0, 0]])) for k in range(5)])
    with Result(path) as r:
        with pytest.raises(InputError, match="no outlet data"):
            FeedRate(r).run()
    with open_feeder(tmp_path, [0.5]) as r:
        with pytest.raises(InputError, match="batches"):
            FeedRate(r, batches=1)
        with pytest.raises(InputError, match="two frames"):
            FeedRate(r).run(stop=1)


# -- the dilute limit ------------------------------------------------------------------
SINE = {"amp_t": ("4.97e-5", "m", "", "0"), "amp_n": ("2e-5", "m", "", "0"), "phase": ("0", "deg", "", "0"),
        "mu": ("0.4", "", "", "0.5"), "restitution": ("0.2", "", "", "0.3")}


def test_the_dilute_limit_is_the_single_part_model_of_the_decks_vibration(tmp_path):
    from vibrofeed.models.constants import G
    from vibrofeed.models.part_on_surface import PartParams, mean_velocity
    from vibrofeed.models.surface import SineWaveform

    exits = 0.1 + np.arange(200) / 250.0
    with open_feeder(tmp_path, exits, speed=0.01, amp=4e-5, variables=SINE) as r:
        fr = FeedRate(r).run().results
        without = FeedRate(r, model=False).run()
    # Gamma_n 0.32 < 1: sliding only, the model of Khan & Sarma §2.3.2 written out by hand
    want = mean_velocity(SineWaveform(FREQ, 4.97e-5, 2e-5, 0.0), PartParams(0.4, 0.4, 0.2), 0.0, G).velocity
    assert fr.model_velocity == pytest.approx(want, rel=1e-12) and want > 0
    assert fr.model_note == ""
    assert fr.velocity_ratio == pytest.approx(fr.mean_velocity / want, rel=1e-12)
    assert fr.shape == 0      # a result without `shape` is of spheres (results before chips)
    assert fr.mean_velocity == pytest.approx(0.01, rel=1e-9)
    assert not {"model_velocity", "model_note", "velocity_ratio"} & set(without.results)
    assert list(without.summary())[-2:] == ["profile_count", "reason"]


def test_a_result_without_the_models_parameters_says_which_it_lacks(tmp_path):
    with open_feeder(tmp_path, 0.1 + np.arange(50) / 100.0, amp=4e-5) as r:
        fr = FeedRate(r).run()
    assert fr.results.model_velocity is None and fr.results.velocity_ratio is None
    assert fr.results.model_note == "the result lacks mu, restitution"
    assert list(fr.summary())[-5:-2] == ["model_velocity", "model_note", "velocity_ratio"]


def test_the_single_part_line_says_what_a_sliding_block_means_for_spheres():
    from vibrofeed.cli.feedrate import SLIDING_BLOCK, single_part

    base = {"model_velocity": 0.02, "model_note": "", "velocity_ratio": 0.9}
    assert SLIDING_BLOCK in single_part({**base, "shape": 0})
    assert SLIDING_BLOCK not in single_part({**base, "shape": 1})  # a chip slides as the model's block
    line = {**base, "shape": 1, "sections": [
        {"section": 1, "model_speed": 0.018, "model_note": "", "speed_ratio": 0.75},
        {"section": 2, "model_speed": 0.051, "model_note": "", "speed_ratio": 0.906}]}
    text = single_part(line)
    assert "1: 18 mm/s (DEM / model 0.750)" in text and "2: 51 mm/s (DEM / model 0.906)" in text


def test_each_section_is_compared_with_the_model_of_its_own_drive():
    from vibrofeed.feeders import Feeder
    from vibrofeed.models.deck import transport

    p = {"freq": 100.0, "amp_t": 3.5e-5, "amp_n": 5e-5, "phase": 0.0, "mu": 0.5, "restitution": 0.3,
         "s2_freq": 150.0, "s2_amp_t": 1e-4, "s2_amp_n": 2e-5, "s2_phase": -30.0, "waveform": 0,
         "sections": 2, "part_size": 3e-4}
    feeder = Feeder.from_values(p)
    two = feeder.section_values(2)
    assert (two["freq"], two["amp_t"], two["amp_n"], two["phase"]) == (150.0, 1e-4, 2e-5, -30.0)
    assert feeder.section_values(1) == p
    # the model of section 2's drive is the model of a track driven as section 2 is
    alone = {**p, "freq": 150.0, "amp_t": 1e-4, "amp_n": 2e-5, "phase": -30.0}
    assert transport(two).velocity == pytest.approx(transport(alone).velocity, rel=1e-12)
