"""optimize-report's pieces on hand-made rows: the Pareto front (the non-dominated points,
for maximised and minimised metrics) and the figures it draws."""

from vibrofeed.optimize.report import _front, figures
from vibrofeed.optimize.spec import parse

TWO = ('deck = "bulk_feeder"\n[variables]\namp_n = { low = 1e-5, high = 1e-4 }\n[objective]\n'
       'maximize = ["parts_per_s", "singulated_fraction"]\n')


def test_the_front_keeps_exactly_the_non_dominated_points():
    spec = parse(TWO, "s.toml")
    points = [(10.0, 0.9), (20.0, 0.5), (15.0, 0.8), (12.0, 0.7), (20.0, 0.4), (5.0, 0.95)]
    # (12, 0.7) is dominated by (15, 0.8); (20, 0.4) by (20, 0.5)
    assert _front(points, spec) == [(5.0, 0.95), (10.0, 0.9), (15.0, 0.8), (20.0, 0.5)]
    minimised = parse(TWO.replace('"singulated_fraction"', '"cv_interarrival"'), "s.toml")
    # now lower is better on the second: (20, 0.4) dominates (20, 0.5) and (12, 0.7) ...
    assert _front(points, minimised) == [(20.0, 0.4)]


def test_figures_of_a_two_objective_study(tmp_path):
    spec = parse(TWO, "s.toml")
    rows = [{"job": k, "stage": "search", "objective": float(10 + k), "objective_err": 1.0,
             "objective_2": 1.0 - 0.05 * k, "objective_2_err": 0.01} for k in range(6)]
    rows.append({"job": 6, "stage": "search", "objective": None, "objective_2": None})  # unmeasured
    doc = {"confirmed": [{"setting": {"amp_n": 2e-5}, "parts_per_s": (14.0, 0.5)}]}
    out = figures(spec, doc, rows, {"amp_n": 1.0}, tmp_path)
    assert [p.name for p in out] == ["convergence.png", "pareto.png", "importance.png"]
    assert all(p.stat().st_size > 1000 for p in out)


def _front_drawn(monkeypatch, spec, rows, tmp_path) -> list[tuple]:
    """The points figures() draws as the line labelled "Pareto front" in pareto.png."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.axes import Axes

    drawn, plot = [], Axes.plot

    def spy(self, *args, **kwargs):
        if kwargs.get("label") == "Pareto front":
            drawn.extend(zip(*args[:2]))
        return plot(self, *args, **kwargs)

    monkeypatch.setattr(Axes, "plot", spy)
    figures(spec, {"confirmed": []}, rows, {}, tmp_path)
    return drawn


def test_the_drawn_front_is_the_studys_front_of_runs_reaching_the_targets(monkeypatch, tmp_path):
    """A run missing an at_least target is infeasible for the study (the sampler is told so
    and confirmation never takes it); the drawn front must not let it push counted runs
    off: (25, 0.9) measured no mass_per_s and (11, 0.95) misses parts_per_s >= 12."""
    spec = parse(TWO + "at_least = { parts_per_s = 12, mass_per_s = 1e-7 }\n", "s.toml")
    values = [(20.0, 0.5, 2e-6), (15.0, 0.8, 1e-6), (11.0, 0.95, 1e-6), (14.0, 0.7, 1e-6), (25.0, 0.9, None)]
    rows = [{"job": k, "stage": "search", "amp_n": 1e-5 * (k + 1), "objective": a, "objective_err": 1.0,
             "objective_2": b, "objective_2_err": 0.01, "parts_per_s": a, "mass_per_s": m}
            for k, (a, b, m) in enumerate(values)]
    # (14, 0.7) is dominated by (15, 0.8); the other two counted runs are the front
    assert sorted(_front_drawn(monkeypatch, spec, rows, tmp_path)) == [(15.0, 0.8), (20.0, 0.5)]
    from vibrofeed.optimize.search import front_entries, pareto_front

    assert [r["job"] for r in pareto_front(spec, rows)] == [0, 1]  # 20 - 1 before 15 - 1
    assert [e["setting"]["amp_n"] for e in front_entries(spec, rows)] == [1e-5, 2e-5]
    assert front_entries(spec, rows)[1]["singulated_fraction"] == (0.8, 0.01)


def test_the_front_ranks_one_error_towards_worse_and_keeps_mixed_directions():
    from vibrofeed.optimize.search import pareto_front

    spec = parse(TWO.replace('"singulated_fraction"', '"cv_interarrival"'), "s.toml")
    # (rate, its error, cv): cv is minimised. (30, 12, 1.0) is on the front (nothing as fast),
    # but one error towards worse (18) it ranks below (20, 1, 0.6) (19); (18, 0.5, 0.7) is
    # dominated by (20, 0.6); (10, 0.5, 0.3) and an equal twin of it are both kept.
    values = [(30.0, 12.0, 1.0), (20.0, 1.0, 0.6), (18.0, 0.5, 0.7), (10.0, 0.5, 0.3), (10.0, 0.5, 0.3)]
    rows = [{"job": k, "stage": "search", "amp_n": 1e-5, "objective": a, "objective_err": e,
             "objective_2": c, "objective_2_err": None} for k, (a, e, c) in enumerate(values)]
    rows.append({"job": 9, "stage": "search", "amp_n": 1e-5, "objective": 50.0, "objective_2": None})
    rows.append({"job": 10000, "stage": "confirm", "amp_n": 1e-5, "objective": 99.0, "objective_2": 0.0})
    assert [r["job"] for r in pareto_front(spec, rows)] == [1, 0, 3, 4]


def test_importance_is_for_reaching_the_best_values_of_a_maximised_objective(tmp_path):
    """On a 10 x 10 grid the rate is high only where amp_t > 0.85 (whatever amp_n) and, elsewhere,
    lowest where amp_n is high: amp_t decides the best runs, amp_n only the worst ones.
    Runs that measured nothing (told -1e30, infeasible) are no runs of the ranking."""
    import optuna
    from optuna.storages import JournalStorage
    from optuna.storages.journal import JournalFileBackend

    from vibrofeed.optimize.report import importances
    from vibrofeed.optimize.search import JOURNAL, distributions

    spec = parse('deck = "bulk_feeder"\n[variables]\namp_t = { low = 0, high = 1 }\n'
                 'amp_n = { low = 0, high = 1 }\n[objective]\nmaximize = "parts_per_s"\n', "s.toml")
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    storage = JournalStorage(JournalFileBackend(str(tmp_path / JOURNAL)))
    study = optuna.create_study(study_name="vibrofeed", storage=storage, direction="maximize")
    grid = [((i + 0.5) / 10, (j + 0.5) / 10) for i in range(10) for j in range(10)]
    for t, n in grid + [(0.05, 0.95)] * 30:
        measured = len(study.trials) < len(grid)
        value = (10.0 if t > 0.85 else -n) if measured else -1e30
        trial = optuna.trial.create_trial(params={"amp_t": t, "amp_n": n}, distributions=distributions(spec),
                                          value=value)
        trial.set_constraint("measured", 0.0 if measured else 1.0)
        study.add_trial(trial)
    got = importances(tmp_path, spec)
    assert set(got) == {"amp_t", "amp_n"} and got["amp_t"] > 0.9 and got["amp_n"] < 0.1


# ---------------------------------------------------------------- the report's pieces
def _figures_seen(monkeypatch, spec, doc, rows, importance, tmp_path):
    """{file name: (figure size in inches, its first axes)} of what figures() saves."""
    import vibrofeed.optimize.report as R

    seen = {}

    def save(fig, path):
        seen[path.name] = (tuple(fig.get_size_inches()), fig.axes[0])
        return path

    monkeypatch.setattr(R, "_save", save)
    figures(spec, doc, rows, importance, tmp_path)
    return seen


def test_the_convergence_error_bars_are_the_runs_errors_none_counting_as_zero(monkeypatch, tmp_path):
    import numpy as np

    spec = parse(TWO, "s.toml")
    rows = [{"job": 0, "stage": "search", "objective": 10.0, "objective_err": 2.0, "objective_2": 0.5},
            {"job": 1, "stage": "search", "objective": 12.0, "objective_2": None},  # no error: bar 0
            {"job": 2, "stage": "search", "objective": 11.0, "objective_err": 0.5, "objective_2": 0.7}]
    seen = _figures_seen(monkeypatch, spec, {"confirmed": []}, rows, {"amp_n": 0.6, "b": 0.4}, tmp_path)
    ax = seen["convergence.png"][1]
    bars = [c for c in ax.containers if c.get_label() == "search run (± 1σ)"][0]
    marker = bars.lines[0]
    assert list(marker.get_xdata()) == [1, 2, 3] and list(marker.get_ydata()) == [10.0, 12.0, 11.0]
    assert marker.get_markersize() == 4
    segments = bars.lines[2][0].get_segments()  # each bar: (x, y - e) to (x, y + e)
    half = [float(s[1][1] - s[0][1]) / 2 for s in segments]
    assert np.allclose(half, [2.0, 0.0, 0.5], atol=1e-12)
    # pareto: only the runs that measured both objectives
    pts = [c for c in seen["pareto.png"][1].collections if c.get_label() == "search runs"][0]
    assert sorted(map(tuple, pts.get_offsets().tolist())) == [(10.0, 0.5), (11.0, 0.7)]


def test_the_figures_sizes_and_an_importance_bar_row_each(monkeypatch, tmp_path):
    spec = parse(TWO, "s.toml")
    rows = [{"job": 0, "stage": "search", "objective": 10.0, "objective_err": 1.0, "objective_2": 0.5}]
    importance = {"a": 0.5, "b": 0.3, "c": 0.2}
    seen = _figures_seen(monkeypatch, spec, {"confirmed": []}, rows, importance, tmp_path)
    sizes = {name: size for name, (size, _) in seen.items()}
    assert sizes["convergence.png"] == (6.4, 4.0) and sizes["pareto.png"] == (5.2, 4.4)
    assert sizes["importance.png"] == (5.2, 0.5 + 0.4 * 3)  # half an inch + 0.4 in a bar


def test_a_folder_without_a_study_is_refused(tmp_path):
    import pytest

    from vibrofeed.errors import UsageError
    from vibrofeed.optimize.report import read

    with pytest.raises(UsageError, match="not a study folder"):
        read(tmp_path)


def test_a_one_objective_report_has_no_front_and_a_two_objective_one_has(monkeypatch, tmp_path):
    import json

    import vibrofeed.optimize.report as R
    from vibrofeed.optimize.search import STEM, STUDY_JSON
    from vibrofeed.sweep import summary as S

    monkeypatch.setattr(R, "importances", lambda folder, spec: {})
    one = TWO.replace('["parts_per_s", "singulated_fraction"]', '"parts_per_s"')
    rows = [{"job": 0, "stage": "search", "amp_n": 2e-5, "objective": 10.0, "objective_err": 1.0,
             "objective_2": 0.5, "objective_2_err": 0.1, "status": "done"}]
    S.write(tmp_path, rows, ["amp_n"], {}, stem=STEM)
    for text, front in ((one, None), (TWO, [2e-5])):
        (tmp_path / STUDY_JSON).write_text(json.dumps({"spec_text": text, "source": "s.toml"}))
        rep = R.report(tmp_path)
        assert rep["runs"] == 1
        assert (None if rep["front"] is None else [e["setting"]["amp_n"] for e in rep["front"]]) == front


def test_runs_without_a_measured_constraint_count_for_the_importance(tmp_path):
    """Trials told no "measured" constraint (older studies) are measured runs."""
    import optuna
    from optuna.storages import JournalStorage
    from optuna.storages.journal import JournalFileBackend

    from vibrofeed.optimize.report import importances
    from vibrofeed.optimize.search import JOURNAL, distributions

    spec = parse('deck = "bulk_feeder"\n[variables]\namp_t = { low = 0, high = 1 }\n'
                 'amp_n = { low = 0, high = 1 }\n[objective]\nmaximize = "parts_per_s"\n', "s.toml")
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    storage = JournalStorage(JournalFileBackend(str(tmp_path / JOURNAL)))
    study = optuna.create_study(study_name="vibrofeed", storage=storage, direction="maximize")
    for i in range(8):
        t, n = (i + 0.5) / 8, ((3 * i) % 8 + 0.5) / 8
        study.add_trial(optuna.trial.create_trial(params={"amp_t": t, "amp_n": n},
                                                  distributions=distributions(spec), value=t))
    assert set(importances(tmp_path, spec)) == {"amp_t", "amp_n"}


def test_the_pareto_figure_draws_a_run_short_of_a_target_hollow(monkeypatch, tmp_path):
    spec = parse(TWO + "at_least = { parts_per_s = 12 }\n", "s.toml")
    # 11 is 1/12 short of 12 (a relative margin below 1); 15 reaches it by 3/12
    rows = [{"job": k, "stage": "search", "amp_n": 1e-5, "objective": a, "objective_err": 0.5,
             "objective_2": b, "parts_per_s": a} for k, (a, b) in enumerate([(15.0, 0.8), (11.0, 0.95)])]
    seen = _figures_seen(monkeypatch, spec, {"confirmed": []}, rows, {}, tmp_path)
    ax = seen["pareto.png"][1]
    by_label = {c.get_label(): c for c in ax.collections}
    assert by_label["search runs"].get_offsets().tolist() == [[15.0, 0.8]]
    assert by_label["missing a target"].get_offsets().tolist() == [[11.0, 0.95]]
    assert list(by_label["search runs"].get_sizes()) == list(by_label["missing a target"].get_sizes()) == [14]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("parts_per_s", "singulated_fraction")
    assert ax.get_legend().get_texts()[0].get_fontsize() == 8


def test_the_confirmed_best_is_a_line_with_its_error_band(monkeypatch, tmp_path):
    spec = parse(TWO, "s.toml")
    rows = [{"job": 0, "stage": "search", "objective": 10.0, "objective_err": 1.0, "objective_2": 0.5}]
    for err, bands in ((0.5, [(13.5, 14.5)]), (0.0, [])):
        doc = {"confirmed": [{"setting": {"amp_n": 2e-5}, "parts_per_s": (14.0, err)}]}
        ax = _figures_seen(monkeypatch, spec, doc, rows, {}, tmp_path)["convergence.png"][1]
        assert [tuple(line.get_ydata()) for line in ax.lines if line.get_label().startswith("confirmed")] \
            == [(14.0, 14.0)]
        spans = [p.get_path().transformed(p.get_patch_transform()).vertices[:, 1] for p in ax.patches]
        assert [(min(v), max(v)) for v in spans] == bands


def test_the_importance_bars_list_the_first_variable_on_top(monkeypatch, tmp_path):
    spec = parse(TWO, "s.toml")
    rows = [{"job": 0, "stage": "search", "objective": 10.0, "objective_err": 1.0, "objective_2": 0.5}]
    importance = {"a": 0.5, "b": 0.3, "c": 0.2}
    ax = _figures_seen(monkeypatch, spec, {"confirmed": []}, rows, importance, tmp_path)["importance.png"][1]
    # barh draws bottom up: the most important (first) variable is the last bar, on top
    assert [p.get_width() for p in ax.patches] == [0.2, 0.3, 0.5]
