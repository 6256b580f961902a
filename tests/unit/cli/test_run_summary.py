"""The one-line summary `vibrofeed run` prints: a result it cannot analyse fully says so and
is still summarised (the run did what it said; its summary must not fail it)."""

import math

import numpy as np

from helpers import parts, write_result
from vibrofeed.engine.runner import RunResult
from vibrofeed.run_summary import run_summary

FREQ = 50.0  # [Hz]


def one_part(path, frames_per_period: float, periods: int = 6):
    """A part resting on a plate that moves normal to itself, A = 10 um, sampled at the given
    number of frames per period."""
    dt = 1 / (FREQ * frames_per_period)
    times = np.arange(0, periods / FREQ + 1e-12, dt)
    w, amp = 2 * math.pi * FREQ, 1e-5
    frames, surface = [], []
    for k, t in enumerate(times):
        z = amp * math.sin(w * t)
        frames.append((k, float(t), parts([1], [[0.0, 0.0, z + 5e-4]])))
        surface.append((np.array([0, 0, z]), np.array([0, 0, amp * w * math.cos(w * t)])))
    write_result(path, frames, surface=surface)
    return RunResult(output=path, log=path.with_suffix(".log"), deck="single_part", ranks=1,
                     n_steps=len(times), dt=1e-6, frames=len(times), sim_time=float(times[-1]), wall=1.0)


def test_frames_too_sparse_for_the_hops_are_said_not_to_count_them(tmp_path):
    line = run_summary(one_part(tmp_path / "sparse.h5", frames_per_period=1))
    assert "hops not counted" in line and "output_dt <= 0.0025 s" in line  # T/8 at 50 Hz


def test_frames_that_follow_the_surface_count_the_hops(tmp_path):
    line = run_summary(one_part(tmp_path / "dense.h5", frames_per_period=20))
    assert "0 hops" in line and "hops not counted" not in line
