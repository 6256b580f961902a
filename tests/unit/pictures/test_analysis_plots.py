"""What the bulk analyses' figures show: the data drawn is the analysis' results (read back
from the matplotlib artists before the figure is written), not just a file that exists;
each names the run it shows."""

import math

import numpy as np
import pytest

from bulk_synthetic import feeder
from vibrofeed.cli.demo import picture_frame
from vibrofeed.pictures import plots
from vibrofeed.pictures.plots import feedrate_figures, singulation_figures
from vibrofeed.postproc import FeedRate, Singulation
from vibrofeed.postproc.feedrate import period_velocities, profile_error
from vibrofeed.results.reader import Result

FREQ = 100.0
FRAMES = np.arange(0, 1.0 + 1e-9, 0.01)


@pytest.fixture
def drawn(monkeypatch):
    """The figures the analyses draw, by file name, kept open (``save`` is replaced)."""
    figures = {}

    def keep(fig, path):
        figures[path.name] = fig
        return path

    monkeypatch.setattr(plots, "save", keep)
    yield figures
    for name, fig in figures.items():   # whatever the styling, every line drawn can be seen
        for ax in fig.axes:
            assert all(line.get_linewidth() > 0 for line in ax.lines), name
    for fig in figures.values():
        plots.pyplot().close(fig)


def names_the_run(fig, file_name):
    """The figure's heading names the result file, the deck and the vibration frequency."""
    text = fig.get_suptitle().replace("\n", " ")
    assert file_name in text and "deck synthetic_bulk" in text and "freq 100 Hz" in text, text


def test_feed_rate_figures_draw_the_exits_the_window_and_the_profile(tmp_path, drawn):
    rate, t0 = 250.0, 0.213
    exits = t0 + np.arange(150) / rate
    with Result(feeder(tmp_path / "f.h5", FRAMES, exits, freq=FREQ, amp=3e-5)) as r:
        fa = FeedRate(r)
        fa.run()
        paths = feedrate_figures(fa, tmp_path)
    fr = fa.results
    assert [p.name for p in paths] == ["feedrate_cumulative.png", "feedrate_velocity_profile.png"]
    ax = drawn["feedrate_cumulative.png"].axes[0]
    steps, fit = ax.lines[0], ax.lines[1]
    # the cumulative count: 0 at the first frame, then one more at each exit; what is drawn is the
    # analysis' own numbers (s, parts, mm/s, ms), equal up to rounding (and a unit's factor)
    assert steps.get_xdata() == pytest.approx(np.r_[0.0, fr.event_times], rel=1e-12)
    assert list(steps.get_ydata()) == list(range(fr.n_events + 1))
    # the fitted rate: a line from the count at the window's start, of slope parts_per_s
    x, y = np.asarray(fit.get_xdata()), np.asarray(fit.get_ydata())
    assert x == pytest.approx([fr.steady_from, fr.steady_to], rel=1e-12)
    n_a = int((fr.event_times < fr.steady_from).sum())
    assert y[0] == pytest.approx(n_a, rel=1e-12)
    assert (y[1] - y[0]) / (x[1] - x[0]) == pytest.approx(fr.parts_per_s, rel=1e-12)
    window = ax.patches[0]  # the axvspan: a rectangle, x in data coordinates
    assert (window.get_x(), window.get_x() + window.get_width()) == pytest.approx(
        (fr.steady_from, fr.steady_to), rel=1e-12)
    assert f"{fr.parts_per_s:.4g}" in fit.get_label()
    assert ax.get_xlabel() == "time [s]" and "[-]" in ax.get_ylabel()
    names_the_run(drawn["feedrate_cumulative.png"], "f.h5")

    ax = drawn["feedrate_velocity_profile.png"].axes[0]
    guide, mean = ax.lines[0], ax.lines[-1]
    assert np.asarray(guide.get_xdata()) == pytest.approx(fr.profile_x * 1e3, rel=1e-12)
    assert np.asarray(guide.get_ydata()) == pytest.approx(fr.profile_velocity * 1e3, rel=1e-12, nan_ok=True)
    assert np.asarray(mean.get_ydata()) == pytest.approx([fr.mean_velocity * 1e3] * 2, rel=1e-12)
    assert mean.get_label().startswith(f"mean {fr.mean_velocity * 1e3:.3g} ± ")
    names_the_run(drawn["feedrate_velocity_profile.png"], "f.h5")


def test_singulation_figures_draw_the_arrivals_against_random_ones_and_the_clusters(tmp_path, drawn):
    rng = np.random.default_rng(3)
    exits = np.sort(rng.uniform(0.0, 1.0, 120))
    lanes = np.arange(len(exits)) % 5 * 1e-3
    with Result(feeder(tmp_path / "s.h5", FRAMES, exits, freq=FREQ, speed=0.05, lanes=lanes)) as r:
        sa = Singulation(r, gap=1e-3, start=0.0, end=1.0, cluster_frames=5)
        sa.run()
        paths = singulation_figures(sa, tmp_path)
    sg = sa.results
    assert [p.name for p in paths] == ["singulation_interarrival.png", "singulation_clusters.png"]
    ax = drawn["singulation_interarrival.png"].axes[0]
    heights = np.array([p.get_height() for p in ax.patches])
    assert heights.sum() == len(sg.interarrival)          # every inter-arrival time, in ms
    lefts = np.array([p.get_x() for p in ax.patches])
    assert lefts[0] == pytest.approx(sg.interarrival.min() * 1e3, rel=1e-12)
    # random arrivals at the same rate: exponential inter-arrival times, N (e^-a/m - e^-b/m) per bin
    random = ax.lines[0]
    edges = np.asarray(random.get_xdata())
    mean = sg.mean_interarrival * 1e3
    expected = len(sg.interarrival) * (np.exp(-edges[:-1] / mean) - np.exp(-edges[1:] / mean))
    assert np.asarray(random.get_ydata())[:-1] == pytest.approx(expected, rel=1e-12)
    assert random.get_ydata()[-1] == random.get_ydata()[-2]   # a step: no drop at the last edge
    assert edges[0] == pytest.approx(lefts[0], rel=1e-12)
    gap = ax.lines[1]
    assert np.asarray(gap.get_xdata()) == pytest.approx([1.0, 1.0], rel=1e-12)  # the gap, 1 ms
    assert gap.get_label() == "gap 1 ms"
    assert f"CV {sg.cv_interarrival:.3g}" in ax.get_title()
    names_the_run(drawn["singulation_interarrival.png"], "s.h5")

    ax = drawn["singulation_clusters.png"].axes[0]
    bars = {round(p.get_x() + p.get_width() / 2): p.get_height() for p in ax.patches}
    assert bars == pytest.approx(sg.cluster_sizes, rel=1e-12)
    assert sum(s * n for s, n in bars.items()) == pytest.approx(sg.cluster_size_counts.sum() / 5, rel=1e-12)
    assert ax.get_title().startswith("5 frames")
    # log scale: clusters of four and more, a hundred times rarer than singles, stay visible
    assert ax.get_yscale() == "log"
    names_the_run(drawn["singulation_clusters.png"], "s.h5")


def test_profile_error_is_the_batch_means_error_per_bin():
    """Two bins, four whole-period intervals in two batches ({0, 1}, {2, 3}): bin 0's batch
    means are (1 + 3 + 2) / 3 = 2 and (4 + 6) / 2 = 5, error std([2, 5]) / sqrt(2) = 1.5;
    bin 1 is seen by one batch only: no error."""
    which = np.array([0, 0, 0, 1, 0, 0])
    values = np.array([1.0, 3.0, 2.0, 7.0, 4.0, 6.0])
    groups = np.array([0, 0, 1, 1, 2, 3])
    err = profile_error(which, values, groups, bins=2, batches=2)
    assert err[0] == pytest.approx(1.5, rel=1e-12)
    assert math.isnan(err[1])


def test_velocity_profile_has_batch_errors_and_thin_bins_drawn_light(tmp_path, drawn):
    """The error bars are each bin's batch-means error, recomputed here from the
    whole-period speeds by explicit batches; bins with few samples are drawn lighter."""
    rng = np.random.default_rng(11)
    exits = 0.213 + np.arange(150) / 250.0
    speeds = rng.uniform(0.015, 0.025, len(exits))
    with Result(feeder(tmp_path / "p.h5", FRAMES, exits, speed=speeds, freq=FREQ)) as r:
        fa = FeedRate(r, bins=8, batches=4).run()
        feedrate_figures(fa, tmp_path)
        fr = fa.results
        window = fa.frames[(fa.times >= fr.steady_from - 1e-12) & (fa.times <= fr.steady_to + 1e-12)]
        x_mid, v, interval, _ = period_velocities(r, window, 0, 0.02)
    # the errors, independently: batches of whole intervals, a bin's mean in each batch
    batches = np.array_split(np.unique(interval), 4)
    which = np.clip(np.searchsorted(fr.profile_edges, x_mid, side="right") - 1, 0, 7)
    expected = np.full(8, np.nan)
    for k in range(8):
        means = [v[(which == k) & np.isin(interval, b)].mean() for b in batches
                 if ((which == k) & np.isin(interval, b)).any()]
        if len(means) >= 2:
            expected[k] = np.std(means, ddof=1) / np.sqrt(len(means))
    assert np.isfinite(expected).sum() >= 4
    assert fr.profile_velocity_err == pytest.approx(expected, rel=1e-9, abs=0, nan_ok=True)
    assert fr.profile_height is None  # a linear track: no profile in height, no height axis

    ax = drawn["feedrate_velocity_profile.png"].axes[0]
    assert ax.get_xlabel() == "position along the track x [mm]"
    drawn_err = {}
    alphas = []
    for container in ax.containers:   # each errorbar: data line, caps, bar segments
        line, _, (bars,) = container.lines
        alphas.append(line.get_alpha() or 1.0)
        for x, seg in zip(line.get_xdata(), bars.get_segments()):
            drawn_err[round(float(x), 9)] = (seg[1][1] - seg[0][1]) / 2   # mm/s, half the bar
    for x, e in zip(fr.profile_x * 1e3, fr.profile_velocity_err * 1e3):
        if np.isfinite(e) and round(float(x), 9) in drawn_err:
            assert drawn_err[round(float(x), 9)] == pytest.approx(e, rel=1e-9, abs=1e-12)
    thin = plots.thin_bins(fr.profile_count)
    assert len(drawn_err) == int((fr.profile_count > 0).sum())   # every bin with samples
    assert thin.any()   # the first bins behind the fill's back end hold few samples
    assert len(ax.containers) == 2 and alphas[1] < alphas[0]
    assert {t.get_text() for t in ax.texts} == {f"n={c}" for c in fr.profile_count[thin]}


def test_thin_bins_are_those_far_below_the_median():
    assert list(plots.thin_bins([0, 1, 10, 12, 9, 2, 11])) == [False, True, False, False, False,
                                                                True, False]
    assert not plots.thin_bins([0, 0]).any()


def test_demo_draws_the_last_frame_of_the_steady_window():
    times = np.arange(0, 1.0 + 1e-9, 0.01)
    assert picture_frame(times, 0.76) == 76
    assert picture_frame(times, 0.765) == 76
    assert picture_frame(times, float("nan")) == -1
