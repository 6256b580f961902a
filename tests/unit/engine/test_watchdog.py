"""The runner's watchdog: when an engine worker counts as hung (engine/watchdog.py)."""

import pytest

from vibrofeed.engine.watchdog import SLOWEST_FACTOR, Watchdog, floor_seconds
from vibrofeed.errors import UsageError


def beat(w, t, step):
    w.saw({"event": "alive", "step": step, "at": t}, t)


def test_silence_longer_than_the_floor_is_a_hang_in_any_phase():
    w = Watchdog(0.0, floor=10.0)
    w.saw({"event": "deck"}, 1.0)
    assert w.stalled(10.9) is None  # 9.9 s of silence
    assert "not answered for 11 s" in w.stalled(12.0)


def test_before_the_run_a_step_that_stands_still_is_no_hang():
    w = Watchdog(0.0, floor=10.0)
    for t in range(1, 100):  # settling a fill in the deck: alive, no steps counted
        beat(w, float(t), None if t < 50 else 7)
    assert w.stalled(99.5) is None


def test_in_the_run_the_limit_scales_with_the_longest_pause():
    w = Watchdog(0.0, floor=10.0)
    beat(w, 0.0, 0)  # the step of the setup
    w.saw({"event": "run"}, 0.0)
    beat(w, 1.0, 100)
    beat(w, 5.0, 200)  # a pause of 4 s (a frame being written): limit max(10, 10 x 4) = 40 s
    assert w.limit() == SLOWEST_FACTOR * 4.0
    for t in range(5, 46):  # alive, but the step stands still (waiting for a hung rank)
        beat(w, float(t), 200)
    assert w.stalled(44.5) is None  # 39.5 s without a step
    assert "took no step for 41 s (limit 40 s" in w.stalled(46.0)


def test_messages_read_late_are_timed_by_the_worker():
    """This process suspended for 500 s (Ctrl-Z) reads the backlog at once: the
    worker's own times say it went on steadily, so the limit stays at the floor."""
    w = Watchdog(0.0, floor=10.0)
    beat(w, 0.0, 0)
    w.saw({"event": "run"}, 0.0)
    for t in range(1, 500):
        w.saw({"event": "alive", "step": 10 * t, "at": float(t)}, 500.0)
    assert w.limit() == 10.0 and w.stalled(500.1) is None


def test_the_floor_comes_from_the_environment(monkeypatch):
    monkeypatch.setenv("VIBROFEED_STALL_SECONDS", "2.5")
    assert floor_seconds() == 2.5
    monkeypatch.setenv("VIBROFEED_STALL_SECONDS", "")  # set to nothing: unset
    assert floor_seconds() == 60.0


@pytest.mark.parametrize("bad", ["x", "-1", "0", "nan", "inf", "６０"])
def test_a_floor_that_means_nothing_is_refused_not_ignored(monkeypatch, bad):
    monkeypatch.setenv("VIBROFEED_STALL_SECONDS", bad)
    with pytest.raises(UsageError) as err:
        floor_seconds()
    assert str(err.value) == (f"environment variable VIBROFEED_STALL_SECONDS={bad} must be a number "
                              "of seconds > 0; correct it or unset it")


def test_the_floor_is_the_environments_unless_given(monkeypatch):
    monkeypatch.setenv("VIBROFEED_STALL_SECONDS", "0.5")  # below 1 s is a floor too
    assert floor_seconds() == 0.5 and Watchdog(0.0).floor == 0.5
    assert Watchdog(0.0, floor=7).floor == 7.0


def test_silence_of_exactly_the_floor_is_not_yet_a_hang():
    w = Watchdog(0.0, floor=10.0)
    assert w.stalled(10.0) is None
    assert w.stalled(10.25) == "the engine worker has not answered for 10 s (stopped or frozen)"


def test_a_standstill_of_exactly_the_limit_is_not_yet_a_hang():
    w = Watchdog(0.0, floor=2.0)
    beat(w, 0.0, 0)
    w.saw({"event": "run"}, 0.0)
    assert w.limit() == 2.0  # no pause seen yet: the floor
    for t in (0.5, 1.0, 1.5, 2.0):
        beat(w, t, 0)  # alive, no step
    assert w.stalled(2.0) is None
    beat(w, 2.5, 0)
    assert w.stalled(2.5) == ("the engine took no step for 2 s (limit 2 s: 10 x the longest pause of "
                              "this run, at least 2 s; a hung MPI rank?)")


def test_the_first_step_seen_in_the_run_is_no_advance():
    """No step to compare it with: the first advance is the next step seen, and the pause
    runs from the start of the run to it."""
    w = Watchdog(0.0, floor=10.0)
    w.saw({"event": "run"}, 0.0)
    beat(w, 5.0, 100)
    assert w.limit() == 10.0 and w.slowest == 0.0
    beat(w, 6.0, 200)
    assert w.slowest == 6.0 and w.limit() == 60.0


def test_a_heartbeat_without_a_step_is_no_advance():
    w = Watchdog(0.0, floor=10.0)
    beat(w, 0.0, 0)
    w.saw({"event": "run"}, 0.0)
    beat(w, 1.0, 100)
    beat(w, 30.0, None)  # the engine's counter unreadable for a moment
    assert w.slowest == 1.0 and w.limit() == 10.0


def test_a_heartbeat_is_timed_when_it_was_sent_never_later_than_now():
    w = Watchdog(0.0, floor=10.0)
    beat(w, 0.0, 0)
    w.saw({"event": "run"}, 0.0)
    w.saw({"event": "alive", "step": 100}, 4.0)               # no time of its own: received now
    assert w.slowest == 4.0 and w.last_advance == 4.0
    w.saw({"event": "alive", "step": 200, "at": 50.0}, 6.0)   # a clock ahead: now at most
    assert w.slowest == 4.0 and w.last_advance == 6.0 and w.last_seen == 6.0
