"""The one build step pyproject.toml cannot declare: the abort shim.

``native/abort_flush.c`` (see its header) is compiled with the MPI compiler
wrapper, ``mpicc`` or ``$MPICC``, into the package as
``vibrofeed/engine/libvibrofeed_abortflush.so``, where
:func:`vibrofeed.engine.runner.abort_shim` finds it.

It is built here, at install time, rather than at first use into a cache:
the shim must link the MPI library that mpi4py and LIGGGHTS use, and that is
the MPI present when the package is installed (mpi4py is compiled against it
then too). A build at first use would need a compiler and a writable cache
on every node a job runs on, and the workers of a sweep would race to make it.
"""

import atexit
import os
import shutil
import tempfile

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.errors import CompileError

SHIM = "vibrofeed.engine.libvibrofeed_abortflush"


def _scratch() -> str:
    folder = tempfile.mkdtemp(prefix="vibrofeed-build-")
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return folder


class BuildShim(build_ext):
    """Compile the shim as a plain shared library with mpicc (the wrapper knows
    the MPI's headers and libraries; it is no Python extension)."""

    def get_ext_filename(self, fullname):
        return os.path.join(*fullname.split(".")) + ".so"  # no Python ABI tag: it is not imported

    def build_extension(self, ext):
        mpicc = os.environ.get("MPICC") or shutil.which("mpicc")
        if not mpicc:
            raise CompileError("vibrofeed needs the MPI C compiler wrapper `mpicc` to build its abort "
                               "shim: apt-get install libopenmpi-dev, or set MPICC to its path")
        target = self.get_ext_fullpath(ext.name)
        self.mkpath(os.path.dirname(target))
        self.spawn([mpicc, "-O2", "-Wall", "-fPIC", "-shared", "-o", target, *ext.sources])


setup(ext_modules=[Extension(SHIM, sources=["native/abort_flush.c"])],
      cmdclass={"build_ext": BuildShim},
      # A fresh scratch folder for each build, removed after it: setuptools never empties its
      # build/lib nor forgets the files an earlier build listed in its egg-info, so a file
      # taken out of the package data would linger in the next wheel (and build/ is CMake's).
      options={"build": {"build_base": _scratch()}, "egg_info": {"egg_base": _scratch()}})
