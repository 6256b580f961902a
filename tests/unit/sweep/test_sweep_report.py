"""``vibrofeed sweep-report`` from hand-made settings and summaries: the mean and its
standard error over replicates, the best setting, the table, the text and which maps are
drawn along which axes (the drawing itself is sweep_maps', faked here)."""

from __future__ import annotations

import json
import math

import pytest

from vibrofeed.pictures import sweep_maps
from vibrofeed.sweep import report as R
from vibrofeed.sweep import summary as S


def entry(merit, err=None, sing=None, unmeasured=None, **parameters):
    """A setting as ``settings`` makes it, the merit being the conveying velocity."""
    e = {"parameters": parameters, "runs": 2, "done": 2, "jobs": [0, 1]}
    for name in R.FIGURES:
        e[name], e[f"{name}_err"], e[f"{name}_unmeasured"] = None, None, None
    e["mean_velocity"], e["mean_velocity_err"] = merit, err
    e["singulated_fraction"] = sing
    e["merit"], e["merit_err"], e["merit_unmeasured"] = merit, err, unmeasured
    e["mean_velocity_unmeasured"] = unmeasured
    return e


# ------------------------------------------------------------------ mean and error
def test_two_replicates_give_the_standard_error_of_their_mean():
    # mean 2; sample variance ((1-2)^2 + (3-2)^2) / (2-1) = 2; error sqrt(2/2) = 1
    mean, err = R.mean_err([1.0, 3.0], [0.1, 0.1])
    assert mean == pytest.approx(2.0, abs=1e-12) and err == pytest.approx(1.0, abs=1e-12)


def test_four_replicates_divide_the_squares_by_three():
    # mean 3; squares 4 + 1 + 0 + 9 = 14; variance 14/3; error sqrt(14/3/4)
    mean, err = R.mean_err([1.0, 2.0, 3.0, 6.0], [])
    assert mean == pytest.approx(3.0, abs=1e-12)
    assert err == pytest.approx(math.sqrt(14 / 12), rel=1e-12)


def test_one_value_keeps_its_own_error_and_none_are_none():
    assert R.mean_err([None, 4.0], [9.0, 0.25]) == (4.0, 0.25)
    assert R.mean_err([None], [None]) == (None, None)


# ------------------------------------------------------------------ best setting
def test_a_setting_exactly_one_combined_error_below_the_top_is_close_and_singulates_better():
    top = entry(10.0, 3.0, sing=0.2, s=1)
    other = entry(5.0, 4.0, sing=0.9, s=2)  # 10 - 5 = hypot(3, 4): within, at the limit
    assert R.best([top, other]) is other
    further = entry(4.99, 4.0, sing=0.9, s=3)  # just past it
    assert R.best([top, further]) is top


def test_a_close_setting_without_singulation_ranks_below_any_measured_singulation():
    top = entry(10.0, 3.0, sing=None, s=1)
    other = entry(9.0, 3.0, sing=0.0, s=2)
    assert R.best([top, other]) is other


def test_no_measured_merit_no_best():
    assert R.best([entry(None, s=1), entry(3.0, unmeasured="too few exits", s=2)]) is None


# ------------------------------------------------------------------ table and text
def rep(entries, best=None, merit="mean_velocity"):
    return {"folder": "out", "deck": "d", "jobs_finished": 2, "jobs_planned": 2, "done": 2,
            "failed": [], "varied": ["s"], "merit": merit, "settings": entries, "best": best,
            "figures": []}


def test_the_table_has_a_header_and_a_row_per_setting_in_the_figures_units():
    e = entry(0.0125, 0.0005, sing=0.5, s=1)
    text = R.table([e], ["s"], ["mean_velocity", "singulated_fraction"])
    head, line = text.split("\n")
    assert head.split() == ["s", "runs", "conveying", "[mm/s]", "singulated", "[%]"]
    # 0.0125 m/s = 12.5 mm/s ± 0.5; 0.5 = 50 %
    assert line.split() == ["1", "2/2", "12.5", "±", "0.5", "50"]


def test_an_unmeasured_figure_is_explained_by_name_and_no_best_says_which_figure():
    e = entry(None, unmeasured="too few exits", s=1)
    lines = R.text(rep([e])).split("\n")
    assert "unmeasured: s=1: conveying: too few exits" in lines
    assert "best: none (no setting has a measured conveying)" in lines
    measured = entry(0.01, s=2)
    assert not any(ln.startswith("unmeasured") for ln in R.text(rep([measured], measured)).split("\n"))


# ------------------------------------------------------------------ load
def test_a_summary_without_axes_has_one_axis_per_varied_parameter(tmp_path):
    rows = [{"job": 0, "replicate": 0, "seed": 1, "a": 1.0, "b": 2.0, "status": S.DONE,
             "error": "", "file": "jobs/job-0000.h5", "run_id": "x", "wall_s": 1.0}]
    S.write(tmp_path, rows, ["a", "b"], {"varied": json.dumps(["a", "b"])})
    _, meta = R.load(tmp_path)
    assert meta["varied"] == ["a", "b"] and meta["axes"] == [["a"], ["b"]]


# ------------------------------------------------------------------ which maps
@pytest.fixture
def drawn(monkeypatch):
    calls = []
    monkeypatch.setattr(sweep_maps, "heat_map", lambda *a: calls.append(("heat", a)) or "heat.png")
    monkeypatch.setattr(sweep_maps, "trends", lambda *a: calls.append(("trends", a)) or "trends.png")
    return calls


def grid(xs, ys):
    return [entry(0.01 * (i + 1), 0.001, sing=0.5, x=x, y=y)
            for i, (x, y) in enumerate((x, y) for x in xs for y in ys)]


def test_one_axis_draws_one_trend_without_series(drawn, tmp_path):
    entries = [entry(0.01 * x, 0.001, sing=0.5, x=x) for x in (1.0, 2.0, 3.0)]
    out = R.plots(entries, [["x"]], "mean_velocity", None, tmp_path)
    assert out == ["trends.png"] and [c[0] for c in drawn] == ["trends"]
    part, a, series, panels = drawn[0][1][:4]
    assert (a, series) == ("x", None) and len(part) == 3
    assert panels[-1] == ("singulated_fraction", "singulated fraction [%]", 100.0)


def test_the_trend_runs_along_the_first_axis_unless_the_other_has_more_values(drawn, tmp_path):
    R.plots(grid([1.0, 2.0], [5.0, 6.0]), [["x"], ["y"]], "mean_velocity", None, tmp_path)
    assert [c[0] for c in drawn] == ["heat", "trends"]
    assert drawn[1][1][1:3] == ("x", "y")  # as many values: no swap
    drawn.clear()
    R.plots(grid([1.0, 2.0], [5.0, 6.0, 7.0]), [["x"], ["y"]], "mean_velocity", None, tmp_path)
    assert drawn[1][1][1:3] == ("y", "x")


def test_a_zipped_axis_is_labelled_by_its_first_parameter_naming_the_others(drawn, tmp_path):
    entries = [entry(0.01 * x, 0.001, x=x, z=2 * x) for x in (1.0, 2.0, 3.0)]
    R.plots(entries, [["x", "z"]], "mean_velocity", None, tmp_path, units={"x": "Hz"})
    axis_label = drawn[0][1][4]
    assert axis_label("x") == "x [Hz] (= z)"


# ------------------------------------------------------------------ settings from rows
def test_a_figure_one_replicate_could_not_measure_is_unmeasured_saying_how_many_did():
    rows = [{"job": 0, "status": S.DONE, "s": 1, "parts_per_s": 2.0, "feedrate_reason": None},
            {"job": 1, "status": S.DONE, "s": 1, "parts_per_s": None, "feedrate_reason": "too few exits"},
            {"job": 2, "status": S.DONE, "s": 2, "parts_per_s": None, "feedrate_reason": "drifting"}]
    two, one = R.settings(rows, ["s"], "parts_per_s")
    assert two["parts_per_s"] is None and two["merit_unmeasured"] == "1 of 2 runs: too few exits"
    assert one["merit_unmeasured"] == "drifting"  # one run: its own reason


def test_a_top_without_an_error_counts_as_exact():
    top = entry(10.0, None, sing=0.1, s=1)
    other = entry(9.5, None, sing=0.9, s=2)  # 0.5 below, both errors unknown: not close
    assert R.best([top, other]) is top


# ------------------------------------------------------------------ text
def test_the_text_of_a_bulk_sweep_shows_the_feed_rate_and_the_figures_measured():
    e = entry(None, s=1)
    e.update(parts_per_s=3.5, parts_per_s_err=0.25, merit=3.5, merit_err=0.25, mean_velocity=0.02,
             singulated_fraction=0.5)
    r = rep([e], e, merit="parts_per_s")
    lines = R.text(r).split("\n")
    assert lines[2].split() == ["s", "runs", "feed", "rate", "[parts/s]", "singulated", "[%]",
                                "conveying", "[mm/s]"]  # no doubles: none measured
    assert lines[-1] == ("best: s=1: feed rate 3.5 ± 0.25 parts/s, singulated 50 % (the highest; "
                         "within one standard error, the better singulation)")
    e["singulated_fraction"] = None
    assert R.text(r).split("\n")[-1] == ("best: s=1: feed rate 3.5 ± 0.25 parts/s (the highest; "
                                         "within one standard error, the better singulation)")


def test_the_first_ten_failed_jobs_are_listed_then_how_many_more():
    r = rep([], None)
    r["failed"] = [{"job": k, "error": "boom", "file": ""} for k in range(12)]
    lines = R.text(r).split("\n")
    assert lines[-2] == "failed: job 9: boom"
    assert lines[-1] == "... and 2 more failed jobs (see summary.csv)"


# ------------------------------------------------------------------ report's plots
def test_the_maps_title_counts_the_runs_done(tmp_path, monkeypatch):
    base = {"replicate": 0, "seed": 1, "error": "", "file": "", "run_id": "x", "wall_s": 1.0}
    rows = [dict(base, job=0, a=1.0, status=S.DONE, mean_velocity=0.01),
            dict(base, job=1, a=2.0, status=S.DONE, mean_velocity=0.02),
            dict(base, job=2, a=3.0, status=S.FAILED, error="boom")]
    S.write(tmp_path, rows, ["a"], {"varied": json.dumps(["a"]), "deck": "d"})
    seen = []
    monkeypatch.setattr(R, "plots", lambda *a: seen.append(a) or [])
    out = R.report(tmp_path, tmp_path / "maps")
    assert out["done"] == 2 and [f["job"] for f in out["failed"]] == [2]
    assert seen[0][1] == [["a"]] and seen[0][6].endswith("; deck d; 3 settings, 2 runs done")


def test_the_plotted_axes_are_the_first_two_numeric_ones_with_more_than_one_value():
    entries = [entry(0.01, x=x, one=1.0, z=2 * x, y=y, w=w) for x in (1.0, 2.0) for y in (3.0, 4.0)
               for w in (5.0, 6.0)]
    chosen = entries[-1]  # w = 6 held there
    axes, part = R.plotted(entries, [["one"], ["x", "z"], ["y"], ["w"]], chosen)
    assert axes == ["x", "y"] and len(part) == 4 and all(e["parameters"]["w"] == 6.0 for e in part)


def test_maps_of_three_axes_hold_the_third_at_the_best_setting(drawn, tmp_path):
    entries = [entry(0.01, 0.001, x=x, y=y, w=w) for x in (1.0, 2.0) for y in (3.0, 4.0) for w in (5.0, 6.0)]
    chosen = entries[0]  # w = 5
    R.plots(entries, [["x"], ["y"], ["w"]], "mean_velocity", chosen, tmp_path, title="T")
    heat = drawn[0][1]
    assert heat[1:5] == ("x", "y", "conveying [mm/s]", 1e3)
    assert len(heat[0]) == 4 and all(e["parameters"]["w"] == 5.0 for e in heat[0])
    assert heat[-1] == "T; other parameters at the best setting's: w 5"


@pytest.mark.parametrize("merit, names", [
    ("parts_per_s", ["parts_per_s", "mean_velocity", "singulated_fraction"]),
    ("mean_velocity", ["mean_velocity", "singulated_fraction"])])
def test_a_bulk_sweeps_trends_add_the_conveying_velocity(drawn, tmp_path, merit, names):
    entries = [entry(0.01 * x, 0.001, x=x) for x in (1.0, 2.0)]
    R.plots(entries, [["x"]], merit, None, tmp_path)
    panels = drawn[0][1][3]
    assert [p[0] for p in panels] == names and panels[0][2] == R.FIGURES[merit][2]


def test_a_zipped_axis_drawn_is_not_held(drawn, tmp_path):
    entries = [entry(0.01 * x, 0.001, x=x, z=2 * x, w=w) for x in (1.0, 2.0) for w in (5.0,)]
    R.plots(entries, [["x", "z"], ["w"]], "mean_velocity", entries[0], tmp_path, title="T")
    assert drawn[0][1][-1] == "T; other parameters at the best setting's: w 5"


def test_a_sweep_whose_runs_counted_exits_has_the_feed_rate_as_merit(tmp_path):
    base = {"replicate": 0, "seed": 1, "error": "", "file": "", "run_id": "x", "wall_s": 1.0,
            "status": S.DONE, "mean_velocity": 0.01, "parts_per_s": None,
            "feedrate_reason": "too few exits"}
    rows = [dict(base, job=0, a=1.0, n_events=3)]
    S.write(tmp_path, rows, ["a"], {"varied": json.dumps(["a"])})
    out = R.report(tmp_path)
    assert out["merit"] == "parts_per_s" and out["best"] is None  # the speed is no stand-in
