"""Every sweep file in sweeps/ and study file in studies/ the docs tell people to run is one
vibrofeed accepts: it loads, names a deck, and each of its runs resolves (the parameter
checks of `vibrofeed run`), so none fails only when someone runs it."""

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
SWEEPS = sorted((REPO / "sweeps").glob("*.toml"))
STUDIES = sorted((REPO / "studies").glob("*.toml"))


def test_there_are_files_to_check():
    assert {p.name for p in SWEEPS} >= {"example.toml", "bowl.toml", "line.toml"}
    assert {p.name for p in STUDIES} >= {"line_singulated_rate.toml", "single_part_phase.toml"}


@pytest.mark.parametrize("path", SWEEPS, ids=lambda p: p.name)
def test_each_sweep_plans_every_run(path):
    from vibrofeed.sweep.plan import plan
    from vibrofeed.sweep.spec import load

    spec = load(path)
    jobs = plan(spec)
    assert len(jobs) >= 2  # a sweep varies something
    assert all(job.run_id and len(job.run_id) == 64 for job in jobs)
    assert len({job.run_id for job in jobs}) == len(jobs)  # no two runs the same


@pytest.mark.parametrize("path", STUDIES, ids=lambda p: p.name)
def test_each_study_loads_with_its_deck(path):
    from vibrofeed.optimize.spec import load
    from vibrofeed.sweep.plan import find_deck

    spec = load(path)
    deck = find_deck(spec)
    # (a description's dotted names too)
    assert {deck.aliases.get(n, n) for n in spec.names} <= set(deck.tunables)
