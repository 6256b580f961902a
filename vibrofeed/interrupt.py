"""One way for a vibrofeed process to stop when told to: Ctrl-C (SIGINT), SIGTERM, SIGHUP.

SIGTERM is what ``timeout``, Slurm at the end of a job's time and a cluster's
preemption send (SIGHUP: a closed terminal or ssh session). The command line
turns them into :class:`Terminated`, a :class:`KeyboardInterrupt`, so every
signal takes one path: every run in flight is stopped, its file marked
``interrupted`` with its frames kept, its scratch folder removed. Runs waited
for in other threads (sweeps, validation) cannot see the main thread's
exception: the runner registers a stopper for each run here, and
:func:`stop_all` calls them and waits until their threads have cleaned up.
Once stopping has begun, no new run starts (:func:`check`). A command that ends on
an error while runs are in flight in other threads stops them the same way
(:func:`stop_left`): they are never left to die with the interpreter.
"""

from __future__ import annotations

import itertools
import signal
import threading
from collections.abc import Callable

from .errors import EXIT_INTERRUPTED


class Terminated(KeyboardInterrupt):
    """SIGTERM (or SIGHUP: the terminal or the ssh session closed) arrived: the
    process ends as after Ctrl-C, with exit status 128 + the signal's number."""

    def __init__(self, signum: int = signal.SIGTERM):
        super().__init__(signum)
        self.signum = signal.Signals(signum)
        self.exit_code = 128 + self.signum


def exit_code(exc: KeyboardInterrupt) -> int:
    return getattr(exc, "exit_code", EXIT_INTERRUPTED)


def message(exc: KeyboardInterrupt) -> str:
    """The command line's one line about it."""
    return f"terminated ({exc.signum.name})" if isinstance(exc, Terminated) else "interrupted"


def reason(exc: KeyboardInterrupt) -> str:
    """What stopped the run, as the result file records it."""
    return f"terminated by {exc.signum.name}" if isinstance(exc, Terminated) else "interrupted by the user"


# The signal that arrived, if any: code that turns the KeyboardInterrupt into another error
# (VTK's importer, met by Ctrl-C while render loads it, raises ImportError) does not hide it.
_received: KeyboardInterrupt | None = None


def _raise_terminated(signum, frame):
    global _received
    _received = Terminated(signum)
    raise Terminated(signum)


def _raise_interrupt(signum, frame):
    global _received
    _received = KeyboardInterrupt()
    signal.default_int_handler(signum, frame)


def received() -> KeyboardInterrupt | None:
    """The interrupt a signal raised in this command, if one did (:func:`install`)."""
    return _received


def install() -> None:
    """Turn SIGTERM and SIGHUP into :class:`Terminated` (from the main thread of a
    command), and remember each of them and Ctrl-C (:func:`received`); a signal this process
    was started ignoring (``nohup``, ``&``) stays ignored."""
    for signum, handler in ((signal.SIGTERM, _raise_terminated), (signal.SIGHUP, _raise_terminated),
                            (signal.SIGINT, _raise_interrupt)):
        if signal.getsignal(signum) is not signal.SIG_IGN:
            signal.signal(signum, handler)


_cond = threading.Condition()
_stoppers: dict[int, Callable[[str], None]] = {}
_ids = itertools.count()
_stopping: KeyboardInterrupt | None = None


def register(stop: Callable[[str], None]) -> int:
    """Add a run's stopper (called with the reason); the key for :func:`unregister`.
    Raises the interrupt at once if the process is already stopping."""
    with _cond:
        check()
        key = next(_ids)
        _stoppers[key] = stop
        return key


def unregister(key: int) -> None:
    with _cond:
        _stoppers.pop(key, None)
        _cond.notify_all()


def check() -> None:
    """Raise the interrupt that is stopping the process, if any: no new work starts."""
    if isinstance(_stopping, Terminated):
        raise Terminated(_stopping.signum)
    if _stopping is not None:
        raise KeyboardInterrupt()


def stop_all(exc: KeyboardInterrupt, timeout: float = 30.0, why: str | None = None) -> None:
    """Stop every registered run with ``why`` (default: ``exc``'s reason) and wait (at
    most ``timeout`` s) until each has recorded how it ended."""
    global _stopping
    with _cond:
        # what the interrupt was, not the exception itself: its traceback would keep every
        # frame it passed through alive to the interpreter's end, where their objects'
        # finalisers fail on a half torn-down interpreter ('Exception ignored in ...': 27
        # lines after render's 'interrupted', from pyvista's plotter)
        _stopping = Terminated(exc.signum) if isinstance(exc, Terminated) else KeyboardInterrupt()
        stoppers = list(_stoppers.values())
    for stop in stoppers:
        stop(why or reason(exc))
    with _cond:
        _cond.wait_for(lambda: not _stoppers, timeout=timeout)


def stop_left(why: str, timeout: float = 30.0) -> bool:
    """Stop the runs still registered as a command ends (an error in the main thread
    while other threads wait for runs) as :func:`stop_all` does; whether there were any.
    A daemon thread left in a run would be cut off mid-call by the interpreter's end,
    its scratch folder kept and its file's status unwritten."""
    with _cond:
        if not _stoppers or _stopping is not None:  # none, or stop_all has had its wait
            return False
    stop_all(KeyboardInterrupt(), timeout, why)
    return True
