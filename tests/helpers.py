"""Helpers shared by the tests (import as ``from helpers import ...``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
DECKS = REPO / "decks"


def vibrofeed(*args, cwd=None, check=False, timeout=600):
    """Run the CLI in a child process (as a user would); returns CompletedProcess."""
    env = dict(os.environ)
    env.pop("VIBROFEED_DEBUG", None)
    proc = subprocess.run([sys.executable, "-m", "vibrofeed.cli", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, env=env, timeout=timeout)
    if check and proc.returncode != 0:
        raise AssertionError(f"vibrofeed {' '.join(map(str, args))} failed:\n{proc.stderr}")
    return proc


def write_result(path, frames, surface=None, variables=None, status="complete"):
    """A result file from synthetic frames: a list of (step, time, parts dict)."""
    from vibrofeed.results.writer import ResultWriter

    variables = variables or {"freq": ("50", "Hz", "vibration frequency", "50")}
    w = ResultWriter(path, deck_name="synthetic", deck_path="synthetic.liggghts",
                     deck_text="# synthetic\n", variables=variables, derived={"dt_used": 1e-6},
                     engine_version="LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)",
                     seed=1)
    for k, (step, t, parts) in enumerate(frames):
        sp = np.zeros(3) if surface is None else surface[k][0]
        sv = np.zeros(3) if surface is None else surface[k][1]
        w.write_frame(step, t, parts, sp, sv)
    if status is None:
        w.close()
    else:
        w.finish(status)
    return path


def parts(ids, positions, radius=5e-4, velocity=None, force=None, mass=1e-6):
    ids = np.asarray(ids)
    n = len(ids)
    positions = np.asarray(positions, dtype=float).reshape(n, 3)
    velocity = np.zeros((n, 3)) if velocity is None else np.asarray(velocity, float).reshape(n, 3)
    force = np.zeros((n, 3)) if force is None else np.asarray(force, float).reshape(n, 3)
    return {"id": ids, "species": np.ones(n, int), "radius": np.full(n, radius),
            "mass": np.full(n, mass), "position": positions, "velocity": velocity,
            "angular_velocity": np.zeros((n, 3)), "force": force}
