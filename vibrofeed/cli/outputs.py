"""Where the commands write: destinations checked before any work, files checked after.

Every command that writes a file or a folder of files asks here first
(:func:`file_destination`, :func:`folder_destination`: a bad destination is
one line and exit status 2 before minutes of work) and, once it has written,
checks that what it is about to report exists and is not empty
(:func:`written`: exit status 1 otherwise). A folder that exists is not
enough: /proc, a read-only mount or a folder of another user accept nothing,
so the check writes (and removes) a nameless file in it.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from ..errors import OutputError, UsageError


def _writable(option: str, given, folder: Path) -> None:
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise UsageError(f"{option} {given}: cannot write in {folder} ({exc.strerror or exc})") from None


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
    return folder


def written(path) -> Path:
    """``path``, once the command wrote it: an :class:`OutputError` (exit 1) if it
    is missing or empty, so that no command reports a file that is not there."""
    out = Path(path)
    try:
        size = out.stat().st_size if out.is_file() else None
    except OSError:
        size = None
    if size is None:
        raise OutputError(f"{path} was not written")
    if size == 0:
        raise OutputError(f"{path} was written empty")
    return out
