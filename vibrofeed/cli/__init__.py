"""The ``vibrofeed`` command line: one module per command.

``COMMANDS`` lists every command with the module that implements it and its
one-line help. Only the module of the command being run is imported (it adds
its own arguments and runs), so ``vibrofeed decks`` does not load the models,
h5py or the plotting libraries that other commands need.

A command module defines ``DESCRIPTION``, ``add_arguments(parser)`` and
``run(args) -> int`` and imports what it needs inside ``run``. Errors of the
:mod:`vibrofeed.errors` tree are printed as one line (``vibrofeed: error:
...``) with their branch's exit status (2 for bad input, 1 for a failed run);
an :class:`OSError` (a full disk, a folder where a file is written, a file
that may not be written) is one line too, with exit status 2 for a path that
cannot be written and 1 otherwise (:func:`vibrofeed.cli.outputs.os_error`);
anything else is a bug and keeps its traceback (``VIBROFEED_DEBUG=1`` shows
tracebacks for the user errors too).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import warnings

from .. import __version__, environment, interrupt
from ..errors import VibrofeedError

# name -> (module, one-line help), in the order `vibrofeed --help` lists them.
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("vibrofeed.cli.demo", "run the main job: a bulk feeder, its feed rate and singulation"),
    "run": ("vibrofeed.cli.run", "run a deck and write an H5MD result"),
    "check": ("vibrofeed.cli.check", "validate result files against the format"),
    "validate": ("vibrofeed.cli.validate", "run DEM and analytic model on the validation cases"),
    "sweep": ("vibrofeed.cli.sweep", "run a deck over a design of parameters (grid, lists, replicates)"),
    "sweep-report": ("vibrofeed.cli.sweep_report", "a sweep's table, best setting and feed-rate maps"),
    "optimize": ("vibrofeed.cli.optimize", "find the best feeder settings in few DEM runs (a study file)"),
    "optimize-report": ("vibrofeed.cli.optimize_report", "a study's answer, convergence, Pareto front, "
                        "importances"),
    "replay": ("vibrofeed.cli.replay", "replay measured vertical-transport trials"),
    "decks": ("vibrofeed.cli.decks", "list the decks in decks/"),
    "params": ("vibrofeed.cli.params", "list a deck's parameters with defaults and units"),
    "prepare": ("vibrofeed.cli.prepare", "write a deck's meshes and templates for a run by hand"),
    "feedrate": ("vibrofeed.cli.feedrate", "feed rate and conveying speed of a bulk-feeder result"),
    "singulation": ("vibrofeed.cli.singulation", "doubles, gaps and clusters of a bulk-feeder result"),
    "orientation": ("vibrofeed.cli.orientation", "parts delivered the right way up, per station and "
                    "along the path"),
    "render": ("vibrofeed.cli.render", "draw a frame (PNG) or a movie (MP4) of a result"),
    "export": ("vibrofeed.cli.export", "write a result as a ParaView time series (.pvd)"),
}


def fail(message: str, code: int) -> int:
    """Print one error line and return the exit status."""
    print(f"vibrofeed: error: {message}", file=sys.stderr)
    return code


# The options `vibrofeed` itself takes before COMMAND (argparse also takes their prefixes).
_TOP_OPTIONS = ("-h", "--help", "--version")


def _unknown_top_option(argv: list[str]) -> str | None:
    """The first word before COMMAND that is an option `vibrofeed` does not take: argparse
    would only say that COMMAND is missing."""
    for word in argv:
        if not word.startswith("-") or word == "--":
            return None
        name = word.split("=", 1)[0]
        if name == "-h" or (len(name) > 2 and any(o.startswith(name) for o in _TOP_OPTIONS[1:])):
            continue
        return word
    return None


def _requested(argv: list[str]) -> str | None:
    """The command named on the command line (the first word that is not an option)."""
    for word in argv:
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


class _Parser(argparse.ArgumentParser):
    """argparse, with its usage errors as the one line every error is."""

    def error(self, message: str):
        # prog is "vibrofeed" or "vibrofeed COMMAND": the error line names the command once.
        command = self.prog.removeprefix("vibrofeed").strip()
        where = f"{command}: " if command else ""
        self.exit(2, f"vibrofeed: error: {where}{message} (see {self.prog} --help)\n")


class _StoreOnce(argparse._StoreAction):
    """An option that takes a value: given twice with two values, it is refused (argparse
    would keep the last without a word)."""

    def __call__(self, parser, namespace, values, option_string=None):
        given = namespace.__dict__.setdefault("_given_options", {})
        if self.dest in given and given[self.dest][1] != values:
            first, text = given[self.dest][0], given[self.dest][2]
            parser.error(f"{first} given twice, as {first} {text} and {option_string} "
                         f"{self._text(values)}; give it once")
        given[self.dest] = (option_string, values, self._text(values))
        super().__call__(parser, namespace, values, option_string)

    @staticmethod
    def _text(values) -> str:
        """The value as the user wrote it (a number read as 1.0 shows as 1; --size as WxH)."""
        if isinstance(values, list):
            return " ".join(map(_StoreOnce._text, values))
        if isinstance(values, tuple):
            return "x".join(map(_StoreOnce._text, values))
        return f"{values:g}" if isinstance(values, float) else str(values)


def _once(parser: argparse.ArgumentParser) -> None:
    """Make every option of ``parser`` that stores a value one that may be given once."""
    for action in parser._actions:
        if type(action) is argparse._StoreAction and action.option_strings:
            action.__class__ = _StoreOnce


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The parser, with the arguments of the requested command only (or of all
    commands when ``argv`` is None, for documentation and tests)."""
    parser = _Parser(
        prog="vibrofeed",
        description="DEM simulation of vibratory feeding of micro-parts with LIGGGHTS.")
    parser.add_argument("--version", action="version", version=f"vibrofeed {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    wanted = set(COMMANDS) if argv is None else {_requested(argv)}
    for name, (module_name, help_text) in COMMANDS.items():
        if name not in wanted:
            sub.add_parser(name, help=help_text, add_help=False)
            continue
        module = importlib.import_module(module_name)
        p = sub.add_parser(name, help=help_text, description=module.DESCRIPTION)
        module.add_arguments(p)
        _once(p)
        p.set_defaults(func=module.run)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """vibrofeed's own warnings (a parameter that looks like a unit slip) as one line."""
    if category.__module__.startswith("vibrofeed"):
        print(f"vibrofeed: warning: {message}", file=sys.stderr)
    else:
        _python_show_warning(message, category, filename, lineno, file, line)


_python_show_warning = warnings.showwarning


def main(argv: list[str] | None = None) -> int:
    warnings.showwarning = _show_warning
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv)
    unknown = _unknown_top_option(argv)
    if unknown is not None:
        parser.error(f"unrecognized option {unknown}")
    args = parser.parse_args(argv)
    args.__dict__.pop("_given_options", None)
    try:  # the documented environment variables: one that means nothing stops the command now
        debug = environment.debug()
        environment.check()
    except VibrofeedError as exc:
        return fail(str(exc), exc.exit_code)
    interrupt.install()  # SIGTERM ends a command as Ctrl-C does
    try:
        try:
            return args.func(args)
        except Exception:  # noqa: BLE001 (an interrupt that a library turned into its own error)
            if interrupt.received() is None:
                raise
            raise interrupt.received() from None
    except KeyboardInterrupt as exc:
        try:  # runs waited for in other threads (sweeps, validation) record their end too
            interrupt.stop_all(exc)
        except KeyboardInterrupt:  # a second signal: leave now
            pass
        kept = getattr(exc, "kept", None)  # a run's: what it left behind, on the same line
        return fail(interrupt.message(exc) + (f"; {kept}" if kept else ""), interrupt.exit_code(exc))
    except BrokenPipeError:
        # The reader stopped (`vibrofeed ... | head`): no traceback, and none again when
        # Python flushes stdout at exit (the recipe of the signal module's documentation).
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except OSError as exc:  # met while writing: a full disk, a folder where a file goes...
        if debug:
            raise
        from .outputs import os_error

        return fail(*os_error(exc))
    except VibrofeedError as exc:
        if debug:
            raise
        partial = getattr(exc, "partial", None)  # the frames a failed run left, on the same line
        kept = (f"; the {partial[1]} frames written before the failure are kept in {partial[0]} "
                "(status: failed)") if partial else ""
        return fail(str(exc) + kept, exc.exit_code)
    finally:
        try:
            interrupt.stop_left("stopped: the command ended on an error")
        except KeyboardInterrupt:  # a signal while waiting for them: leave now
            pass
