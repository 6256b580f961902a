"""The run's progress display: warnings from the engine worker reach the user
whether or not a progress bar is shown."""

import io
import os
import sys

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


class Tty(io.StringIO):
    def isatty(self):
        return True


def test_a_bar_on_a_terminal_lines_elsewhere_unless_told(monkeypatch):
    assert RunProgress("p", stream=Tty()).mode == "bar"
    assert RunProgress("p", stream=io.StringIO()).mode == "lines"
    assert RunProgress("p", enabled=True, stream=io.StringIO()).mode == "bar"
    assert RunProgress("p", enabled=False, stream=Tty()).mode is None
    monkeypatch.setattr("sys.stderr", io.StringIO())
    assert RunProgress("p").stream is sys.stderr


@pytest.fixture
def clock(monkeypatch):
    import vibrofeed.run_progress as P

    now = [0.0]
    monkeypatch.setattr(P.time, "monotonic", lambda: now[0])
    return now


def lines_of(progress, clock, events):
    """The lines printed for ``events``: (clock time, event) pairs after a run of 10 steps of 0.1 s."""
    progress({"event": "run", "n_steps": 10, "dt": 0.1})
    for t, event in events:
        clock[0] = t
        progress({"event": "progress", **event})
    return progress.stream.getvalue().splitlines()


def test_a_line_is_due_five_seconds_after_the_last_at_a_further_tenth(clock):
    step1 = {"step": 1, "time": 0.1, "wall": 2.0}  # 0.5 steps/s: 9 steps left in 18 s
    lines = lines_of(RunProgress("p", stream=io.StringIO()), clock,
                     [(5.0, step1), (11.0, step1), (64.0, step1), (65.0, step1)])
    # 5 s after the run began, the first tenth: a line; the same tenth again only after 60 s
    assert lines == ["p: t = 0.1/1 s (10%), 0.0005k steps/s, ETA 18s"] * 2


def test_no_line_before_five_seconds_or_at_the_start(clock):
    assert lines_of(RunProgress("p", stream=io.StringIO()), clock,
                    [(4.9, {"step": 2, "time": 0.2, "wall": 4.9}), (61.0, {"step": 0, "time": 0.0})]) == []
    progress = RunProgress("p", stream=io.StringIO())
    progress({"event": "run", "n_steps": 100, "dt": 0.1})
    clock[0] = 5.0
    progress({"event": "progress", "step": 1, "time": 0.1, "wall": 5.0})  # still in the first tenth
    assert progress.stream.getvalue() == ""


def test_a_line_without_the_wall_time_has_no_rate(clock):
    lines = lines_of(RunProgress("p", stream=io.StringIO()), clock, [(5.0, {"step": 5, "time": 0.5})])
    assert lines == ["p: t = 0.5/1 s (50%), nank steps/s"]


def test_a_bar_counts_steps_and_shows_the_time(clock):
    stream = io.StringIO()
    progress = RunProgress("p", enabled=True, stream=stream)
    progress({"event": "run", "n_steps": 10, "dt": 0.1})
    bar = progress.bar
    assert (bar.total, bar.desc, bar.unit, bar.unit_scale, bar.leave) == (10, "p", "step", True, False)
    assert (bar.ncols, bar.dynamic_ncols) == (100, False)  # no terminal: a fixed width
    clock[0] = 10.0  # lines are due, but not beside a bar
    progress({"event": "progress", "step": 5, "time": 0.5, "wall": 10.0})
    progress({"event": "progress", "step": 8, "time": 0.8, "wall": 12.0})
    assert bar.n == 8 and bar.postfix == "t=0.8/1 s"
    progress({"event": "done"})
    assert progress.bar is None and "p: t = " not in stream.getvalue()
    progress.close()  # twice: nothing left to close


def terminal(columns):
    """A pseudo-terminal of ``columns`` columns (0: one that reports no size), as a stream."""
    import fcntl
    import pty
    import struct
    import termios

    master, slave = pty.openpty()
    if columns:
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, columns, 0, 0))
    return master, os.fdopen(slave, "w")


@pytest.mark.parametrize("columns, fixed", [(0, True), (1, False), (80, False)])
def test_a_terminal_without_a_size_gets_a_fixed_width(columns, fixed):
    master, stream = terminal(columns)
    try:
        progress = RunProgress("p", stream=stream)
        progress({"event": "run", "n_steps": 10, "dt": 0.1})
        assert progress.mode == "bar" and (progress.bar.ncols == 100) == fixed
        assert bool(progress.bar.dynamic_ncols) is not fixed
        progress.close()
    finally:
        stream.close()
        os.close(master)


class NoFd(io.StringIO):
    def fileno(self):
        raise ValueError("no file descriptor")


class Plain:
    """A stream with no fileno at all."""

    def __init__(self):
        self.text = []

    def write(self, s):
        self.text.append(s)

    def flush(self):
        pass

    def isatty(self):
        return False


def test_a_bar_on_a_stream_that_is_no_terminal_gets_a_fixed_width(tmp_path):
    with open(tmp_path / "log.txt", "w") as f:  # a file: OSError (not a terminal)
        streams = [f, NoFd(), Plain(), io.StringIO()]
        for stream in streams:
            progress = RunProgress("p", enabled=True, stream=stream)
            progress({"event": "run", "n_steps": 10, "dt": 0.1})
            assert progress.bar.ncols == 100 and not progress.bar.dynamic_ncols
            progress.close()


def test_a_wall_time_of_a_second_or_less_still_gives_a_rate(clock):
    """Any positive wall time measures a rate, however short: 5 steps in 1 s is 5 steps/s,
    the 5 left take 1 s; 6 steps in 0.5 s is 12 steps/s, the 4 left take 1/3 s."""
    lines = lines_of(RunProgress("p", stream=io.StringIO()), clock,
                     [(5.0, {"step": 5, "time": 0.5, "wall": 1.0}),
                      (10.0, {"step": 6, "time": 0.6, "wall": 0.5})])
    assert lines == ["p: t = 0.5/1 s (50%), 0.005k steps/s, ETA 1s",
                     "p: t = 0.6/1 s (60%), 0.012k steps/s, ETA 0s"]


def test_a_thousand_steps_per_second_read_as_1k(clock):
    # half of 10**6 steps in 500 s: 1000 steps/s, the other half in 500 s = 8m20s
    progress = RunProgress("p", stream=io.StringIO())
    progress({"event": "run", "n_steps": 10**6, "dt": 1e-6})
    clock[0] = 500.0
    progress({"event": "progress", "step": 500_000, "time": 0.5, "wall": 500.0})
    assert progress.stream.getvalue() == "p: t = 0.5/1 s (50%), 1k steps/s, ETA 8m20s\n"
