"""The analytic models of vibratory transport and their cross-check against DEM.

models/     the analytic theory (importable without the DEM machinery)
cases.py    the validation cases, one TOML file each in cases/
crosscheck.py  a case run through LIGGGHTS and through the model, compared
deck_models.py deck parameters -> model objects (the same numbers for both)
plots.py    the figures of ``vibrofeed validate``
replay/     measured trials replayed (``vibrofeed replay``)
studies/    one-off studies kept apart from the library code
"""
