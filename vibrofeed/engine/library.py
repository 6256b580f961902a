"""ctypes binding to the LIGGGHTS shared library (``libliggghts.so.3``).

One :class:`Liggghts` object is one engine instance on an MPI communicator
passed in through mpi4py, like LAMMPS' own Python module. Every C function used
here has its signature declared once, in :func:`_load`.

LIGGGHTS ends the *process* on an input error (``error->all`` calls ``exit``,
``error->one`` calls ``MPI_Abort``), so no exception can be raised here for
engine errors: run an instance in a worker process of its own and turn its
exit into an exception in the parent (see :mod:`vibrofeed.engine.runner`).
A second instance in the same process floods warnings about duplicate
styles: keep one instance per process.
"""

from __future__ import annotations

import ctypes
import os
from collections.abc import Iterable, Sequence

import numpy as np

from .. import environment
from ..errors import LibraryNotFound

LIBRARY_NAME = "libliggghts.so.3"

_c_double_p = ctypes.POINTER(ctypes.c_double)


# Per-atom quantities this binding can read: name -> (C type, values per atom).
# Scalars are 1-D C arrays, vectors are LAMMPS 2-D arrays (a pointer per atom
# into one contiguous block).
PER_ATOM = {
    "id": (ctypes.c_int, 1),  # LIGGGHTS 3.8 (2013 LAMMPS): tagint is int
    "type": (ctypes.c_int, 1),
    "radius": (ctypes.c_double, 1),
    "rmass": (ctypes.c_double, 1),
    "x": (ctypes.c_double, 3),
    "v": (ctypes.c_double, 3),
    "f": (ctypes.c_double, 3),
    "omega": (ctypes.c_double, 3),
    # body id of each sphere of a multisphere part (fix multisphere sets it);
    # not allocated for plain spheres
    "molecule": (ctypes.c_int, 1),
}



def _mpi_comm_type():
    """The C type of MPI_Comm for the MPI library mpi4py was built against."""
    from mpi4py import MPI

    if MPI._sizeof(MPI.Comm) == ctypes.sizeof(ctypes.c_int):
        return ctypes.c_int  # MPICH-style integer handles
    return ctypes.c_void_p  # Open MPI: a pointer


def _load(path: str | None = None) -> ctypes.CDLL:
    """Load the library and declare the signatures of the functions we call."""
    name = path or environment.liggghts_lib() or LIBRARY_NAME
    try:
        # RTLD_GLOBAL: LIGGGHTS' plugins and MPI need the symbols visible.
        lib = ctypes.CDLL(name, mode=ctypes.RTLD_GLOBAL)
    except OSError as exc:
        raise LibraryNotFound(
            f"cannot load the LIGGGHTS library {name} ({exc}); "
            "install it with `apt-get install libliggghts-dev` or set VIBROFEED_LIGGGHTS_LIB"
        ) from exc

    vp = ctypes.c_void_p
    lib.lammps_open.argtypes = [ctypes.c_int, ctypes.POINTER(ctypes.c_char_p),
                                _mpi_comm_type(), ctypes.POINTER(vp)]
    lib.lammps_open.restype = None
    lib.lammps_close.argtypes = [vp]
    lib.lammps_close.restype = None
    lib.lammps_file.argtypes = [vp, ctypes.c_char_p]
    lib.lammps_file.restype = None
    lib.lammps_command.argtypes = [vp, ctypes.c_char_p]
    lib.lammps_command.restype = ctypes.c_char_p
    lib.lammps_free.argtypes = [vp]
    lib.lammps_free.restype = None
    lib.lammps_extract_global.argtypes = [vp, ctypes.c_char_p]
    lib.lammps_extract_global.restype = vp
    lib.lammps_extract_atom.argtypes = [vp, ctypes.c_char_p]
    lib.lammps_extract_atom.restype = vp
    lib.lammps_extract_variable.argtypes = [vp, ctypes.c_char_p, ctypes.c_char_p]
    lib.lammps_extract_variable.restype = vp
    lib.lammps_get_natoms.argtypes = [vp]
    lib.lammps_get_natoms.restype = ctypes.c_int
    return lib


class Liggghts:
    """A LIGGGHTS instance on an MPI communicator.

    Parameters
    ----------
    args:
        Command-line arguments (without the program name), e.g.
        ``["-log", "run.log", "-screen", "run.screen", "-var", "freq", "50"]``.
        Do not pass ``-screen none``: this LIGGGHTS crashes when it then reads a
        mesh file; send the screen output to a file instead.
    comm:
        An mpi4py communicator (default ``MPI.COMM_WORLD``). All ranks of it
        must create the instance and issue the same commands.
    """

    def __init__(self, args: Sequence[str] = (), comm=None, library: str | None = None):
        from mpi4py import MPI

        self.comm = MPI.COMM_WORLD if comm is None else comm
        self._lib = _load(library)
        argv_list = [b"liggghts"] + [str(a).encode() for a in args]
        argv = (ctypes.c_char_p * len(argv_list))(*argv_list)
        handle = _mpi_comm_type()(MPI._handleof(self.comm))
        self._ptr = ctypes.c_void_p()
        self._lib.lammps_open(len(argv_list), argv, handle, ctypes.byref(self._ptr))
        if not self._ptr:
            raise RuntimeError("lammps_open returned no instance")

    # -- input ---------------------------------------------------------------
    def file(self, path: str | os.PathLike) -> None:
        """Execute an input file (a deck), as ``liggghts -in path`` would."""
        self._lib.lammps_file(self._ptr, os.fspath(path).encode())

    def command(self, line: str) -> None:
        """Execute one input command."""
        self._lib.lammps_command(self._ptr, line.encode())

    def commands(self, lines: Iterable[str]) -> None:
        for line in lines:
            self.command(line)

    # -- output --------------------------------------------------------------
    def variable(self, name: str) -> float:
        """Evaluate an equal-style variable now (collective on all ranks)."""
        ptr = self._lib.lammps_extract_variable(self._ptr, name.encode(), None)
        if not ptr:
            raise KeyError(f"no equal-style variable {name!r} is defined")
        try:
            return ctypes.cast(ptr, _c_double_p)[0]
        finally:
            self._lib.lammps_free(ptr)

    def has_variable(self, name: str) -> bool:
        try:
            self.variable(name)
        except KeyError:
            return False
        return True

    def _global(self, name: str, ctype):
        ptr = self._lib.lammps_extract_global(self._ptr, name.encode())
        if not ptr:
            raise KeyError(f"LIGGGHTS has no global quantity {name!r}")
        return ctypes.cast(ptr, ctypes.POINTER(ctype))[0]

    @property
    def dt(self) -> float:
        return self._global("dt", ctypes.c_double)

    def step_counter(self):
        """A pointer to the engine's step counter (``update->ntimestep``, int64), for a
        thread that watches the run go: reading it needs no collective call."""
        ptr = self._lib.lammps_extract_global(self._ptr, b"ntimestep")
        return ctypes.cast(ptr, ctypes.POINTER(ctypes.c_int64)) if ptr else None

    @property
    def nlocal(self) -> int:
        return self._global("nlocal", ctypes.c_int)

    @property
    def natoms(self) -> int:
        return self._lib.lammps_get_natoms(self._ptr)

    def local_atoms(self, names: Iterable[str]) -> dict[str, np.ndarray]:
        """Copies of per-atom arrays of the atoms owned by this rank.

        Returns ``{name: array}`` with ``nlocal`` rows (shape ``(nlocal,)`` or
        ``(nlocal, 3)``), in this rank's storage order.
        """
        n = self.nlocal
        out = {}
        for name in names:
            ctype, width = PER_ATOM[name]
            dtype = np.int32 if ctype is ctypes.c_int else np.float64
            if n == 0:  # arrays may not even be allocated
                out[name] = np.zeros((0,) if width == 1 else (0, width), dtype)
                continue
            ptr = self._lib.lammps_extract_atom(self._ptr, name.encode())
            if not ptr:
                raise KeyError(f"LIGGGHTS has no per-atom quantity {name!r} in this atom style")
            if width == 1:
                data = ctypes.cast(ptr, ctypes.POINTER(ctype))
                out[name] = np.ctypeslib.as_array(data, shape=(n,)).copy()
            else:
                rows = ctypes.cast(ptr, ctypes.POINTER(ctypes.POINTER(ctype)))
                out[name] = np.ctypeslib.as_array(rows[0], shape=(n, width)).copy()
        return out

    def close(self) -> None:
        if self._ptr:
            self._lib.lammps_close(self._ptr)
            self._ptr = ctypes.c_void_p()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
