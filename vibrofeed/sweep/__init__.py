"""Sweeps: many runs of one deck over a design of parameters (``vibrofeed sweep``).

- :mod:`.spec` reads the sweep file (TOML) and refuses what it cannot run,
  naming the line; its fingerprint ties an output folder to one sweep.
- :mod:`.plan` expands it into jobs (grid, zipped lists, explicit points,
  replicates with distinct seeds), checks every job's parameters as
  ``vibrofeed run`` does, and orders them longest expected first.
- :mod:`.folder` owns the output folder: the spec's fingerprint, a lock, the
  manifest, and which jobs a rerun skips (their files checked, not merely present).
- :mod:`.summary` keeps ``summary.h5`` and ``summary.csv``, one row per finished job, as a
  ledger (a journal line per job, the files rewritten atomically now and then; the optimiser's
  ``study.*`` too); :mod:`.metrics` computes a finished job's figures.
- :mod:`.execute` runs the jobs through the executor validation shares
  (:mod:`vibrofeed.engine.batch`), ``-j`` at a time or across the groups of
  ranks of an ``mpirun`` (rank 0 dispatches); :mod:`.progress` reports done /
  running / failed and the ETA.
- :mod:`.report` is ``vibrofeed sweep-report``: the table, the best setting, the maps.
"""
