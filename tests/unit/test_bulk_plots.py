"""What the bulk analyses' figures show: the data drawn is the analysis' results (read back
from the matplotlib artists before the figure is written), not just a file that exists."""

import numpy as np
import pytest

from bulk_synthetic import feeder
from vibrofeed.postproc import FeedRate, Singulation
from vibrofeed.postproc import feedrate as feedrate_module
from vibrofeed.postproc import singulation as singulation_module
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

    monkeypatch.setattr(feedrate_module, "save", keep)
    monkeypatch.setattr(singulation_module, "save", keep)
    yield figures
    for name, fig in figures.items():   # whatever the styling, every line drawn can be seen
        for ax in fig.axes:
            assert all(line.get_linewidth() > 0 for line in ax.lines), name
    from vibrofeed.figures import pyplot

    for fig in figures.values():
        pyplot().close(fig)


def test_feed_rate_figures_draw_the_exits_the_window_and_the_profile(tmp_path, drawn):
    rate, t0 = 250.0, 0.213
    exits = t0 + np.arange(150) / rate
    with Result(feeder(tmp_path / "f.h5", FRAMES, exits, freq=FREQ, amp=3e-5)) as r:
        fa = FeedRate(r)
        fa.run()
        paths = fa.plot(tmp_path)
    fr = fa.results
    assert [p.name for p in paths] == ["feedrate_cumulative.png", "feedrate_velocity_profile.png"]
    ax = drawn["feedrate_cumulative.png"].axes[0]
    steps, fit = ax.lines[0], ax.lines[1]
    # the cumulative count: 0 at the first frame, then one more at each exit
    assert steps.get_xdata() == pytest.approx(np.r_[0.0, fr.event_times])
    assert list(steps.get_ydata()) == list(range(fr.n_events + 1))
    # the fitted rate: a line from the count at the window's start, of slope parts_per_s
    x, y = np.asarray(fit.get_xdata()), np.asarray(fit.get_ydata())
    assert x == pytest.approx([fr.steady_from, fr.steady_to])
    n_a = int((fr.event_times < fr.steady_from).sum())
    assert y[0] == pytest.approx(n_a)
    assert (y[1] - y[0]) / (x[1] - x[0]) == pytest.approx(fr.parts_per_s)
    window = ax.patches[0]  # the axvspan: a rectangle, x in data coordinates
    assert (window.get_x(), window.get_x() + window.get_width()) == pytest.approx(
        (fr.steady_from, fr.steady_to))
    assert f"{fr.parts_per_s:.4g}" in fit.get_label()

    ax = drawn["feedrate_velocity_profile.png"].axes[0]
    profile, mean = ax.lines[0], ax.lines[1]
    assert np.asarray(profile.get_xdata()) == pytest.approx(fr.profile_x * 1e3)
    assert np.asarray(profile.get_ydata()) == pytest.approx(fr.profile_velocity * 1e3, nan_ok=True)
    assert np.asarray(mean.get_ydata()) == pytest.approx([fr.mean_velocity * 1e3] * 2)
    assert f"{fr.mean_velocity * 1e3:.3g} mm/s" in mean.get_label()


def test_singulation_figures_draw_the_arrivals_against_random_ones_and_the_clusters(tmp_path, drawn):
    rng = np.random.default_rng(3)
    exits = np.sort(rng.uniform(0.0, 1.0, 120))
    lanes = np.arange(len(exits)) % 5 * 1e-3
    with Result(feeder(tmp_path / "s.h5", FRAMES, exits, freq=FREQ, speed=0.05, lanes=lanes)) as r:
        sa = Singulation(r, gap=1e-3, start=0.0, end=1.0, cluster_frames=5)
        sa.run()
        paths = sa.plot(tmp_path)
    sg = sa.results
    assert [p.name for p in paths] == ["singulation_interarrival.png", "singulation_clusters.png"]
    ax = drawn["singulation_interarrival.png"].axes[0]
    heights = np.array([p.get_height() for p in ax.patches])
    assert heights.sum() == len(sg.interarrival)          # every inter-arrival time, in ms
    lefts = np.array([p.get_x() for p in ax.patches])
    assert lefts[0] == pytest.approx(sg.interarrival.min() * 1e3)
    # random arrivals at the same rate: exponential inter-arrival times, N (e^-a/m - e^-b/m) per bin
    random = ax.lines[0]
    edges = np.asarray(random.get_xdata())
    mean = sg.mean_interarrival * 1e3
    expected = len(sg.interarrival) * (np.exp(-edges[:-1] / mean) - np.exp(-edges[1:] / mean))
    assert np.asarray(random.get_ydata())[:-1] == pytest.approx(expected)
    assert random.get_ydata()[-1] == random.get_ydata()[-2]   # a step: no drop at the last edge
    assert edges[0] == pytest.approx(lefts[0])
    gap = ax.lines[1]
    assert np.asarray(gap.get_xdata()) == pytest.approx([1.0, 1.0])  # the gap, 1 ms
    assert gap.get_label() == "gap 1 ms"
    assert f"CV {sg.cv_interarrival:.3g}" in ax.get_title()

    ax = drawn["singulation_clusters.png"].axes[0]
    bars = {round(p.get_x() + p.get_width() / 2): p.get_height() for p in ax.patches}
    assert bars == pytest.approx(sg.cluster_sizes)
    assert sum(s * n for s, n in bars.items()) == pytest.approx(sg.cluster_size_counts.sum() / 5)
    assert ax.get_title().startswith("5 frames")
