"""The same run on 1 and 2 MPI ranks gives the same trajectory."""

import numpy as np

from vibrofeed.results.reader import Result

from helpers import vibrofeed


def test_one_and_two_ranks_agree(tmp_path):
    args = ["-q", "-p", "t_end=0.03", "-p", "amp_n=2e-4", "-p", "rolling=1"]
    vibrofeed("run", "single_part", "-o", tmp_path / "np1.h5", *args, check=True)
    vibrofeed("run", "single_part", "-o", tmp_path / "np2.h5", "-n", "2", *args, check=True)
    with Result(tmp_path / "np1.h5") as a, Result(tmp_path / "np2.h5") as b:
        assert b.run_info["ranks"] == 2 and a.run_info["ranks"] == 1
        assert a.n_frames == b.n_frames > 100
        # Same operations in the same order: bitwise identical, not just close.
        assert np.array_equal(a.position, b.position)
        assert np.array_equal(a.velocity, b.velocity)
        assert np.array_equal(a.angular_velocity, b.angular_velocity)
        assert np.abs(a.angular_velocity).max() > 0  # rolling=1: the part does spin
