"""One way to stop (vibrofeed/interrupt.py): SIGTERM and SIGHUP as Ctrl-C, runs in
other threads stopped and waited for, no run started once stopping began."""

import os
import signal
import threading
import time

import pytest

from vibrofeed import interrupt


@pytest.fixture
def fresh(monkeypatch):
    """The module's process-wide state, empty, and the signal handlers restored after."""
    monkeypatch.setattr(interrupt, "_stoppers", {})
    monkeypatch.setattr(interrupt, "_stopping", None)
    saved = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGHUP)}
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
    while len(interrupt._stoppers) < 3:
        time.sleep(0.01)
    interrupt.stop_all(interrupt.Terminated())
    returned = time.monotonic()
    assert sorted(n for n, _ in ended) == [0, 1, 2] and all(t <= returned for _, t in ended)
    # Once stopping, no run starts: register and check raise the same kind of interrupt.
    with pytest.raises(interrupt.Terminated):
        interrupt.register(lambda why: None)
    with pytest.raises(interrupt.Terminated):
        interrupt.check()
