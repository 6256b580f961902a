"""Studies: the feeder settings a designer needs, found in few DEM runs (``vibrofeed optimize``).

- :mod:`.spec` reads the study file (the deck, fixed parameters, design variables,
  constraints, objective, budget, robustness) and refuses what it cannot run, naming the line.
- :mod:`.screen` is the cheap first stage: each section's drive as the analytic models see
  it (peak acceleration and displacement, hopping, the single-part conveying speed) and the
  constraints' margins of a setting.
- :mod:`.objective` turns a run's metrics into objective values with errors.
- :mod:`.search` runs a study: screen, search (Optuna), confirmation, robustness.
- :mod:`.report` is ``vibrofeed optimize-report``.
"""
