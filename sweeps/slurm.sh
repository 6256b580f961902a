#!/bin/bash
# A vibrofeed sweep on many nodes of a Slurm cluster: the same command as on a
# workstation, started by srun (or mpirun) instead of -j.
#
#   sbatch sweeps/slurm.sh sweeps/example.toml results/example
#
# How it runs: every task is one MPI rank of `vibrofeed sweep`. The ranks form groups
# of ranks_per_run (from the sweep file); rank 0 hands out the jobs one at a time,
# longest first, to whichever group is free, runs one itself, and writes
# each finished job's row into DIR/summary.h5 and DIR/summary.csv (a journal line per
# job, the two files rewritten now and then). Each job is its own process (its
# own mpirun when ranks_per_run > 1) started on its group leader's node, so a job
# that crashes becomes a failed row and the allocation goes on. Idle ranks sleep
# between polls: they cost no CPU.
#
# Killed (time limit, scancel, node failure)? Submit the same command again: finished
# jobs are kept (their result files are checked against the job's run id), the others
# run. Add --retry-failed to run the failed ones again. The summary is true at every
# instant; `vibrofeed sweep-report DIR` reads it while the sweep runs.
#
# Tested here under `mpirun -np 2` on one machine. Each job's own mpirun (ranks_per_run
# > 1) starts on its leader's node: vibrofeed removes the SLURM_* variables of the
# allocation (and the outer MPI job's) from the job's environment, so that mpirun runs
# locally; on a new cluster, check it once with a small sweep.

#SBATCH --job-name=vibrofeed-sweep
#SBATCH --nodes=4
#SBATCH --ntasks-per-node=32        # a multiple of ranks_per_run: a group never spans two nodes
#SBATCH --cpus-per-task=1
#SBATCH --time=12:00:00
#SBATCH --output=%x-%j.out          # one line per finished job, with the ETA

set -euo pipefail

SWEEP=${1:?usage: sbatch sweeps/slurm.sh SWEEP.toml [DIR]}
DIR=${2:-results/$(basename "$SWEEP" .toml)}
REPO=${VIBROFEED_REPO:-$SLURM_SUBMIT_DIR}   # the clone with .venv/ (bash bootstrap.sh setup)

cd "$REPO"
# Check the sweep file (every job's parameters, with the line of any problem) and show
# what this submission will run before the ranks start.
.venv/bin/vibrofeed sweep "$SWEEP" -o "$DIR" --dry-run | head -n 1

# One rank per task. With ranks_per_run > 1 the leader starts its job's own mpirun on
# its node: keep --ntasks-per-node a multiple of ranks_per_run (the groups are
# consecutive ranks, and Slurm numbers the tasks of a node consecutively).
# The sweep exits 1 when some jobs failed (their errors are in DIR/summary.csv): the
# report is still worth drawing, so keep the status for the end.
status=0
srun --mpi=pmix .venv/bin/vibrofeed sweep "$SWEEP" -o "$DIR" || status=$?
# or, with Open MPI's own launcher:
#   mpirun -np "$SLURM_NTASKS" .venv/bin/vibrofeed sweep "$SWEEP" -o "$DIR" || status=$?

.venv/bin/vibrofeed sweep-report "$DIR" --plot "$DIR/plots"
exit $status
