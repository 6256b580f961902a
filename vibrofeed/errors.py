"""Every error vibrofeed reports to its user, in one tree.

::

    VibrofeedError
    ├── InputError        exit status 2: the request is wrong; fix it and ask again
    │   ├── UsageError        a command-line option or argument
    │   ├── DeckError         a deck cannot be found or read, or breaks the deck conventions
    │   ├── ParameterError    a run parameter is unknown, malformed or non-physical
    │   ├── CaseError         a validation case file is malformed
    │   └── TrialFileError    a measured-trial file cannot be read
    └── RunError          exit status 1: a valid request failed while it was carried out
        ├── EngineError       LIGGGHTS stopped with an error (message, deck file:line)
        ├── LibraryNotFound   the LIGGGHTS shared library cannot be loaded
        ├── OutputError       a result cannot be written where asked
        └── ResultError       a file is not a readable vibrofeed result
            └── IncompleteResult  the run that wrote it did not complete

The command line prints any of them as one line (``vibrofeed: error: ...``)
and exits with the branch's ``exit_code``; anything else is a bug and keeps
its traceback. Library users catch :class:`VibrofeedError` or a branch.
"""

from __future__ import annotations

EXIT_FAILED = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


class VibrofeedError(Exception):
    """Base of the errors vibrofeed reports to its user as one line."""

    exit_code = EXIT_FAILED


# ----------------------------------------------------------------- input errors
class InputError(VibrofeedError, ValueError):
    """The request is wrong (a name, a value, a file's content): exit status 2."""

    exit_code = EXIT_USAGE


class UsageError(InputError):
    """A command-line option or argument is missing or out of range."""


class DeckError(InputError):
    """A deck cannot be found or read, or does not follow the deck conventions."""


class ParameterError(InputError):
    """A run parameter is unknown, malformed or non-physical."""


class CaseError(InputError):
    """A validation case file is malformed."""


class TrialFileError(InputError):
    """A file is not a readable measured vertical-transport trial."""

    def __init__(self, path, problem: str):
        self.path = str(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")


# ----------------------------------------------------------------- run failures
class RunError(VibrofeedError, RuntimeError):
    """A valid request failed while it was carried out: exit status 1.

    ``partial`` is ``(path, frames)`` when a failed run left frames behind.
    """

    exit_code = EXIT_FAILED
    partial: tuple | None = None


class EngineError(RunError):
    """LIGGGHTS stopped with an error.

    Attributes: ``message`` (LIGGGHTS' text), ``deck`` (path of the file the
    failing command is in: the deck or a file it includes), ``line`` and
    ``command`` (the command that failed, when it is known), ``phase``
    (``deck``, ``setup`` or ``run``), ``step`` and ``time`` (of the last frame
    written before the error), ``log``.
    """

    def __init__(self, message: str, *, deck: str | None = None, line: int | None = None,
                 command: str | None = None, phase: str | None = None,
                 step: int | None = None, time: float | None = None, log: str | None = None):
        self.message, self.deck, self.line, self.command = message, deck, line, command
        self.phase, self.step, self.time, self.log = phase, step, time, log
        super().__init__(str(self))

    def __str__(self) -> str:
        where = ""
        if self.line is not None:
            where = f" at {self.deck}:{self.line}: {self.command}"
        elif self.phase == "run" and self.step is not None:
            where = f" during the run, after the frame at t = {self.time:.6g} s (step {self.step})"
        elif self.phase == "run":
            where = " during the run"
        elif self.phase == "setup":
            where = " while setting up the run"
        return f"LIGGGHTS error: {self.message}{where}"


class LibraryNotFound(RunError):
    """The LIGGGHTS shared library could not be loaded."""


class OutputError(RunError):
    """The result cannot be written where asked."""


class ResultError(RunError):
    """A file is not a readable vibrofeed result."""


class IncompleteResult(ResultError):
    """The run that wrote the file did not complete."""


def said(value) -> str:
    """``value`` as a message shows it: as the user writes it, not as Python or numpy spell
    it. A number plainly (a numpy scalar as its number: ``0.05``, not ``np.float64(0.05)``;
    a float in its shortest exact form), text without quotes, ``true``/``false``, and lists
    and tables as TOML writes them (``[0.4, "a"]``, ``{ low = 1 }``): the sweep and study
    files' own words."""
    return _said(value, inner=False)


def _said(value, inner: bool) -> str:
    if getattr(value, "shape", None) == () and hasattr(value, "item"):  # a numpy scalar
        value = value.item()
    elif hasattr(value, "tolist") and not isinstance(value, list | tuple):  # a numpy array
        value = value.tolist()
    if isinstance(value, bytes):
        value = value.decode(errors="replace")
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_said(v, True) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_said(v, True)}" for k, v in value.items()) + " }"
    if isinstance(value, str) and inner:
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return str(value)


class ParameterWarning(UserWarning):
    """A value that runs but is almost certainly a slip (:mod:`vibrofeed.plausibility`; also
    importable from vibrofeed.parameters, its home before the feeders warned too)."""
