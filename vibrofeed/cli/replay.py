"""``vibrofeed replay``: replay measured vertical-transport trials through the
model of Yako et al. (ICRA 2024) or a LIGGGHTS wall, or fit its friction."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..errors import UsageError
from .numbers import real

DESCRIPTION = ("Drive the vertical-transport model (or a LIGGGHTS wall) with the measured platform "
               "motion of trial files and compare the predicted part position with the measured one; "
               "or, with --fit, fit one kinetic friction coefficient for all trials and one normal "
               "force per trial.")

REPLAY_KEYS = ("mean_abs_error_mm", "max_displacement_mm", "final_measured_mm",
               "final_predicted_mm", "stuck_fraction")


def add_arguments(p) -> None:
    from .options import ranks

    p.add_argument("trials", nargs="+", metavar="TRIAL.csv", help="measured trial files")
    p.add_argument("--mass", type=real(above=0), metavar="KG", help="part mass [kg]")
    p.add_argument("--normal-force", type=real(above=0), metavar="N", help="grasp (normal) force [N]")
    p.add_argument("--mu-s", type=real(above=0), metavar="X", help="static friction coefficient")
    p.add_argument("--mu-k", type=real(above=0), metavar="Y", help="kinetic friction coefficient")
    p.add_argument("--engine", choices=("model", "dem"), default="model",
                   help="model (Coulomb stick/slip of Yako et al.) or dem (LIGGGHTS wall; needs "
                        "mu_s = mu_k)")
    p.add_argument("--fit", action="store_true",
                   help="fit mu_k (shared) and the normal force of each trial (needs --mass, --mu-s)")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--plot", metavar="FILE.png",
                   help="plot measured and predicted part position (its folder must exist)")
    p.add_argument("-o", "--output", metavar="DIR",
                   help="folder for the DEM engine's result files (default replay-results)")
    p.add_argument("-n", "--ranks", type=ranks, metavar="RANKS",
                   help="MPI ranks (DEM engine; default 1)")


def _positive(name: str, value) -> float:
    if value is None:
        raise UsageError(f"{name} is required")
    if not value > 0:
        raise UsageError(f"{name} must be > 0, got {value}")
    return float(value)


def _refuse_with_fit(args) -> None:
    """What --fit cannot take: the figures it fits (a value given would be silently replaced
    by the fitted one), a plot, and the DEM engine (the fit is the model's)."""
    if not args.fit:
        return
    for option, value, fitted in (("--mu-k", args.mu_k, "the kinetic friction shared by the trials"),
                                  ("--normal-force", args.normal_force, "a normal force per trial")):
        if value is not None:
            raise UsageError(f"{option}: --fit fits {fitted}; drop {option}, or replay without "
                             "--fit to use it")
    if args.engine == "dem":
        raise UsageError("--engine dem: --fit fits the model of Yako et al.; drop --engine dem (replay "
                         "the fitted values through the DEM engine without --fit)")
    if args.plot:
        raise UsageError("--plot draws a replay; --fit prints the fit only (replay with the fitted "
                         "--mu-k and --normal-force to plot it)")


def run(args) -> int:
    from ..models.constants import G
    from ..validation.replay.trials import read_trial
    from .options import no_effect, slips
    from .outputs import file_destination, folder_destination

    _refuse_with_fit(args)
    slips(("--mass", args.mass, "kg"), ("--mu-s", args.mu_s, "-"), ("--mu-k", args.mu_k, "-"))
    for option, value in (("-o", args.output), ("-n", args.ranks)):
        if value is not None and args.engine == "model":
            no_effect(option, f"the model engine{' of --fit' if args.fit else ''} runs no LIGGGHTS; "
                              f"{option} is for --engine dem")
    args.output = "replay-results" if args.output is None else args.output
    args.ranks = 1 if args.ranks is None else args.ranks
    plot = None if args.plot is None else file_destination("--plot", args.plot, (".png",))
    if args.engine == "dem":
        folder_destination("-o", args.output, create=False, parents=True)
    trials = [read_trial(path) for path in args.trials]
    mass = _positive("--mass", args.mass)
    mu_s = _positive("--mu-s", args.mu_s)
    if args.fit:
        return _fit(args, trials, mass, mu_s)
    force = _positive("--normal-force", args.normal_force)
    mu_k = _positive("--mu-k", args.mu_k)
    if mu_k > mu_s:
        raise UsageError(f"--mu-k ({mu_k}) cannot exceed --mu-s ({mu_s})")
    if args.engine == "dem" and mu_k != mu_s:
        raise UsageError("the DEM engine has one friction coefficient (LIGGGHTS): give equal "
                         "--mu-s and --mu-k")
    if force * mu_s <= mass * G:
        print(f"vibrofeed: note: --normal-force {force:g} N is below m g / mu_s = "
              f"{mass * G / mu_s:.4g} N: the part cannot stay stuck on a still wall", file=sys.stderr)
    results = []
    for trial in trials:
        if args.engine == "model":
            from ..validation.replay.fit import replay

            results.append(replay(trial, mass, force, mu_s, mu_k))
        else:
            from ..validation.replay.dem import replay_dem

            out = Path(args.output) / f"{trial.name}.h5"
            results.append(replay_dem(trial, mass, force, mu_k, out, ranks=args.ranks))
    rows = [{"trial": r.name, "engine": args.engine, **{k: getattr(r, k) for k in REPLAY_KEYS}}
            for r in results]
    if args.json:
        print(json.dumps(rows[0] if len(rows) == 1 else rows, indent=2))
    else:
        for r in results:
            print(f"{r.name} ({args.engine}): mean abs error {r.mean_abs_error_mm:.3f} mm "
                  f"(largest measured displacement {r.max_displacement_mm:.3f} mm); final measured "
                  f"{r.final_measured_mm:+.3f} mm, predicted {r.final_predicted_mm:+.3f} mm; "
                  f"stuck {r.stuck_fraction:.0%} of the time")
    if plot is not None:
        from ..validation.plots import plot_replay
        from .outputs import written

        path = written(plot_replay(results, plot, engine=args.engine))
        if not args.json:
            print(f"figure: {path}")
    return 0


def _fit(args, trials, mass: float, mu_s: float) -> int:
    from ..validation.replay.fit import fit_trials

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
