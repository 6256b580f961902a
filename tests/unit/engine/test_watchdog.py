"""The runner's watchdog: when an engine worker counts as hung (engine/watchdog.py)."""

from vibrofeed.engine.watchdog import SLOWEST_FACTOR, Watchdog, floor_seconds


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
    for bad in ("", "x", "-1", "0"):
        monkeypatch.setenv("VIBROFEED_STALL_SECONDS", bad)
        assert floor_seconds() == 60.0
