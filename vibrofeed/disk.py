"""The file system under a path: where it is mounted and how much may still be written
(the one place the command line, the runner and the exports ask, for their "no space
left on MOUNT" lines)."""

from __future__ import annotations

import os
from pathlib import Path


def mount_point(path) -> str:
    """The mount point of the file system holding ``path`` (need not exist yet: its
    nearest existing ancestor counts)."""
    path = Path(path).resolve()
    while not os.path.ismount(path):
        path = path.parent
    return str(path)


def free_bytes(folder) -> int | None:
    """Bytes this process may still write in ``folder`` (root may use the reserved blocks);
    None when the file system does not say (some virtual ones report no blocks at all)."""
    try:
        st = os.statvfs(folder)
    except OSError:
        return None
    if st.f_blocks == 0:
        return None
    return (st.f_bfree if os.geteuid() == 0 else st.f_bavail) * st.f_frsize
