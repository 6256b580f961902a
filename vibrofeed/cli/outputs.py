"""Where the commands write: destinations checked before any work, files checked after.

Every command that writes a file or a folder of files asks here first
(:func:`file_destination`, :func:`folder_destination`: a bad destination is
one line and exit status 2 before minutes of work; a full disk, exit status 1)
and, once it has written, checks that what it is about to report is whole
(:func:`written`: exit status 1 otherwise). A folder that exists is not
enough: /proc, a read-only mount or a folder of another user accept nothing,
so the check writes (and removes) a nameless file in it. Whole means more than
not empty: a writer that meets a full disk may stop half-way and say nothing
(VTK's PNG writer does), so a PNG must reach its end chunk, an MP4 its index,
a VTK XML file its closing tag and an HDF5 file must open. A command that can
choose where its writer writes uses :func:`replaced`: the file appears under its
name only once whole, and an older file of that name survives a failure.

Any other :class:`OSError` a command meets while writing reaches
:func:`vibrofeed.cli.main`, which prints it as one line through
:func:`os_error` (exit status 2 for a path that cannot be written, 1 for a
full disk or an I/O error).
"""

from __future__ import annotations

import errno
import os
import secrets
import struct
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from ..disk import free_bytes, mount_point
from ..errors import EXIT_FAILED, EXIT_USAGE, OutputError, UsageError

# errno of an OSError -> exit status: a path the user gave that cannot be written is
# the request's fault (2); a full disk or a failing device is the run's (1, the default).
_BAD_PATH = {errno.EISDIR, errno.ENOTDIR, errno.EACCES, errno.EPERM, errno.EROFS, errno.ENOENT,
             errno.ENAMETOOLONG, errno.EEXIST, errno.ELOOP}
# Errors only writing meets: one that does not name its file (a plotting library's) is
# told where the command was writing.
_FULL = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG}

# The destinations this command checked (file_destination, folder_destination), latest last.
_destinations: list[Path] = []


def _full(folder) -> str:
    """``; no space left on MOUNT`` when ``folder``'s file system is full, else ''."""
    return f"; no space left on {mount_point(folder)}" if free_bytes(folder) == 0 else ""


def os_error(exc: OSError) -> tuple[str, int]:
    """(one-line message, exit status) of an OSError a command met while writing."""
    what = exc.strerror or str(exc).split("\n", 1)[0] or type(exc).__name__
    target = exc.filename
    if target is None and exc.errno in _FULL and _destinations:
        target = _destinations[-1]
    if exc.errno == errno.ENOSPC and target is not None:  # (target need not exist: mount_point)
        what = f"no space left on {mount_point(target)}"
    if exc.filename is not None and exc.filename2 is not None:
        where = f"cannot move {exc.filename} to {exc.filename2}: "
    elif exc.filename is not None:
        where = f"{exc.filename}: "
    elif target is not None:
        where = f"writing into {target}: "
    else:
        where = ""
    code = EXIT_USAGE if exc.errno in _BAD_PATH else EXIT_FAILED
    return " ".join(f"{where}{what}".split()), code


def _writable(option: str, given, folder: Path) -> None:
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise UsageError(f"{option} {given}: cannot write in {folder} ({exc.strerror or exc})") from None
    if free_bytes(folder) == 0:  # a file could be created, but not one byte written into it
        raise OutputError(f"{option} {given}: no space left on {mount_point(folder)}")


def _existing_folder(option: str, given, folder: Path, parents: bool) -> Path:
    """``folder`` if it exists; with ``parents``, the nearest ancestor that does (the
    command creates the rest). Refused if that is not a folder or takes no file."""
    if parents:
        while not folder.exists() and folder != folder.parent:
            folder = folder.parent
    if not folder.is_dir():
        why = "is not a folder" if folder.exists() else "does not exist"
        raise UsageError(f"{option} {given}: folder {folder} {why}")
    _writable(option, given, folder)
    return folder


def file_destination(option: str, path, suffixes: tuple[str, ...] = (), parents: bool = False) -> Path:
    """``path``, a file the command will write: refused if it is a folder, if its
    folder does not exist (with ``parents``: cannot be created) or takes no
    file, or (with ``suffixes``) if its suffix is not one of them."""
    out = Path(path).expanduser()
    if suffixes and out.suffix.lower() not in suffixes:
        raise UsageError(f"{option} {path}: must end in {' or '.join(suffixes)}")
    if out.is_dir():
        raise UsageError(f"{option} {path}: is a folder; give a file name")
    if out.exists() and not out.is_file():
        raise UsageError(f"{option} {path}: exists and is not a regular file")
    _existing_folder(option, path, out.absolute().parent, parents)
    _destinations.append(out)
    return out


def folder_destination(option: str, path, create: bool = True, parents: bool = False) -> Path:
    """``path``, a folder the command will write into, created now when ``create``
    (else when the command writes). A mistyped parent is refused rather than
    created silently, unless ``parents`` (a default such as results/NAME)."""
    folder = Path(path).expanduser()
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"{option} {path}: not a folder")
    target = folder.absolute()
    _existing_folder(option, path, target if folder.is_dir() else target.parent, parents)
    if create and not folder.is_dir():
        try:
            folder.mkdir(parents=parents, exist_ok=True)
        except OSError as exc:
            raise UsageError(f"{option} {path}: cannot create it ({exc.strerror or exc})") from None
    _destinations.append(folder)
    return folder


def names_in(option: str, folder, names) -> None:
    """Refuse, before any work, a file the command will write into ``folder`` whose name
    is taken by something that is not a file (a folder called ``RUN.pvd``)."""
    for name in names:
        path = Path(folder) / name
        if path.exists() and not path.is_file():
            what = "a folder" if path.is_dir() else "not a regular file"
            raise UsageError(f"{option} {folder}: {path} is {what}; the command writes a file there")


def not_an_input(option: str | None, given, path, inputs) -> None:
    """Refuse, before any work, a file the command would write at ``path`` that is one of the
    files it reads (``inputs``): it would be replaced while read, or by what was made of it.
    ``option``: the option that named ``path`` (None for a default name, said as such)."""
    target = Path(path).expanduser().absolute()
    for source in inputs:
        source = Path(source).expanduser()
        same = source.resolve() == target.resolve()
        if not same and source.exists() and target.exists():
            same = os.path.samefile(source, target)  # (a hard link)
        if same:
            said = f"{option} {given}" if option else f"the output {given} (the default: name it with -o)"
            raise UsageError(f"{said}: writing {path} would replace {source}, which the command "
                             "reads; give another output")


# ----------------------------------------------------------------- whole files
_PNG = b"\x89PNG\r\n\x1a\n"


def _png(f, size: int) -> str | None:
    if f.read(8) != _PNG:
        return "it does not start as a PNG"
    pos = 8
    while pos + 8 <= size:  # chunks: length, type (8 bytes), then data and CRC
        f.seek(pos)
        length, kind = struct.unpack(">I4s", f.read(8))
        pos += 12 + length
        if kind == b"IEND":
            return None if pos <= size else "its end chunk is cut"
    return f"its image data stops after {size} bytes, before the end chunk"


def _iso_media(f, size: int) -> str | None:
    """An MP4 (ISO base media file): top-level boxes that tile the file, one of them the index."""
    pos, kinds = 0, set()
    while pos < size:
        f.seek(pos)
        head = f.read(16)
        if len(head) < 8:
            return f"it stops inside a box header at byte {pos}"
        n, kind = struct.unpack(">I4s", head[:8])
        if n == 1 and len(head) == 16:  # a 64-bit size follows
            n = struct.unpack(">Q", head[8:])[0]
        elif n == 0:  # the last box runs to the end of the file
            n = size - pos
        if n < 8:
            return f"it has a malformed box at byte {pos}"
        kinds.add(kind)
        pos += n
    if pos != size:
        return f"its data stops after {size} of {pos} bytes"
    return None if b"moov" in kinds else "it has no index (moov box): the movie was not finished"


_VTK_END = b"</VTKFile>"


def _vtk_xml(f, size: int) -> str | None:
    end = size  # past the closing tag: white space only, however much (read back in blocks)
    while end > 0:
        start = max(0, end - 4096)
        f.seek(start)
        kept = f.read(end - start).rstrip()
        end = start + len(kept)
        if kept:
            break
    f.seek(max(0, end - len(_VTK_END)))
    return None if f.read(end - f.tell()) == _VTK_END else f"it stops before {_VTK_END.decode()}"


def _hdf5(path: Path) -> str | None:
    import h5py

    try:
        with h5py.File(path, "r"):
            return None
    except OSError as exc:
        return f"HDF5 cannot open it ({str(exc).splitlines()[0] if str(exc) else 'damaged'})"


_CHECKS = {".png": _png, ".mp4": _iso_media, ".pvd": _vtk_xml, ".vtp": _vtk_xml, ".vtu": _vtk_xml}


def incomplete(path) -> str | None:
    """Why the file at ``path`` is not whole for its kind (by suffix: PNG, MP4, VTK XML,
    HDF5; any other kind only not empty), or None when it is."""
    path = Path(path)
    size = path.stat().st_size
    if size == 0:
        return "it is empty"
    suffix = path.suffix.lower()
    if suffix in (".h5", ".h5md", ".hdf5"):
        return _hdf5(path)
    check = _CHECKS.get(suffix)
    if check is None:
        return None
    with open(path, "rb") as f:
        return check(f, size)


def written(path, name=None) -> Path:
    """``path``, once the command wrote it: an :class:`OutputError` (exit 1) if it is
    missing, empty or cut short (:func:`incomplete`), so that no command reports a file
    that is not there. ``name``: the file as the user knows it, for the message."""
    out = Path(path)
    name = out if name is None else name
    try:
        why = incomplete(out) if out.is_file() else "missing"
    except OSError as exc:
        why = exc.strerror or str(exc)
    if why == "missing":
        raise OutputError(f"{name} was not written")
    if why == "it is empty":
        raise OutputError(f"{name} was written empty{_full(out.absolute().parent)}")
    if why is not None:
        raise OutputError(f"{name} is incomplete: {why}{_full(out.absolute().parent)}")
    return out


@contextmanager
def replaced(path) -> Iterator[Path]:
    """A temporary name beside ``path`` (same suffix: writers choose the format by it)
    for the block to write; once it has, the file is checked whole (:func:`written`) and
    renamed to ``path``. On any failure the temporary file is removed: ``path`` is never a
    partial file, and an older file of that name is kept."""
    path = Path(path)
    tmp = path.with_name(f".{path.stem}.{secrets.token_hex(4)}.part{path.suffix}")
    try:
        yield tmp
        written(tmp, name=path)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
