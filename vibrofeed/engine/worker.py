"""The engine worker: one process per MPI rank, driving one LIGGGHTS run.

Started by :mod:`vibrofeed.engine.runner` (``python -m vibrofeed.engine.worker
SPEC.json``, under its own ``mpirun`` for several ranks), never imported by
the parent: LIGGGHTS ends this process on an error, and only this process.

The worker executes the deck with ``driver=1``, so the deck sets everything up
but neither dumps nor runs. It then reads the deck's contract variables
(``n_steps``, ``output_every``, ``surface_*``: see ``results.layout``), runs
``output_every`` steps at a time and, between runs, gathers the particles to
rank 0, which appends a frame to the H5MD file and flushes it.

Rank 0 reports to the parent on stdout, one JSON object per line prefixed
with ``@vibrofeed``: phases (``deck``, ``setup``, ``run``), progress, the end,
and every second a heartbeat with the engine's step (:class:`Heartbeat`). The
end is recorded in the file as ``running`` (the runner writes ``complete`` as it
renames the file); SIGTERM flushes the frames and records ``interrupted``
(:class:`OnTerminate`).

A bulk feeder's deck (it defines ``outlet_x``, ``catch_z``, ``n_inserted``,
``body_spheres``: ``results.layout.BULK_CONTRACT``) also gets parts as bodies
(:mod:`.bodies`: one row per multisphere clump, with its orientation), outlet
events and the mass balance (:mod:`.outlet`), and the track mesh and clump
template the runner's prepare hook made (``spec["prepared"]``) in the file. A
feeder line's deck (``sections`` > 1) also defines each further section's motion
(``s2_surface_*``: ``results.layout.surface_variables``), recorded at every frame beside
section 1's, and the file says which section each track vertex belongs to. A line with an
orienting station (an air jet, :mod:`.jets`) is sensed at every frame on rank 0; new firings
redefine the jet's switch before the next segment (collective) and are recorded
(``vibrofeed/jet``).

A bulk run given a target error (``spec["target_error"]``, ``vibrofeed run --target-error``)
stops once the feed rate's relative error is at or below it (:class:`TargetError`): rank 0
judges the file written so far with :class:`~vibrofeed.postproc.feedrate.FeedRate`, as
``vibrofeed feedrate`` will judge the result, and every rank learns whether to stop. The file
records why the run ended (``parameters/run@stop_reason``).
"""

from __future__ import annotations

import errno
import json
import math
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import DeckError  # the deck cannot be run as vibrofeed drives it
from ..models.constants import G
from ..results import layout as L
from .bodies import aggregate, atom_parts, spheres
from .protocol import MARK

PER_ATOM = ("id", "type", "radius", "rmass", "x", "v", "omega", "f")
HEARTBEAT_SECONDS = 1.0
# --target-error: a check reads every frame so far, so checks are spaced by this fraction of
# the time run so far: their total cost is that of ~1/CHECK_FRACTION reads per e-fold of the
# run, and a run stops at most this fraction later than a check at every frame would stop it.
CHECK_FRACTION = 0.05


class Reporter:
    """Rank 0's messages to the parent; silent on other ranks. Thread-safe: the
    heartbeat reports from its own thread."""

    def __init__(self, rank: int):
        self.rank = rank
        self._lock = threading.Lock()

    def __call__(self, event: str, **data) -> None:
        if self.rank == 0:
            text = MARK + json.dumps({"event": event, **data}) + "\n"
            with self._lock:
                sys.stdout.write(text)
                sys.stdout.flush()


class Heartbeat:
    """Rank 0 says ``alive`` every HEARTBEAT_SECONDS with the engine's step, from a
    thread (the engine releases the GIL while it runs), so the parent can tell a
    worker that stopped answering (stopped, or waiting for a hung rank) from a
    slow one."""

    def __init__(self, report: Reporter):
        self.report = report
        self._counter = None  # the engine's step counter, while there is an engine
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._beat, daemon=True)
        if report.rank == 0:
            self._thread.start()

    def watch(self, counter) -> None:
        """Report the step read from ``counter`` (None: stop reading it, before the engine closes)."""
        with self._lock:
            self._counter = counter

    def _beat(self) -> None:
        while not self._stop.wait(HEARTBEAT_SECONDS):
            with self._lock:
                step = int(self._counter[0]) if self._counter is not None else None
            self.report("alive", step=step, at=time.monotonic())

    def stop(self) -> None:
        """End the beats and wait for the last one: the worker leaves with ``os._exit``,
        which would cut a message short mid-write."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()


class OnTerminate:
    """SIGTERM (the runner stopping the run, or the parent's death) flushes the
    frames written so far and records the end, then exits 143 at once.

    A Python signal handler would wait for the engine's current ``run`` to
    return; instead SIGTERM is blocked in every thread (call :meth:`block`
    before MPI or any thread starts) and one thread waits for it."""

    writer = None  # rank 0's ResultWriter, once open

    @staticmethod
    def block() -> None:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})

    def __init__(self):
        threading.Thread(target=self._wait, daemon=True).start()

    def _wait(self) -> None:
        signal.sigwait({signal.SIGTERM})
        writer = self.writer
        if writer is not None:
            try:
                writer.finish(L.STATUS_INTERRUPTED, "the engine worker was sent SIGTERM")
            except Exception:  # ending anyway: the runner reports what it can
                pass
        sys.stdout.flush()
        os._exit(128 + signal.SIGTERM)


def engine_version(log_path: str) -> str:
    try:
        with open(log_path, errors="replace") as fh:
            first = fh.readline().strip()
    except OSError:
        first = ""
    return first if first.startswith("LIGGGHTS") else "LIGGGHTS (version line not found in log)"


_EXIT_HOOKS = []  # keep the ctypes callbacks alive


def flush_on_engine_exit(writer) -> None:
    """Write the writer's pending frames when LIGGGHTS ends the process.

    An engine error calls C exit() (error->all) or MPI_Abort (error->one) from
    inside a library call: no Python exception, no Python atexit. A C exit
    handler (glibc's on_exit; atexit itself is not exported) covers the
    first; the abort shim's hook (native/abort_flush.c, when preloaded)
    covers the second.
    """
    import ctypes

    def flush(*_):
        try:
            writer.flush()
        except Exception:  # the process is ending: never raise into C
            pass

    on_exit_cb = ctypes.CFUNCTYPE(None, ctypes.c_int, ctypes.c_void_p)(flush)
    abort_cb = ctypes.CFUNCTYPE(None)(flush)
    _EXIT_HOOKS.extend([on_exit_cb, abort_cb])
    libc = ctypes.CDLL("libc.so.6")
    libc.on_exit(on_exit_cb, None)
    setter = getattr(ctypes.CDLL(None), "vibrofeed_set_abort_hook", None)
    if setter is not None:
        setter.argtypes = [ctypes.CFUNCTYPE(None)]
        setter(abort_cb)


def gather_atoms(lmp, comm, names=PER_ATOM) -> dict | None:
    """Per-atom arrays of every atom on rank 0 (None elsewhere)."""
    local = lmp.local_atoms(names)
    if comm.size == 1:
        return local
    pieces = comm.gather(local, root=0)
    if comm.rank != 0:
        return None
    return {k: np.concatenate([p[k] for p in pieces]) for k in names}


def gather_parts(lmp, comm) -> dict | None:
    """All particles on rank 0 (None elsewhere), as the writer wants them."""
    cat = gather_atoms(lmp, comm)
    return None if cat is None else atom_parts(cat)


def _load_array(value, keys=()):
    """An array given inline (nested lists) or as a file (.npz under one of
    ``keys``, .npy, or whitespace text such as a LIGGGHTS clump file)."""
    if value is None:
        return None
    if isinstance(value, (str, os.PathLike)):
        path = Path(value)
        if path.suffix == ".npz":
            with np.load(path) as data:
                key = next((k for k in keys if k in data.files), data.files[0])
                return data[key]
        if path.suffix == ".npy":
            return np.load(path)
        return np.loadtxt(path, ndmin=2)
    return np.asarray(value)


def prepared_geometry(spec: dict) -> tuple[tuple | None, np.ndarray | None]:
    """(track (vertices, triangles) or None, body template (n, 4) or None) from
    the prepare hook's part of the spec (vibrofeed.geometry.Prepared)."""
    prepared = spec.get("prepared") or {}
    track = prepared.get("track")
    if isinstance(track, (str, os.PathLike)):
        path = Path(track)
        with np.load(path) as data:
            track = (data["vertices"], data["triangles"])
    if track is not None:
        track = (np.asarray(track[0], dtype=float).reshape(-1, 3),
                 np.asarray(track[1], dtype=np.int32).reshape(-1, 3))
    template = _load_array(prepared.get("body_template"), ("body_template", "template"))
    if template is not None:
        template = np.asarray(template, dtype=float).reshape(-1, 4)
    return track, template


class BulkFrames:
    """A bulk feeder's frames: parts as bodies, outlet events, the mass balance.

    Built on every rank (the deck's variables are evaluated collectively);
    :meth:`frame` returns (parts, events, rejects, counts) on rank 0, None elsewhere;
    rejects (parts fallen off a side) only for a feeder that has them (a line:
    vibrofeed.feeders.Feeder.has_rejects), else None.
    """

    def __init__(self, lmp, spec: dict):
        from ..feeders.feeder import Feeder
        from .outlet import LineOutlet, Outlet, gravity_vector

        self.n_spheres = int(round(lmp.variable("body_spheres")))
        g = lmp.variable("g") if lmp.has_variable("g") else G
        variables = spec.get("variables", {})
        incline = float(variables.get("incline", 0.0))
        where = (lmp.variable("outlet_x"), lmp.variable("catch_z"), gravity_vector(g, incline))
        # the feeder the deck's parameters describe (None: a deck of one's own without the
        # feeders' vocabulary, run as a single track)
        self.feeder = Feeder.from_values(variables) if "part_size" in variables else None
        feeder = self.feeder
        # parts fallen off a side, caught by the section they fell from (a line)
        self.rejects = feeder is not None and feeder.has_rejects
        self.outlet = (LineOutlet(*where, feeder.catch_x, feeder.exit_band) if self.rejects
                       else Outlet(*where))
        # recirculation (a line's rejects back to the inlet): the driver's, never by hand
        self.returns = None
        if feeder is not None and feeder.returns_rejects:
            from .returns import Returns

            self.returns = Returns(float(variables.get("return_delay", 0.0)),
                                   int(float(variables.get("seed", 5489))), lmp.dt)
        # a line's air jets (orienting stations): sensed and fired by the driver (.jets)
        self.jets = None
        if feeder is not None and feeder.has_jets:
            from .jets import Jets

            self.jets = Jets(feeder)
        self.atom_ranges = None  # {body: (first, last atom id)} at the last frame (ideal jets)
        self.track, self.template = prepared_geometry(spec)
        if self.jets is not None:  # the jets classify in the analyses' body frame
            self.jets.use_template(self.template)
        # which vertices of the track move with which further element (None: it has none, or
        # the track does not tell)
        further = feeder is not None and bool(feeder.further_elements)
        self.track_sections = track_sections(self.track, variables) if further else None
        self.names = PER_ATOM + (("molecule",) if self.n_spheres > 1 else ())
        self.warnings: list[str] = []
        if further and self.track is not None and self.track_sections is None:
            self.warnings.append("the line's track mesh does not end with its further sections' "
                                 "meshes: the file cannot say which vertices move with which section")
        if self.template is not None and self.n_spheres > 1 and len(self.template) != self.n_spheres:
            raise ValueError(f"the body template has {len(self.template)} spheres, the deck's "
                             f"body_spheres is {self.n_spheres}")

    def template_from_first_body(self, lmp, comm) -> None:
        """Without a template from the prepare hook, take the first clump as it is
        now (orientations are then relative to that clump's pose at the start)."""
        if self.n_spheres <= 1 or self.template is not None:
            return
        atoms = gather_atoms(lmp, comm, self.names)
        template = None
        if atoms is not None and len(atoms["id"]):
            first = atoms["molecule"] == atoms["molecule"].min()
            order = np.argsort(atoms["id"][first])
            x = atoms["x"][first][order]
            template = np.column_stack([x - x.mean(axis=0), atoms["radius"][first][order]])
            self.warnings.append("no body template from the deck's prepare hook: orientations "
                                 "are relative to the first part's pose at the start")
        self.template = comm.bcast(template, root=0) if comm.size > 1 else template
        if self.jets is not None:
            self.jets.use_template(self.template)

    def frame(self, lmp, comm, time: float):
        inserted = int(round(lmp.variable("n_inserted")))  # collective: on every rank
        returned = self.returns.returned(lmp) if self.returns is not None else None
        if returned is not None:
            inserted += returned  # a returned part is inserted anew
        atoms = gather_atoms(lmp, comm, self.names)
        if atoms is None:
            return None
        if self.jets is not None and self.jets.ideal and self.n_spheres > 1:
            from .jets import atom_ranges

            self.atom_ranges = atom_ranges(atoms)
        if self.n_spheres > 1:
            parts, incomplete = aggregate(atoms, self.template, self.n_spheres)
            if incomplete and not any("incomplete" in w for w in self.warnings):
                self.warnings.append(f"{incomplete} clump(s) with fewer than {self.n_spheres} "
                                     f"spheres at t = {time:g} s (identity orientation)")
        else:
            parts = spheres(atoms)
        if self.rejects:
            events, rejects, counts = self.outlet.step(time, parts, inserted)
            if returned is not None:
                counts["returned"] = returned
            return parts, events, rejects, counts
        events, counts = self.outlet.step(time, parts, inserted)
        return parts, events, None, counts


def surface_state(lmp, section: int = 1) -> tuple[list, list]:
    """(position, velocity) of a section's surface now, from the deck's equal-style variables
    (section 1: surface_*, section k: s<k>_surface_*); collective, on every rank."""
    names = L.surface_variables(section)
    return [lmp.variable(n) for n in names[0]], [lmp.variable(n) for n in names[1]]


def surface_rotation(lmp) -> tuple[list, list]:
    """A rotating surface's (angle, angular velocity) as rotation vectors about z, from the
    deck's ``L.ROTATION_VARIABLES``; collective, on every rank."""
    angle, rate = (lmp.variable(n) for n in L.ROTATION_VARIABLES)
    return [0.0, 0.0, angle], [0.0, 0.0, rate]


def rotating(lmp) -> bool:
    """Whether the deck's surface turns (it defines both ``L.ROTATION_VARIABLES``); one of them
    alone is refused before anything runs."""
    have = [lmp.has_variable(n) for n in L.ROTATION_VARIABLES]
    if any(have) and not all(have):
        missing = [n for n, h in zip(L.ROTATION_VARIABLES, have) if not h]
        raise DeckError(f"the deck defines its surface's rotation only in part: {', '.join(missing)} "
                        "missing (docs/decks.md)")
    return all(have)


def recorded_sections(lmp, spec: dict) -> int:
    """The sections whose motion the deck defines: 1, or a line's 2, 3, ... (s<k>_surface_x
    defined for k = 2 ... n). A line (``sections`` > 1) whose deck does not define them cannot be
    recorded as FORMAT.md says: refused before anything runs."""
    n = 1
    while lmp.has_variable(L.surface_variables(n + 1)[0][0]):
        n += 1
    wanted = int(float(spec.get("variables", {}).get("sections", 1)))
    if wanted > n:
        missing = [name for k in range(n + 1, wanted + 1) for group in L.surface_variables(k)
                   for name in group if not lmp.has_variable(name)]
        raise DeckError(f"a line of {wanted} sections: the deck does not define the equal-style "
                        f"variable(s) {', '.join(missing)} of its sections' motion (docs/decks.md)")
    for k in range(2, n + 1):  # all six, as for section 1 (DECK_CONTRACT)
        missing = [name for group in L.surface_variables(k) for name in group
                   if not lmp.has_variable(name)]
        if missing:
            raise DeckError(f"the deck defines section {k}'s motion only in part: "
                            f"{', '.join(missing)} missing")
    return n


def track_sections(track, variables: dict) -> np.ndarray | None:
    """(V,) the section (1-based) of each vertex of a line's track, or None when it cannot be
    told. The prepare hook writes section 1's mesh, then appends each further section's
    (vibrofeed.feeders.Feeder.further_meshes of the same parameters), each with its own
    vertices: the track's last vertices must be those meshes exactly, and only then are they
    theirs."""
    from ..feeders.feeder import Feeder

    if track is None:
        return None
    vertices = track[0]
    try:
        further = [m[0] for m in Feeder.from_values(variables).further_meshes()]
    except (ValueError, ArithmeticError):  # a bad value, or a dimension missing (0: a division by it)
        return None
    n1 = len(vertices) - sum(len(v) for v in further)
    if n1 <= 0 or not further or not np.array_equal(vertices[n1:], np.concatenate(further)):
        return None
    return np.repeat(np.arange(1, len(further) + 2, dtype=np.int32), [n1] + [len(v) for v in further])


def _includes(spec: dict) -> dict[str, str]:
    """The texts of the files the deck includes, by path relative to its folder."""
    main = Path(spec["deck"]).name
    return {path: text for path, text in spec.get("sources", {}).items() if path != main}


def engine_arguments(spec: dict) -> list[str]:
    """LIGGGHTS' command line: log and screen files, the deck's variables, ``driver=1``."""
    args = ["-log", spec["log"], "-screen", spec["screen"], "-echo", "log", "-nocite"]
    for name, value in spec["variables"].items():
        args += ["-var", name, str(value)]
    for name, value in ((spec.get("prepared") or {}).get("variables") or {}).items():
        args += ["-var", name, str(value)]  # e.g. mesh_dir, from the deck's prepare hook
    deck_dir = spec.get("deck_dir") or str(Path(spec["deck"]).parent)  # (a generated deck's is elsewhere)
    return args + ["-var", "driver", "1", "-var", "deck_dir", deck_dir]


def read_contract(lmp) -> tuple[int, int, float, bool]:
    """(n_steps, output_every, dt, is a bulk deck) from the deck's contract variables."""
    missing = [name for name in L.DECK_CONTRACT if not lmp.has_variable(name)]
    bulk_names = [name for name in L.BULK_CONTRACT if lmp.has_variable(name)]
    if bulk_names and len(bulk_names) < len(L.BULK_CONTRACT):  # a bulk deck: all of them
        missing += [name for name in L.BULK_CONTRACT if name not in bulk_names]
    if missing:
        raise DeckError(f"the deck does not define the equal-style variable(s) "
                         f"{', '.join(missing)} that vibrofeed reads (see docs/decks.md)")
    n_steps = int(round(lmp.variable("n_steps")))
    every = int(round(lmp.variable("output_every")))
    dt = lmp.dt
    if every < 1:
        raise DeckError(f"output_dt is shorter than the timestep ({dt:g} s): "
                          "no frame would ever be written")
    if n_steps < 1:
        raise DeckError(f"t_end is shorter than the timestep ({dt:g} s): nothing to run")
    return n_steps, every, dt, bool(bulk_names)


def derived_constants(lmp, names) -> dict:
    """The deck's constants as evaluated now (time-dependent ones are recorded per frame, if at all)."""
    derived = {}
    for name in names:
        try:
            derived[name] = lmp.variable(name)
        except KeyError:
            pass
    return derived


def set_up(lmp, spec: dict) -> None:
    """The driver's commands after the deck, and the setup run."""
    lmp.commands(spec.get("before_run", ()))
    lmp.command("thermo_modify flush yes")
    lmp.command("run 0")
    # Step and time as the engine counts them (a deck may have run stages before).
    lmp.command("variable vibrofeed_step equal step")
    lmp.command("variable vibrofeed_time equal time")


def open_writer(spec: dict, derived: dict, ranks: int, natoms: int, bulk, sections: int = 1,
                turns: bool = False):
    """Rank 0's result writer, flushed also when LIGGGHTS ends the process."""
    from ..results.writer import Recording, ResultWriter

    variables = {name: (value, *spec["var_meta"][name]) for name, value in spec["variables"].items()}
    writer = ResultWriter(
        spec["output"], deck_name=spec["deck_name"], deck_path=spec["deck"],
        deck_text=Path(spec["deck"]).read_text(), includes=_includes(spec), variables=variables,
        derived=derived,
        engine_version=engine_version(spec["log"]), seed=spec.get("seed"),
        ranks=ranks, command=spec.get("command", ""), run_id=spec.get("run_id", ""),
        capacity_hint=max(natoms // (bulk.n_spheres if bulk else 1), 1),
        recording=Recording.of(bulk.feeder if bulk is not None else None, sections, turns),
        target_error=spec.get("target_error"), description=spec.get("description"),
        **({} if bulk is None else {"track": bulk.track, "outlet": bulk.outlet.attributes(),
                                    "body_template": bulk.template,
                                    "track_sections": bulk.track_sections}))
    flush_on_engine_exit(writer)
    return writer


def segments(spec: dict, n_steps: int, every: int, dt: float) -> list[tuple]:
    """The run, as (commands, steps, setup) segments with a frame after each.

    A plain deck: output_every steps at a time, no commands, resuming without
    setup. A schedule (prescribed motion): each segment first redefines
    variables, then runs with setup, because LIGGGHTS re-creates a redefined
    variable at a new index and movers find it again only at setup.
    """
    schedule = spec.get("schedule")
    if not schedule:
        return [((), min(every, n_steps - k), False) for k in range(0, n_steps, every)]
    out, total = [], 0
    for seg in schedule:  # a segment ends after "steps" steps, or at time "until"
        steps = int(seg["steps"]) if "steps" in seg else int(round(float(seg["until"]) / dt)) - total
        if steps < 1:
            raise DeckError(f"schedule segment {len(out)} is shorter than the timestep ({dt:g} s)")
        total += steps
        out.append((seg.get("commands", ()), steps, True))
    return out


class Frames:
    """Takes the frames: the particles (or a bulk deck's bodies, outlet events and
    mass balance) to rank 0's writer; warns once when parts go missing."""

    def __init__(self, lmp, comm, writer, bulk, report: Reporter, sections: int = 1,
                 turns: bool = False):
        self.lmp, self.comm, self.writer, self.bulk, self.report = lmp, comm, writer, bulk, report
        self.sections = sections  # whose motion is recorded: section 1 and a line's further ones
        self.turns = turns  # the surface also rotates (a bowl): its angle and rate are recorded
        self.counts = None  # the mass balance of the last frame (bulk decks, rank 0)
        self.commands: list[str] = []  # to give before the next segment (a line's returns)
        self._lost_reported = False

    def take(self) -> float:
        """Write a frame of the engine's state now; its time."""
        lmp = self.lmp
        pos, vel = surface_state(lmp)
        further = [surface_state(lmp, k) for k in range(2, self.sections + 1)]
        rotation = surface_rotation(lmp) if self.turns else None
        step = int(round(lmp.variable("vibrofeed_step")))
        t = lmp.variable("vibrofeed_time")
        if self.bulk is None:
            parts = gather_parts(lmp, self.comm)
            if self.writer is not None:
                self.writer.write_frame(step, t, parts, pos, vel, section_surfaces=further,
                                        surface_rotation=rotation)
            return t
        got = self.bulk.frame(lmp, self.comm, t)
        returns, jets = self.bulk.returns, self.bulk.jets
        if returns is not None:  # collective: every rank gives the same commands
            self.commands = returns.schedule(lmp, self.comm, t, self.bulk.outlet.reject_times)
        firings = None
        if jets is not None:  # collective too: rank 0 senses, every rank redefines the jets
            fire, firings = jets.step(self.comm, t, got[0] if got is not None else None,
                                      self.bulk.atom_ranges)
            self.commands = [*self.commands, *fire]
        if self.writer is not None:
            parts, events, rejects, counts = got
            if firings is not None:
                self.writer.write_events(firings, L.JET)
            if events is not None:
                self.writer.write_events(events)
            if rejects is not None:
                self.writer.write_events(rejects, L.REJECTS)
            self.writer.write_frame(step, t, parts, pos, vel, counts=counts, section_surfaces=further,
                                    surface_rotation=rotation)
            self.counts = counts
            lost = counts["lost"]
            if lost and not self._lost_reported:
                when = ("while the pre-fill settled, before the vibration" if t == 0
                        else f"by t = {t:g} s")
                self.report("warning", message=f"{lost} part(s) disappeared without crossing "
                                               f"the outlet {when} (mass balance)")
                self._lost_reported = True
        return t


@dataclass(frozen=True)
class Verdict:
    """A feed rate's relative ``error`` (NaN: not measured) judged against a target with the
    frames up to time ``t``: ``reached``, else ``why`` not."""

    reached: bool
    error: float
    t: float
    why: str = ""


def judge_feed_rate(result, target: float, stop: int | None = None) -> Verdict:
    """Whether ``result`` (its frames up to ``stop``, default all) measures its feed rate to
    a relative error at or below ``target`` as :class:`~vibrofeed.postproc.feedrate.FeedRate`
    with its defaults (what ``vibrofeed feedrate`` reports) measures it: batch-means error over
    rate. Never before FeedRate measures a rate at all (enough exits, a bed it calls steady),
    its steady window holds all its batches (whole periods each) and the bed's drift could be
    judged."""
    from ..errors import InputError
    from ..postproc.feedrate import MIN_EXITS, FeedRate
    from ..postproc.line import batch_cuts

    t = float(result.time[:stop][-1])
    fr = FeedRate(result, model=False)  # (the single-part model does not touch the rate)
    exits = int(np.count_nonzero(result.outlet["time"] <= t))
    if exits < max(MIN_EXITS, fr.batches):  # no window can hold enough: spare reading the frames
        return Verdict(False, math.nan, t, f"too few exits to measure ({exits} so far; need ≥ "
                                           f"{max(MIN_EXITS, fr.batches)} in the window)")
    try:
        fr.run(stop=stop)
    except InputError as exc:  # too few frames, no steady window yet
        return Verdict(False, math.nan, t, str(exc))
    r = fr.results
    if r.reason:  # too few exits in the window, or a bed that drifts over it
        return Verdict(False, math.nan, t, r.reason)
    freq = float(result.parameters.get("freq", 0.0))
    held = len(batch_cuts(r.steady_from, r.steady_to, freq, fr.batches)) - 1
    if held < fr.batches:
        return Verdict(False, math.nan, t, f"the steady window ({r.steady_to - r.steady_from:.3g} s) "
                                           f"holds {held} of the {fr.batches} batches")
    if not r.bed_trends:
        return Verdict(False, math.nan, t, "too few frames in the window to judge the bed steady")
    error = r.parts_per_s_err / r.parts_per_s if r.parts_per_s > 0 else math.nan
    if not error <= target:
        return Verdict(False, error, t, f"relative error {error:.3g}")
    return Verdict(True, error, t)


class TargetError:
    """Stops a bulk run once its feed rate's relative error is at or below ``target``.

    :meth:`reached` after every frame, on every rank: now and then (:data:`CHECK_FRACTION`)
    and at the last frame, rank 0 judges the file so far (:func:`judge_feed_rate`) and
    broadcasts the decision, as the engine's commands that follow are collective. The times
    are the engine's, the same on every rank, so every rank checks at the same frames.
    """

    def __init__(self, target: float, comm):
        self.target, self.comm = float(target), comm
        self.verdict: Verdict | None = None  # the last check's, on rank 0
        self._first = self._checked = None  # times of the first frame and of the last check

    def _due(self, t: float) -> bool:
        if self._first is None:
            self._first = self._checked = t
        return t > self._checked and t - self._checked >= CHECK_FRACTION * (t - self._first)

    def reached(self, writer, t: float, last: bool = False) -> bool:
        """Whether to stop after the frame at ``t`` (``writer``: rank 0's, None elsewhere)."""
        if not (last or self._due(t)):
            return False
        self._checked = t
        reached = None
        if writer is not None:
            self.verdict = judge_feed_rate(writer.read_back(), self.target)
            reached = self.verdict.reached
        return self.comm.bcast(reached, root=0) if self.comm.size > 1 else reached

    def stop_reason(self, at_end: bool) -> str:
        """Why the run ended (rank 0, after its last frame was judged; FORMAT.md,
        ``parameters/run@stop_reason``)."""
        v, target = self.verdict, f"{L.STOP_AT_TARGET} {self.target:g}"
        if not at_end:
            return f"{target} reached: {v.error:.3g} at t = {v.t:.4g} s"
        said = (f"reached at the last frame: {v.error:.3g}" if v.reached
                else f"not reached at t = {v.t:.4g} s: {v.why}")
        return f"{L.STOP_AT_END} ({target} {said})"


def run_segments(lmp, frames: Frames, segs: list[tuple], report: Reporter,
                 target: TargetError | None = None) -> tuple[int, float, int]:
    """A frame, then each segment and a frame after it, until the last segment or until
    ``target`` is reached; (steps run, wall seconds, frames taken)."""
    started = time.monotonic()
    done = 0
    last_report = 0.0
    for k, segment in enumerate([*segs, None]):  # None: the frame after the last segment
        t = frames.take()
        stop = segment is None
        if target is not None:  # collective; the last frame is judged for the record
            stop = target.reached(frames.writer, t, last=stop) or stop
        now = time.monotonic()
        if stop or now - last_report > 0.2:
            writer = frames.writer
            report("progress", step=done, time=t, frames=writer.frames if writer else 0,
                   natoms=lmp.natoms, wall=now - started)
            last_report = now
        if stop:
            return done, time.monotonic() - started, k + 1
        commands, steps, setup = segment
        # a new fix (a line's returns) or a redefined variable (a jet's) needs a run with setup
        if frames.commands:
            commands, setup = (*commands, *frames.commands), True
            frames.commands = []
        lmp.commands(commands)
        lmp.command(f"run {steps} post no" if setup else f"run {steps} pre no post no")
        done += steps


def target_error(spec: dict, is_bulk: bool, comm) -> TargetError | None:
    """The run's :class:`TargetError` (``spec["target_error"]``), None without one; a deck
    without an outlet measures no feed rate: refused (the runner refuses it first)."""
    target = spec.get("target_error")
    if target is None:
        return None
    if not is_bulk:
        raise DeckError("a target error needs a deck with an outlet (a bulk feeder): this one "
                        "measures no feed rate")
    return TargetError(target, comm)


def bulk_warnings(bulk) -> list[str]:
    if bulk is None:
        return []
    if bulk.outlet.not_ballistic:
        bulk.warnings.append(f"{bulk.outlet.not_ballistic} outlet event(s) timed at their frame: "
                             "their free flight back never reached catch_z")
    return bulk.warnings


def run(spec: dict, heartbeat: Heartbeat | None = None, on_term: OnTerminate | None = None) -> int:
    from mpi4py import MPI

    from .library import Liggghts

    comm = MPI.COMM_WORLD
    report = heartbeat.report if heartbeat is not None else Reporter(comm.rank)
    report("deck")
    lmp = Liggghts(engine_arguments(spec), comm=comm)
    if heartbeat is not None:
        heartbeat.watch(lmp.step_counter())
    lmp.file(spec["deck"])
    n_steps, every, dt, is_bulk = read_contract(lmp)
    target = target_error(spec, is_bulk, comm)
    sections = recorded_sections(lmp, spec)
    turns = rotating(lmp)
    derived = derived_constants(lmp, spec["constants"])

    report("setup")
    set_up(lmp, spec)
    bulk = None
    if is_bulk:
        bulk = BulkFrames(lmp, spec)
        bulk.template_from_first_body(lmp, comm)
    writer = (open_writer(spec, derived, comm.size, lmp.natoms, bulk, sections, turns)
              if comm.rank == 0 else None)
    if on_term is not None:
        on_term.writer = writer

    segs = segments(spec, n_steps, every, dt)
    n_steps = sum(steps for _, steps, _ in segs)
    n_frames = 1 + len(segs)
    report("run", n_steps=n_steps, dt=dt, output_every=every, n_frames=n_frames,
           natoms=lmp.natoms)
    frames = Frames(lmp, comm, writer, bulk, report, sections, turns)
    done, wall, taken = run_segments(lmp, frames, segs, report, target)

    for message in bulk_warnings(bulk):
        report("warning", message=message)
    reason = None
    if writer is not None:  # rank 0: the only one that judged the feed rate
        at_end = taken == n_frames
        reason = L.STOP_AT_END if target is None else target.stop_reason(at_end)
        # "complete" is the runner's to write, as it renames OUT.h5.part to OUT.h5 (FORMAT.md)
        writer.finish(L.STATUS_RUNNING, "the engine reached the end of the run" if at_end else
                      "the engine stopped the run at its target error", wall_seconds=wall,
                      stop_reason=reason)
    report("done", step=done, frames=taken, wall=wall, natoms=lmp.natoms, counts=frames.counts,
           stop_reason=reason)
    if heartbeat is not None:
        heartbeat.watch(None)
    lmp.close()
    return 0


def no_space(exc: BaseException) -> bool:
    """Whether ``exc`` is a full disk (h5py reports it in the text of its error)."""
    return (isinstance(exc, OSError) and exc.errno == errno.ENOSPC) or \
        "No space left on device" in str(exc) or f"errno = {errno.ENOSPC}," in str(exc)


def close_on_full_disk(spec: dict, writer) -> None:
    """The disk filled: give back the space the runner held for this (``spec["reserve"]``) and
    close rank 0's file whole, marked failed, without the batch it could not write."""
    reserve = spec.get("reserve")
    if reserve:
        Path(reserve).unlink(missing_ok=True)
    if writer is not None:
        try:
            writer.finish(L.STATUS_FAILED, "no space left on the device while writing the frames: "
                                           "the frames written before are kept")
        except Exception:  # nothing more to be done here; the runner says what it can
            pass


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    OnTerminate.block()  # before MPI and any thread start: they inherit the mask
    on_term = OnTerminate()
    spec = json.loads(Path(argv[0]).read_text())
    from mpi4py import MPI

    report = Reporter(MPI.COMM_WORLD.rank)
    heartbeat = Heartbeat(report)
    try:
        return run(spec, heartbeat, on_term)
    except DeckError as exc:
        report("error", message=str(exc))
        return 3
    except Exception as exc:  # a bug or an I/O failure: tell the parent, then stop all ranks
        extra = {"no_space": True} if no_space(exc) else {}
        if extra:
            close_on_full_disk(spec, on_term.writer)
        report("error", message=f"{type(exc).__name__}: {exc}", **extra)
        if MPI.COMM_WORLD.size > 1:
            MPI.COMM_WORLD.Abort(1)
        return 4
    finally:
        heartbeat.stop()


def _exit(code: int) -> None:
    """Leave without running C exit handlers: the frame-flushing handler of
    ``flush_on_engine_exit`` is for LIGGGHTS ending the process mid-run, and
    after Python has finalised calling it would crash."""
    from mpi4py import MPI

    sys.stdout.flush()
    sys.stderr.flush()
    if not MPI.Is_finalized():
        MPI.Finalize()
    os._exit(code)


if __name__ == "__main__":
    _exit(main())
