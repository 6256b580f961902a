"""The runner's decisions that need no engine (vibrofeed/engine/runner.py): the ranks a run may
take, its identity, when a finished file stands in for a rerun, where the output goes, what a
partial file holds, the mass balance, and the error a user reads when the worker stops early.
"""

import hashlib
import json
import math
import os
import signal
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from helpers import parts
from vibrofeed import __version__
from vibrofeed.decks import Deck
from vibrofeed.engine import runner
from vibrofeed.engine.runner import (
    RANKS_PER_CORE,
    RunResult,
    _diagnose,
    _display,
    _frames_in,
    _mass_balance_problem,
    _prepare_output,
    _reusable,
    _unreadable,
    check_at_once,
    check_ranks,
    check_target_error,
    clean_environment,
    max_ranks,
    run_id,
    worker_command,
    worker_environment,
)
from vibrofeed.errors import EngineError, OutputError, RunError, UsageError, said
from vibrofeed.results import layout as L
from vibrofeed.results.writer import ResultWriter

DECK_TEXT = ("variable freq index 50 # [Hz] f\n"   # 1
             "\n"
             "units si\n"                           # 3
             "fix bad all nope ${freq}\n"           # 4
             "run 10\n")                            # 5


def make_deck(folder: Path, text: str = DECK_TEXT, name: str = "d") -> Deck:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.liggghts"
    path.write_text(text)
    return Deck(path)


# -- RunResult ---------------------------------------------------------------------------------
def test_a_run_result_starts_empty_and_not_reused(tmp_path):
    r = RunResult(output=tmp_path / "a.h5", log=tmp_path / "a.log", deck="d", ranks=2)
    assert (r.n_steps, r.dt, r.frames, r.natoms, r.sim_time, r.wall) == (0, 0.0, 0, 0, 0.0, 0.0)
    assert r.reused is False and r.parameters == {} and r.run_id == "" and r.stop_reason == ""
    assert r.target_error is None and r.stopped_early is False


def test_steps_per_second_and_stopped_early():
    r = RunResult(output=Path("a.h5"), log=Path("a.log"), deck="d", ranks=1, n_steps=10, wall=0.5)
    assert r.steps_per_second == pytest.approx(20.0, rel=1e-12)    # 10 steps in half a second
    r.wall = 2.0
    assert r.steps_per_second == pytest.approx(5.0, rel=1e-12)
    r.wall = 0.0  # a reused result took no time: no rate, no division by zero
    assert math.isnan(r.steps_per_second)
    r.stop_reason = "target error 0.05 reached: 0.04 at t = 1 s"
    assert r.stopped_early is True
    r.stop_reason = "t_end (target error 0.05 not reached at t = 1 s: relative error 0.1)"
    assert r.stopped_early is False


# -- ranks -------------------------------------------------------------------------------------
@pytest.fixture
def three_cores(monkeypatch):
    """A machine where this process may use 3 cores (and 5 exist), no limit set, no Slurm."""
    monkeypatch.delenv("VIBROFEED_MAX_RANKS", raising=False)
    monkeypatch.delenv("SLURM_NTASKS", raising=False)

    def affinity(pid):
        assert pid == 0, "this process's own affinity"
        return {0, 2, 4}

    monkeypatch.setattr(runner.os, "sched_getaffinity", affinity, raising=False)
    monkeypatch.setattr(runner.os, "cpu_count", lambda: 5)


def test_the_rank_limit_is_four_per_usable_core(three_cores):
    assert RANKS_PER_CORE == 4
    assert max_ranks() == 12  # the 3 cores of the affinity mask, not the 5 of the machine


def test_runs_at_once_are_held_to_the_rank_limit_as_one_run_is(three_cores):
    """sweep and optimize -j 1000 started a thousand LIGGGHTS processes on a 3-core machine."""
    check_at_once(12, 1)
    check_at_once(6, 2)
    check_at_once(1, 12)
    with pytest.raises(UsageError) as err:
        check_at_once(13, 1)
    assert str(err.value) == ("-j 13: 13 runs at once is 13 ranks, more than this machine can run: at "
                              "most 12 (4 per core or the Slurm tasks; set VIBROFEED_MAX_RANKS to change "
                              "the limit); give -j 12 or less")
    # a command whose ranks are its -n says so
    with pytest.raises(UsageError, match=r"^-j 5: 5 runs at once of -n 3 ranks each is 15 "):
        check_at_once(5, 3, ranks_name="-n ")
    with pytest.raises(UsageError, match=r"^-j 5: 5 runs at once of ranks_per_run = 3 ranks each is 15 "
                                         r"ranks, .*; give -j 4 or less$"):
        check_at_once(5, 3)


def test_without_an_affinity_mask_every_core_counts(three_cores, monkeypatch):
    monkeypatch.delattr(runner.os, "sched_getaffinity")
    assert max_ranks() == 20
    monkeypatch.setattr(runner.os, "cpu_count", lambda: None)  # unknown: one core
    assert max_ranks() == 4


@pytest.mark.parametrize("slurm, limit", [("40", 40), ("12", 12), ("8", 12), ("x", 12), ("", 12)])
def test_a_slurm_allocation_raises_the_limit_to_its_tasks(three_cores, monkeypatch, slurm, limit):
    monkeypatch.setenv("SLURM_NTASKS", slurm)
    assert max_ranks() == limit


@pytest.mark.parametrize("env, limit", [("7", 7), ("1", 1), ("100", 100), ("", 12), (" ", 12)])
def test_vibrofeed_max_ranks_overrides_when_set(three_cores, monkeypatch, env, limit):
    monkeypatch.setenv("VIBROFEED_MAX_RANKS", env)
    assert max_ranks() == limit


@pytest.mark.parametrize("env", ["0", "-3", "x", "abc", "2.5", "４"])
def test_vibrofeed_max_ranks_that_is_no_rank_count_is_refused(three_cores, monkeypatch, env):
    monkeypatch.setenv("VIBROFEED_MAX_RANKS", env)
    with pytest.raises(UsageError) as err:
        max_ranks()
    assert str(err.value) == (f"environment variable VIBROFEED_MAX_RANKS={env} must be a whole number "
                              "of MPI ranks, at least 1; correct it or unset it")


def test_vibrofeed_max_ranks_overrides_a_slurm_allocation(three_cores, monkeypatch):
    monkeypatch.setenv("SLURM_NTASKS", "40")
    monkeypatch.setenv("VIBROFEED_MAX_RANKS", "7")
    assert max_ranks() == 7


@pytest.mark.parametrize("ranks", [1, 2, 5])
def test_check_ranks_accepts_positive_integers_up_to_the_limit(monkeypatch, ranks):
    monkeypatch.setenv("VIBROFEED_MAX_RANKS", "5")
    assert check_ranks(ranks) == ranks


@pytest.mark.parametrize("ranks", [0, -1, True, False, 1.0, 2.0, "2", None])
def test_check_ranks_refuses_what_is_not_a_positive_integer(monkeypatch, ranks):
    monkeypatch.setenv("VIBROFEED_MAX_RANKS", "5")
    with pytest.raises(UsageError) as caught:
        check_ranks(ranks)
    assert str(caught.value) == f"the number of ranks must be a positive integer, got {said(ranks)}"
    assert "'" not in str(caught.value)


def test_check_ranks_refuses_one_past_the_limit(monkeypatch):
    monkeypatch.setenv("VIBROFEED_MAX_RANKS", "5")
    with pytest.raises(UsageError) as caught:
        check_ranks(6)
    # the limit set by the variable is said as that, not as ranks per core
    assert str(caught.value) == "6 ranks is more than this machine can run: at most 5 (VIBROFEED_MAX_RANKS=5)"
    monkeypatch.delenv("VIBROFEED_MAX_RANKS")
    monkeypatch.setenv("SLURM_NTASKS", "100000")  # a huge allocation: its tasks are the limit
    assert check_ranks(100000) == 100000
    with pytest.raises(UsageError, match="at most 100000 "):
        check_ranks(100001)


# -- run id ------------------------------------------------------------------------------------
def test_the_run_id_is_the_sha256_of_the_state_point(tmp_path):
    """Closed form (docstring): SHA-256 of the canonical JSON (sorted keys, no spaces) of the
    deck's name and sources, the parameters as strings, the driver's commands, the schedule
    and the version; the target error only when given."""
    deck = make_deck(tmp_path)
    state = {"deck": "d", "sources": {"d.liggghts": DECK_TEXT}, "parameters": {"a": "1", "b": "2.5"},
             "before_run": ["fix x all y"], "schedule": [{"steps": 3}], "vibrofeed": __version__}
    text = json.dumps(state, sort_keys=True, separators=(",", ":"))
    rid = run_id(deck, {"b": 2.5, "a": 1}, ("fix x all y",), [{"steps": 3}])
    assert rid == hashlib.sha256(text.encode()).hexdigest()
    state["target_error"] = 0.05
    text = json.dumps(state, sort_keys=True, separators=(",", ":"))
    assert run_id(deck, {"a": "1", "b": "2.5"}, ["fix x all y"], [{"steps": 3}], target_error="0.05") == \
        hashlib.sha256(text.encode()).hexdigest()


def test_the_run_id_changes_with_everything_that_changes_the_computation(tmp_path, monkeypatch):
    deck = make_deck(tmp_path / "a")
    values = {"freq": "50", "t_end": "0.1"}
    base = run_id(deck, values)
    assert len(base) == 64 and int(base, 16) >= 0
    # the same computation: parameter order, numbers or their strings, no commands or none
    assert run_id(deck, {"t_end": "0.1", "freq": "50"}) == base
    assert run_id(deck, {"freq": 50, "t_end": 0.1}) == base
    assert run_id(deck, values, before_run=[], schedule=None, target_error=None) == base
    # the same deck copied elsewhere is the same computation
    assert run_id(make_deck(tmp_path / "b"), values) == base
    others = [
        run_id(deck, {"freq": "51", "t_end": "0.1"}),                  # a parameter's value
        run_id(deck, {"freq": "50", "t_end": "0.1", "seed": "1"}),     # one more parameter
        run_id(deck, values, before_run=["fix g all gravity"]),        # commands added
        run_id(deck, values, schedule=[{"steps": 10}]),                # a schedule
        run_id(deck, values, target_error=0.05),                       # a target error
        run_id(deck, values, target_error=0.04),
        run_id(make_deck(tmp_path / "c", name="e"), values),           # another deck name
        run_id(make_deck(tmp_path / "d", DECK_TEXT + "# more\n"), values),  # another text
    ]
    monkeypatch.setattr(runner, "__version__", __version__ + ".post1")
    others.append(run_id(deck, values))                                # another vibrofeed
    assert len(set(others)) == len(others) and base not in others


def test_the_run_id_covers_the_included_files(tmp_path):
    (tmp_path / "include").mkdir()
    block = tmp_path / "include" / "b.liggghts"
    block.write_text("units si\n")
    deck = make_deck(tmp_path, "variable freq index 50 # [Hz] f\ninclude ${deck_dir}/include/b.liggghts\n")
    before = run_id(deck, {"freq": "50"})
    block.write_text("units cgs\n")
    assert run_id(Deck(deck.path), {"freq": "50"}) != before


def test_check_target_error_refuses_what_is_not_a_number():
    bulk = Deck.find("bulk_feeder")
    for bad in ([0.1], {}, object()):  # TypeError from float()
        with pytest.raises(UsageError, match="target error must be a number"):
            check_target_error(bad, bulk)
    assert check_target_error(0.5, bulk) == 0.5


# -- reusing a finished result -----------------------------------------------------------------
def write_run(path, rid, steps=(100, 150, 250), times=(0.1, 0.15, 0.25), sizes=(2, 3, 5),
              status=L.STATUS_COMPLETE, wall=None, target=None, stop_reason=None):
    """A result file of run ``rid``: frame k at steps[k], times[k] holding sizes[k] parts."""
    w = ResultWriter(path, deck_name="d", deck_path="d.liggghts", deck_text=DECK_TEXT,
                     variables={"freq": ("50", "Hz", "f", "50")}, derived={"dt_used": 1e-3},
                     engine_version="LIGGGHTS (synthetic)", seed=1, run_id=rid, target_error=target)
    for step, t, n in zip(steps, times, sizes):
        w.write_frame(step, t, parts(np.arange(1, n + 1), np.zeros((n, 3))), np.zeros(3), np.zeros(3))
    w.finish(status, wall_seconds=wall, stop_reason=stop_reason)
    return path


def test_a_complete_result_of_the_same_run_is_reused_as_it_is(tmp_path):
    deck = make_deck(tmp_path)
    out = write_run(tmp_path / "r.h5", "abc", wall=12.5, target=0.05,
                    stop_reason="target error 0.05 reached: 0.04 at t = 0.25 s")
    got = _reusable(out, "abc", deck, {"freq": "50"}, 3)
    assert got.reused is True and got.run_id == "abc" and got.output == out
    assert got.log == tmp_path / "r.log" and got.deck == "d" and got.ranks == 3
    assert got.parameters == {"freq": "50"}
    assert got.frames == 3 and got.natoms == 5            # the parts in the last frame
    assert got.n_steps == 150                             # 250 - 100: steps run between frames
    assert got.sim_time == pytest.approx(0.15, abs=1e-12)  # s: 0.25 - 0.1
    assert got.dt == pytest.approx(1e-3, rel=1e-9)         # s: 0.15 s / 150 steps
    assert got.wall == 12.5 and got.target_error == 0.05
    assert got.stop_reason == "target error 0.05 reached: 0.04 at t = 0.25 s" and got.stopped_early


def test_a_result_without_frames_or_wall_time_reuses_as_zeros(tmp_path):
    deck = make_deck(tmp_path)
    got = _reusable(write_run(tmp_path / "one.h5", "abc", (7,), (0.5,), (4,)), "abc", deck, {}, 1)
    assert (got.frames, got.natoms, got.n_steps, got.dt, got.sim_time) == (1, 4, 0, 0.0, 0.0)
    assert got.wall == 0.0 and got.target_error is None and got.stop_reason == ""
    got = _reusable(write_run(tmp_path / "none.h5", "abc", (), (), ()), "abc", deck, {}, 1)
    assert (got.frames, got.natoms, got.n_steps, got.dt, got.sim_time) == (0, 0, 0, 0.0, 0.0)


def test_nothing_else_stands_in_for_a_run(tmp_path):
    deck = make_deck(tmp_path)
    complete = write_run(tmp_path / "r.h5", "abc")
    assert _reusable(complete, "abd", deck, {}, 1) is None           # another run's result
    assert _reusable(tmp_path / "missing.h5", "abc", deck, {}, 1) is None
    folder = tmp_path / "folder.h5"
    folder.mkdir()
    assert _reusable(folder, "abc", deck, {}, 1) is None              # not a file
    for status in (L.STATUS_RUNNING, L.STATUS_FAILED, L.STATUS_INTERRUPTED):
        path = write_run(tmp_path / f"{status}.h5", "abc", status=status)
        assert _reusable(path, "abc", deck, {}, 1) is None           # ResultError: incomplete
    garbage = tmp_path / "garbage.h5"
    garbage.write_bytes(b"not hdf5")
    assert _reusable(garbage, "abc", deck, {}, 1) is None             # ResultError: not HDF5
    with h5py.File(complete, "r+") as f:                              # KeyError: no frames table
        del f[f"{L.PARTS}/position"]
    assert _reusable(complete, "abc", deck, {}, 1) is None


# -- the worker's command and environment ------------------------------------------------------
def test_one_rank_runs_the_worker_alone(monkeypatch):
    monkeypatch.setattr(runner.shutil, "which", lambda name: pytest.fail("no mpirun for one rank"))
    base = [sys.executable, "-m", "vibrofeed.engine.worker", "s.json"]
    assert worker_command("s.json", 1) == base
    assert worker_command("s.json", 1, Path("/lib/shim.so")) == base  # the shim goes by LD_PRELOAD


def test_several_ranks_run_under_mpirun(monkeypatch):
    monkeypatch.setattr(runner.shutil, "which", lambda name: f"/opt/bin/{name}")
    monkeypatch.setattr(runner.os, "geteuid", lambda: 1000)
    base = [sys.executable, "-m", "vibrofeed.engine.worker", "s.json"]
    assert worker_command("s.json", 2) == ["/opt/bin/mpirun", "-n", "2", "--oversubscribe", *base]
    assert worker_command("s.json", 3, Path("/lib/shim.so")) == [
        "/opt/bin/mpirun", "-n", "3", "--oversubscribe", "-x", "LD_PRELOAD=/lib/shim.so", *base]
    monkeypatch.setattr(runner.os, "geteuid", lambda: 0)  # Open MPI refuses root without the flag
    assert worker_command("s.json", 2) == ["/opt/bin/mpirun", "-n", "2", "--oversubscribe",
                                           "--allow-run-as-root", *base]
    monkeypatch.delattr(runner.os, "geteuid")  # no such notion here
    assert "--allow-run-as-root" not in worker_command("s.json", 2)


def test_several_ranks_without_mpirun_are_refused(monkeypatch):
    monkeypatch.setattr(runner.shutil, "which", lambda name: None)
    with pytest.raises(RunError, match="mpirun not found"):
        worker_command("s.json", 2)


def test_the_worker_environment_preloads_the_shim_for_a_singleton_only(monkeypatch):
    monkeypatch.setenv("OMPI_COMM_WORLD_RANK", "3")
    monkeypatch.setenv("VIBROFEED_TEST_KEPT", "yes")
    monkeypatch.delenv("LD_PRELOAD", raising=False)
    shim = Path("/lib/shim.so")
    env = worker_environment(1, None)
    assert "LD_PRELOAD" not in env and "OMPI_COMM_WORLD_RANK" not in env
    assert env["VIBROFEED_TEST_KEPT"] == "yes"
    assert worker_environment(1, shim)["LD_PRELOAD"] == "/lib/shim.so"
    assert "LD_PRELOAD" not in worker_environment(2, shim)  # mpirun -x gives it to the ranks
    monkeypatch.setenv("LD_PRELOAD", "/lib/other.so")  # kept, after the shim
    assert worker_environment(1, shim)["LD_PRELOAD"] == "/lib/shim.so /lib/other.so"
    assert worker_environment(2, shim)["LD_PRELOAD"] == "/lib/other.so"


def test_a_singleton_starts_mpi_without_a_server_or_ucx_and_several_ranks_as_launched(monkeypatch):
    monkeypatch.setenv("OMPI_MCA_pml", "ucx")  # a surrounding launch's: not the worker's
    one, two = worker_environment(1, None), worker_environment(2, None)
    assert one["OMPI_MCA_ess_singleton_isolated"] == "1" and one["OMPI_MCA_pml"] == "ob1"
    assert not any(k.startswith("OMPI_MCA_") for k in two)  # mpirun picks for the ranks


def test_clean_environment_reads_this_process_by_default(monkeypatch):
    monkeypatch.setenv("PMIX_RANK", "1")
    monkeypatch.setenv("VIBROFEED_TEST_KEPT", "yes")
    env = clean_environment()
    assert env["VIBROFEED_TEST_KEPT"] == "yes" and "PMIX_RANK" not in env
    assert os.environ["PMIX_RANK"] == "1"


# -- the output --------------------------------------------------------------------------------
def test_prepare_output_makes_the_folder_and_names_part_and_log(tmp_path):
    out, part, log = _prepare_output(tmp_path / "new" / "deeper" / "r.h5")
    assert out == (tmp_path / "new" / "deeper" / "r.h5").resolve() and out.parent.is_dir()
    assert part == out.with_name("r.h5.part") and log == out.with_name("r.log")
    assert not part.exists() and not out.exists()  # the write probe leaves nothing
    out, part, log = _prepare_output(str(tmp_path / "new" / "plain"))  # an existing folder; no suffix
    assert (part.name, log.name) == ("plain.part", "plain.log")


def test_prepare_output_expands_the_home_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("HOME", str(tmp_path))
    out, _, _ = _prepare_output("~/r.h5")
    assert out == (tmp_path / "r.h5").resolve()


def test_prepare_output_refuses_what_cannot_be_written(tmp_path):
    folder = tmp_path / "out"
    folder.mkdir()
    with pytest.raises(OutputError, match="is a directory; give a file name such as"):
        _prepare_output(folder)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OutputError, match="cannot create folder"):
        _prepare_output(blocker / "r.h5")
    (tmp_path / "r.h5.part").mkdir()  # the partial file cannot be created
    with pytest.raises(OutputError, match="cannot write"):
        _prepare_output(tmp_path / "r.h5")


# -- what a partial file holds -----------------------------------------------------------------
def test_frames_in_a_file_and_in_what_is_not_one(tmp_path):
    path = write_run(tmp_path / "r.h5", "x", status=L.STATUS_RUNNING)
    assert _frames_in(path) == (3, 250, 0.25)
    one = write_run(tmp_path / "one.h5", "x", (7,), (0.5,), (1,), status=L.STATUS_RUNNING)
    assert _frames_in(one) == (1, 7, 0.5)
    empty = write_run(tmp_path / "empty.h5", "x", (), (), (), status=L.STATUS_RUNNING)
    assert _frames_in(empty) == (0, None, None)
    assert _frames_in(tmp_path / "missing.h5") == (0, None, None)      # OSError
    garbage = tmp_path / "garbage.h5"
    garbage.write_bytes(b"not hdf5")
    assert _frames_in(garbage) == (0, None, None)                      # OSError
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = 1
    assert _frames_in(tmp_path / "other.h5") == (0, None, None)       # KeyError


def test_frames_in_a_file_a_full_disk_left_a_frame_apart(tmp_path):
    """The disk filled up between a frame's datasets (seen once in 80 runs of the full-disk
    engine test: the step written, its time not): the frames counted are those written whole."""
    for short in ("time", "value", "step"):
        path = write_run(tmp_path / f"{short}.h5", "x", status=L.STATUS_RUNNING)
        with h5py.File(path, "a") as f:
            ds = f[f"{L.PARTS}/position/{short}"]
            ds.resize(len(ds) - 1, axis=0)
        assert _frames_in(path) == (2, 150, 0.15), short  # the last whole frame
    first = write_run(tmp_path / "first.h5", "x", (7,), (0.5,), (1,), status=L.STATUS_RUNNING)
    with h5py.File(first, "a") as f:  # the first frame's step alone
        f[f"{L.PARTS}/position/time"].resize(0, axis=0)
    assert _frames_in(first) == (0, None, None)


def flock(path):
    """An exclusive lock on ``path`` as a rank still writing it would hold (HDF5 locks with flock)."""
    import fcntl

    fd = os.open(path, os.O_RDONLY)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    return fd


def test_a_file_a_stray_rank_holds_open_is_read_without_a_lock(tmp_path):
    path = write_run(tmp_path / "r.h5", "x", status=L.STATUS_RUNNING)
    fd = flock(path)
    try:
        assert _frames_in(path) == (3, 250, 0.25)
        assert _unreadable(path) is False
    finally:
        os.close(fd)


def test_unreadable_is_a_file_that_exists_but_hdf5_cannot_open(tmp_path):
    assert _unreadable(tmp_path / "missing.h5") is False
    garbage = tmp_path / "garbage.h5"
    garbage.write_bytes(b"not hdf5")
    assert _unreadable(garbage) is True
    with h5py.File(tmp_path / "ok.h5", "w"):
        pass
    assert _unreadable(tmp_path / "ok.h5") is False


# -- the mass balance --------------------------------------------------------------------------
def test_a_closed_mass_balance_is_no_problem():
    assert _mass_balance_problem(None) is None
    assert _mass_balance_problem({}) is None
    assert _mass_balance_problem({"inserted": 10, "on_track": 4, "exited": 6, "lost": 0}) is None
    assert _mass_balance_problem({"inserted": 10, "on_track": 4, "exited": 6}) is None  # no count of losses


def test_lost_parts_are_named_with_every_count():
    counts = {"inserted": 100, "on_track": 40, "exited": 57, "lost": 3}
    assert _mass_balance_problem(counts) == (
        "3 of 100 parts were lost (they left without crossing the outlet): the mass balance does "
        "not close (inserted 100, on the track 40, exited 57)")
    one = {"inserted": 10, "on_track": 4, "exited": 5, "lost": 1}
    assert _mass_balance_problem(one).startswith("1 of 10 parts were lost")


def test_parts_counted_twice_and_a_lines_counts():
    counts = {"inserted": 10, "on_track": 5, "exited": 7, "lost": -2}
    assert _mass_balance_problem(counts) == (
        "2 part(s) counted twice: the mass balance does not close (inserted 10, on the track 5, "
        "exited 7)")
    assert _mass_balance_problem({**counts, "lost": -1}).startswith("1 part(s) counted twice:")
    line = {"inserted": 20, "on_track": 5, "exited": 9, "rejected": 4, "lost": 2}
    assert _mass_balance_problem(line) == (
        "2 of 20 parts were lost (they left without crossing the outlet): the mass balance does "
        "not close (inserted 20, on the track 5, exited 9, rejected 4)")
    assert _mass_balance_problem({**line, "returned": 3}).endswith(
        "(inserted 20, on the track 5, exited 9, rejected 4, returned 3)")


# -- the error a user reads --------------------------------------------------------------------
@pytest.fixture
def failed(tmp_path, monkeypatch):
    """A run folder (the working directory): the deck, and the worker's log, screen and stderr."""
    monkeypatch.chdir(tmp_path)
    deck = make_deck(tmp_path)
    files = {name: tmp_path / name for name in ("d.log", "screen.txt", "stderr.txt")}

    def diagnose(rc, events, log="", screen="", stderr="", step=None, t=None):
        for name, text in zip(files, (log, screen, stderr)):
            if text is not None:
                files[name].write_text(text)
        return _diagnose(rc, events, deck, files["d.log"], files["screen.txt"], files["stderr.txt"],
                         step, t)

    diagnose.deck = deck
    diagnose.log = files["d.log"]
    return diagnose


PHASES = [{"event": "deck"}, {"event": "setup"}, {"event": "run", "dt": 1e-3},
          {"event": "progress", "step": 10}, {"event": "warning", "message": "w"}]
ECHO = ("LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0)\n"
        "variable freq index 50 # [Hz] f\n"
        "\n"
        "units si\n"
        "fix bad all nope ${freq}\n"
        "fix bad all nope 50\n")
NOPE = 'ERROR: Invalid fix style: "nope" (./src/modify.cpp:850)\n'


def test_the_workers_own_error_is_the_message(failed):
    events = [*PHASES[:1], {"event": "error", "message": "DeckError: bad contract"},
              {"event": "error", "message": "second"}]
    e = failed(4, events, log=ECHO + NOPE)  # its own message wins over the log's
    assert type(e) is RunError and str(e) == "deck d: DeckError: bad contract"


def test_an_error_in_the_deck_names_its_line(failed):
    e = failed(1, PHASES[:1], log=ECHO + NOPE, step=None)
    assert type(e) is EngineError
    assert (e.message, e.deck, e.line, e.command) == ('Invalid fix style: "nope"', "d.liggghts", 4,
                                                      "fix bad all nope ${freq}")
    assert (e.phase, e.step, e.time, e.log) == ("deck", None, None, str(failed.log))


def test_the_failed_command_is_the_one_echoed_before_the_error(failed):
    # a command echoed after the ERROR line (another rank's output) is not the culprit
    e = failed(1, PHASES[:1], log=ECHO.replace("fix bad all nope 50\n", "") + NOPE + "run 10\n")
    assert (e.line, e.command) == (4, "fix bad all nope ${freq}")


def test_an_error_only_on_the_screen_takes_the_last_command_echoed(failed):
    # error->one writes only to the screen: the log's last echoed command failed
    e = failed(1, PHASES[:1], log=ECHO, screen="x\n" + NOPE)
    assert (e.message, e.line, e.command, e.phase) == ('Invalid fix style: "nope"', 4,
                                                        "fix bad all nope ${freq}", "deck")


def test_an_error_in_the_deck_without_a_known_command(failed):
    e = failed(1, PHASES[:1], log="LIGGGHTS (Version)\n" + NOPE)
    assert (e.deck, e.line, e.command) == ("d.liggghts", None, None)


def test_an_error_in_an_included_file_names_that_file(failed, tmp_path):
    (tmp_path / "include").mkdir()
    (tmp_path / "include" / "b.liggghts").write_text("units si\nfix bad all nope\n")
    deck = make_deck(tmp_path, "variable freq index 50 # [Hz] f\ninclude ${deck_dir}/include/b.liggghts\n"
                               "run 10\n", name="inc")
    failed.log.write_text("variable freq index 50 # [Hz] f\nunits si\nfix bad all nope\n" + NOPE)
    e = _diagnose(1, PHASES[:1], deck, failed.log, tmp_path / "none", tmp_path / "none", None, None)
    assert (e.deck, e.line, e.command) == ("include/b.liggghts", 2, "fix bad all nope")


@pytest.mark.parametrize("events, phase, where", [
    (PHASES[:2], "setup", " while setting up the run"),
    (PHASES, "run", " during the run, after the frame at t = 0.25 s (step 250)"),
])
def test_an_error_after_the_deck_names_the_phase_and_the_last_frame(failed, events, phase, where):
    e = failed(1, events, log=ECHO + NOPE, step=250, t=0.25)
    assert (e.phase, e.line, e.command, e.deck) == (phase, None, None, "d.liggghts")
    assert (e.step, e.time) == (250, 0.25)
    assert str(e) == 'LIGGGHTS error: Invalid fix style: "nope"' + where


def test_an_aborted_rank_is_an_engine_error_with_the_last_lines_of_stderr(failed):
    stderr = "one\ntwo\nthree\nMPI_ABORT was invoked on rank 1\nfive\n\n"
    e = failed(1, PHASES, log=ECHO, stderr=stderr, step=250, t=0.25)
    assert type(e) is EngineError and (e.phase, e.step, e.time, e.log) == ("run", 250, 0.25, str(failed.log))
    assert e.message == ("LIGGGHTS aborted on one rank (its message is in that rank's output): "
                         "three MPI_ABORT was invoked on rank 1 five")
    # an abort further back than the last three lines is not this one
    e = failed(1, PHASES, log=ECHO, stderr="MPI_ABORT\n2\n3\n4\n")
    assert type(e) is RunError and str(e).endswith(": 2 3 4")


@pytest.mark.parametrize("rc, events, text", [
    (-9, PHASES, "the engine was killed by signal 9 (SIGKILL) during the run phase"),
    (-1, PHASES[:2], "the engine was killed by signal 1 (SIGHUP) during the setup phase"),
    (-signal.SIGTERM, [], "the engine was killed by signal 15 (SIGTERM) during the start phase"),
    (0, PHASES, "the engine worker exited with status 0 during the run phase"),
    (1, [], "the engine worker exited with status 1 during the start phase"),
    (None, PHASES[:1], "the engine worker exited with status None during the deck phase"),
])
def test_a_worker_that_ended_without_a_message(failed, rc, events, text):
    e = failed(rc, events, log=ECHO, screen=None, stderr=None)  # no screen, no stderr file
    assert type(e) is RunError and str(e) == text


def test_a_worker_that_exited_says_what_it_printed_last(failed):
    e = failed(3, PHASES, log=ECHO, stderr="a\nb\nTraceback\nKeyError: 'x'\nexit\n")
    assert str(e) == ("the engine worker exited with status 3 during the run phase: "
                      "Traceback KeyError: 'x' exit")


def test_paths_are_shown_relative_to_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert _display(tmp_path / "a" / "d.liggghts") == os.path.join("a", "d.liggghts")
    assert _display(Path("/elsewhere/d.liggghts")) == "/elsewhere/d.liggghts"



# -- a hung worker: stopped, and its output's reader waited for ----------------------------------
def test_a_hung_worker_is_stopped_and_its_output_reader_joined(monkeypatch):
    """The reader is a daemon thread: left reading the pipe as the interpreter ends, it
    could be cut off holding the pipe's lock."""
    import subprocess
    import threading

    joined = []

    class Recorded(threading.Thread):
        def join(self, timeout=None):
            super().join(timeout)
            joined.append(self.is_alive())

    class Stalled:
        def __init__(self, now, floor=None):
            pass

        def saw(self, event, now):
            pass

        def stalled(self, now):
            return "no heartbeat for 30 s"

    monkeypatch.setattr(runner.threading, "Thread", Recorded)
    monkeypatch.setattr(runner, "Watchdog", Stalled)
    run = object.__new__(runner._Run)
    run.events, run.on_event, run.hung = [], None, None
    run.proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"],
                                stdout=subprocess.PIPE, text=True, start_new_session=True)
    run.follow()
    assert run.hung == "no heartbeat for 30 s" and run.rc == -signal.SIGTERM
    assert joined == [False]  # joined, and ended: nothing left reading


def test_a_run_that_will_take_long_says_so_before_it_starts(monkeypatch):
    """-p dt=1e-12 started a run of 75 days without a word."""
    import warnings

    from vibrofeed.decks import Deck
    from vibrofeed.engine.runner import LongRunWarning, long_run, warn_long_run
    from vibrofeed.parameters import contact_times, resolve, run_steps

    monkeypatch.delenv("VIBROFEED_LONG_RUN_HOURS", raising=False)
    deck = Deck.find("single_part")
    values = resolve(deck, {"dt": "1e-12", "t_end": "0.2"})
    # by hand: 2e11 steps of a lone sphere, 5 us a step and 0.3 us for its one sphere
    step = 5e-6 + 0.3e-6
    assert long_run(values) == (
        f"this run will take about {0.2 / 1e-12 * step / 86400:.3g} days: 2e+11 steps of "
        f"dt=1e-12 s at {1 / step:,.0f} steps/s (one core, its parts' spheres counted); "
        "VIBROFEED_LONG_RUN_HOURS=1 sets when this is said")
    with pytest.warns(LongRunWarning, match="^this run will take about 12.3 days"):
        warn_long_run(values)
    # the deck's own timestep: the output interval in whole steps of at most 1/50 of the
    # Hertz time (decks/include/contact_time.liggghts, dt_auto)
    numbers = {}
    for name, text in resolve(deck, {}).items():
        try:
            numbers[name] = float(text)
        except ValueError:
            pass
    steps, dt = run_steps(numbers)
    hertz = contact_times(numbers)["hertz"]
    assert dt == numbers["output_dt"] / math.ceil(numbers["output_dt"] / (hertz / 50))
    assert steps == pytest.approx(numbers["t_end"] / dt, rel=1e-12)  # a count of steps
    # below the threshold nothing is said; the threshold is the user's
    assert long_run(resolve(deck, {})) is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warn_long_run(resolve(deck, {}))
    monkeypatch.setenv("VIBROFEED_LONG_RUN_HOURS", str(steps * step / 3600 / 2))
    assert long_run(resolve(deck, {})).startswith(f"this run will take about {round(steps * step)}s: ")
    monkeypatch.setenv("VIBROFEED_LONG_RUN_HOURS", "2000")
    assert long_run(values) is None


def test_a_stopped_runs_status_waits_for_a_rank_still_closing_the_file(tmp_path):
    """A hung rank's run once kept status "running": its rank 0, killed with its group, still
    held the file's lock when the runner marked it. The mark waits for the lock (here a
    process holding it 1 s), and gives up at once on a file that is not locked."""
    import subprocess
    import time

    from helpers import write_result

    path = tmp_path / "r.h5.part"
    write_result(path, [(0, 0.0, parts([1], [[0.001, 0.0, 1e-4]]))], status=None)
    holder = subprocess.Popen(
        [sys.executable, "-c", f"import h5py, time\nf = h5py.File({str(path)!r}, 'r+')\n"
                               "print('open', flush=True)\ntime.sleep(1.0)\nf.close()"],
        stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "open"
    assert runner._locked(path)
    assert runner._mark(path, L.STATUS_FAILED, "hung", seconds=20) is True
    holder.wait()
    with h5py.File(path, "r") as f:
        assert f[L.RUN].attrs["status"] == L.STATUS_FAILED and f[L.RUN].attrs["message"] == "hung"
    # not HDF5 (nothing to wait for): refused at once, not after the 20 s
    (tmp_path / "text.h5").write_text("not hdf5")
    start = time.monotonic()
    assert runner._mark(tmp_path / "text.h5", L.STATUS_FAILED, "x", seconds=20) is False
    assert time.monotonic() - start < 5
