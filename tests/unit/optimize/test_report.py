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
