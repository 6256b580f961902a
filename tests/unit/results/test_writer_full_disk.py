"""A batch the disk cannot take (issue 36: a full disk left a .part that did not open, saying
'running'): the writer drops it whole, so the file can still be closed with the frames
written before it, every series as long as ``step``, and marked failed."""

from __future__ import annotations

import errno

import h5py
import numpy as np
import pytest

from helpers import parts
from vibrofeed.results import layout as L
from vibrofeed.results.check import check_file
from vibrofeed.results.writer import ResultWriter


def test_a_batch_the_disk_cannot_take_is_dropped_whole(tmp_path, monkeypatch):
    w = ResultWriter(tmp_path / "r.h5.part", deck_name="d", deck_path="d.liggghts", deck_text="units si\n",
                     variables={"freq": ("50", "Hz", "f", "50")}, derived={"dt_used": 1e-5},
                     engine_version="LIGGGHTS (synthetic)", seed=1, run_id="ab" * 32, max_delay=60)
    for k in range(3):  # written: 3 frames on disk
        w.write_frame(k, 0.01 * k, parts([1], [[0, 0, 0]]), np.zeros(3), np.zeros(3))
    w.flush()
    real = ResultWriter._append

    def full(ds, k, block):  # the disk fills while the velocities are written
        real(ds, k, block)  # (the series grown first, as _append does)
        if ds.name.endswith("velocity/value"):
            raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(ResultWriter, "_append", staticmethod(full))
    for k in range(3, 5):
        w.write_frame(k, 0.01 * k, parts([1, 2], [[0, 0, 0], [1e-3, 0, 0]]), np.zeros(3), np.zeros(3))
    with pytest.raises(OSError):
        w.flush()
    monkeypatch.setattr(ResultWriter, "_append", staticmethod(real))
    assert w.written == 3
    w.finish(L.STATUS_FAILED, "no space left")
    with h5py.File(tmp_path / "r.h5.part") as f:
        for name in ("id", "position", "velocity", "mass", "species", "radius"):
            assert f[f"{L.PARTS}/{name}/value"].shape[0] == 3, name
        assert f[f"{L.SURFACE}/position/value"].shape[0] == 3
        assert f[L.RUN].attrs["status"] == L.STATUS_FAILED
    report = check_file(tmp_path / "r.h5.part", allow_incomplete=True)
    assert report.ok and report.frames == 3, report.problems
