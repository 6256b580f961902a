"""Sweep files, their expansion into jobs, the summary and the resume logic (no engine).

The engine side (real runs, a failing job, SIGKILL, mpirun) is tests/engine/test_sweep.py."""

from __future__ import annotations

import csv
import hashlib
import json
import math
import os

import numpy as np
import pytest

from helpers import parts, write_result
from vibrofeed.errors import InputError, ParameterError, UsageError
from vibrofeed.sweep import folder as F
from vibrofeed.sweep import plan as P
from vibrofeed.sweep import report as R
from vibrofeed.sweep import summary as S
from vibrofeed.sweep.execute import describe
from vibrofeed.sweep.spec import fingerprint, key_lines, parse

# The form the issue asks for, verbatim.
ISSUE = """\
deck = "bulk_feeder"
ranks_per_run = 1
replicates = 2
[fixed]
t_end = 1.0
[grid]
amp_n = [5e-5, 1e-4]
phase = [0.0, 90.0]
"""


def spec_of(text: str, tmp_path=None):
    path = (tmp_path / "s.toml") if tmp_path is not None else "s.toml"
    return parse(text, path)


def refused(text: str, exc=InputError, planned=False) -> str:
    with pytest.raises(exc) as info:
        spec = parse(text, "s.toml")
        if planned:
            P.plan(spec)
    return str(info.value)


# ------------------------------------------------------------------ expansion
def test_the_issue_form_expands_to_grid_times_replicates_with_distinct_seeds():
    spec = spec_of(ISSUE)
    jobs = P.plan(spec)
    assert len(jobs) == 2 * 2 * 2
    # first axis slowest, replicates innermost
    assert [(j.setting["amp_n"], j.setting["phase"], j.replicate) for j in jobs[:4]] == \
        [(5e-5, 0.0, 0), (5e-5, 0.0, 1), (5e-5, 90.0, 0), (5e-5, 90.0, 1)]
    default = int(P.find_deck(spec).tunables["seed"].default)
    assert [j.seed for j in jobs] == [default, default + 1] * 4
    assert all(j.params["t_end"] == "1.0" and j.values["t_end"] == "1.0" for j in jobs)
    assert jobs[0].params["amp_n"] == "5e-05"  # shortest exact repr of the TOML float
    # every job is another run: distinct run ids, and distinct files
    assert len({j.run_id for j in jobs}) == 8 and len({j.file for j in jobs}) == 8
    assert jobs[3].file == "jobs/job-0003.h5"


def test_zip_groups_vary_together_and_points_are_one_axis():
    spec = spec_of("""
deck = "bulk_feeder"
[fixed]
seed = 11
[grid]
phase = [0, 90, 180]
[zip.stroke]
freq = [50, 100]
amp_t = [2e-4, 5e-5]
[[point]]
gate_width = 0
[[point]]
gate_width = 4.5e-4
fill_to = 0.68
""")
    assert [a.kind for a in spec.axes] == ["grid", "zip", "point"]
    assert spec.varied == ["phase", "freq", "amp_t", "gate_width", "fill_to"]
    jobs = P.plan(spec)
    assert len(jobs) == 3 * 2 * 2
    pairs = {(j.setting["freq"], j.setting["amp_t"]) for j in jobs}
    assert pairs == {(50, 2e-4), (100, 5e-5)}  # zipped, never crossed
    assert {j.seed for j in jobs} == {11}
    # a point that does not name a parameter runs it at the deck's default
    first = next(j for j in jobs if j.setting["gate_width"] == 0)
    assert "fill_to" not in first.setting and first.values["fill_to"] == "0.9"
    assert [j.setting.get("fill_to") for j in jobs[:2]] == [None, 0.68]


def test_a_varied_seed_without_replicates_and_no_axes_at_all():
    jobs = P.plan(spec_of('deck = "single_part"\n[grid]\nseed = [3, 7]\n'))
    assert [j.seed for j in jobs] == [3, 7] and [j.params["seed"] for j in jobs] == ["3", "7"]
    (only,) = P.plan(spec_of('deck = "single_part"\n[fixed]\nt_end = 0.1\n'))
    assert only.setting == {"t_end": 0.1} and only.index == 0


def test_dispatch_is_longest_expected_first():
    spec = spec_of('deck = "bulk_feeder"\n[grid]\nt_end = [0.5, 2.0, 1.0]\nn_parts = [100, 300]\n')
    jobs = P.plan(spec)
    order = P.dispatch_order(jobs)
    costs = [j.cost for j in order]
    assert costs == sorted(costs, reverse=True)
    assert (order[0].setting["t_end"], order[0].setting["n_parts"]) == (2.0, 300)
    # cost = t_end x parts (module docstring); inlet parts count, a given timestep divides
    assert P.cost({"t_end": "2", "n_parts": "300"}) == pytest.approx(600)
    assert P.cost({"t_end": "2", "n_parts": "0", "inlet_rate": "100"}) == pytest.approx(400)
    assert P.cost({"t_end": "1", "dt": "1e-6"}) == pytest.approx(1e6, rel=1e-12)


# ------------------------------------------------------------------ refusals, with lines
@pytest.mark.parametrize("text, line, words", [
    ('deck = "bulk_feeder"\nreplicate = 2\n', 2, "unknown key replicate"),
    ('deck = "bulk_feeder"\n[grid]\namp_n = [1e-5, 2e-5]\n[grids]\nx = [1]\n', 4, "unknown key grids"),
    ('deck = "bulk_feeder"\n[fixed]\nt_end = [1, 2]\n', 3, "one number or string"),
    ('deck = "bulk_feeder"\n[fixed]\nt_end = 1\n[grid]\n\nt_end = [1, 2]\n', 6, "set twice"),
    ('deck = "bulk_feeder"\n[grid]\namp_n = []\n', 3, "non-empty list"),
    ('deck = "bulk_feeder"\n[grid]\namp_n = [1e-5, 1e-5]\n', 3, "lists a value twice"),
    ('deck = "bulk_feeder"\n[grid]\nmu = [true, false]\n', 3, "not a number or a string"),
    ('deck = "bulk_feeder"\n[zip.s]\nfreq = [50, 100]\n# note\namp_t = [1e-4]\n', 5, "equal lengths"),
    ('deck = "bulk_feeder"\n[grid]\nphase = [0]\n[[point]]\nmu = 0.3\n[[point]]\nphase = 9\n', 7,
     "set twice"),
    ('deck = "bulk_feeder"\nreplicates = 3\n[grid]\nseed = [1, 2]\n', 4, "replicates set the seeds"),
    ('deck = "bulk_feeder"\nreplicates = 0\n', 2, "replicates must be a whole number >= 1"),
    ('deck = "bulk_feeder"\nranks_per_run = 1.5\n', 2, "ranks_per_run must be"),
    # sections of the wrong kind
    ('deck = "bulk_feeder"\nfixed = 1\n', 2, "fixed must be a table [fixed]"),
    ('deck = "bulk_feeder"\ngrid = [1, 2]\n', 2, "grid must be a table [grid]"),
    ('deck = "bulk_feeder"\nzip = "s"\n', 2, "zip must be a table [zip]"),
    ('deck = "bulk_feeder"\npoint = 1\n', 2, "point must be [[point]] tables"),
    ('deck = "bulk_feeder"\n[point]\nmu = 0.3\n', 2, "point must be [[point]] tables"),
    ('deck = "bulk_feeder"\n[zip.s]\n', 2, "zip.s must be a table of lists"),       # an empty group
    ('deck = "bulk_feeder"\n[zip]\ns = 5\n', 3, "zip.s must be a table of lists"),  # not a table
    ('deck = "  "\n', 1, "deck must be a deck name or a file name"),
    ("deck = 5\n", 1, "deck must be a deck name or a file name"),
    # two replicates already set the seeds: a varied seed is refused from two on
    ('deck = "bulk_feeder"\nreplicates = 2\n[grid]\nseed = [1, 2]\n', 4, "replicates set the seeds"),
])
def test_structural_problems_are_refused_naming_the_line(text, line, words):
    message = refused(text)
    assert message.startswith(f"s.toml:{line}: "), message
    assert words in message, message


def test_invalid_toml_keeps_tomllibs_position_and_a_missing_deck_is_named():
    assert "line 2" in refused('deck = "bulk_feeder"\n[grid\n')
    assert "no deck" in refused("[grid]\nphase = [0]\n")


@pytest.mark.parametrize("text, line, words", [
    # an unknown parameter, with the deck's list and a close match
    ('deck = "bulk_feeder"\n[fixed]\nt_end = 0.5\n[grid]\namp_nn = [1e-5, 2e-5]\n', 5,
     "unknown parameter amp_nn for deck bulk_feeder (did you mean amp_n?)"),
    ('deck = "bulk_feeder"\n[[point]]\nmu = 0.3\n[[point]]\nmu = 0.4\nbogus = 1\n', 6,
     "unknown parameter bogus"),
    ('deck = "bulk_feeder"\n[fixed]\ndeck_dir = "x"\n', 3, "set by vibrofeed itself"),
    # a value the deck's checks refuse, in a list spread over lines: the key's line
    ('deck = "bulk_feeder"\n[grid]\nphase = [0, 90]\namp_n = [\n  5e-5,\n  0.5,\n]\n', 4,
     "job 1 (phase=0 amp_n=0.5): parameter amp_n=0.5 m must be in [0, 0.01]"),
    # a relation between a fixed and a varied value: the varied one is named first
    ('deck = "bulk_feeder"\n[fixed]\nt_end = 0.01\n[grid]\noutput_dt = [0.001, 0.1]\n', 5,
     "output_dt=0.1 s is longer than the run"),
    ('deck = "bulk_feeder"\n[zip.a]\nfreq = [100, 200]\namp_n = [1e-4, 5e-3]\n', 4,
     "moves the surface at"),
    ('deck = "single_part"\nreplicates = 2\n[fixed]\nseed = "x"\n', 4, "seed"),
    ('deck = "no_such_deck"\n', 1, "no deck no_such_deck"),
])
def test_parameters_are_checked_as_vibrofeed_run_checks_them_naming_the_line(text, line, words):
    message = refused(text, exc=InputError, planned=True)
    assert message.startswith(f"s.toml:{line}: "), message
    assert words in message, message


def test_every_invalid_job_is_counted_and_the_rank_count_is_checked(monkeypatch):
    message = refused('deck = "single_part"\n[grid]\nrestitution = [0.01, 0.02, 0.5]\n',
                      ParameterError, planned=True)
    assert "(2 of 3 jobs are invalid)" in message
    monkeypatch.setenv("VIBROFEED_MAX_RANKS", "4")
    message = refused('deck = "single_part"\nranks_per_run = 5\n', UsageError, planned=True)
    assert message.startswith("s.toml:2: ranks_per_run:") and "at most 4" in message


def test_a_deck_file_is_found_next_to_the_sweep_file(tmp_path):
    from helpers import DECKS

    (tmp_path / "decks").mkdir()
    deck = tmp_path / "decks" / "mine.liggghts"
    deck.write_text((DECKS / "single_part.liggghts").read_text().replace("${deck_dir}/include",
                                                                        str(DECKS / "include")))
    spec = parse('deck = "decks/mine.liggghts"\n', tmp_path / "s.toml")
    assert P.find_deck(spec).path == deck


# ------------------------------------------------------------------ line finder, fingerprint
def test_key_lines_follow_tables_arrays_of_tables_and_multiline_values():
    text = """# comment
deck = "x"            # 2
[grid]                # 3
a = [1,               # 4
  2, [3, 4],
]
"b" = ['x = 1']       # 7
[zip.s]               # 8
c = [1]               # 9
[[point]]             # 10
d = 1                 # 11
[[point]]             # 12
d = 2                 # 13
e = \"\"\"
f = 1
\"\"\"
[ fixed ]             # 17
g.h = 2               # 18
"""
    lines = key_lines(text)
    assert lines[("deck",)] == 2 and lines[("grid",)] == 3 and lines[("grid", "a")] == 4
    assert lines[("grid", "b")] == 7 and lines[("zip", "s")] == 8 and lines[("zip", "s", "c")] == 9
    assert lines[("point", 0)] == 10 and lines[("point", 0, "d")] == 11
    assert lines[("point", 1, "d")] == 13 and lines[("point", 1, "e")] == 14
    assert ("point", 1, "f") not in lines  # inside a multi-line string
    assert lines[("fixed",)] == 17 and lines[("fixed", "g", "h")] == 18


def test_the_fingerprint_is_of_the_content_not_the_layout():
    a = parse(ISSUE, "a.toml")
    relaid = """# the same sweep, laid out otherwise
replicates = 2
deck="bulk_feeder"
ranks_per_run = 1
[grid]
phase = [ 0.0,
  90.0 ]   # degrees
amp_n = [5e-5, 1e-4]
[fixed]
t_end = 1.0
"""
    b = parse(relaid, "b.toml")
    assert b.data == a.data and b.fingerprint == a.fingerprint
    c = parse(ISSUE.replace("1e-4", "2e-4"), "c.toml")
    assert c.fingerprint != a.fingerprint
    assert a.fingerprint == fingerprint(a.data) and len(a.fingerprint) == 64


# ------------------------------------------------------------------ the summary
def rows_for(jobs, parameters, status=S.DONE, **metrics):
    from vibrofeed.sweep.execute import base_row

    out = []
    for j in jobs:
        row = base_row(j, parameters)
        row.update(status=status, file=j.file, wall_s=1.5 + j.index, **metrics)
        out.append(row)
    return out


def test_summary_rows_round_trip_through_hdf5_and_csv(tmp_path):
    spec = spec_of(ISSUE)
    jobs = P.plan(spec)
    params = [p for p in spec.parameters if p != "seed"]
    rows = rows_for(jobs[:3], params, parts_per_s=346.7, cv_interarrival=math.nan, n_events=288)
    rows[1].update(status=S.FAILED, error="LIGGGHTS error: boom, with a comma", file="",
                   parts_per_s=None, n_events=None)
    S.write(tmp_path, list(reversed(rows)), params, {"fingerprint": spec.fingerprint, "n_jobs": 8})
    back, meta = S.read(tmp_path)
    assert [r["job"] for r in back] == [0, 1, 2]  # sorted by job
    assert meta["fingerprint"] == spec.fingerprint and meta["n_jobs"] == 8
    assert meta["columns"][:3] == ["job", "replicate", "seed"] and meta["parameters"] == params
    assert meta["metrics"] == ["parts_per_s", "cv_interarrival", "n_events"]
    expected = [{k: (None if isinstance(v, float) and math.isnan(v) else v or None if k == "error"
                     else v) for k, v in r.items()} for r in rows]
    expected[1]["file"] = None
    assert back == expected
    assert back[0]["amp_n"] == 5e-5 and back[0]["phase"] == 0.0 and back[0]["seed"] == jobs[0].seed
    with open(tmp_path / S.CSV_NAME, newline="") as f:
        table = list(csv.DictReader(f))
    assert [int(r["job"]) for r in table] == [0, 1, 2]
    assert table[1]["error"] == "LIGGGHTS error: boom, with a comma" and table[1]["parts_per_s"] == ""
    assert float(table[0]["parts_per_s"]) == 346.7 and table[0]["cv_interarrival"] == ""
    assert float(table[2]["wall_s"]) == rows[2]["wall_s"]
    # only the two files: no temporary file left behind
    assert sorted(p.name for p in tmp_path.iterdir()) == [S.CSV_NAME, S.H5_NAME]


def test_an_interrupted_summary_write_leaves_the_previous_summary(tmp_path, monkeypatch):
    spec = spec_of(ISSUE)
    jobs = P.plan(spec)
    S.write(tmp_path, rows_for(jobs[:1], []), [], {})
    before = (tmp_path / S.H5_NAME).read_bytes()

    def fail(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(OSError):
        S.write(tmp_path, rows_for(jobs[:2], []), [], {})
    assert (tmp_path / S.H5_NAME).read_bytes() == before
    assert len(S.read(tmp_path)[0]) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == [S.CSV_NAME, S.H5_NAME]


def test_a_folder_without_summary_reads_empty(tmp_path):
    assert S.read(tmp_path) == ([], {})


# ------------------------------------------------------------------ resume
def test_resume_keeps_true_rows_and_reruns_the_rest():
    spec = spec_of(ISSUE)
    jobs = P.plan(spec)
    rows = rows_for(jobs[:6], [])
    rows[1]["status"] = S.FAILED
    rows[2]["run_id"] = "0" * 64  # an older deck or vibrofeed: another run
    rows[3]["status"] = S.FAILED
    rows[3]["run_id"] = "1" * 64
    good = {0, 4}  # job 5's file does not check
    kept, todo = F.resume(jobs, rows, False, lambda j: j.index in good)
    assert [r["job"] for r in kept] == [0, 1, 4]
    assert [j.index for j in todo] == [2, 3, 5, 6, 7]
    kept, todo = F.resume(jobs, rows, True, lambda j: j.index in good)
    assert [r["job"] for r in kept] == [0, 4]
    assert [j.index for j in todo] == [1, 2, 3, 5, 6, 7]


def test_a_result_counts_as_done_only_complete_and_with_the_jobs_run_id(tmp_path):
    spec = spec_of(ISSUE)
    job = P.plan(spec)[0]
    job.file = "jobs/a.h5"
    (tmp_path / "jobs").mkdir()
    path = tmp_path / job.file
    frames = [(k, 0.01 * k, parts([1], [[0, 0, 5e-4]])) for k in range(3)]
    assert not F.result_is_true(tmp_path, job)  # absent
    write_result(path, frames, status=None)  # a run that did not complete
    job.run_id = hashlib.sha256(str(path).encode()).hexdigest()  # the id write_result gives
    assert not F.result_is_true(tmp_path, job)
    write_result(path, frames)
    assert F.result_is_true(tmp_path, job)
    job.run_id = "0" * 64
    assert not F.result_is_true(tmp_path, job)  # complete, but of another run
    path.write_bytes(b"not hdf5")
    assert not F.result_is_true(tmp_path, job)


def test_a_folder_of_another_sweep_or_of_other_files_is_refused(tmp_path):
    spec = spec_of(ISSUE, tmp_path)
    jobs = P.plan(spec)
    folder = tmp_path / "out"
    assert F.check_folder(folder, spec) is False  # new
    folder.mkdir()
    F.write_manifest(folder, spec, jobs, "bulk_feeder.liggghts")
    assert F.check_folder(folder, spec) is True
    changed = parse(ISSUE.replace("replicates = 2", "replicates = 3"), tmp_path / "s.toml")
    with pytest.raises(UsageError, match=r"holds another sweep .* differs in replicates\)"):
        F.check_folder(folder, changed)
    other = tmp_path / "other"
    (other / "jobs").mkdir(parents=True)
    with pytest.raises(UsageError, match="no sweep.json"):
        F.check_folder(other, spec)
    lock = F.lock(folder)
    try:
        import subprocess
        import sys

        code = ("import sys; from pathlib import Path; from vibrofeed.sweep.folder import lock\n"
                f"try:\n    lock(Path({str(folder)!r}))\nexcept Exception as e:\n    print(e)")
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout
        assert "another vibrofeed sweep is running" in out
    finally:
        os.close(lock)


def test_the_dry_run_table_lists_every_job_with_its_state():
    spec = spec_of(ISSUE)
    jobs = P.plan(spec)
    text = describe(jobs, spec, {0: S.DONE, 3: S.FAILED})
    lines = text.splitlines()
    assert lines[0].split() == ["job", "rep", "seed", "amp_n", "phase", "cost", "state"]
    assert len(lines) == 9
    assert lines[1].split()[-1] == "done" and lines[4].split()[-1] == "failed"
    assert lines[2].endswith("to run")


# ------------------------------------------------------------------ report
def test_settings_average_replicates_with_their_standard_error():
    rows = [
        {"job": 0, "status": S.DONE, "a": 1.0, "parts_per_s": 100.0, "parts_per_s_err": 9.0},
        {"job": 1, "status": S.DONE, "a": 1.0, "parts_per_s": 110.0, "parts_per_s_err": 9.0},
        {"job": 2, "status": S.DONE, "a": 1.0, "parts_per_s": 120.0, "parts_per_s_err": 9.0},
        {"job": 3, "status": S.DONE, "a": 2.0, "parts_per_s": 50.0, "parts_per_s_err": 4.0},
        {"job": 4, "status": S.FAILED, "a": 2.0, "parts_per_s": None, "parts_per_s_err": None},
    ]
    one, two = R.settings(rows, ["a"], "parts_per_s")
    assert (one["done"], one["runs"], two["done"], two["runs"]) == (3, 3, 1, 2)
    assert one["merit"] == pytest.approx(110.0, rel=1e-12)
    assert one["merit_err"] == pytest.approx(np.std([100, 110, 120], ddof=1) / math.sqrt(3), rel=1e-12)
    assert (two["merit"], two["merit_err"]) == (50.0, 4.0)  # one run: its own batch-means error


def _entry(a, rate, err, singulated):
    return {"parameters": {"a": a}, "merit": rate, "merit_err": err, "singulated_fraction": singulated}


def test_the_best_setting_is_the_highest_feed_rate_ties_broken_by_singulation():
    entries = [_entry(1, 100.0, 5.0, 0.1), _entry(2, 95.0, 3.0, 0.6), _entry(3, 80.0, 2.0, 0.9)]
    # 100 - 95 = 5 <= hypot(5, 3): a tie within one standard error -> the better singulation
    assert R.best(entries)["parameters"] == {"a": 2}
    entries[1]["merit"] = 90.0  # 10 > hypot(5, 3): no longer a tie
    assert R.best(entries)["parameters"] == {"a": 1}
    no_singulation = [_entry(1, 1.0, 0.5, None), _entry(2, 1.2, 0.5, None)]
    assert R.best(no_singulation)["parameters"] == {"a": 2}
    assert R.best([_entry(1, None, None, None)]) is None


# ------------------------------------------------------------------ local execution, with a fake runner
def test_local_workers_take_the_longest_jobs_first_and_the_summary_follows_every_job(tmp_path):
    import threading

    from vibrofeed.sweep.execute import Recorder, run_local
    from vibrofeed.sweep.progress import SweepProgress

    spec = spec_of('deck = "bulk_feeder"\n[grid]\nt_end = [0.5, 2.0, 1.0, 1.5]\n')
    jobs = P.plan(spec)
    started, seen_rows = [], []
    gate = threading.Lock()

    def fake(job):
        with gate:
            started.append(job.setting["t_end"])
        row = rows_for([job], ["t_end"])[0]
        if job.setting["t_end"] == 1.0:
            row.update(status=S.FAILED, error="LIGGGHTS error: boom")
        return row, True

    progress = SweepProgress(jobs, 2, enabled=False)
    recorder = Recorder(tmp_path, [], ["t_end"], {"n_jobs": 4}, progress)
    assert S.read(tmp_path)[0] == []  # the summary exists, empty, before the first job ends
    original = recorder.add

    def add(job, row, computed):
        original(job, row, computed)
        seen_rows.append(len(S.read(tmp_path)[0]))  # written before the next job is recorded

    recorder.add = add
    run_local(jobs, 2, fake, recorder, progress)
    assert started[:2] == [2.0, 1.5] and sorted(started) == [0.5, 1.0, 1.5, 2.0]
    assert seen_rows == [1, 2, 3, 4]
    rows = S.read(tmp_path)[0]
    assert [r["status"] for r in rows] == [S.DONE, S.DONE, S.FAILED, S.DONE]
    assert (progress.done, progress.failed, progress.running) == (3, 1, {})


def test_a_bug_in_a_job_thread_is_raised_not_swallowed(tmp_path):
    from vibrofeed.sweep.execute import Recorder, run_local
    from vibrofeed.sweep.progress import SweepProgress

    jobs = P.plan(spec_of('deck = "bulk_feeder"\n[grid]\nt_end = [0.5, 2.0]\n'))

    def broken(job):
        raise ZeroDivisionError("a bug")

    with pytest.raises(ZeroDivisionError):
        run_local(jobs, 1, broken, Recorder(tmp_path, [], [], {}), SweepProgress(jobs, 1, enabled=False))


def test_the_eta_scales_the_cost_left_by_the_time_per_cost_so_far():
    from vibrofeed.sweep.progress import SweepProgress

    jobs = P.plan(spec_of('deck = "bulk_feeder"\n[grid]\nt_end = [1.0, 2.0, 3.0]\n'))
    p = SweepProgress(jobs, 2, enabled=False)
    assert p.eta() is None
    p.started(jobs[0])
    p.running[jobs[0].index] -= 10.0  # it took 10 s
    p.finished(jobs[0], {"status": S.DONE})
    # cost of job 0: 1.0 x 300 parts; left: (2 + 3) x 300 at the same pace, on 2 workers
    assert p.eta() == pytest.approx(10.0 * 5 / 1 / 2, rel=1e-3)
    p.finished(jobs[1], {"status": S.DONE}, computed=False)  # an earlier result: no time counted
    assert p.eta() == pytest.approx(10.0 * 3 / 1 / 2, rel=1e-3)


def test_report_maps_keep_every_parameter_of_a_zipped_axis():
    """A grid axis x a zipped pair: the map holds every setting (the zipped partner varies with
    its axis, it is not held at the best setting's value), and a third axis is held there."""
    from vibrofeed.sweep import report as R

    entries = []
    for fill in (100, 200, 300):
        for k, gamma in enumerate((0.0, 1e-4, 2e-4, 4e-4, 8e-4)):
            for extra in (1, 2):
                entries.append({"parameters": {"n_parts": fill, "surface_energy": gamma,
                                               "surface_energy_pp": gamma, "phase": extra},
                                "merit": fill - k + extra})
    chosen = entries[-1]
    groups = [["n_parts"], ["surface_energy", "surface_energy_pp"], ["phase"]]
    axes, part = R.plotted(entries, groups, chosen)
    assert axes == ["n_parts", "surface_energy"]
    assert len(part) == 15 and {e["parameters"]["phase"] for e in part} == {2}
    assert {(e["parameters"]["n_parts"], e["parameters"]["surface_energy"]) for e in part} == {
        (f, g) for f in (100, 200, 300) for g in (0.0, 1e-4, 2e-4, 4e-4, 8e-4)}


# ------------------------------------------------------------------ reading the file
def test_a_sweep_file_that_is_not_utf8_is_refused_naming_the_file(tmp_path):
    from vibrofeed.sweep.spec import load

    path = tmp_path / "latin.toml"
    text = 'deck = "bulk_feeder"\ndescription = "débit"\n'
    path.write_bytes(text.encode("latin-1"))  # é is the one byte 0xe9, not UTF-8
    with pytest.raises(InputError) as info:
        load(path)
    message = str(info.value)
    # the file, then why: the byte and where (21 + 16 bytes precede the é), on one line
    assert message.startswith(f"cannot read sweep file {path}: "), message
    assert "can't decode byte 0xe9 in position 37" in message and "\n" not in message
    assert info.value.__cause__ is None and info.value.__suppress_context__  # no traceback chained
    path.write_text(text, encoding="utf-8")
    assert load(path).description == "débit"


def test_a_sweep_file_that_cannot_be_read_is_refused_naming_the_file_and_why(tmp_path):
    from vibrofeed.sweep.spec import load

    for path, why in ((tmp_path / "none.toml", "No such file or directory"), (tmp_path, "Is a directory")):
        with pytest.raises(InputError) as info:
            load(path)
        assert str(info.value) == f"cannot read sweep file {path}: {why}"


# ------------------------------------------------------------------ deep key paths
@pytest.mark.parametrize("text, line, words", [
    # a nested table's key: its full dotted path, its own line (not its table's)
    ('deck = "bulk_feeder"\n[zip.stroke]\nfreq = [50, 100]\namp_t = []\n', 4,
     "zip.stroke.amp_t must be a non-empty list of values, got []"),
    ('deck = "bulk_feeder"\n[zip.stroke]\nfreq = [50, 100]\n\namp_t = [1e-4, 1e-4]\n', 5,
     "zip.stroke.amp_t lists a value twice"),
    ('deck = "bulk_feeder"\n[zip.stroke]\nfreq = [50, 100]\namp_t = [1e-4, true]\n', 4,
     "zip.stroke.amp_t: true is not a number or a string"),
    ('deck = "bulk_feeder"\n[zip]\nstroke.freq = [50, 100]\nstroke.amp_t = [1e-4]\n', 4,
     "zip.stroke: amp_t has 1 values, the lists before it 2"),
    ('deck = "bulk_feeder"\nzip.stroke.freq = [50, 50]\n', 2, "zip.stroke.freq lists a value twice"),
    # a quoted part holding a dot, spaces around the dots (TOML ignores them)
    ('deck = "bulk_feeder"\n[zip."s.1"]\nfreq = [50, 100]\namp_t = [1e-4]\n', 4,
     "zip.s.1: amp_t has 1 values"),
    ('deck = "bulk_feeder"\n[ zip . "s.1" ]\nfreq = [50, 100]\namp_t = [1e-4]\n', 4,
     "zip.s.1: amp_t has 1 values"),
    # a dotted key is one dotted name (a feeder description's): the line of the dotted key
    ('deck = "bulk_feeder"\n[fixed]\nt_end = 1\ng.h = [2]\n', 4, "[fixed] g.h must be one number or string"),
    ('deck = "bulk_feeder"\n[grid]\nphase = [0, 90]\nx.y = 1\n', 4, "x.y must be a non-empty list of values"),
    ('deck = "bulk_feeder"\n[[point]]\nmu = 0.3\n[[point]]\nphase = 0\nx.y = [1]\n', 6,
     "[[point]] x.y must be one number or string"),
    ('deck = "bulk_feeder"\n\nfoo.bar = 1\n', 3, "unknown key foo"),
    # inline tables: no line of their own keys, so the line of the key holding the table
    ('deck = "bulk_feeder"\n[zip]\n\ns = { freq = [50, 50] }\n', 4, "zip.s.freq lists a value twice"),
    ('deck = "bulk_feeder"\n\npoint = [{ mu = 0.3 }, { mu = [1, 2] }]\n', 3,
     "[[point]] mu must be one number or string, got [1, 2]"),
    # the second [[point]] table's key, not the first one's
    ('deck = "bulk_feeder"\n[[point]]\nmu = 0.3\n[[point]]\nphase = 0\nmu = [1, 2]\n', 6,
     "[[point]] mu must be one number or string, got [1, 2]"),
])
def test_a_nested_key_is_named_by_its_full_path_and_its_own_line(text, line, words):
    message = refused(text)
    assert message.startswith(f"s.toml:{line}: "), message
    assert words in message, message


@pytest.mark.parametrize("text, line, words", [
    ('deck = "bulk_feeder"\n[[point]]\nmu = 0.3\n[[point]]\nmu = 0.4\nfill_to = 1.5\n', 6,
     "job 1 (mu=0.4 fill_to=1.5): parameter fill_to=1.5 must be in [0, 1]"),
    ('deck = "bulk_feeder"\n[zip.stroke]\nfreq = [100, 200]\n\namp_n = [1e-4, 2e-2]\n', 5,
     "job 1 (freq=200 amp_n=0.02): parameter amp_n=0.02 m must be in [0, 0.01]"),
])
def test_a_job_refused_by_the_deck_names_the_deep_key_that_set_the_value(text, line, words):
    message = refused(text, exc=ParameterError, planned=True)
    assert message.startswith(f"s.toml:{line}: "), message
    assert words in message, message


def test_a_key_path_is_placed_on_its_own_line_else_on_the_nearest_one_above_it():
    text = ('deck = "bulk_feeder"\n'       # 1
            '[fixed]\n'                    # 2
            't_end = 0.5\n'                # 3
            '[zip.stroke]\n'               # 4
            'freq = [50, 100]\n'           # 5
            'amp_t = [\n'                  # 6
            '  2e-4,\n'
            '  5e-5,\n'
            ']\n'
            '[[point]]\n'                  # 10
            'mu = 0.3\n'                   # 11
            '[[point]]\n'                  # 12
            'mu = 0.4\n'                   # 13
            'fill_to = 0.5\n')             # 14
    spec = spec_of(text)
    assert spec.line_of("zip", "stroke", "amp_t") == 6
    assert spec.line_of("zip", "stroke", "amp_t", 1) == 6   # a value of the list: the list's line
    assert spec.line_of("zip", "stroke", "nothing") == 4    # not in the file: its table's line
    assert spec.line_of("point", 1, "fill_to") == 14 and spec.line_of("point", 0, "mu") == 11
    assert spec.line_of("point", 1, "mu") == 13 and spec.line_of("point", 1) == 12
    assert spec.line_of("fixed", "t_end") == 3
    assert spec.line_of("nowhere", "at", "all") is None and spec.line_of() is None
    assert spec.where("zip", "stroke", "amp_t") == "s.toml:6" and spec.where("nowhere") == "s.toml"
    # where each parameter is set: a zipped one under its group, a point's at its first point
    assert spec.place("amp_t") == ("zip", "stroke", "amp_t") and spec.place("t_end") == ("fixed", "t_end")
    assert spec.place("fill_to") == ("point", 1, "fill_to") and spec.place("mu") == ("point", 0, "mu")
    assert spec.place("unknown") == ()


def test_key_lines_split_dotted_paths_as_toml_does():
    text = ('[ a . "b.c" ]\n'       # 1
            "x . 'y.z' = 1\n"       # 2
            '"q r".s = 2\n')        # 3
    lines = key_lines(text)
    assert lines[("a", "b.c")] == 1 and lines[("a", "b.c", "x", "y.z")] == 2
    assert lines[("a", "b.c", "q r", "s")] == 3
    # the tables a dotted key makes are on its line
    assert lines[("a", "b.c", "x")] == 2 and lines[("a", "b.c", "q r")] == 3


# ------------------------------------------------------------------ replicates and their seeds
def test_each_replicate_runs_the_base_seed_plus_its_number():
    spec = spec_of('deck = "bulk_feeder"\nreplicates = 3\n[fixed]\nseed = 40\n[grid]\namp_n = [5e-5, 1e-4]\n')
    jobs = P.plan(spec)
    assert [(j.index, j.replicate, j.seed) for j in jobs] == [
        (0, 0, 40), (1, 1, 41), (2, 2, 42), (3, 0, 40), (4, 1, 41), (5, 2, 42)]
    for j in jobs:
        # the run is given that seed, checked as vibrofeed run checks it
        assert j.params["seed"] == j.values["seed"] == str(40 + j.replicate)
        assert j.label(spec.varied) == f"amp_n={j.setting['amp_n']} seed={40 + j.replicate}"
    for setting in (jobs[:3], jobs[3:]):
        assert len({j.seed for j in setting}) == 3          # replicates differ by their seed alone
        assert len({j.run_id for j in setting}) == 3 and len({j.file for j in setting}) == 3
        assert {j.setting["amp_n"] for j in setting} == {setting[0].setting["amp_n"]}


def test_the_base_seed_is_the_decks_default_a_whole_float_or_the_only_replicate():
    default = int(P.find_deck(spec_of('deck = "bulk_feeder"\n')).tunables["seed"].default)
    jobs = P.plan(spec_of('deck = "bulk_feeder"\nreplicates = 2\n'))
    assert [j.seed for j in jobs] == [default, default + 1]
    jobs = P.plan(spec_of('deck = "bulk_feeder"\nreplicates = 2\n[fixed]\nseed = 7.0\n'))
    assert [(j.seed, j.params["seed"]) for j in jobs] == [(7, "7"), (8, "8")]
    (only,) = P.plan(spec_of('deck = "bulk_feeder"\n[fixed]\nseed = 9\n'))
    assert (only.replicate, only.seed, only.params["seed"]) == (0, 9, "9")


def test_a_seed_that_is_not_a_whole_number_is_refused_not_truncated():
    # vibrofeed run -p seed=7.5 refuses it: a sweep must not run seeds 7 and 8 instead
    message = refused('deck = "bulk_feeder"\nreplicates = 2\n[fixed]\nseed = 7.5\n', ParameterError,
                      planned=True)
    assert message.startswith("s.toml:4: job 0: parameter seed=7.5 must be an integer"), message
    assert "(2 of 2 jobs are invalid)" in message


# ------------------------------------------------------------------ expected cost
@pytest.mark.parametrize("values, want", [
    ({}, 1.0),                                                  # one part for one second
    ({"t_end": "2", "n_parts": "3"}, 6.0),
    ({"t_end": "abc", "n_parts": "3"}, 3.0),                   # not a number: the default 1 s
    ({"t_end": "inf", "n_parts": "3"}, 3.0),                   # not finite: the default
    ({"t_end": "nan", "n_parts": "3"}, 3.0),
    ({"t_end": "2", "n_parts": "many"}, 2.0),                  # the default: one part
    ({"t_end": "2", "n_parts": "0"}, 2.0),                     # at least one part
    ({"t_end": "2", "n_parts": "0.5"}, 2.0),
    ({"t_end": "2", "n_parts": "1.5"}, 3.0),
    ({"t_end": "2", "n_parts": "3", "inlet_rate": "fast"}, 6.0),   # the default: no inlet
    ({"t_end": "2", "n_parts": "3", "inlet_rate": "10"}, 46.0),    # 3 + 10/s x 2 s parts
    ({"t_end": "2", "inlet_rate": "10"}, 42.0),                # no n_parts: one, and the inlet's 20
    ({"t_end": "2", "n_parts": "3", "dt": "fine"}, 6.0),       # no timestep given: not divided
    ({"t_end": "2", "n_parts": "3", "dt": "0"}, 6.0),
    ({"t_end": "2", "n_parts": "3", "dt": "-1e-6"}, 6.0),
    ({"t_end": "2", "n_parts": "3", "dt": "inf"}, 6.0),
    ({"t_end": "2", "n_parts": "3", "dt": "0.5"}, 12.0),
])
def test_the_expected_cost_takes_the_default_of_a_value_that_is_not_a_number(values, want):
    assert P.cost(values) == pytest.approx(want, rel=1e-12)


# ------------------------------------------------------------------ another sweep in the folder
FIXED = {f"p{k}": 1.0 for k in range(9)}


def _edited(n):
    """The fixed values of a sweep file, the first ``n`` of them (p0, p1...) edited."""
    fixed = {k: (2.0 if i < n else v) for i, (k, v) in enumerate(FIXED.items())}
    return {"deck": "bulk_feeder", "fixed": fixed}


@pytest.mark.parametrize("n, words", [
    (0, "its content"),
    (1, "fixed.p0"),
    (5, "fixed.p0, fixed.p1, fixed.p2, fixed.p3, fixed.p4"),
    (6, "fixed.p0, fixed.p1, fixed.p2, fixed.p3, fixed.p4, fixed.p5"),             # six: all named
    (7, "fixed.p0, fixed.p1, fixed.p2, fixed.p3, fixed.p4, fixed.p5 and 1 more"),  # the seventh counted
    (9, "fixed.p0, fixed.p1, fixed.p2, fixed.p3, fixed.p4, fixed.p5 and 3 more"),
])
def test_the_change_names_up_to_six_keys_and_counts_the_rest(n, words):
    from vibrofeed.sweep.spec import describe_change

    assert describe_change(_edited(0), _edited(n)) == words


def test_the_change_names_added_removed_nested_and_retyped_keys():
    from vibrofeed.sweep.spec import describe_change

    old = {"deck": "bulk_feeder", "replicates": 2, "fixed": {"t_end": 1}, "zip": {"s": {"freq": [50, 100]}},
           "point": [{"mu": 0.3}]}
    new = {"deck": "bulk_feeder", "fixed": {"t_end": 1.0, "seed": 3}, "zip": {"s": {"freq": [50, 200]}},
           "point": [{"mu": 0.3}, {"mu": 0.4}]}
    # t_end 1 -> 1.0 is another sweep file (another fingerprint): it is named too
    assert describe_change(old, new) == "fixed.seed, fixed.t_end, point, replicates, zip.s.freq"
    assert fingerprint({"fixed": {"t_end": 1}}) != fingerprint({"fixed": {"t_end": 1.0}})


def test_a_folder_of_a_sweep_changed_in_seven_keys_names_six_and_counts_one(tmp_path):
    lines = "".join(f"p{k} = {k}\n" for k in range(9))
    text = 'deck = "single_part"\n[fixed]\n' + lines
    spec = parse(text, tmp_path / "s.toml")
    folder = tmp_path / "out"
    folder.mkdir()
    F.write_manifest(folder, spec, [], "single_part.liggghts")
    edited = parse('deck = "single_part"\n[fixed]\n' + "".join(
        f"p{k} = {k + 100 if k < 7 else k}\n" for k in range(9)), tmp_path / "s.toml")
    with pytest.raises(UsageError) as info:
        F.check_folder(folder, edited)
    assert ("differs in fixed.p0, fixed.p1, fixed.p2, fixed.p3, fixed.p4, fixed.p5 and 1 more); "
            "its results would be mixed") in str(info.value)


# ------------------------------------------------------------------ key lines, exactly
def test_key_lines_skip_every_line_inside_a_multiline_value_and_record_nothing_else():
    # Line 3 reads like a table header and lines 7-8 like keys: all three are inside a
    # value. The "]" and the quotes of line 1's comment close nothing; line 5's two
    # one-line strings leave no string open.
    text = ("a = [          # ] a bracket in a comment does not close it\n"  # 1
            "  [1, 2],\n"                                                   # 2
            "  [3, 4]\n"                                                    # 3
            "]\n"                                                           # 4
            'b = ["""x""", """y"""]\n'                                      # 5
            "c = '''\n"                                                     # 6
            "d = 1\n"                                                       # 7
            "e = 2\n"                                                       # 8
            "'''\n"                                                         # 9
            "[t]\n"                                                         # 10
            "f = 3\n")                                                      # 11
    assert key_lines(text) == {("a",): 1, ("b",): 5, ("c",): 6, ("t",): 10, ("t", "f"): 11}


def test_key_lines_of_a_dotted_key_name_its_key_and_its_tables_only():
    # a key path, its dotted prefixes; never the value's words, never the empty path
    assert key_lines('g.h = "x y"\n[p.q]\nr = 1\n') == {("g",): 1, ("g", "h"): 1, ("p",): 2,
                                                        ("p", "q"): 2, ("p", "q", "r"): 3}


# ------------------------------------------------------------------ the top-level keys
def test_defaults_of_an_almost_empty_sweep_file():
    spec = spec_of('deck = " bulk_feeder "\n')
    assert (spec.deck, spec.ranks_per_run, spec.replicates, spec.description) == ("bulk_feeder", 1, 1, "")
    assert spec.target_error is None and spec.fixed == {} and spec.axes == []


@pytest.mark.parametrize("value", ['"0.05"', "0", "0.0", "-0.5", "1", "1.5", "true"])
def test_a_target_error_outside_the_open_unit_interval_or_not_a_number_is_refused(value):
    message = refused(f'deck = "bulk_feeder"\ntarget_error = {value}\n')
    assert message.startswith("s.toml:2: target_error must be a number in (0, 1)"), message


@pytest.mark.parametrize("value", [1e-9, 0.05, 0.999])
def test_a_target_error_inside_the_open_unit_interval_is_kept(value):
    assert spec_of(f'deck = "bulk_feeder"\ntarget_error = {value!r}\n').target_error == value


def test_the_change_ignores_the_key_order_inside_a_point_table():
    from vibrofeed.sweep.spec import describe_change

    # a point's keys as the file gives them (not sorted); sweep.json keeps that order
    text = 'deck = "bulk_feeder"\nreplicates = {}\n[[point]]\nmu = 0.3\nfill_to = 0.5\n'
    old = json.loads(json.dumps(parse(text.format(2), "s.toml").data))
    new = parse(text.format(3), "s.toml").data
    assert list(new["point"][0]) == ["mu", "fill_to"]
    assert describe_change(old, new) == "replicates"


# ------------------------------------------------------------------ plan: seeds, values, file names
def _seedless_deck(tmp_path):
    """single_part without its seed variable (nothing in it is random)."""
    from helpers import DECKS

    text = (DECKS / "single_part.liggghts").read_text()
    kept = [line for line in text.splitlines(keepends=True) if not line.startswith("variable seed ")]
    assert len(kept) == len(text.splitlines()) - 1
    (tmp_path / "noseed.liggghts").write_text("".join(kept).replace("${deck_dir}/include",
                                                                    str(DECKS / "include")))


def test_replicates_of_a_deck_without_a_seed_are_refused_one_run_is_not(tmp_path):
    _seedless_deck(tmp_path)
    for text in ('deck = "noseed.liggghts"\n', 'deck = "noseed.liggghts"\nreplicates = 1\n'):
        (job,) = P.plan(parse(text, tmp_path / "s.toml"))
        assert job.seed is None and "seed" not in job.params
    with pytest.raises(ParameterError) as info:
        P.plan(parse('deck = "noseed.liggghts"\nreplicates = 2\n', tmp_path / "s.toml"))
    assert str(info.value).startswith(f"{tmp_path / 's.toml'}:2: deck noseed has no seed parameter")


def test_one_invalid_job_is_named_without_a_count():
    # restitution must be in (0.05, 1]: job 1 alone is refused
    message = refused('deck = "single_part"\n[grid]\nrestitution = [0.5, 0.01, 0.6]\n',
                      ParameterError, planned=True)
    assert message.startswith("s.toml:3: job 1 (restitution=0.01): parameter restitution=0.01"), message
    assert "jobs are invalid" not in message and message.endswith("coefficientRestitution > 0.05)")


def test_a_value_is_passed_to_the_deck_as_written():
    assert (P.value_text("0.5"), P.value_text(3), P.value_text(5e-5), P.value_text(0.1)) == \
        ("0.5", "3", "5e-05", "0.1")
    (job,) = P.plan(spec_of('deck = "bulk_feeder"\n[fixed]\nt_end = "0.5"\n'))  # a number as a string
    assert job.params["t_end"] == "0.5" and job.values["t_end"] == "0.5"


@pytest.mark.parametrize("replicates, first, last", [
    (10000, "jobs/job-0000.h5", "jobs/job-9999.h5"),     # four digits hold job 9999
    (10001, "jobs/job-00000.h5", "jobs/job-10000.h5"),   # job 10000 needs five: every name gets them
])
def test_job_files_are_numbered_with_as_many_digits_as_the_last_job_needs(monkeypatch, replicates,
                                                                          first, last):
    import vibrofeed.engine.runner as runner

    # checking 10 000 jobs for real takes seconds: the names alone are tested here
    monkeypatch.setattr(P, "resolve", lambda deck, params: dict(params))
    monkeypatch.setattr(runner, "run_id", lambda deck, values, target_error=None: "id")
    jobs = P.plan(spec_of(f'deck = "single_part"\nreplicates = {replicates}\n'))
    assert len(jobs) == replicates and (jobs[0].file, jobs[-1].file) == (first, last)
    assert len({j.file for j in jobs}) == replicates


# ------------------------------------------------------------------ the folder
def test_a_complete_result_without_frames_is_not_a_done_job(tmp_path):
    job = P.plan(spec_of(ISSUE))[0]
    job.file = "jobs/a.h5"
    (tmp_path / "jobs").mkdir()
    path = write_result(tmp_path / job.file, [])
    job.run_id = hashlib.sha256(str(path).encode()).hexdigest()  # the id write_result gives
    assert not F.result_is_true(tmp_path, job)
    write_result(path, [(0, 0.0, parts([1], [[0, 0, 5e-4]]))])
    assert F.result_is_true(tmp_path, job)  # one frame: done


def test_a_sweep_json_that_is_not_json_or_cannot_be_read_is_refused(tmp_path, monkeypatch):
    spec = spec_of(ISSUE, tmp_path)
    (tmp_path / F.SPEC_NAME).write_text('{"fingerprint": ')  # cut short
    with pytest.raises(UsageError, match="sweep.json is not readable; it is not a sweep folder"):
        F.check_folder(tmp_path, spec)
    from pathlib import Path

    def unreadable(self, *args, **kwargs):
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(Path, "read_text", unreadable)  # a disk error (root reads any mode)
    with pytest.raises(UsageError, match="sweep.json is not readable; it is not a sweep folder"):
        F.check_folder(tmp_path, spec)


def test_clear_leftovers_removes_temporary_copies_and_scratch_folders_only(tmp_path):
    (tmp_path / "jobs" / ".vibrofeed-abc").mkdir(parents=True)
    (tmp_path / "jobs" / ".vibrofeed-abc" / "log.lammps").write_text("x")
    (tmp_path / ".summary.h5.x1.tmp").write_text("half")
    (tmp_path / ".sweep.json.x2.tmp").write_text("half")
    kept = [tmp_path / "summary.h5", tmp_path / "jobs" / "job-0000.h5", tmp_path / "jobs" / ".vibrofeed-x.h5",
            tmp_path / "jobs" / "job-0001.h5.part", tmp_path / "jobs" / "job-0001.log.part"]
    for p in kept:
        p.write_text("keep")
    (tmp_path / "jobs" / "job-0002.log.part").write_text("a killed run's, without frames")
    gone = F.clear_leftovers(tmp_path)
    assert sorted(p.name for p in gone) == [".summary.h5.x1.tmp", ".sweep.json.x2.tmp", ".vibrofeed-abc",
                                            "job-0002.log.part"]
    assert not any(p.exists() for p in gone) and all(p.exists() for p in kept)


def test_a_name_the_deck_lacks_is_refused_before_any_job_is_checked():
    deck = P.find_deck(spec_of('deck = "bulk_feeder"\n'))
    message = refused('deck = "bulk_feeder"\n[fixed]\nt_end = 0.5\n[grid]\namp_nn = [1e-5, 2e-5]\n',
                      ParameterError, planned=True)
    # not as a job's error (no "job 0 (...)", no count of invalid jobs): the name, the deck's names
    assert message == ("s.toml:5: unknown parameter amp_nn for deck bulk_feeder (did you mean amp_n?); "
                       f"valid parameters: {', '.join(deck.tunables)}")
    message = refused('deck = "bulk_feeder"\n[fixed]\ndeck_dir = "x"\n', ParameterError, planned=True)
    assert message == "s.toml:3: parameter deck_dir is set by vibrofeed itself, not by a sweep"


def test_a_refused_job_names_the_line_of_the_parameter_its_error_is_about():
    # amp_n comes first in the file and in the alphabet, but the error is about fill_to
    message = refused('deck = "bulk_feeder"\n[grid]\namp_n = [5e-5, 1e-4]\nfill_to = [0.5, 1.5]\n',
                      ParameterError, planned=True)
    assert message.startswith("s.toml:4: job 1 (amp_n=5e-05 fill_to=1.5): parameter fill_to=1.5 "), message


@pytest.mark.parametrize("text, line, words", [
    # the same setting, its keys in another order
    ('deck = "bulk_feeder"\n[[point]]\nmu = 0.3\nfill_to = 0.5\n[[point]]\nfill_to = 0.5\nmu = 0.3\n', 2,
     "two [[point]] tables are the same setting"),
    ('deck = "bulk_feeder"\n[[point]]\n[[point]]\nmu = 0.3\n', 2, "each [[point]] must set at least one"),
    ('deck = "bulk_feeder"\npoint = [1, 2]\n', 2, "each [[point]] must set at least one"),
])
def test_points_that_set_nothing_or_the_same_setting_are_refused(text, line, words):
    message = refused(text)
    assert message.startswith(f"s.toml:{line}: "), message
    assert words in message, message


def test_key_lines_end_a_multiline_string_at_its_closing_quotes_whatever_the_comment_holds():
    text = ("c = '''\n"                                  # 1
            "text\n"                                     # 2
            "''' # closed: ''' and ''' in a comment\n"   # 3: three quotes, the first close it
            "d = 1\n")                                   # 4
    assert key_lines(text) == {("c",): 1, ("d",): 4}


def test_clear_leftovers_neither_follows_nor_trips_on_a_linked_scratch_folder(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "data").write_text("keep")
    (tmp_path / "out" / "jobs").mkdir(parents=True)
    (tmp_path / "out" / "jobs" / ".vibrofeed-link").symlink_to(elsewhere, target_is_directory=True)
    F.clear_leftovers(tmp_path / "out")  # rmtree refuses a link: ignored, never raised
    assert (elsewhere / "data").read_text() == "keep"


def test_the_lock_file_is_readable_by_all_and_executable_by_none(tmp_path):
    old = os.umask(0o022)
    try:
        fd = F.lock(tmp_path)
    finally:
        os.umask(old)
    try:
        assert (tmp_path / F.LOCK_NAME).stat().st_mode & 0o777 == 0o644
    finally:
        os.close(fd)


# ------------------------------------------------------------------ sizes that cannot be done
def test_a_sweep_of_more_jobs_than_it_can_plan_is_refused_before_it_makes_them():
    """replicates = 1000000000 with --dry-run was killed by the kernel at 23 GB: the jobs are
    counted first, and what would fit is said."""
    text = ISSUE.replace("replicates = 2", "replicates = 1000000000")
    message = refused(text, UsageError, planned=True)
    assert message == ("s.toml:3: 4 setting(s) x replicates = 1000000000 make 4,000,000,000 jobs, more "
                       "than a sweep plans: at most 100,000 (each job is checked and kept in memory "
                       "before the first run: 100,000 take about 4 minutes and 0.5 GB); replicates = "
                       "25000 at most, or split the sweep")
    # at the limit it is counted, not refused (the jobs themselves are not made here)
    assert P.check_size(spec_of(ISSUE.replace("replicates = 2", "replicates = 25000"))) == P.MAX_JOBS
    assert "replicates = 25000 at most" in refused(ISSUE.replace("replicates = 2", "replicates = 25001"),
                                                   UsageError, planned=True)
    # a grid too large on its own names its longest list
    grid = ISSUE.replace("replicates = 2", "replicates = 1").replace(
        "phase = [0.0, 90.0]", "phase = [" + ", ".join(str(k) for k in range(400)) + "]\n"
        "freq = [" + ", ".join(str(50 + k) for k in range(200)) + "]")
    assert refused(grid, UsageError, planned=True).startswith(
        "s.toml:8: 2 x 400 x 200 settings make 160,000 jobs, more than a sweep plans")


def test_sweep_minus_j_beyond_the_machine_is_refused_before_anything(tmp_path, monkeypatch):
    from helpers import REPO, vibrofeed

    monkeypatch.setenv("VIBROFEED_MAX_RANKS", "4")
    out = tmp_path / "out"
    proc = vibrofeed("sweep", REPO / "sweeps" / "example.toml", "-o", out, "-j", "1000")
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert proc.stderr.startswith("vibrofeed: error: -j 1000: 1000 runs at once is 1000 ranks, more than "
                                  "this machine can run: at most 4")
    assert not out.exists()
