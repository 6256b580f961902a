"""Run a deck through LIGGGHTS in a worker process and collect its result.

The parent never loads LIGGGHTS: an engine error ends the worker, and the
parent turns that end into an :class:`EngineError` naming LIGGGHTS' message
and the deck line. The worker is started with the MPI launcher variables of
any surrounding MPI job removed from its environment (``OMPI_*``, ``PMIX_*``,
``OPAL_*``, ``ORTE_*``, and a Slurm allocation's ``SLURM_*``), as a singleton
or under its own ``mpirun`` on the local node, so a failing run inside a sweep
never takes the sweep down with it.

While the run goes, frames land in ``OUT.h5.part``; only a completed run is
renamed to ``OUT.h5``, replacing an earlier one only then. A run that fails or
is interrupted after writing frames leaves ``OUT.h5.part`` with its frames and
``parameters/run@status`` saying what happened; one that fails before its first
frame leaves nothing.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import queue
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from .. import __version__, environment, interrupt
from ..decks import Deck
from ..disk import mount_point
from ..errors import EngineError, OutputError, RunError, UsageError, said
from ..parameters import resolve
from ..results import layout as L
from . import scratch
from .log import failed_command, find_error
from .protocol import MARK
from .watchdog import Watchdog

# SLURM_ too: under a Slurm allocation (a sweep started by srun or mpirun in a batch job) the
# worker's own mpirun would spread its ranks over the allocation's nodes instead of the
# leader's, and a singleton worker would take itself for a task of the srun step.
_LAUNCHER_PREFIXES = ("OMPI_", "PMIX_", "OPAL_", "ORTE_", "PRTE_", "HYDRA_", "PMI_", "SLURM_")

# Ranks started per core at most: Open MPI oversubscribes on request, but far
# beyond the cores a run only slows down, and thousands of ranks never start.
RANKS_PER_CORE = 4

# Space held in each run's scratch folder, beside its output, and given back when the disk
# fills: enough for the worker to drop the batch it could not write and close the file whole,
# marked failed (HDF5 cut short mid-flush leaves a file that does not open).
RESERVE_BYTES = 512 * 1024


@dataclass
class RunResult:
    output: Path
    log: Path
    deck: str
    ranks: int
    n_steps: int = 0
    dt: float = 0.0
    frames: int = 0
    natoms: int = 0
    sim_time: float = 0.0
    wall: float = 0.0
    parameters: dict = field(default_factory=dict)
    run_id: str = ""
    reused: bool = False  # an earlier complete result with the same run id was kept
    target_error: float | None = None  # the feed rate's relative error the run was to stop at
    stop_reason: str = ""  # why the engine ended it (layout.STOP_AT_END, ...; FORMAT.md)

    @property
    def stopped_early(self) -> bool:
        """Whether the run stopped before its end, its target error reached."""
        return L.stopped_early(self.stop_reason)

    @property
    def steps_per_second(self) -> float:
        return self.n_steps / self.wall if self.wall > 0 else float("nan")


def clean_environment(env: Mapping[str, str] | None = None) -> dict:
    """The environment minus the variables of a surrounding MPI launch."""
    env = dict(os.environ if env is None else env)
    return {k: v for k, v in env.items() if not k.startswith(_LAUNCHER_PREFIXES)}


def abort_shim() -> Path | None:
    """The library that flushes LIGGGHTS' output before MPI_Abort
    (``VIBROFEED_ABORT_SHIM`` overrides).

    The package's installer builds it next to this module from
    ``native/abort_flush.c`` (setup.py). Without it the message of an
    ``error->one`` (e.g. a mesh file that cannot be opened) is lost in an
    unflushed buffer; runs still work.
    """
    given = environment.abort_shim()  # (one that does not exist is refused)
    if given is not None:
        return given
    path = Path(__file__).resolve().parent / "libvibrofeed_abortflush.so"
    return path if path.is_file() else None


def max_ranks() -> int:
    """The most MPI ranks a run may ask for here: RANKS_PER_CORE per core this
    process may use, or the tasks of a Slurm allocation, or VIBROFEED_MAX_RANKS."""
    given = environment.max_ranks()  # (one that is no number of ranks is refused)
    if given is not None:
        return given
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    slurm = os.environ.get("SLURM_NTASKS", "")
    return max(RANKS_PER_CORE * cores, int(slurm) if slurm.isdigit() else 0)


def _limit_said(limit: int) -> str:
    """Where the rank limit ``limit`` comes from, in words for an error."""
    if environment.max_ranks() is not None:
        return f"at most {limit} (VIBROFEED_MAX_RANKS={limit})"
    return (f"at most {limit} ({RANKS_PER_CORE} per core or the Slurm tasks; set VIBROFEED_MAX_RANKS "
            "to change the limit)")


def check_ranks(ranks) -> int:
    """``ranks`` if it is a number of MPI ranks this machine can start, else UsageError."""
    if isinstance(ranks, bool) or not isinstance(ranks, int) or ranks < 1:
        raise UsageError(f"the number of ranks must be a positive integer, got {said(ranks)}")
    limit = max_ranks()
    if ranks > limit:
        raise UsageError(f"{ranks} ranks is more than this machine can run: {_limit_said(limit)}")
    return ranks


# A run estimated to take longer than this [h] says so before it starts, unless
# VIBROFEED_LONG_RUN_HOURS sets another threshold.
LONG_RUN_HOURS = 1.0


class LongRunWarning(UserWarning):
    """A run estimated to take longer than ``VIBROFEED_LONG_RUN_HOURS`` (:func:`warn_long_run`)."""


def estimated_seconds(values: Mapping[str, str]) -> tuple[float, float, float] | None:
    """(wall seconds, steps, timestep [s]) a run of resolved ``values`` is estimated to take on
    one core (:func:`vibrofeed.parameters.run_steps`, each step at
    :func:`~vibrofeed.parameters.step_seconds`: its parts' spheres count); None when it cannot
    be estimated."""
    import math

    from ..parameters import run_steps, step_seconds

    numbers = {}
    for name, text in values.items():
        try:
            numbers[name] = float(text)
        except (TypeError, ValueError):
            continue
    estimate = run_steps(numbers)
    if estimate is None or not math.isfinite(estimate[0]):
        return None
    steps, dt = estimate
    return steps * step_seconds(numbers), steps, dt


def long_run(values: Mapping[str, str]) -> str | None:
    """How long a run of resolved ``values`` will take, when more than
    ``VIBROFEED_LONG_RUN_HOURS`` (:func:`estimated_seconds`); None when less, or not estimated."""
    from ..values import duration

    estimate = estimated_seconds(values)
    hours = environment.long_run_hours() or LONG_RUN_HOURS
    if estimate is None:
        return None
    seconds, steps, dt = estimate
    if seconds <= hours * 3600:
        return None
    span = f"{seconds / 86400:.3g} days" if seconds >= 2 * 86400 else duration(seconds)
    given = "" if float(values.get("dt", 0) or 0) > 0 else " (automatic)"
    return (f"this run will take about {span}: {steps:.3g} steps of dt={dt:.3g} s{given} at "
            f"{steps / seconds:,.0f} steps/s (one core, its parts' spheres counted); "
            f"VIBROFEED_LONG_RUN_HOURS={hours:g} sets when this is said")


def warn_long_run(values: Mapping[str, str]) -> None:
    """Say before a run starts how long it will take, when that is long (:func:`long_run`)."""
    import warnings

    text = long_run(values)
    if text:
        warnings.warn(text, LongRunWarning, stacklevel=3)


def check_at_once(workers: int, ranks: int, ranks_name: str = "ranks_per_run = ") -> None:
    """``-j workers`` runs of ``ranks`` MPI ranks each, at once: UsageError when that is more
    ranks than this machine can run (:func:`max_ranks`), as one run of that many is.
    ``ranks_name``: how the user gave ``ranks`` (a sweep's key, a command's ``-n``)."""
    limit = max_ranks()
    if workers > 1 and workers * ranks > limit:
        each = f" of {ranks_name}{ranks} ranks each" if ranks > 1 else ""
        raise UsageError(f"-j {workers}: {workers} runs at once{each} is {workers * ranks} ranks, more "
                         f"than this machine can run: {_limit_said(limit)}; give -j "
                         f"{max(limit // ranks, 1)} or less")


def run_id(deck: Deck, values: Mapping[str, str], before_run=None, schedule=None,
           target_error: float | None = None) -> str:
    """The identity of a run (signac's state point idea): a SHA-256 over the
    text of the deck and of every file it includes, the resolved parameters,
    any commands a driver adds, the target error if any (it decides where the run
    ends), and the vibrofeed version. Equal ids mean the same computation, so a
    complete result with the id can stand in for it."""
    state = {
        "deck": deck.name,
        "sources": deck.sources,
        "parameters": {k: str(v) for k, v in sorted(values.items())},
        "before_run": list(before_run or ()),
        "schedule": schedule,
        "vibrofeed": __version__,
    }
    if target_error is not None:  # absent otherwise: the ids of other runs stay as they were
        state["target_error"] = float(target_error)
    text = json.dumps(state, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def check_target_error(target, deck: Deck) -> float | None:
    """``target`` (the feed rate's relative error to stop at) if ``deck`` can be stopped at
    it, else UsageError: it must lie in (0, 1), and the deck must have an outlet (define
    the bulk-feeder variables of ``layout.BULK_CONTRACT``, as the worker tells a bulk deck)."""
    if target is None:
        return None
    try:
        value = float(target)
    except (TypeError, ValueError):
        raise UsageError(f"target error must be a number, got {said(target)}") from None
    if not 0 < value < 1:  # NaN too
        raise UsageError(f"target error {target} is outside (0, 1): it is the feed rate's "
                         "relative error (0.03: 3 %)")
    if not any(name in deck.formulas for name in L.BULK_CONTRACT):
        raise UsageError(f"target error: deck {deck.name} has no outlet (it is not a bulk feeder) "
                         "and measures no feed rate")
    return value


def _reusable(out: Path, rid: str, deck: Deck, values, ranks: int) -> RunResult | None:
    """A RunResult for ``out`` if it is a complete result with run id ``rid`` that ``vibrofeed
    check`` accepts (an earlier vibrofeed may have completed a run that check rejects)."""
    if not out.is_file():
        return None
    from ..errors import ResultError
    from ..results.reader import Result

    try:
        with Result(out) as r:  # refuses files of runs that did not complete
            if r.run_id != rid:
                return None
            frames = r.n_frames
            natoms = int(r.present(frames=[frames - 1])[0]) if frames else 0
            n_steps = int(r.step[-1] - r.step[0]) if frames else 0
            sim_time = float(r.time[-1] - r.time[0]) if frames else 0.0
            wall = float(r.run_info.get("wall_seconds", 0.0))
            target, reason = r.target_error, r.stop_reason
    except (ResultError, KeyError):
        return None
    if check_problem(out):  # a result vibrofeed check rejects stands in for no run
        return None
    return RunResult(output=out, log=out.with_suffix(".log"), deck=deck.name, ranks=ranks,
                     n_steps=n_steps, dt=sim_time / n_steps if n_steps else 0.0, frames=frames,
                     natoms=natoms, sim_time=sim_time, wall=wall, parameters=dict(values),
                     run_id=rid, reused=True, target_error=target, stop_reason=reason)


def worker_command(spec_path: str, ranks: int, shim: Path | None = None) -> list[str]:
    base = [sys.executable, "-m", "vibrofeed.engine.worker", spec_path]
    if ranks == 1:
        return base  # an MPI singleton
    mpirun = shutil.which("mpirun")
    if mpirun is None:
        raise RunError("mpirun not found: install openmpi-bin to run on several ranks")
    cmd = [mpirun, "-n", str(ranks), "--oversubscribe"]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        cmd.append("--allow-run-as-root")  # Open MPI refuses root otherwise
    if shim is not None:
        cmd += ["-x", f"LD_PRELOAD={shim}"]  # the ranks only, not mpirun itself
    return cmd + base


# A singleton's MPI start, as Open MPI does it by default, spawns an orted server and probes
# UCX (0.37 s of wall here); neither is of use to one rank that never spawns nor talks to
# another, and without them MPI_Init takes 0.06 s (BENCHMARKS.md). (clean_environment has
# taken every OMPI_ variable out: a surrounding launch's settings are not the worker's.)
SINGLETON_MPI = {"OMPI_MCA_ess_singleton_isolated": "1", "OMPI_MCA_pml": "ob1"}


def worker_environment(ranks: int, shim: Path | None) -> dict:
    env = clean_environment()
    if ranks == 1:
        env.update(SINGLETON_MPI)
    if shim is not None and ranks == 1:
        env["LD_PRELOAD"] = f"{shim} {env['LD_PRELOAD']}" if env.get("LD_PRELOAD") else str(shim)
    return env


def _with_parent_death_signal(cmd: list[str]) -> list[str]:
    """``cmd`` run so that it gets SIGTERM when vibrofeed dies (even by
    SIGKILL), through util-linux's setpriv: an exec wrapper, unlike a Python
    preexec_fn, which is not safe to fork from a program with threads."""
    setpriv = shutil.which("setpriv")
    return [setpriv, "--pdeathsig", "TERM", "--"] + cmd if setpriv else cmd


def unfinished(path: Path) -> Path:
    """The name ``path`` has while its run goes (``OUT.h5.part``, ``OUT.log.part``): renamed
    to ``path`` only when the run completes, so a finished result and its log are replaced
    together, by a run that finished too."""
    return path.with_name(path.name + ".part")


def output_files(output) -> tuple[Path, Path, Path]:
    """The files a run into ``output`` writes: the result, its unfinished ``OUT.part`` and
    its log (``OUT.log``: the result's suffix replaced; ``OUT.log.part`` while it runs)."""
    out = Path(output).expanduser().absolute()
    log = out.with_suffix(".log") if out.suffix else out.with_name(out.name + ".log")
    return out, out.with_name(out.name + ".part"), log


def deck_inputs(deck: Deck) -> set[Path]:
    """The files a run of ``deck`` reads: the deck, the files it includes, the files its
    commands name under ``${deck_dir}`` (meshes) and the feeder description it came from."""
    files = {deck.path, *(c.file for c in deck.commands if c.file is not None)}
    for c in deck.commands:
        for word in c.text.split():
            if word.startswith("${deck_dir}/"):
                files.add(deck.include_dir / word.removeprefix("${deck_dir}/"))
    if deck.description is not None:
        files.add(Path(deck.description.path))
    return {f.resolve() for f in files}


def check_output(deck: Deck, output, option: str = "output") -> None:
    """Refuse, before anything runs, an ``output`` whose files (:func:`output_files`) would
    pass for another's or replace an input: a name ending in ``.part`` (a complete result
    would be left under the name of an unfinished one, which ``vibrofeed check`` fails), a
    ``.log`` (the result and its log would be one file), and any of its files being one the
    run reads (:func:`deck_inputs`)."""
    out, part, log = output_files(output)
    if out.name.endswith(".part"):
        raise UsageError(f"{option} {output}: a name ending in .part is a run's unfinished result "
                         f"(the run writes {part.name} until it completes); give the result's own "
                         f"name, such as {out.name.removesuffix('.part')}")
    if out == log:
        raise UsageError(f"{option} {output}: the run writes its LIGGGHTS log as OUT.log, so the "
                         "result and its log would be one file; give the result another suffix "
                         "(.h5)")
    inputs = deck_inputs(deck)
    for what, path in (("the result", out), ("its unfinished result", part), ("its log", log),
                       ("its unfinished log", unfinished(log))):
        if path.resolve() in inputs:
            raise UsageError(f"{option} {output}: {what} would replace {path.name}, which the run "
                             f"reads (deck {deck.name}); give another output name")


def _prepare_output(output) -> tuple[Path, Path, Path]:
    out = Path(output).expanduser().resolve()
    if out.is_dir():
        raise OutputError(f"output {output} is a directory; give a file name such as {out / 'result.h5'}")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create folder {out.parent} for the output: {exc.strerror}") from None
    part = out.with_name(out.name + ".part")
    try:
        with open(part, "wb"):
            pass
        part.unlink()
    except OSError as exc:
        raise OutputError(f"cannot write {output}: {exc.strerror}") from None
    log = out.with_suffix(".log") if out.suffix else out.with_name(out.name + ".log")
    return out, part, log


def _frames_in(path: Path) -> tuple[int, int | None, float | None]:
    """(frames, last step, last time) held by a result file; (0, None, None) if unreadable. A
    frame counts once its step, its time and its positions are all written: a disk that filled
    up between them leaves the datasets a frame apart."""
    try:
        import h5py

        # No lock: a rank that outlived its group's kill may still hold the file open.
        with h5py.File(path, "r", locking=False) as f:
            position = f[f"{L.PARTS}/position"]
            step, time = position["step"], position["time"]
            n = min(len(step), len(time), len(position["value"]))
            if n == 0:
                return 0, None, None
            return n, int(step[n - 1]), float(time[n - 1])
    except (OSError, KeyError):
        return 0, None, None


def _unreadable(path: Path) -> bool:
    """A file that exists but HDF5 cannot open (never deleted: it may hold frames)."""
    if not path.exists():
        return False
    try:
        import h5py

        with h5py.File(path, "r", locking=False):
            return False
    except OSError:
        return True


def run_deck(deck: Deck, params: Mapping[str, str], output, *, ranks: int = 1,
             on_event: Callable[[dict], None] | None = None, command: str = "",
             before_run: list[str] | None = None, schedule: list[dict] | None = None,
             reuse: bool = False, target_error: float | None = None) -> RunResult:
    """Run ``deck`` with ``params`` (name -> value strings) into ``output``.

    ``before_run``: LIGGGHTS commands issued after the deck, before the first
    step. ``schedule``: a prescribed run as segments ``{"commands": [...],
    "steps": n}`` (commands, then n steps with setup, then a frame) instead of
    the deck's own ``n_steps`` in frames of ``output_every``.

    ``on_event`` receives the worker's messages (``run``, ``progress``,
    ``done``...) as dicts, for progress display. ``reuse``: keep ``output``
    and return at once if it is a complete result with this run's id (see
    :func:`run_id`). ``target_error``: a bulk feeder's run stops as soon as its feed
    rate's relative error (as ``vibrofeed feedrate`` reports it) is at or below it, else
    at its end; ``RunResult.stop_reason`` says which (:func:`check_target_error`).
    Raises :class:`~vibrofeed.errors.ParameterError` or
    :class:`~vibrofeed.errors.UsageError` before starting anything if a
    parameter, the rank count or the target error is bad, :class:`OutputError` if the output
    cannot be written (a full disk included), :class:`EngineError` if
    LIGGGHTS stops with an error, :class:`RunError` for any other failure of
    the run: a worker that stops answering (:mod:`.watchdog`), parts lost or
    a mass balance that does not close. KeyboardInterrupt (Ctrl-C, or SIGTERM
    through :mod:`vibrofeed.interrupt`) stops the worker and marks the file
    ``interrupted``.
    """
    interrupt.check()  # a process being stopped starts no run (queued runs of other threads)
    check_ranks(ranks)
    target_error = check_target_error(target_error, deck)
    values = resolve(deck, params)
    check_output(deck, output)
    rid = run_id(deck, values, before_run, schedule, target_error)
    out, part, log = _prepare_output(output)
    if reuse:
        kept = _reusable(out, rid, deck, values, ranks)
        if kept is not None:
            return kept
    warn_long_run(values)
    # An earlier OUT.h5 stays until this run completes and replaces it (os.replace in finish):
    # a rerun that fails or is killed must not take a finished result with it.
    part.unlink(missing_ok=True)
    unfinished(log).unlink(missing_ok=True)  # a killed run's; OUT.log stays with OUT.h5
    scratch.remove_abandoned(out.parent)

    run = _Run(deck, values, rid, out, part, log, ranks, on_event, target_error)
    key = interrupt.register(run.stop)
    try:
        run.prepare(command, before_run, schedule)
        run.start()
        run.follow()
        if run.stopped is not None:  # by interrupt.stop_all, from the main thread
            raise KeyboardInterrupt(run.stopped)
        return run.finish()
    except KeyboardInterrupt as exc:
        exc.kept = run.interrupted(run.stopped or interrupt.reason(exc))  # what the user is told
        raise
    finally:
        run.remove_scratch()
        interrupt.unregister(key)


class _Run:
    """One run of the worker, in steps: its scratch folder and spec, the process,
    its messages, and how it ended (``OUT.h5``, or ``OUT.h5.part`` with a status)."""

    def __init__(self, deck: Deck, values: dict, rid: str, out: Path, part: Path, log: Path,
                 ranks: int, on_event, target_error: float | None = None):
        self.deck, self.values, self.rid, self.ranks = deck, values, rid, ranks
        self.target_error = target_error
        self.out, self.part, self.log = out, part, log
        self.log_part = unfinished(log)  # the LIGGGHTS log until the run completes
        self.on_event = on_event
        self.tmp: Path | None = None
        self.proc: subprocess.Popen | None = None
        self.events: list[dict] = []
        self.rc: int | None = None
        self.hung: str | None = None     # why the watchdog gave up on the worker
        self.stopped: str | None = None  # why another thread stopped the run
        self._starting = threading.Lock()  # stop() and start() one after the other
        self.started = time.monotonic()

    def prepare(self, command: str, before_run, schedule) -> None:
        """The scratch folder: the deck's own files for this run (meshes,
        templates, if it declares a prepare hook) and the worker's spec."""
        try:
            self.tmp = scratch.make(self.out.parent)
            scratch.name_outputs(self.tmp, self.part, self.log_part)
            with open(self.reserve, "wb") as fh:
                fh.write(bytes(RESERVE_BYTES))
                fh.flush()
                os.fsync(fh.fileno())
            self._write_spec(command, before_run, schedule)
        except OSError as exc:
            if exc.errno != errno.ENOSPC:
                raise
            raise OutputError(f"no space left on {mount_point(self.out.parent)} for the run's scratch "
                              f"folder in {self.out.parent}") from None

    def _write_spec(self, command: str, before_run, schedule) -> None:
        deck, values = self.deck, self.values
        prepared = deck.prepare(values, self.tmp)
        spec = {
            "deck": str(deck.path), "deck_dir": str(deck.include_dir), "deck_name": deck.name,
            "variables": values,
            "var_meta": {n: [v.unit, v.description, v.default] for n, v in deck.tunables.items()},
            "constants": deck.constants,
            "output": str(self.part), "log": str(self.log_part), "screen": str(self.screen),
            "seed": int(float(values["seed"])) if "seed" in values else None,
            "command": command, "run_id": self.rid, "sources": deck.sources,
            "before_run": list(before_run or ()),
            "schedule": schedule,
            "reserve": str(self.reserve),  # to free when the disk fills
            "target_error": self.target_error,  # stop once the feed rate is this precise (None: t_end)
            # extra -var values, the track mesh and the clump template (vibrofeed.geometry.Prepared)
            "prepared": prepared.to_spec() if prepared is not None else None,
            # the feeder description the deck was generated from (recorded with the result)
            "description": None if deck.description is None else {
                "text": deck.description.source, "name": deck.description.name,
                "path": str(deck.description.path.resolve())},
        }
        self.spec_path.write_text(json.dumps(spec))

    @property
    def screen(self) -> Path:
        return self.tmp / "screen.txt"

    @property
    def reserve(self) -> Path:
        return self.tmp / "reserve"

    @property
    def spec_path(self) -> Path:
        return self.tmp / "spec.json"

    @property
    def stderr_path(self) -> Path:
        return self.tmp / "stderr.txt"

    def start(self) -> None:
        self.started = time.monotonic()
        shim = abort_shim()
        with self._starting, open(self.stderr_path, "w") as stderr:
            if self.stopped is not None:
                raise KeyboardInterrupt(self.stopped)
            self.proc = subprocess.Popen(
                _with_parent_death_signal(worker_command(str(self.spec_path), self.ranks, shim)),
                stdout=subprocess.PIPE, stderr=stderr, env=worker_environment(self.ranks, shim),
                cwd=str(self.out.parent), text=True, start_new_session=True)

    def follow(self) -> None:
        """Pass the worker's messages on until it ends, or until the watchdog
        finds it hung (then it is stopped, and ``hung`` says why)."""
        lines: queue.Queue = queue.Queue()

        def read(stream):
            for line in stream:
                lines.put(line)
            lines.put(None)

        reader = threading.Thread(target=read, args=(self.proc.stdout,), daemon=True)
        reader.start()
        watch = Watchdog(time.monotonic())
        while True:
            try:
                line = lines.get(timeout=0.5)
            except queue.Empty:  # judged only with every message read: if this process
                self.hung = watch.stalled(time.monotonic())  # was suspended, it is behind
                if self.hung is not None:
                    _stop(self.proc)
                    break
                continue
            if line is None:
                break
            if line.startswith(MARK):
                try:
                    event = json.loads(line[len(MARK):])
                except ValueError:  # cut short by the worker's end
                    continue
                watch.saw(event, time.monotonic())
                if event["event"] != "alive":  # the heartbeat is the watchdog's only
                    self.events.append(event)
                    if self.on_event is not None:
                        self.on_event(event)
        self.rc = self.proc.wait()
        # After a hung worker is stopped its pipe ends too; a process that escaped the
        # group could hold it open, so the reader is waited for a while only.
        reader.join(timeout=5)

    def stop(self, why: str) -> None:
        """Stop the worker from another thread; the run's own thread records the end."""
        with self._starting:
            self.stopped = why
            if self.proc is not None:
                _signal_group(self.proc, signal.SIGTERM)

    def interrupted(self, why: str) -> str:
        """Stop the worker; keep its frames marked ``interrupted`` with its log (or nothing,
        before the first frame); what was kept, in words."""
        if self.proc is not None:
            _stop(self.proc)
        frames = _frames_in(self.part)[0] if self.part.exists() else 0
        if frames:
            if _mark(self.part, L.STATUS_INTERRUPTED, why):
                return (f"the {frames} frames written before the interruption are kept in "
                        f"{self.part} (status: interrupted)")
            return (f"the {frames} frames written are kept in {self.part}, which could not be "
                    "marked interrupted")
        if _unreadable(self.part):
            return f"{self.part} is kept as it is: HDF5 cannot open it"
        self.part.unlink(missing_ok=True)
        self.log_part.unlink(missing_ok=True)
        return f"interrupted before its first frame: nothing written ({self.out.name} not touched)"

    def event(self, kind: str) -> dict | None:
        return next((e for e in self.events if e["event"] == kind), None)

    def finish(self) -> RunResult:
        """The result of a run that reached its end, else the error it ended with."""
        done = self.event("done")
        if self.hung is not None:
            self.fail(RunError(f"deck {self.deck.name}: {self.hung}: stopped it"))
        if self.rc != 0 or done is None:
            self.fail(self.diagnose())
        unbalanced = _mass_balance_problem(done.get("counts"))
        if unbalanced:
            self.fail(RunError(f"deck {self.deck.name}: {unbalanced}"))
        self.complete()
        start = self.event("run")
        result = RunResult(output=self.out, log=self.log, deck=self.deck.name, ranks=self.ranks,
                           parameters=self.values, run_id=self.rid,
                           target_error=self.target_error, stop_reason=done.get("stop_reason", ""))
        result.wall = time.monotonic() - self.started
        result.n_steps, result.dt = done["step"], start["dt"]  # steps run: fewer if stopped early
        result.frames, result.natoms = done["frames"], done["natoms"]
        result.sim_time = result.n_steps * result.dt
        return result

    def complete(self) -> None:
        """Mark the file ``complete``, check it as ``vibrofeed check`` would and rename it to
        OUT.h5, one step after the other: only a file that is about to be OUT.h5 says
        ``complete`` (a kill between them leaves a ``.part`` that ``vibrofeed check`` fails),
        and a result that check rejects is a failed run (its file says ``failed``)."""
        from ..results.writer import mark_file_status

        if not mark_file_status(self.part, L.STATUS_COMPLETE):
            self.fail(OutputError(f"cannot mark {self.part} complete"))
        rejected = check_problem(self.part)
        if rejected:
            self.fail(RunError(f"deck {self.deck.name}: the result is not sound, vibrofeed check "
                               f"rejects it: {rejected}"))
        os.replace(self.part, self.out)
        if self.log_part.exists():  # the log goes with its result, never before it
            os.replace(self.log_part, self.log)

    def diagnose(self) -> RunError:
        frames, last_step, last_time = _frames_in(self.part) if self.part.exists() else (0, None, None)
        own = self.event("error")
        if own is not None and own.get("no_space"):
            where = f"{self.part} ({frames} frames)" if frames else str(self.part)
            return OutputError(f"no space left on {mount_point(self.part.parent)} while writing {where}")
        return _diagnose(self.rc, self.events, self.deck, self.log_part, self.screen, self.stderr_path,
                         last_step, last_time)

    def fail(self, error: RunError):
        """Record ``error`` in the file (kept if it holds frames, or after a full
        disk whatever it holds) and raise it; ``error.partial`` names the file
        if it holds frames and says ``failed``."""
        frames = _frames_in(self.part)[0] if self.part.exists() else 0
        full = isinstance(error, OutputError) and str(error).startswith("no space left")
        if frames:
            if _mark(self.part, L.STATUS_FAILED, str(error)):
                error.partial = (self.part, frames)
        elif not full and not _unreadable(self.part):
            self.part.unlink(missing_ok=True)  # nothing in it; a file we cannot read is kept
        raise error

    def remove_scratch(self) -> None:
        if self.tmp is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)


def check_problem(path: Path) -> str | None:
    """The first error ``vibrofeed check`` finds in the result ``path`` of a run that reached
    its end (a part faster than the drive can make it, lost parts, ...; the file may still be
    a ``.part``), else None: a run whose own result check would reject has failed."""
    from ..results.check import check_file  # h5py: only when needed

    errors = [p for p in check_file(path, allow_incomplete=True).problems if p.level == "error"]
    if not errors:
        return None
    more = len(errors) - 1
    return errors[0].message + (f" (and {more} more problem{'s' * (more > 1)}: vibrofeed check "
                                f"--allow-incomplete {path.name} lists them)" if more else "")


def _mass_balance_problem(counts: dict | None) -> str | None:
    """What is wrong with a bulk run's final mass balance, or None."""
    if not counts or counts.get("lost", 0) == 0:
        return None
    inserted, lost = counts["inserted"], counts["lost"]
    what = (f"{lost} of {inserted} parts were lost (they left without crossing the outlet)"
            if lost > 0 else f"{-lost} part(s) counted twice")
    return (f"{what}: the mass balance does not close (inserted {inserted}, on the track "
            f"{counts['on_track']}, exited {counts['exited']}"
            + (f", rejected {counts['rejected']}" if "rejected" in counts else "")
            + (f", returned {counts['returned']})" if "returned" in counts else ")"))


def _signal_group(proc: subprocess.Popen, sig: int) -> None:
    try:
        os.killpg(proc.pid, sig)
        os.killpg(proc.pid, signal.SIGCONT)  # a stopped worker acts on the signal only once woken
    except ProcessLookupError:
        pass


def _group_ended(proc: subprocess.Popen, seconds: float) -> bool:
    """Wait up to ``seconds`` for the worker and every process of its group (the MPI
    ranks can outlive mpirun) to end."""
    end = time.monotonic() + seconds
    try:
        proc.wait(timeout=seconds)
    except subprocess.TimeoutExpired:
        return False
    while time.monotonic() < end:
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.05)
    return False


def _stop(proc: subprocess.Popen) -> None:
    """End the worker and its ranks: SIGTERM (it flushes its frames and exits), SIGKILL
    after 10 s; returns when none is left that could still write the result."""
    _signal_group(proc, signal.SIGTERM)
    if not _group_ended(proc, 10):
        _signal_group(proc, signal.SIGKILL)
        _group_ended(proc, 10)


def _mark(path: Path, status: str, why: str, seconds: float = 15.0) -> bool:
    """Set a stopped run's file status, waiting up to ``seconds`` for the file's lock: an MPI
    rank that outlived its group's end may still be closing the file (on a loaded machine
    the status once stayed ``running``). False if it still cannot be opened."""
    from ..results.writer import mark_file_status  # h5py: only when needed

    end = time.monotonic() + seconds
    while _locked(path) and time.monotonic() < end:  # (a file not locked: marked at once)
        time.sleep(0.2)
    return mark_file_status(path, status, why)


def _locked(path: Path) -> bool:
    """Whether another process holds the HDF5 file's lock."""
    import h5py

    try:
        with h5py.File(path, "r+"):
            return False
    except OSError as exc:
        return "lock" in str(exc).lower()


def _read(path: Path) -> str:
    try:
        return path.read_text(errors="replace")
    except OSError:
        return ""


def _diagnose(rc, events, deck: Deck, log: Path, screen: Path, stderr: Path,
              step: int | None, t: float | None) -> RunError:
    """Turn a worker that stopped early into the error a user should read.

    ``step`` and ``t`` are those of the last frame written, if any.
    """
    phase = next((e["event"] for e in reversed(events) if e["event"] in ("deck", "setup", "run")), None)
    own = next((e for e in events if e["event"] == "error"), None)
    if own is not None:
        return RunError(f"deck {deck.name}: {own['message']}")
    log_text, screen_text = _read(log), _read(screen)
    err, in_log = find_error(log_text), True
    if err is None:  # error->one writes to the screen only
        err, in_log = find_error(screen_text), False
    if err is not None:
        line = command = None
        where = deck.path
        if phase == "deck":
            cmd = failed_command(log_text, deck, before=err.line_index if in_log else None)
            if cmd is not None:  # in the deck or in a file it includes
                line, command, where = cmd.line, cmd.text, cmd.file or deck.path
        return EngineError(err.message, deck=_display(where), line=line, command=command,
                           phase=phase, step=step, time=t, log=str(log))
    tail = " ".join(_read(stderr).strip().splitlines()[-3:])
    if "MPI_ABORT" in tail:
        return EngineError("LIGGGHTS aborted on one rank (its message is in that rank's output): "
                           + tail, phase=phase, step=step, time=t, log=str(log))
    if rc is not None and rc < 0:
        return RunError(f"the engine was killed by signal {-rc} "
                        f"({signal.Signals(-rc).name}) during the {phase or 'start'} phase")
    return RunError(f"the engine worker exited with status {rc} during the {phase or 'start'} phase"
                    + (f": {tail}" if tail else ""))


def _display(path: Path) -> str:
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)
