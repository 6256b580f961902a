"""One way to stop (vibrofeed/interrupt.py): SIGTERM and SIGHUP as Ctrl-C, runs in
other threads stopped and waited for, no run started once stopping began."""

import os
import signal
import threading
import time

import pytest

from helpers import run_in_flight
from vibrofeed import interrupt


@pytest.fixture
def fresh(monkeypatch):
    """The module's process-wide state, empty, and the signal handlers restored after."""
    monkeypatch.setattr(interrupt, "_stoppers", {})
    monkeypatch.setattr(interrupt, "_stopping", None)
    monkeypatch.setattr(interrupt, "_received", None)
    saved = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGHUP, signal.SIGINT)}
    for s in saved:  # as a command started from a terminal has them (the suite may run under nohup)
        signal.signal(s, signal.default_int_handler if s == signal.SIGINT else signal.SIG_DFL)
    yield
    for s, handler in saved.items():
        signal.signal(s, handler)


def test_sigterm_and_sighup_become_keyboard_interrupts_with_their_exit_status(fresh):
    interrupt.install()
    for signum, code in ((signal.SIGTERM, 143), (signal.SIGHUP, 129)):
        with pytest.raises(KeyboardInterrupt) as caught:
            os.kill(os.getpid(), signum)
            time.sleep(1)  # the handler runs at the next bytecode; never reached
        exc = caught.value
        assert isinstance(exc, interrupt.Terminated) and interrupt.exit_code(exc) == code
        assert interrupt.message(exc) == f"terminated ({signal.Signals(signum).name})"
        assert interrupt.reason(exc) == f"terminated by {signal.Signals(signum).name}"
    ctrl_c = KeyboardInterrupt()
    assert (interrupt.exit_code(ctrl_c), interrupt.message(ctrl_c)) == (130, "interrupted")


def test_a_signal_ignored_at_start_stays_ignored(fresh):
    signal.signal(signal.SIGHUP, signal.SIG_IGN)  # as under nohup
    interrupt.install()
    assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
    assert signal.getsignal(signal.SIGTERM) is interrupt._raise_terminated


def test_stop_all_stops_every_run_and_waits_for_their_threads(fresh):
    ended = []

    def run(name, stop_event):
        key = interrupt.register(lambda why: stop_event.set())
        stop_event.wait(5)
        time.sleep(0.2)  # recording the end takes a while
        ended.append((name, time.monotonic()))
        interrupt.unregister(key)

    events = [threading.Event() for _ in range(3)]
    threads = [threading.Thread(target=run, args=(i, e)) for i, e in enumerate(events)]
    for t in threads:
        t.start()
    deadline = time.monotonic() + 5  # fail, not hang, if the runs cannot register
    while len(interrupt._stoppers) < 3:
        assert time.monotonic() < deadline, "the runs did not register"
        time.sleep(0.01)
    interrupt.stop_all(interrupt.Terminated())
    returned = time.monotonic()
    assert sorted(n for n, _ in ended) == [0, 1, 2] and all(t <= returned for _, t in ended)
    # Once stopping, no run starts: register and check raise the same kind of interrupt.
    with pytest.raises(interrupt.Terminated):
        interrupt.register(lambda why: None)
    with pytest.raises(interrupt.Terminated):
        interrupt.check()


def test_terminated_defaults_to_sigterm_and_ctrl_c_has_its_own_words():
    exc = interrupt.Terminated()
    assert exc.signum is signal.SIGTERM and exc.exit_code == 143
    ctrl_c = KeyboardInterrupt()
    assert interrupt.reason(ctrl_c) == "interrupted by the user"
    assert interrupt.exit_code(ctrl_c) == 130


def test_stopping_on_ctrl_c_tells_the_runs_why_and_refuses_new_ones(fresh):
    told = []
    key = interrupt.register(told.append)
    other = interrupt.register(told.append)
    assert key != other
    interrupt.unregister(other)
    interrupt.unregister(12345)  # an unknown key: nothing to do
    assert list(interrupt._stoppers) == [key]
    threading.Timer(0.05, interrupt.unregister, (key,)).start()  # the run records its end
    interrupt.stop_all(KeyboardInterrupt(), timeout=5)
    assert told == ["interrupted by the user"] and not interrupt._stoppers
    with pytest.raises(KeyboardInterrupt) as caught:
        interrupt.check()
    assert not isinstance(caught.value, interrupt.Terminated)


def test_a_new_run_is_refused_with_the_signal_that_stops_the_process(fresh):
    interrupt.stop_all(interrupt.Terminated(signal.SIGHUP), timeout=0)
    with pytest.raises(interrupt.Terminated) as caught:
        interrupt.register(lambda why: None)
    assert caught.value.signum is signal.SIGHUP and caught.value.exit_code == 129
    assert not interrupt._stoppers


class Condition:
    """threading.Condition, recording how long stop_all would wait."""

    def __init__(self):
        self.waits = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def wait_for(self, predicate, timeout=None):
        self.waits.append((predicate(), timeout))
        return predicate()


def test_stop_all_waits_thirty_seconds_at_most(fresh, monkeypatch):
    cond = Condition()
    monkeypatch.setattr(interrupt, "_cond", cond)
    monkeypatch.setitem(interrupt._stoppers, 1, lambda why: None)  # a run that never ends
    interrupt.stop_all(KeyboardInterrupt())
    assert cond.waits == [(False, 30.0)]


def test_stop_left_stops_the_runs_a_failed_command_left_and_waits_for_them(fresh):
    """A command ending on an error stops the runs other threads still wait for, as
    Ctrl-C does: each is told why, has recorded its end when stop_left returns, and
    stop_left says there were some."""
    record: list = []
    thread = run_in_flight(record, wait=5)
    assert interrupt.stop_left("stopped: the command ended on an error", timeout=5) is True
    assert record == ["stopped: the command ended on an error", "recorded its end"]
    assert not interrupt._stoppers
    with pytest.raises(KeyboardInterrupt):  # and no run starts after
        interrupt.check()
    thread.join(5)


def test_stop_left_with_no_run_left_stops_nothing(fresh):
    assert interrupt.stop_left("why") is False
    assert interrupt._stopping is None
    interrupt.check()  # later runs of this process may still start
    interrupt.unregister(interrupt.register(lambda why: None))


def test_stop_left_after_stop_all_neither_stops_nor_waits_again(fresh, monkeypatch):
    """Ctrl-C's stop_all had its wait for a run that would not end: stop_left, in the
    command's last step, neither calls that run's stopper again nor waits for it."""
    told = []
    interrupt.register(told.append)  # a run that never unregisters
    interrupt.stop_all(KeyboardInterrupt(), timeout=0)
    assert told == ["interrupted by the user"]
    cond = Condition()
    monkeypatch.setattr(interrupt, "_cond", cond)
    assert interrupt.stop_left("stopped: the command ended on an error") is False
    assert told == ["interrupted by the user"] and cond.waits == []


def test_stop_left_waits_thirty_seconds_at_most(fresh, monkeypatch):
    """As long as stop_all waits after Ctrl-C: the command line calls stop_left with
    its default."""
    cond = Condition()
    monkeypatch.setattr(interrupt, "_cond", cond)
    told = []
    monkeypatch.setitem(interrupt._stoppers, 1, told.append)  # a run that never ends
    assert interrupt.stop_left("stopped: the command ended on an error") is True
    assert told == ["stopped: the command ended on an error"]
    assert cond.waits == [(False, 30.0)]


def test_the_interrupt_that_stops_the_process_keeps_no_frame_alive(fresh):
    """Render's Ctrl-C printed 27 lines of 'Exception ignored in ... __del__' after
    'interrupted': the interrupt kept as the process's reason to stop held its traceback, so
    the plotter in render's frame lived on until the interpreter was half torn down."""
    import gc
    import weakref

    class Plotter:
        pass

    def render():
        plotter = Plotter()
        render.plotter = weakref.ref(plotter)
        raise KeyboardInterrupt

    try:
        render()
    except KeyboardInterrupt as exc:
        interrupt.stop_all(exc)
    gc.collect()
    assert render.plotter() is None
    assert interrupt._stopping.__traceback__ is None
    with pytest.raises(KeyboardInterrupt):
        interrupt.check()  # (still stopping: no new run starts)


def test_ctrl_c_a_library_turns_into_its_own_error_is_an_interrupt(fresh, monkeypatch, capsys):
    """Ctrl-C while render loaded VTK ended in a 29-line traceback of VTK's ImportError, exit
    status 1."""
    from vibrofeed import cli
    from vibrofeed.cli import render

    def loading(args):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1)  # the handler runs at the next bytecode; never reached
        except BaseException:  # as VTK's importer does: its own error instead
            raise ImportError("Failed to load vtkRenderingContextOpenGL2") from None

    monkeypatch.setattr(render, "run", loading)
    assert cli.main(["render", "r.h5"]) == 130
    assert capsys.readouterr().err == "vibrofeed: error: interrupted\n"
    monkeypatch.setattr(interrupt, "_received", None)  # without a signal, the error is the error

    def failing(args):
        raise ImportError("Failed to load vtkRenderingContextOpenGL2")

    monkeypatch.setattr(render, "run", failing)
    with pytest.raises(ImportError):
        cli.main(["render", "r.h5"])
