"""The analytic models' cross-check against DEM (the models are ``vibrofeed.models``).

cases.py       the validation cases, one TOML file each in cases/
crosscheck.py  a case run through LIGGGHTS and through the model, compared
micro_checks.py  the comparison kinds of the micro-scale surface forces
outcome.py     what a case produces: its runs, compared rows, outcome
plots.py       the figures of ``vibrofeed validate``
replay/        measured trials replayed (``vibrofeed replay``)
studies/       one-off studies kept apart from the library code (feeding, vertical)
"""
