"""The ``vibrofeed`` command line.

Every command reports a problem as one line on stderr starting with
``vibrofeed: error:`` and exits with a non-zero status; tracebacks are kept
for bugs (set ``VIBROFEED_DEBUG=1`` to see them for user errors too).
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import sys

from . import __version__

EXIT_USAGE = 2
EXIT_FAILED = 1
EXIT_INTERRUPTED = 130


class UserError(Exception):
    """A problem the user can fix; printed as one line."""


def _fail(message: str, code: int = EXIT_FAILED) -> int:
    print(f"vibrofeed: error: {message}", file=sys.stderr)
    return code


# ---------------------------------------------------------------------------- run
def cmd_run(args) -> int:
    from .decks import Deck
    from .engine.runner import run_deck
    from .parameters import parse_assignments
    from .progress import RunProgress
    from .summary import run_summary

    deck = Deck.find(args.deck)
    params = parse_assignments(args.param)
    output = args.output or f"{deck.name}.h5"
    progress = RunProgress(deck.name, enabled=False if args.quiet else None)
    try:
        result = run_deck(deck, params, output, ranks=args.ranks, on_event=progress,
                          command=shlex.join(["vibrofeed"] + sys.argv[1:]))
    finally:
        progress.close()
    print(run_summary(result))
    return 0


# -------------------------------------------------------------------------- check
def cmd_check(args) -> int:
    from .results.check import check_file

    worst = 0
    reports = [check_file(path, allow_incomplete=args.allow_incomplete) for path in args.files]
    if args.json:
        print(json.dumps([{
            "file": r.path, "ok": r.ok, "frames": r.frames, "parts": r.parts, "status": r.status,
            "problems": [{"level": p.level, "where": "/" + p.where, "message": p.message}
                         for p in r.problems]} for r in reports], indent=2))
    for r in reports:
        if not args.json:
            verdict = "OK" if r.ok else "INVALID"
            print(f"{verdict}: {r.path}: {r.frames} frames, {r.parts} parts, status {r.status or '?'}")
            for p in r.problems:
                print(f"  {p}")
        if not r.ok:
            worst = EXIT_FAILED
    return worst


# ------------------------------------------------------------------------ validate
def _fmt(x: float) -> str:
    if x != x:
        return "nan"
    if x == int(x) and abs(x) < 1e6:
        return f"{int(x)}"
    return f"{x:.6g}"


def _table(rows) -> list[str]:
    table = [("case", "quantity", "model", "DEM", "rel diff", "tolerance", "")]
    for r in rows:
        tol = f"{_fmt(r.tolerance)} {r.unit}".strip() if r.tolerance_type == "abs" \
            else f"{r.tolerance:.1%}"
        rel = "-" if r.rel_diff is None else f"{r.rel_diff:+.2%}"
        table.append((r.case, r.quantity, _fmt(r.model), _fmt(r.dem), rel,
                      tol, "pass" if r.passed else "FAIL"))
    widths = [max(len(row[i]) for row in table) for i in range(len(table[0]))]
    lines = []
    for k, row in enumerate(table):
        lines.append("  ".join(c.ljust(w) for c, w in zip(row, widths)).rstrip())
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    return lines


def cmd_validate(args) -> int:
    from .engine.errors import RunError
    from .validation import cases as C
    from .validation.crosscheck import CrossCheck

    if args.list:
        names = C.available()
        width = max(map(len, names))
        for name in names:
            case = C.find(name)
            print(f"{name:<{width}}  [{case.kind}] {case.title}")
        return 0
    selected = [C.find(n) for n in (args.cases or C.available())]
    say = (lambda *a: None) if args.json else (lambda text: print(text, file=sys.stderr))
    rows, figures, failed, errors = [], [], [], []
    for case in selected:
        say(f"== {case.name}: {case.title}")
        check = CrossCheck(case, args.output, ranks=args.ranks, jobs=args.jobs, reuse=args.reuse,
                           on_run=lambda label, state, c=case: say(f"   {c.name} [{label}]: {state}"))
        try:
            outcome = check.run()
        except (RunError, C.CaseError) as exc:  # one broken case does not stop the others
            errors.append(f"{case.name}: {exc}")
            failed.append(case.name)
            say(f"   {case.name}: error: {exc}")
            continue
        rows += outcome.rows
        figures += outcome.figures
        if not outcome.passed:
            failed.append(case.name)
        if not args.json and len(selected) > 1:
            say("\n".join("   " + line for line in _table(outcome.rows)))
    if args.json:
        print(json.dumps([r.as_dict() for r in rows], indent=2))
    else:
        print("\n".join(_table(rows)))
        n_fail = sum(not r.passed for r in rows)
        print(f"\n{len(rows) - n_fail}/{len(rows)} quantities within tolerance"
              + (f"; failing cases: {', '.join(failed)}" if failed else ""))
        for f in figures:
            print(f"figure: {f}")
    for e in errors:
        print(f"vibrofeed: error: case {e}", file=sys.stderr)
    return EXIT_FAILED if failed else 0


# -------------------------------------------------------------------------- replay
REPLAY_KEYS = ("mean_abs_error_mm", "max_displacement_mm", "final_measured_mm",
               "final_predicted_mm", "stuck_fraction")


def _positive(name: str, value) -> float:
    if value is None:
        raise UserError(f"{name} is required")
    if not value > 0:
        raise UserError(f"{name} must be > 0, got {value}")
    return float(value)


def cmd_replay(args) -> int:
    from .validation.trials import read_trial

    trials = [read_trial(path) for path in args.trials]
    mass = _positive("--mass", args.mass)
    mu_s = _positive("--mu-s", args.mu_s)
    if args.fit:
        return _replay_fit(args, trials, mass, mu_s)
    force = _positive("--normal-force", args.normal_force)
    mu_k = _positive("--mu-k", args.mu_k)
    if mu_k > mu_s:
        raise UserError(f"--mu-k ({mu_k}) cannot exceed --mu-s ({mu_s})")
    if args.engine == "dem" and mu_k != mu_s:
        raise UserError("the DEM engine has one friction coefficient (LIGGGHTS): give equal "
                        "--mu-s and --mu-k")
    g = 9.81
    if force * mu_s <= mass * g:
        print(f"vibrofeed: note: --normal-force {force:g} N is below m g / mu_s = "
              f"{mass * g / mu_s:.4g} N: the part cannot stay stuck on a still wall", file=sys.stderr)
    results = []
    for trial in trials:
        if args.engine == "model":
            from .validation.replay_fit import replay

            results.append(replay(trial, mass, force, mu_s, mu_k))
        else:
            from pathlib import Path

            from .validation.replay_dem import replay_dem

            out = Path(args.output) / f"{trial.name}.h5"
            results.append(replay_dem(trial, mass, force, mu_k, out, ranks=args.ranks))
    rows = [{"trial": r.name, "engine": args.engine, **{k: getattr(r, k) for k in REPLAY_KEYS}}
            for r in results]
    if args.json:
        print(json.dumps(rows[0] if len(rows) == 1 else rows, indent=2))
    else:
        for r in results:
            print(f"{r.name} ({args.engine}): mean abs error {r.mean_abs_error_mm:.3f} mm "
                  f"(largest measured displacement {r.max_displacement_mm:.3f} mm); final "
                  f"measured {r.final_measured_mm:+.3f} mm, predicted {r.final_predicted_mm:+.3f} mm; "
                  f"stuck {r.stuck_fraction:.0%} of the time")
    if args.plot:
        from .validation.plots import plot_replay

        path = plot_replay(results, args.plot, engine=args.engine)
        if not args.json:
            print(f"figure: {path}")
    return 0


def _replay_fit(args, trials, mass: float, mu_s: float) -> int:
    from .validation.replay_fit import fit_trials

    if len(trials) < 1:
        raise UserError("--fit needs at least one trial")
    fit = fit_trials(trials, mass=mass, mu_s=mu_s)
    rows = [{"trial": t.name, "normal_force": fit.normal_force[t.name],
             "normal_force_mg": fit.normal_force_mg[t.name],
             "mean_abs_error_mm": fit.mae_mm[t.name]} for t in trials]
    if args.json:
        print(json.dumps({"mass": mass, "mu_s": mu_s, "mu_k": fit.mu_k, "trials": rows,
                          "mean_abs_error_mm": fit.mean_mae_mm}, indent=2))
        return 0
    print(f"fitted kinetic friction mu_k = {fit.mu_k:.4f} (mu_s = {mu_s}, mass {mass} kg)")
    for row in rows:
        print(f"  {row['trial']}: normal force {row['normal_force']:.4g} N "
              f"({row['normal_force_mg']:.3f} m g), mean abs error {row['mean_abs_error_mm']:.3f} mm")
    print(f"mean of the mean abs errors: {fit.mean_mae_mm:.3f} mm")
    return 0


# ------------------------------------------------------------------ decks, params
def cmd_decks(args) -> int:
    from .decks import Deck, available, decks_dir

    names = available()
    if not names:
        return _fail(f"no decks in {decks_dir()}")
    width = max(map(len, names))
    for name in names:
        print(f"{name:<{width}}  {Deck.find(name).title}")
    return 0


def cmd_params(args) -> int:
    from .decks import Deck

    deck = Deck.find(args.deck)
    rows = [(v.name, v.default, v.unit, v.description) for v in deck.tunables.values()]
    if args.json:
        print(json.dumps([dict(zip(("name", "default", "unit", "description"), r)) for r in rows],
                         indent=2))
        return 0
    print(f"{deck.name}: {deck.title}\n  ({deck.path})\n")
    w = [max(len(str(r[i])) for r in rows) for i in range(3)]
    for name, default, unit, text in rows:
        print(f"  {name:<{w[0]}}  {default:<{w[1]}}  {unit:<{w[2]}}  {text}")
    return 0


# ---------------------------------------------------------------------------- main
def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="vibrofeed",
        description="DEM simulation of vibratory feeding of micro-parts with LIGGGHTS.")
    parser.add_argument("--version", action="version", version=f"vibrofeed {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("run", help="run a deck and write an H5MD result",
                       description="Run a deck through LIGGGHTS and write one H5MD result file "
                                   "(OUT.h5, with the LIGGGHTS log next to it as OUT.log).")
    p.add_argument("deck", metavar="DECK", help="deck file, or a deck name from decks/ (see `vibrofeed decks`)")
    p.add_argument("-p", "--param", action="append", metavar="NAME=VALUE",
                   help="set a deck parameter (repeatable; see `vibrofeed params DECK`)")
    p.add_argument("-o", "--output", metavar="OUT.h5", help="result file (default: DECK.h5 here)")
    p.add_argument("-n", "--ranks", type=int, default=1, metavar="RANKS",
                   help="MPI ranks for LIGGGHTS (default 1)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("check", help="validate result files against the format",
                       description="Check that result files follow the vibrofeed H5MD layout "
                                   "(FORMAT.md). Exit status 1 if any file is invalid.")
    p.add_argument("files", nargs="+", metavar="FILE.h5")
    p.add_argument("--allow-incomplete", action="store_true",
                   help="accept files of runs that were killed or failed (frames are still checked)")
    p.add_argument("--json", action="store_true", help="print the reports as JSON")
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("validate", help="run DEM and analytic model on the validation cases",
                       description="Run each validation case (validation/cases/*.toml) through "
                                   "LIGGGHTS and through the analytic model on the same parameters, "
                                   "print model vs DEM with tolerances and write PNG figures. "
                                   "Exit status 1 if any quantity is out of tolerance.")
    p.add_argument("cases", nargs="*", metavar="CASE", help="case names (default: all; see --list)")
    p.add_argument("-o", "--output", default="validation-results", metavar="DIR",
                   help="folder for DEM results and figures (default: validation-results)")
    p.add_argument("--list", action="store_true", help="list the cases and exit")
    p.add_argument("--json", action="store_true",
                   help="print the table as JSON rows (case, quantity, model, dem, rel_diff, tolerance, passed)")
    p.add_argument("-j", "--jobs", type=int, default=2, metavar="N",
                   help="DEM runs at once (default 2)")
    p.add_argument("-n", "--ranks", type=int, default=1, metavar="RANKS", help="MPI ranks per DEM run")
    p.add_argument("--reuse", action="store_true",
                   help="reuse DEM results already in DIR that hold exactly the case's parameters")
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser("replay", help="replay measured vertical-transport trials",
                       description="Drive the vertical-transport model (or a LIGGGHTS wall) with the "
                                   "measured platform motion of trial files and compare the predicted "
                                   "part position with the measured one; or, with --fit, fit one "
                                   "kinetic friction coefficient for all trials and one normal force "
                                   "per trial.")
    p.add_argument("trials", nargs="+", metavar="TRIAL.csv", help="measured trial files")
    p.add_argument("--mass", type=float, metavar="KG", help="part mass [kg]")
    p.add_argument("--normal-force", type=float, metavar="N", help="grasp (normal) force [N]")
    p.add_argument("--mu-s", type=float, metavar="X", help="static friction coefficient")
    p.add_argument("--mu-k", type=float, metavar="Y", help="kinetic friction coefficient")
    p.add_argument("--engine", choices=("model", "dem"), default="model",
                   help="model (Coulomb stick/slip, seed 000) or dem (LIGGGHTS wall; needs mu_s = mu_k)")
    p.add_argument("--fit", action="store_true",
                   help="fit mu_k (shared) and the normal force of each trial (needs --mass, --mu-s)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--plot", metavar="FILE.png", help="plot measured and predicted part position")
    p.add_argument("-o", "--output", default="replay-results", metavar="DIR",
                   help="folder for the DEM engine's result files (default replay-results)")
    p.add_argument("-n", "--ranks", type=int, default=1, metavar="RANKS", help="MPI ranks (DEM engine)")
    p.set_defaults(func=cmd_replay)

    p = sub.add_parser("decks", help="list the decks in decks/")
    p.set_defaults(func=cmd_decks)

    p = sub.add_parser("params", help="list a deck's parameters with defaults and units")
    p.add_argument("deck", metavar="DECK")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=cmd_params)
    return parser


def main(argv=None) -> int:
    from .decks import DeckError
    from .engine.errors import RunError
    from .validation.cases import CaseError
    from .validation.trials import TrialFileError
    from .parameters import ParameterError
    from .results.reader import ResultError

    parser = build_parser()
    args = parser.parse_args(argv)
    debug = bool(os.environ.get("VIBROFEED_DEBUG"))
    try:
        return args.func(args)
    except KeyboardInterrupt:
        return _fail("interrupted", EXIT_INTERRUPTED)
    except (ParameterError, DeckError, CaseError, TrialFileError, UserError) as exc:
        if debug:
            raise
        return _fail(str(exc), EXIT_USAGE)
    except (RunError, ResultError) as exc:
        if debug:
            raise
        code = _fail(str(exc))
        partial = getattr(exc, "partial", None)
        if partial:
            print(f"vibrofeed: the {partial[1]} frames written before the failure are kept in "
                  f"{partial[0]} (status: failed)", file=sys.stderr)
        return code


if __name__ == "__main__":
    sys.exit(main())
