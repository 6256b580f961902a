"""vibrofeed: DEM simulation of vibratory bulk feeding of micro-parts."""

import os as _os

# Single-threaded BLAS: vibrofeed's linear algebra is small, MPI ranks already
# use the cores, and OpenBLAS' own threads deadlock a fork (a run's worker
# process) made while another thread uses numpy. Set before numpy loads.
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

__version__ = "0.1.0"

# Public names, loaded on first use (PEP 562) so that `import vibrofeed` and
# the command line stay light: h5py, scipy and the engine binding load only
# when something needs them.
_EXPORTS = {
    "Deck": "vibrofeed.decks",
    "run_deck": "vibrofeed.engine.runner",
    "RunResult": "vibrofeed.engine.runner",
    "run_many": "vibrofeed.engine.batch",
    "RunRequest": "vibrofeed.engine.batch",
    "Result": "vibrofeed.results.reader",
    "ResultWriter": "vibrofeed.results.writer",
    "Recording": "vibrofeed.results.writer",
    "check_file": "vibrofeed.results.check",
    "AnalysisBase": "vibrofeed.postproc",
    "Transport": "vibrofeed.postproc",
    "Flights": "vibrofeed.postproc",
    "VibrofeedError": "vibrofeed.errors",
    "InputError": "vibrofeed.errors",
    "RunError": "vibrofeed.errors",
}
__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'vibrofeed' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(__all__)
