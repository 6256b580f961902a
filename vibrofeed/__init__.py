"""vibrofeed: DEM simulation of vibratory bulk feeding of micro-parts."""

import os as _os

# Single-threaded BLAS: vibrofeed's linear algebra is small, MPI ranks already
# use the cores, and OpenBLAS' own threads deadlock a fork (a run's worker
# process) made while another thread uses numpy. Set before numpy loads.
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

__version__ = "0.1.0"
