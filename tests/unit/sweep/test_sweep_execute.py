"""``vibrofeed sweep`` with the runner and the analysis faked (no LIGGGHTS): the folder it
makes (none for a dry run), its lines, the rows of jobs whose run or analysis fails, and the
MPI checks on a fake communicator."""

from __future__ import annotations

import io
from types import SimpleNamespace

import pytest

from vibrofeed.errors import RunError, UsageError
from vibrofeed.sweep import execute as E
from vibrofeed.sweep import summary as S
from vibrofeed.sweep.plan import plan
from vibrofeed.sweep.spec import load

SPEC = 'deck = "bulk_feeder"\nreplicates = 1\n[grid]\namp_n = [5e-5, 1e-4]\n'


@pytest.fixture
def spec_path(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(SPEC)
    return path


@pytest.fixture
def fake(monkeypatch):
    """run_deck answers at once (or raises what ``fail`` gives); the analysis measures
    a conveying velocity (or raises ``analysis``)."""
    state = SimpleNamespace(fail=None, analysis=None, reused=False, runs=[])

    def run_deck(deck, params, path, **kw):
        state.runs.append(path.name)
        if state.fail is not None:
            raise state.fail
        return SimpleNamespace(wall=7.0, reused=state.reused)

    def metrics(path):
        if state.analysis is not None:
            raise state.analysis
        return {"mean_velocity": 0.01}

    monkeypatch.setattr(E, "run_deck", run_deck)
    monkeypatch.setattr(E, "metrics", metrics)
    return state


class Comm:
    def __init__(self, size):
        self.size = size

    def Get_size(self):
        return self.size


def test_numbers_keep_the_type_their_text_says():
    assert E._number("3") == 3 and isinstance(E._number("3"), int)
    assert E._number("2.5") == pytest.approx(2.5, abs=0)
    assert isinstance(E._number("1e3"), float) and isinstance(E._number("2.0"), float)
    assert E._number("abc") == "abc"


def test_a_sweep_runs_every_job_and_says_so(spec_path, tmp_path, fake, capsys):
    out = io.StringIO()
    assert E.sweep(spec_path, output=tmp_path / "out", out=out) == 0
    folder = (tmp_path / "out").absolute()
    assert out.getvalue() == f"sweep: 2 of 2 jobs finished, 2 done, 0 failed -> {folder / S.CSV_NAME}\n"
    err = capsys.readouterr().err
    assert err.startswith("sweep ") and "workers: 1, 1 rank per run)" in err  # not quiet, 1 worker
    assert [r["status"] for r in S.read(folder)[0]] == [S.DONE, S.DONE]


def test_a_quiet_sweep_prints_nothing_on_stderr(spec_path, tmp_path, fake, capsys):
    E.sweep(spec_path, output=tmp_path / "out", quiet=True, out=io.StringIO())
    assert capsys.readouterr().err == ""


def test_failed_jobs_end_the_sweep_with_a_run_error_after_their_rows(spec_path, tmp_path, fake):
    fake.fail = RunError("LIGGGHTS error:\n  boom")
    out = io.StringIO()
    with pytest.raises(RunError, match="2 of 2 jobs failed"):
        E.sweep(spec_path, output=tmp_path / "out", out=out, quiet=True)
    assert ", 0 done, 2 failed -> " in out.getvalue()
    rows = S.read(tmp_path / "out")[0]
    assert [r["error"] for r in rows] == ["LIGGGHTS error: boom"] * 2


def test_a_dry_run_lists_the_jobs_and_makes_no_folder(spec_path, tmp_path, fake):
    out = io.StringIO()
    assert E.sweep(spec_path, output=tmp_path / "out", dry_run=True, out=out) == 0
    assert not (tmp_path / "out").exists() and fake.runs == []
    lines = out.getvalue().splitlines()
    assert "(workers: 1, 1 rank per run)" in lines[0]
    assert lines[1].split() == ["job", "rep", "seed", "amp_n", "cost", "state"]
    assert len(lines) == 4 and all(line.split()[-2:] == ["to", "run"] for line in lines[2:])


def test_under_mpirun_a_group_needs_ranks_per_run_ranks(tmp_path, fake):
    path = tmp_path / "s.toml"
    path.write_text("ranks_per_run = 2\n" + SPEC)
    out = io.StringIO()
    assert E.sweep(path, output=tmp_path / "out", dry_run=True, comm=Comm(3), out=out) == 0
    assert "(3 MPI ranks of which 1 idle: not a multiple of ranks_per_run, 2 ranks per run)" in out.getvalue()
    E.sweep(path, output=tmp_path / "out", dry_run=True, comm=Comm(2), out=io.StringIO())  # one group
    with pytest.raises(UsageError, match="needs at least that many ranks; mpirun started 1"):
        E.sweep(path, output=tmp_path / "out", dry_run=True, comm=Comm(1), out=io.StringIO())


def test_a_failed_analysis_is_the_jobs_failure_and_counts_as_computed(spec_path, tmp_path, fake):
    spec = load(spec_path)
    job = plan(spec)[0]
    fake.analysis = ValueError("no frames")
    row, computed = E.run_job(job, tmp_path, None, 1, ["amp_n"])
    assert row["status"] == S.FAILED and row["error"] == "analysis failed: ValueError: no frames"
    assert computed is True
    fake.reused = True
    row, computed = E.run_job(job, tmp_path, None, 1, ["amp_n"])
    assert computed is False and row["wall_s"] == pytest.approx(7.0, abs=0)


def test_a_sweep_goes_on_in_the_folder_of_an_earlier_one(spec_path, tmp_path, fake):
    E.sweep(spec_path, output=tmp_path / "out", quiet=True, out=io.StringIO())
    out = io.StringIO()
    assert E.sweep(spec_path, output=tmp_path / "out", quiet=True, out=out) == 0
    assert ", 2 done, 0 failed -> " in out.getvalue()


def test_the_runs_warnings_go_to_warn_with_their_job(spec_path, tmp_path, monkeypatch):
    job = plan(load(spec_path))[1]
    warned = []

    def run_deck(deck, params, path, on_event, **kw):
        on_event({"event": "progress", "message": "not this"})
        on_event({"event": "warning", "message": "dt large"})
        raise RunError("stopped")

    monkeypatch.setattr(E, "run_deck", run_deck)
    row, _ = E.run_job(job, tmp_path, None, 1, ["amp_n"], warn=lambda j, m: warned.append((j.index, m)))
    assert warned == [(1, "dt large")] and row["error"] == "stopped"


def test_a_job_run_and_analysed_here_is_done_and_computed(spec_path, tmp_path, fake):
    row, computed = E.run_job(plan(load(spec_path))[0], tmp_path, None, 1, ["amp_n"])
    assert row["status"] == S.DONE and row["mean_velocity"] == pytest.approx(0.01, abs=0)
    assert computed is True


def test_under_mpirun_minus_j_is_refused(spec_path, tmp_path, fake):
    with pytest.raises(UsageError, match="drop -j"):
        E.sweep(spec_path, output=tmp_path / "out", workers=2, dry_run=True, comm=Comm(2), out=io.StringIO())
