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
