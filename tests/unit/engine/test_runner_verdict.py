"""A run that reached its end has succeeded only if ``vibrofeed check`` accepts its result:
the runner checks the file before renaming it to OUT.h5, and ``--reuse`` keeps no result that
check rejects (issue 36: a run that exited 0 whose file check called INVALID)."""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest

from helpers import parts
from vibrofeed.decks import Deck
from vibrofeed.engine import runner
from vibrofeed.errors import RunError
from vibrofeed.results import layout as L
from vibrofeed.results.check import check_file
from vibrofeed.results.writer import ResultWriter

DECK = "variable freq index 50 # [Hz] f\nunits si\n"
RID = "ab" * 32


def write(path, speed: float, status=L.STATUS_RUNNING):
    """A run's file: one part at rest, then moving at ``speed`` [m/s] (0.01 s later, as far
    as that speed takes it), on a surface standing still."""
    w = ResultWriter(path, deck_name="d", deck_path="d.liggghts", deck_text=DECK,
                     variables={"freq": ("50", "Hz", "f", "50")}, derived={"dt_used": 1e-5},
                     engine_version="LIGGGHTS (synthetic)", seed=1, run_id=RID)
    w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), np.zeros(3), np.zeros(3))
    w.write_frame(1000, 0.01, parts([1], [[speed * 0.01, 0, 0]], velocity=[[speed, 0, 0]]),
                  np.zeros(3), np.zeros(3))
    w.finish(status)
    return path


def a_run(tmp_path, speed):
    """A _Run whose worker ended well (status 0, its ``done`` sent) having written ``speed``."""
    (tmp_path / "d.liggghts").write_text(DECK)
    deck = Deck(tmp_path / "d.liggghts")
    out, part, log = runner.output_files(tmp_path / "r.h5")
    run = runner._Run(deck, {"freq": "50"}, RID, out, part, log, 1, None)
    write(part, speed)
    run.rc = 0
    run.events = [{"event": "run", "dt": 1e-5},
                  {"event": "done", "step": 1000, "frames": 2, "natoms": 1, "counts": None}]
    return run


def test_a_sound_run_completes(tmp_path):
    run = a_run(tmp_path, 0.5)  # below the 1 m/s any part may reach
    result = run.finish()
    assert result.output == tmp_path / "r.h5" and not run.part.exists()
    with h5py.File(result.output) as f:
        assert f[L.RUN].attrs["status"] == L.STATUS_COMPLETE
    assert check_file(result.output).ok


def test_a_run_whose_result_check_rejects_has_failed(tmp_path):
    run = a_run(tmp_path, 8e4)  # the part, at 8e4 m/s
    with pytest.raises(RunError) as err:
        run.finish()
    message = str(err.value)
    assert message.startswith("deck d: the result is not sound, vibrofeed check rejects it: part 1 "
                              "moves at 8e+04 m/s at frame 1")
    assert "(and 1 more problem: vibrofeed check --allow-incomplete r.h5.part lists them)" in message
    assert "\n" not in message
    assert not (tmp_path / "r.h5").exists()            # never renamed to the result
    assert err.value.partial == (run.part, 2)          # the frames kept, the file says why
    with h5py.File(run.part) as f:
        assert f[L.RUN].attrs["status"] == L.STATUS_FAILED
        assert f[L.RUN].attrs["message"] == message


def test_a_failed_check_keeps_an_earlier_result(tmp_path):
    earlier = write(tmp_path / "r.h5", 0.5, L.STATUS_COMPLETE)
    before = earlier.read_bytes()
    with pytest.raises(RunError):
        a_run(tmp_path, 8e4).finish()
    assert earlier.read_bytes() == before


def test_reuse_keeps_no_result_that_check_rejects(tmp_path):
    (tmp_path / "d.liggghts").write_text(DECK)
    deck = Deck(tmp_path / "d.liggghts")
    sound = write(tmp_path / "sound.h5", 0.5, L.STATUS_COMPLETE)
    assert runner._reusable(sound, RID, deck, {}, 1).reused
    unsound = write(tmp_path / "unsound.h5", 8e4, L.STATUS_COMPLETE)  # completed by an older vibrofeed
    assert not check_file(unsound).ok
    assert runner._reusable(unsound, RID, deck, {}, 1) is None


def test_check_problem_is_none_for_a_sound_file_and_the_first_error_else(tmp_path):
    assert runner.check_problem(write(tmp_path / "a.h5", 0.5)) is None
    with h5py.File(write(tmp_path / "b.h5", 0.5), "r+") as f:
        f[f"{L.PARTS}/mass/value"][1, 0] = -1.0   # one problem only: no count of others
    assert runner.check_problem(tmp_path / "b.h5") == (
        "part 1 has a mass of -1 kg at frame 1 (t = 0.01 s): a part's mass is finite and positive")


# -- a finished result's companions (issue 36) -------------------------------------------------
def test_the_log_is_written_unfinished_and_goes_with_its_result(tmp_path):
    run = a_run(tmp_path, 0.5)
    run.prepare("", None, None)
    try:
        spec = json.loads(run.spec_path.read_text())
    finally:
        run.remove_scratch()
    assert spec["log"] == str(tmp_path / "r.log.part")   # LIGGGHTS never writes OUT.log itself
    (tmp_path / "r.log").write_text("the earlier run's log\n")
    run.log_part.write_text("this run's log\n")
    assert run.finish().log == tmp_path / "r.log"
    assert (tmp_path / "r.log").read_text() == "this run's log\n" and not run.log_part.exists()


def test_a_run_that_fails_leaves_the_earlier_results_log_as_it_was(tmp_path):
    # as a rerun killed with SIGKILL does: the earlier r.h5 and r.log stay a pair
    earlier = write(tmp_path / "r.h5", 0.5, L.STATUS_COMPLETE)
    (tmp_path / "r.log").write_text("the earlier run's log\n")
    run = a_run(tmp_path, 8e4)
    run.log_part.write_text("this run's log\n")
    with pytest.raises(RunError):
        run.finish()
    assert check_file(earlier).ok
    assert (tmp_path / "r.log").read_text() == "the earlier run's log\n"
    assert run.log_part.read_text() == "this run's log\n"    # beside its r.h5.part, for diagnosis


def test_a_run_interrupted_before_its_first_frame_leaves_nothing_and_says_so(tmp_path):
    run = a_run(tmp_path, 0.5)
    run.part.unlink()
    ResultWriter(run.part, deck_name="d", deck_path="d.liggghts", deck_text=DECK,
                 variables={"freq": ("50", "Hz", "f", "50")}, derived={}, engine_version="LIGGGHTS",
                 seed=1).close()                      # opened, no frame yet (the pre-fill settling)
    run.log_part.write_text("LIGGGHTS (Version ...)\n")
    kept = run.interrupted("terminated by SIGTERM")
    assert kept == "interrupted before its first frame: nothing written (r.h5 not touched)"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.liggghts"]


def test_a_run_interrupted_after_frames_keeps_them_marked_and_says_where(tmp_path):
    run = a_run(tmp_path, 0.5)
    run.log_part.write_text("LIGGGHTS (Version ...)\n")
    kept = run.interrupted("interrupted by the user")
    assert kept == (f"the 2 frames written before the interruption are kept in {run.part} "
                    "(status: interrupted)")
    with h5py.File(run.part) as f:
        assert f[L.RUN].attrs["status"] == L.STATUS_INTERRUPTED
        assert f[L.RUN].attrs["message"] == "interrupted by the user"
    assert run.log_part.exists()
