"""The same run on 1 and 2 MPI ranks gives the same trajectory, to round-off.

The plate is split between the ranks, so the contact forces on the part can be
summed in another order: the last bit may differ. Over this short run (0.03 s,
two hops) nothing amplifies that, so the trajectories must agree to 1e-9
relative; a decomposition error (a lost contact, a ghost counted twice) would
show up at the scale of the motion itself.
"""

import numpy as np

from helpers import vibrofeed
from vibrofeed.results.reader import Result


def test_one_and_two_ranks_agree(tmp_path):
    args = ["-q", "-p", "t_end=0.03", "-p", "amp_n=2e-4", "-p", "rolling=1"]
    vibrofeed("run", "single_part", "-o", tmp_path / "np1.h5", *args, check=True)
    vibrofeed("run", "single_part", "-o", tmp_path / "np2.h5", "-n", "2", *args, check=True)
    with Result(tmp_path / "np1.h5") as a, Result(tmp_path / "np2.h5") as b:
        assert b.run_info["ranks"] == 2 and a.run_info["ranks"] == 1
        assert a.n_frames == b.n_frames > 100
        for name in ("position", "velocity", "angular_velocity"):
            x, y = getattr(a, name), getattr(b, name)
            assert np.abs(x - y).max() <= 1e-9 * np.abs(x).max(), name
        assert np.abs(a.angular_velocity).max() > 0  # rolling=1: the part does spin
