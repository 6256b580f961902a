"""The run's progress display: warnings from the engine worker reach the user
whether or not a progress bar is shown."""

import io

import pytest

from vibrofeed.run_progress import RunProgress


def test_warnings_are_printed_without_a_bar():
    stream = io.StringIO()
    progress = RunProgress("bulk_feeder", enabled=False, stream=stream)
    progress({"event": "run", "n_steps": 10, "dt": 1e-6})
    progress({"event": "warning", "message": "2 part(s) disappeared without crossing the outlet"})
    progress.close()
    assert stream.getvalue() == ("vibrofeed: warning: bulk_feeder: 2 part(s) disappeared without "
                                 "crossing the outlet\n")


def test_warnings_are_printed_beside_a_bar():
    stream = io.StringIO()
    progress = RunProgress("bulk_feeder", enabled=True, stream=stream)
    progress({"event": "run", "n_steps": 10, "dt": 1e-6})
    progress({"event": "warning", "message": "no body template"})
    progress({"event": "progress", "step": 5, "time": 5e-6})
    progress({"event": "done"})
    assert "vibrofeed: warning: bulk_feeder: no body template" in stream.getvalue()


def test_without_a_terminal_progress_comes_as_lines(monkeypatch):
    """Piped or in a batch job: a line at each further tenth of the run, not more
    often than every 5 s, at least every 60 s; none at the start or the end."""
    import vibrofeed.run_progress as P

    clock = [0.0]
    monkeypatch.setattr(P.time, "monotonic", lambda: clock[0])
    stream = io.StringIO()  # not a terminal
    progress = RunProgress("bulk_feeder", stream=stream)
    progress({"event": "run", "n_steps": 1000, "dt": 1e-3})
    steps = {}
    for wall in range(1, 401):  # 2.5 steps/s: 400 s for the run
        clock[0] = float(wall)
        step = int(2.5 * wall)
        progress({"event": "progress", "step": step, "time": step * 1e-3, "wall": float(wall)})
        steps[step] = wall
    lines = stream.getvalue().splitlines()
    assert len(lines) == 9  # the tenths 1..9; the 10th is the end
    assert lines[0] == "bulk_feeder: t = 0.1/1 s (10%), 0.0025k steps/s, ETA 6m00s"
    assert lines[-1] == "bulk_feeder: t = 0.9/1 s (90%), 0.0025k steps/s, ETA 40s"


def test_without_a_terminal_slow_progress_still_shows_every_minute(monkeypatch):
    import vibrofeed.run_progress as P

    clock = [0.0]
    monkeypatch.setattr(P.time, "monotonic", lambda: clock[0])
    stream = io.StringIO()
    progress = RunProgress("single_part", stream=stream)
    progress({"event": "run", "n_steps": 10**6, "dt": 1e-6})
    for wall in range(1, 181):  # 1 % of the run in 3 minutes
        clock[0] = float(wall)
        progress({"event": "progress", "step": 55 * wall, "time": 55e-6 * wall, "wall": float(wall)})
    lines = stream.getvalue().splitlines()
    assert [line.split("(")[1].split(")")[0] for line in lines] == ["0.33%", "0.66%", "0.99%"]
    assert lines[0].endswith("ETA 5h02m")  # (10**6 - 3300) steps at 55 steps/s


def test_quiet_shows_no_progress_but_the_warnings():
    stream = io.StringIO()
    progress = RunProgress("single_part", enabled=False, stream=stream)
    progress({"event": "run", "n_steps": 10, "dt": 1e-3})
    progress({"event": "progress", "step": 5, "time": 5e-3, "wall": 100.0})
    assert stream.getvalue() == ""


@pytest.mark.parametrize("seconds, text", [
    (0, "0s"), (59.4, "59s"), (59.6, "1m00s"), (61, "1m01s"), (3599.4, "59m59s"),
    (3599.6, "1h00m"), (3661, "1h01m"), (36000, "10h00m"),
])
def test_a_duration_reads_in_seconds_minutes_or_hours_at_its_boundaries(seconds, text):
    """One format for a run's ETA, a sweep's and a study's (vibrofeed.values.duration)."""
    from vibrofeed.values import duration

    assert duration(seconds) == text
