"""A sweep's jobs: the expansion of the design, each job checked as ``vibrofeed run`` checks it.

Job ``k`` runs ``deck`` with the fixed values, the ``k``-th combination of the
axes (the first axis varies slowest) and the replicate's seed; its result is
``jobs/job-<k>.h5`` in the sweep's folder. Seeds: replicate ``r`` of a setting
runs with ``seed + r`` (``seed`` from ``[fixed]``, else the deck's default);
the bulk feeder turns each seed into its own primes for LIGGGHTS
(``vibrofeed.geometry.insertion_seeds``), so neighbouring seeds give
independent fills.

Dispatch order is longest expected first (the classic LPT rule: a long job
started last would leave the other workers idle at the end). The expected
cost of a job is relative: simulated time x parts (``t_end`` x (``n_parts`` +
``inlet_rate`` x ``t_end``), at least one part), divided by ``dt`` when the
timestep is given; it orders jobs of one sweep and scales the ETA, nothing more.
"""

from __future__ import annotations

import difflib
import itertools
import math
from dataclasses import dataclass
from pathlib import Path

from ..decks import RESERVED, Deck
from ..errors import DeckError, ParameterError, UsageError
from ..parameters import resolve
from .spec import SweepSpec


@dataclass
class Job:
    index: int
    replicate: int
    seed: int | None
    setting: dict  # the parameters the sweep file names, as written there (TOML values)
    params: dict  # name -> value string, as run_deck takes them (the seed included)
    values: dict  # the resolved parameters (deck defaults included)
    run_id: str
    cost: float
    file: str  # the result, relative to the sweep's folder
    target_error: float | None = None  # stop at this relative feed-rate error (run_deck's)

    def label(self, varied: list[str]) -> str:
        bits = [f"{name}={self.setting[name]}" for name in varied if name in self.setting]
        return " ".join(bits + [f"seed={self.seed}"]) if self.seed is not None else " ".join(bits)


def value_text(value) -> str:
    """A TOML value as a deck parameter string: ints as written, floats by
    their shortest exact repr (5e-05, 0.0001), strings as they are."""
    if isinstance(value, float):
        return repr(value)
    return str(value)


def find_deck(spec: SweepSpec) -> Deck:
    """The sweep's deck: a file relative to the sweep file's folder, or a deck name."""
    given = Path(spec.deck)
    near = spec.source.parent / given
    try:
        return Deck.find(near if near.is_file() and not given.is_absolute() else spec.deck)
    except DeckError as exc:
        raise DeckError(f"{spec.where('deck')}: {exc}") from None


def _check_names(spec: SweepSpec, deck: Deck) -> None:
    """Every name the file sets is the deck's (or, for a feeder description, one of its dotted
    names: resolve reads them, and refuses one parameter given by both names)."""
    tunables = deck.tunables
    for name in spec.parameters:
        if name in RESERVED:
            raise ParameterError(f"{spec.where(*spec.place(name))}: parameter {name} is set by "
                                 "vibrofeed itself, not by a sweep")
        if deck.aliases.get(name) == "seed" and name in spec.varied and spec.replicates > 1:
            raise ParameterError(f"{spec.where(*spec.place(name))}: {name} (the seed) is varied and "
                                 "replicates > 1: replicates set the seeds (seed, seed+1, ...); fix "
                                 "it or set replicates = 1")
        if name not in tunables and name not in deck.aliases:
            close = difflib.get_close_matches(name, [*tunables, *deck.aliases], n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            raise ParameterError(f"{spec.where(*spec.place(name))}: unknown parameter {name} for "
                                 f"deck {deck.name}{hint}; valid parameters: {', '.join(tunables)}")
    if spec.replicates > 1 and "seed" not in tunables:
        raise ParameterError(f"{spec.where('replicates')}: deck {deck.name} has no seed parameter, "
                             "so its replicates would be the same run; set replicates = 1")


def settings(spec: SweepSpec) -> list[dict]:
    """Every combination of the axes (first axis slowest), as name -> TOML value."""
    combos = itertools.product(*(axis.values for axis in spec.axes)) if spec.axes else [()]
    out = []
    for combo in combos:
        setting = dict(spec.fixed)
        for part in combo:
            setting.update(part)
        out.append(setting)
    return out


def cost(values: dict) -> float:
    """Relative expected cost of a run (module docstring)."""
    def number(name, default):
        try:
            x = float(values.get(name, default))
        except ValueError:
            return default
        return x if math.isfinite(x) else default

    t_end = number("t_end", 1.0)
    parts = max(1.0, number("n_parts", 1.0) + number("inlet_rate", 0.0) * t_end)
    dt = number("dt", 0.0)
    return t_end * parts / (dt if dt > 0 else 1.0)


def _culprit(spec: SweepSpec, message: str, setting: dict) -> tuple:
    """The key path of the parameter a ParameterError is about: of the names
    the message shows (``name=`` or ``'name'``), the first varied one, else
    the first fixed one; () if it names none of the file's parameters."""
    def first(names):
        found = [(i, n) for n in names if n in setting
                 for i in (message.find(f"{n}="), message.find(f"'{n}'")) if i >= 0]
        return min(found)[1] if found else None

    name = first(spec.varied) or first(list(spec.fixed))
    return spec.place(name) if name else ()


# The most jobs a sweep plans: each is checked as vibrofeed run checks it and kept with its
# values (about 2.5 ms and 4.3 kB a job: sweeps/example.toml with 1 200 jobs on a 2-core Xeon,
# 2026-12-03), so 100 000 jobs take about 4 minutes and 0.5 GB before the first run
# (replicates = 1000000000 was killed by the kernel at 23 GB).
MAX_JOBS = 100_000


def check_size(spec: SweepSpec) -> int:
    """The number of jobs of ``spec``, counted without making them; UsageError naming the
    line of what makes them too many (:data:`MAX_JOBS`)."""
    settings_n = math.prod(len(axis.values) for axis in spec.axes)
    total = settings_n * spec.replicates
    if total <= MAX_JOBS:
        return total
    if spec.replicates > 1 and settings_n <= MAX_JOBS:
        key, what = ("replicates",), f"{settings_n} setting(s) x replicates = {spec.replicates}"
        fits = f"replicates = {max(MAX_JOBS // settings_n, 1)} at most"
    else:
        longest = max(spec.axes, key=lambda a: len(a.values))
        key = ("point",) if longest.kind == "point" else spec.place(longest.keys[0])
        sizes = " x ".join(str(len(a.values)) for a in spec.axes)
        what = f"{sizes} settings" + (f" x replicates = {spec.replicates}" if spec.replicates > 1 else "")
        fits = "fewer values"
    raise UsageError(f"{spec.where(*key)}: {what} make {total:,} jobs, more than a sweep plans: at most "
                     f"{MAX_JOBS:,} (each job is checked and kept in memory before the first run: "
                     f"{MAX_JOBS:,} take about 4 minutes and 0.5 GB); {fits}, or split the sweep")


def plan(spec: SweepSpec, deck: Deck | None = None) -> list[Job]:
    """The jobs of ``spec``, each checked; ParameterError naming the line of
    the first parameter that fails (and how many jobs fail in all)."""
    from ..engine.runner import check_ranks, check_target_error, run_id

    deck = deck or find_deck(spec)
    _check_names(spec, deck)
    try:
        check_target_error(spec.target_error, deck)
    except UsageError as exc:
        raise UsageError(f"{spec.where('target_error')}: {exc}") from None
    try:
        check_ranks(spec.ranks_per_run)
    except UsageError as exc:
        raise UsageError(f"{spec.where('ranks_per_run')}: ranks_per_run: {exc}") from None
    total = check_size(spec)
    combos = settings(spec)
    width = max(4, len(str(total - 1)))
    has_seed = "seed" in deck.tunables
    jobs, first_error, bad = [], None, 0
    for k, (setting, r) in enumerate(itertools.product(combos, range(spec.replicates))):
        params = {name: value_text(v) for name, v in setting.items()}
        seed = None
        if has_seed:
            named = next((n for n in setting if deck.aliases.get(n, n) == "seed"), "seed")
            base = setting.get(named, deck.tunables["seed"].default)
            try:
                x = float(base)
            except ValueError:
                x = math.nan
            # not a whole number: run as written, so that resolve refuses it below, naming it
            # (never truncated: 7.5 is no seed 7)
            seed = int(x) + r if x.is_integer() else None
            if seed is not None:
                params[named] = str(seed)
        try:
            values = resolve(deck, params)
        except ParameterError as exc:
            bad += 1
            if first_error is None:
                label = " ".join(f"{n}={v}" for n, v in setting.items() if n in spec.varied)
                first_error = (_culprit(spec, str(exc), setting), k, label, str(exc))
            continue
        jobs.append(Job(index=k, replicate=r, seed=seed, setting=setting, params=params,
                        values=values, run_id=run_id(deck, values, target_error=spec.target_error),
                        cost=cost(values), file=f"jobs/job-{k:0{width}d}.h5",
                        target_error=spec.target_error))
    if first_error is not None:
        key, k, label, message = first_error
        more = f" ({bad} of {total} jobs are invalid)" if bad > 1 else ""
        job = f"job {k}" + (f" ({label})" if label else "")
        raise ParameterError(f"{spec.where(*key)}: {job}: {message}{more}")
    return jobs


def dispatch_order(jobs: list[Job]) -> list[Job]:
    """Longest expected first; ties in job order."""
    return sorted(jobs, key=lambda j: (-j.cost, j.index))
