"""The worker's decisions that need no engine (vibrofeed/engine/worker.py): LIGGGHTS' command
line, the engine's version, the arrays and files the prepare hook hands over, which track
vertices are a line's section 2, how the run is cut into segments, when a target error is
checked and what the file says about it, the end-of-run warnings and a full disk."""

import dataclasses
import errno
import math
import threading
import time
import types

import numpy as np
import pytest

from helpers import DECKS
from vibrofeed.decks import Deck
from vibrofeed.engine import worker
from vibrofeed.engine.worker import (
    CHECK_FRACTION,
    TargetError,
    Verdict,
    _includes,
    _load_array,
    bulk_warnings,
    engine_arguments,
    engine_version,
    no_space,
    segments,
    track_sections,
)
from vibrofeed.errors import DeckError
from vibrofeed.feeders.feeder import section_from
from vibrofeed.line import section_mesh
from vibrofeed.parameters import resolve


# -- LIGGGHTS' command line, version and the deck's includes -----------------------------------
def test_engine_arguments_pass_the_variables_and_driver_mode():
    spec = {"log": "/run/d.log", "screen": "/tmp/s/screen.txt", "deck": "/decks/d.liggghts",
            "variables": {"freq": "50", "seed": 3},
            "prepared": {"variables": {"mesh_dir": "/tmp/s"}, "track": None}}
    head = ["-log", "/run/d.log", "-screen", "/tmp/s/screen.txt", "-echo", "log", "-nocite",
            "-var", "freq", "50", "-var", "seed", "3"]
    tail = ["-var", "driver", "1", "-var", "deck_dir", "/decks"]
    assert engine_arguments(spec) == head + ["-var", "mesh_dir", "/tmp/s"] + tail
    for prepared in (None, {}, {"variables": None}, {"track": "t.npz"}):  # no extra variables
        assert engine_arguments({**spec, "prepared": prepared}) == head + tail
    del spec["prepared"]
    assert engine_arguments(spec) == head + tail


def test_engine_version_is_the_logs_first_line(tmp_path):
    log = tmp_path / "d.log"
    log.write_text("LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, compiled 2024)  \nunits si\n")
    assert engine_version(str(log)) == "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, compiled 2024)"
    log.write_text("units si\nLIGGGHTS (Version 3.8.0)\n")  # only the first line counts
    assert engine_version(str(log)) == "LIGGGHTS (version line not found in log)"
    assert engine_version(str(tmp_path / "missing.log")) == "LIGGGHTS (version line not found in log)"


def test_includes_are_the_sources_but_the_deck_itself():
    sources = {"d.liggghts": "deck", "include/b.liggghts": "block", "include/c.liggghts": "c"}
    spec = {"deck": "/decks/d.liggghts", "sources": sources}
    assert _includes(spec) == {"include/b.liggghts": "block", "include/c.liggghts": "c"}
    assert _includes({"deck": "/decks/d.liggghts"}) == {}


# -- arrays from the prepare hook --------------------------------------------------------------
def test_load_array_inline_and_none():
    assert _load_array(None) is None
    got = _load_array([[1.0, 2.0], [3.0, 4.0]])
    assert isinstance(got, np.ndarray) and got.tolist() == [[1.0, 2.0], [3.0, 4.0]]


def test_load_array_from_an_npz_takes_the_first_key_found(tmp_path):
    path = tmp_path / "t.npz"
    np.savez(path, first=np.array([1.0]), template=np.array([2.0]), body_template=np.array([3.0]))
    # the keys in the order asked for, whatever the file's order; else the file's first array
    assert _load_array(path, ("body_template", "template")).tolist() == [3.0]
    assert _load_array(str(path), ("missing", "template")).tolist() == [2.0]
    assert _load_array(path).tolist() == [1.0]
    assert _load_array(path, ("missing",)).tolist() == [1.0]


def test_load_array_from_npy_and_text(tmp_path):
    np.save(tmp_path / "t.npy", np.arange(6.0).reshape(3, 2))
    assert _load_array(tmp_path / "t.npy").tolist() == [[0, 1], [2, 3], [4, 5]]
    (tmp_path / "clump.txt").write_text("1e-4 0 0 7.5e-5\n")  # one sphere: still a table
    got = _load_array(str(tmp_path / "clump.txt"))
    assert got.shape == (1, 4) and got.tolist() == [[1e-4, 0.0, 0.0, 7.5e-5]]


# -- a line's track: which vertices are section 2's --------------------------------------------
@pytest.fixture(scope="module")
def line():
    """A line's parameters (the bulk feeder's defaults, two sections) and its section 2 mesh
    at rest as the prepare hook appends it."""
    values = resolve(Deck(DECKS / "bulk_feeder.liggghts"), {"sections": "2"})
    return values, section_mesh(section_from(values))[0]


def test_the_vertices_after_section_1_are_section_2(line):
    values, second = line
    first = np.random.default_rng(0).uniform(size=(5, 3))
    got = track_sections((np.vstack([first, second]), None), values)
    assert got.dtype == np.int32 and got.tolist() == [1] * 5 + [2] * len(second)
    got = track_sections((np.vstack([first[:1], second]), None), values)  # one vertex of section 1
    assert got.tolist() == [1] + [2] * len(second)


def test_a_track_that_does_not_end_with_section_2_cannot_be_told(line):
    values, second = line
    first = np.random.default_rng(0).uniform(size=(5, 3))
    assert track_sections(None, values) is None
    assert track_sections((second, None), values) is None                  # no section 1 at all
    assert track_sections((second[1:], None), values) is None              # shorter than section 2
    moved = np.vstack([first, second])
    moved[-1, 0] += 1e-9                                                   # one vertex elsewhere
    assert track_sections((moved, None), values) is None


def test_parameters_that_describe_no_section_2_cannot_be_told(line):
    values, second = line
    track = (np.vstack([np.zeros((2, 3)), second]), None)
    assert track_sections(track, {**values, "s2_length": "long"}) is None   # ValueError
    assert track_sections(track, {**values, "s2_wiper_height": "4e-4", "s2_wiper_at": "0.999"}) is None
    # a line deck that does not describe section 2 by the s2_* variables: its width missing
    # (0) was a ZeroDivisionError that ended the run instead of this warning's None
    no_width = {k: v for k, v in values.items() if k != "s2_width"}
    assert track_sections(track, no_width) is None


# -- segments ----------------------------------------------------------------------------------
@pytest.mark.parametrize("n_steps, every, steps", [
    (12, 4, [4, 4, 4]),
    (10, 4, [4, 4, 2]),       # an uneven last segment
    (9, 4, [4, 4, 1]),        # a last segment of one step
    (3, 4, [3]),              # a run shorter than a frame interval
    (1, 1, [1]),
])
def test_a_plain_run_is_cut_into_output_intervals(n_steps, every, steps):
    for spec in ({}, {"schedule": None}, {"schedule": []}):
        assert segments(spec, n_steps, every, 1e-3) == [((), n, False) for n in steps]


def test_a_schedule_runs_its_segments_with_setup():
    spec = {"schedule": [{"steps": 3, "commands": ["variable a equal 1"]},
                         {"until": 0.010},          # to t = 10 ms: 10 - 3 steps
                         {"steps": "1", "commands": ["variable a equal 2"]},
                         {"until": "0.0159"}]}      # to 15.9 ms: 16 steps in all, 16 - 11
    assert segments(spec, 999, 7, 1e-3) == [(["variable a equal 1"], 3, True), ((), 7, True),
                                            (["variable a equal 2"], 1, True), ((), 5, True)]


@pytest.mark.parametrize("schedule, index", [
    ([{"steps": 0}], 0),
    ([{"steps": 2}, {"until": 0.002}], 1),          # ends where the one before ended
    ([{"until": 0.0004}], 0),                       # less than half a step: rounds to none
])
def test_a_schedule_segment_shorter_than_a_step_is_refused(schedule, index):
    with pytest.raises(DeckError) as caught:
        segments({"schedule": schedule}, 100, 10, 1e-3)
    assert str(caught.value) == f"schedule segment {index} is shorter than the timestep (0.001 s)"


# -- the target error --------------------------------------------------------------------------
def test_a_verdict_is_a_frozen_record():
    v = Verdict(True, 0.01, 1.5)
    assert (v.reached, v.error, v.t, v.why) == (True, 0.01, 1.5, "")
    with pytest.raises(dataclasses.FrozenInstanceError):
        v.reached = False


class Judge:
    """judge_feed_rate stand-in: the verdicts to give in turn, and the results it judged."""

    def __init__(self, *verdicts):
        self.verdicts, self.judged = list(verdicts), []

    def __call__(self, result, target, stop=None):
        self.judged.append((result, target))
        return self.verdicts.pop(0)


class Writer:
    def read_back(self):
        return "the file so far"


ONE_RANK = types.SimpleNamespace(size=1, rank=0)


def test_checks_are_spaced_by_a_fraction_of_the_time_run(monkeypatch):
    """A check at t is due once t - (the last check) >= CHECK_FRACTION (t - the first frame's
    t): from a first frame at 10 s, after a check at 29 s (19 >= 0.95) the next is due at 30 s
    exactly (1 >= 0.05 x 20), not at 29.9 s (0.9 < 0.995), and after it at 31.6 s (1.6 >=
    1.08), not at 31 s (1 < 1.05)."""
    assert CHECK_FRACTION == 0.05
    judge = Judge(*[Verdict(False, 0.2, 0.0, "relative error 0.2")] * 3)
    monkeypatch.setattr(worker, "judge_feed_rate", judge)
    target = TargetError("0.1", ONE_RANK)
    assert target.target == 0.1 and target.verdict is None

    class Clocked(Writer):
        def read_back(self):
            return self.t

    writer, checked = Clocked(), []
    for t in (10.0, 10.0, 29.0, 29.9, 30.0, 30.5, 31.0, 31.6):
        writer.t = t
        assert target.reached(writer, t) is False
        if len(judge.judged) > len(checked):
            checked.append(t)
    assert checked == [29.0, 30.0, 31.6] and judge.judged[0] == (29.0, 0.1)
    assert target.verdict.why == "relative error 0.2"


def test_the_last_frame_is_always_judged(monkeypatch):
    judge = Judge(Verdict(False, 0.2, 0.0, "x"), Verdict(True, 0.05, 0.0), Verdict(False, 0.2, 0.0, "x"))
    monkeypatch.setattr(worker, "judge_feed_rate", judge)
    target, writer = TargetError(0.1, ONE_RANK), Writer()
    assert target.reached(writer, 10.0) is False and not judge.judged   # the first frame
    assert target.reached(writer, 29.0) is False and len(judge.judged) == 1
    assert target.reached(writer, 29.5, last=True) is True              # not due, but the last
    assert len(judge.judged) == 2
    alone = TargetError(0.1, ONE_RANK)
    assert alone.reached(writer, 0.0, last=True) is False               # a run of one frame
    assert len(judge.judged) == 3


def test_a_rank_without_the_writer_waits_for_rank_0(monkeypatch):
    monkeypatch.setattr(worker, "judge_feed_rate", lambda *a, **k: pytest.fail("only rank 0 judges"))
    assert TargetError(0.1, ONE_RANK).reached(None, 0.0, last=True) is None


def test_the_stop_reason_says_what_was_judged():
    target = TargetError(0.05, ONE_RANK)
    target.verdict = Verdict(True, 0.04123, 1.23456)
    assert target.stop_reason(at_end=False) == "target error 0.05 reached: 0.0412 at t = 1.235 s"
    assert target.stop_reason(at_end=True) == "t_end (target error 0.05 reached at the last frame: 0.0412)"
    target.verdict = Verdict(False, math.nan, 2.0, "too few exits to measure (3 so far)")
    assert target.stop_reason(at_end=True) == ("t_end (target error 0.05 not reached at t = 2 s: "
                                               "too few exits to measure (3 so far))")


# -- the end of the run ------------------------------------------------------------------------
def test_bulk_warnings_add_the_events_timed_at_their_frame():
    assert bulk_warnings(None) == []
    bulk = types.SimpleNamespace(outlet=types.SimpleNamespace(not_ballistic=0), warnings=["a"])
    assert bulk_warnings(bulk) == ["a"]
    bulk.outlet.not_ballistic = 3
    assert bulk_warnings(bulk) == ["a", "3 outlet event(s) timed at their frame: their free flight "
                                        "back never reached catch_z"]


@pytest.mark.parametrize("exc, full", [
    (OSError(errno.ENOSPC, "disk full"), True),                     # the errno
    (OSError(errno.EACCES, "Permission denied"), False),
    (RuntimeError("Can't write data (No space left on device)"), True),  # h5py's text
    (RuntimeError("file write failed: time = x, errno = 28, error message = 'disk'"), True),
    (RuntimeError("file write failed: errno = 280, error message = 'x'"), False),
    (ValueError("errno = 2, nothing to do with a disk"), False),
    (KeyError("x"), False),
])
def test_a_full_disk_is_told_by_errno_or_text(exc, full):
    assert errno.ENOSPC == 28
    assert no_space(exc) is full


# -- the heartbeat ends before the worker does ----------------------------------------------------
class SlowReport:
    """A rank's reporter whose messages take a while to write, recording when each ends."""

    def __init__(self, rank: int):
        self.rank, self.ended, self.started = rank, [], threading.Event()

    def __call__(self, event: str, **data) -> None:
        self.started.set()
        time.sleep(0.3)
        self.ended.append((event, data["step"]))


def test_stopping_the_heartbeat_waits_for_the_message_being_written(monkeypatch):
    """The worker leaves with os._exit right after: a beat cut off mid-write would reach
    the parent as half a line."""
    monkeypatch.setattr(worker, "HEARTBEAT_SECONDS", 0.01)
    report = SlowReport(rank=0)
    beat = worker.Heartbeat(report)
    beat.watch(np.array([42]))
    assert report.started.wait(5), "no beat within 5 s"
    beat.stop()
    assert report.ended and report.ended[0] == ("alive", 42)
    written = len(report.ended)
    time.sleep(0.1)
    assert len(report.ended) == written  # and no beat after stop


def test_other_ranks_have_no_heartbeat_to_stop(monkeypatch):
    monkeypatch.setattr(worker, "HEARTBEAT_SECONDS", 0.01)
    report = SlowReport(rank=1)
    beat = worker.Heartbeat(report)
    time.sleep(0.05)
    beat.stop()
    assert not report.started.is_set()
