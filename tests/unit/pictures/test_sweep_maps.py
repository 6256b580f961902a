"""What `vibrofeed sweep-report --plot` draws: the settings' figures on the varied axes, with
units, legends that say what the lines are, and the sweep named (read back from the
matplotlib artists before the figure is written)."""

import numpy as np
import pytest

from vibrofeed.pictures import sweep_maps
from vibrofeed.sweep.report import best, plots


def entry(freq, amp, rate, err, singulated=0.5, **more):
    return {"parameters": {"freq": freq, "amp_n": amp, **more}, "runs": 2, "done": 2, "jobs": [0, 1],
            "merit": rate, "merit_err": err, "parts_per_s": rate, "parts_per_s_err": err,
            "mean_velocity": rate * 1e-4, "mean_velocity_err": err * 1e-4,
            "singulated_fraction": singulated, "singulated_fraction_err": 0.01,
            "doubles_rate": None, "doubles_rate_err": None}


@pytest.fixture
def drawn(monkeypatch):
    figures = {}

    def keep(fig, path):
        figures[path.name] = fig
        return path

    monkeypatch.setattr(sweep_maps, "save", keep)
    yield figures
    for fig in figures.values():
        sweep_maps.pyplot().close(fig)


def test_maps_hold_the_settings_with_units_legends_and_the_sweep_named(tmp_path, drawn):
    freqs, amps = [80.0, 100.0, 120.0], [4e-5, 5e-5]
    entries = [entry(f, a, rate=f * a * 1e5, err=1.0 + f / 100) for f in freqs for a in amps]
    chosen = best(entries)
    names = plots(entries, [["freq"], ["amp_n"]], "parts_per_s", chosen, tmp_path,
                  units={"freq": "Hz", "amp_n": "m"}, title="sweep freq_amp; deck bulk_feeder")
    assert [p.rsplit("/", 1)[-1] for p in names] == ["sweep_map.png", "sweep_vs_freq.png"]

    fig = drawn["sweep_map.png"]
    ax = fig.axes[0]
    assert ax.get_xlabel() == "freq [Hz]" and ax.get_ylabel() == "amp_n [m]"
    grid = ax.images[0].get_array()
    expected = np.array([[f * a * 1e5 for f in freqs] for a in amps])
    assert np.asarray(grid) == pytest.approx(expected, rel=1e-12)
    assert fig.axes[1].get_ylabel() == "feed rate [parts/s]"   # the colour bar
    assert "best setting" in [t.get_text() for t in ax.get_legend().get_texts()]
    assert fig.get_suptitle().startswith("sweep freq_amp; deck bulk_feeder")

    fig = drawn["sweep_vs_freq.png"]
    rate, speed, singulated = fig.axes[:3]
    assert rate.get_xlabel() == "freq [Hz]" and rate.get_ylabel() == "feed rate [parts/s]"
    assert speed.get_ylabel() == "conveying [mm/s]"
    assert singulated.get_ylabel() == "singulated fraction [%]"
    labels = [t.get_text() for t in rate.get_legend().get_texts()]
    assert labels == ["amp_n [m] = 4e-05", "amp_n [m] = 5e-05"]   # one line per value of the other axis
    # the error bars are the settings' errors
    line, _, (bars,) = rate.containers[0].lines
    assert np.asarray(line.get_ydata()) == pytest.approx([f * 4e-5 * 1e5 for f in freqs], rel=1e-12)
    half = [(s[1][1] - s[0][1]) / 2 for s in bars.get_segments()]
    assert half == pytest.approx([1.0 + f / 100 for f in freqs], rel=1e-12)
    assert fig.get_suptitle().startswith("sweep freq_amp")


def test_a_third_axis_is_held_at_the_best_setting_and_the_heading_says_so(tmp_path, drawn):
    entries = [entry(f, a, rate=f * a * 1e5 * (2 if mu == 0.5 else 1), err=1.0, mu=mu)
               for f in (80.0, 100.0) for a in (4e-5, 5e-5) for mu in (0.3, 0.5)]
    chosen = best(entries)
    assert chosen["parameters"]["mu"] == 0.5
    plots(entries, [["freq"], ["amp_n"], ["mu"]], "parts_per_s", chosen, tmp_path,
          units={"freq": "Hz"}, title="sweep s")
    fig = drawn["sweep_map.png"]
    assert fig.get_suptitle().replace("\n", " ") == "sweep s; other parameters at the best setting's: mu 0.5"
    grid = np.asarray(fig.axes[0].images[0].get_array())
    assert grid == pytest.approx(np.array([[80 * 4 * 2, 100 * 4 * 2], [80 * 5 * 2, 100 * 5 * 2]]), rel=1e-12)
