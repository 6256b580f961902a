"""``vibrofeed optimize``: the feeder settings a designer needs, found in few DEM runs."""

from __future__ import annotations

import sys

from .options import count, jobs

DESCRIPTION = ("Search a study file's design variables (bounds, choices) for the best value of its "
               "objective (a metric of the feed-rate and singulation analyses, or two: a Pareto "
               "front) within its constraints (actuator acceleration and stroke, frequency range, "
               "inequalities, targets to reach). The analytic models screen the space first and "
               "seed the search; a setting they rule out is never sent to DEM. Optuna's TPE sampler "
               "proposes the DEM runs (-j at a time, or across the ranks of mpirun); the best few "
               "are confirmed with fresh seeds and the best re-run over the [robustness] values. "
               "Writes DIR/study.csv, DIR/study.h5, DIR/study.json; killed, it continues with "
               "--resume without repeating a finished run; --retry-failed runs its failed runs again.")


def add_arguments(p) -> None:
    p.add_argument("study", metavar="STUDY.toml", help="the study file (see docs/optimize.md)")
    p.add_argument("-o", "--output", metavar="DIR",
                   help="folder for the runs and the study's files (default: results/<STUDY>)")
    p.add_argument("-j", "--jobs", type=jobs, default=1, metavar="K",
                   help="DEM runs at a time without mpirun (default 1)")
    p.add_argument("--budget", type=count("DEM runs"), metavar="N",
                   help="DEM runs of the search (default: the study file's budget.runs)")
    p.add_argument("--resume", action="store_true",
                   help="continue the study in DIR (finished runs are not repeated)")
    p.add_argument("--retry-failed", action="store_true",
                   help="continue the study in DIR and run its failed runs again (a run whose DEM "
                        "finished and whose analysis failed is analysed again, not rerun)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")


def run(args) -> int:
    from ..optimize.search import optimize
    from ..sweep.execute import serve
    from .options import dispatched

    return dispatched(args, serve, lambda comm: optimize(
        args.study, args.output, workers=args.jobs, budget=args.budget, resume=args.resume,
        quiet=args.quiet, comm=comm, out=sys.stdout, retry_failed=args.retry_failed))
