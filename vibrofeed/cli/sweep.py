"""``vibrofeed sweep``: many runs of one deck over a design of parameters, safe to kill and rerun."""

from __future__ import annotations

import sys

from .options import jobs

DESCRIPTION = ("Run every job of a sweep file (a deck, fixed parameters, a grid, zipped lists or "
               "explicit points, replicates with distinct seeds) through the isolated runner, -j at a "
               "time or across the ranks of mpirun, and keep DIR/summary.h5 and DIR/summary.csv true "
               "after every job. A rerun skips finished jobs (their files checked) and retries failed "
               "ones with --retry-failed.")


def add_arguments(p) -> None:
    p.add_argument("sweep", metavar="SWEEP.toml", help="the sweep file (see docs/commands.md)")
    p.add_argument("-o", "--output", metavar="DIR",
                   help="folder for the results and the summary (default: results/<SWEEP>)")
    p.add_argument("--dry-run", action="store_true",
                   help="check the sweep, print the job table (and what a rerun would skip), run nothing")
    p.add_argument("--retry-failed", action="store_true",
                   help="run the jobs the summary lists as failed again")
    p.add_argument("-j", "--jobs", type=jobs, default=1, metavar="K",
                   help="jobs at a time without mpirun (default 1; each uses ranks_per_run ranks)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")


def run(args) -> int:
    from ..sweep.execute import serve, sweep
    from .options import dispatched

    return dispatched(args, serve, lambda comm: sweep(
        args.sweep, args.output, workers=args.jobs, retry_failed=args.retry_failed,
        dry_run=args.dry_run, quiet=args.quiet, comm=comm, out=sys.stdout))
