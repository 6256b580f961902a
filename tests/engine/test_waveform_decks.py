"""The deck's waveforms: the mesh is where vibrofeed records the surface, and
the recorded motion is the model's waveform (models.deck)."""

import math
import shutil
import subprocess

import numpy as np
import pytest

from helpers import DECKS, vibrofeed
from vibrofeed.models import deck as dm
from vibrofeed.results.reader import Result

WAVEFORMS = {0: "sine", 1: "square", 2: "stick-slip", 3: "Coulomb pump"}
PARAMS = {"freq": "50", "amp_t": "1e-4", "amp_n": "8e-5", "phase": "60", "duty": "0.7"}


def read_stl_vertices(path):
    return np.array([[float(v) for v in line.split()[1:4]]
                     for line in open(path) if line.strip().startswith("vertex")])


@pytest.mark.parametrize("waveform", sorted(WAVEFORMS))
def test_mesh_is_where_the_surface_is_recorded(tmp_path, waveform):
    # Run the deck by hand with a mesh dump and a print of the recorded surface.
    deck = tmp_path / "d.liggghts"
    text = (DECKS / "single_part.liggghts").read_text()
    extra = ("dump stl all mesh/stl 100 mesh_*.stl\n"
             "variable rec_step equal step\n"
             'fix rec all print 100 "${rec_step} ${surface_x} ${surface_z}" file surface.txt screen no\n')
    marker = "# ------------------------------------------------------------------ run"
    deck.write_text(text.replace(marker, extra + marker))
    shutil.copytree(DECKS / "meshes", tmp_path / "meshes")
    shutil.copytree(DECKS / "include", tmp_path / "include")
    args = ["liggghts", "-in", str(deck), "-var", "deck_dir", str(tmp_path), "-var", "t_end", "0.004",
            "-var", "waveform", str(waveform), "-log", "log", "-nocite"]
    for k, v in PARAMS.items():
        args += ["-var", k, v]
    subprocess.run(args, cwd=tmp_path, check=True, capture_output=True)
    # check/timestep/gran reports the timestep's fractions of the Rayleigh and
    # Hertz times in the thermo output, for a user running by hand
    log = (tmp_path / "log").read_text()
    assert "ts[1]" in log and "ts[2]" in log
    reference = read_stl_vertices(DECKS / "meshes" / "plate.stl")
    surface = np.loadtxt(tmp_path / "surface.txt")
    assert len(surface) >= 5
    plate_len = None
    for step, sx, sz in surface:
        v = read_stl_vertices(tmp_path / f"mesh_{int(step)}.stl")
        if plate_len is None:  # the scale: the strip's x extent
            plate_len = (v[:, 0].max() - v[:, 0].min()) / (reference[:, 0].max() - reference[:, 0].min())
        moved = v - reference * plate_len
        # STL dumps print 6 significant digits: ~1e-7 m on the plate's x
        # coordinates (~1e-2 m), ~1e-10 m on its z (~1e-4 m), which resolves the
        # O(w dt amp) ~ 5e-8 m between a mover's Riemann sum and amp sin(w t).
        assert np.allclose(moved[:, 0], sx, atol=1e-5 * np.abs(v[:, 0]).max())
        assert np.allclose(moved[:, 2], sz, atol=1e-5 * np.abs(v[:, 2]).max() + 1e-12)


@pytest.mark.parametrize("waveform", sorted(WAVEFORMS))
def test_recorded_surface_is_the_model_waveform(tmp_path, waveform):
    out = tmp_path / "w.h5"
    args = ["run", "single_part", "-q", "-o", out, "-p", "t_end=0.02", "-p", "output_dt=2e-4",
            "-p", f"waveform={waveform}", "-p", "rolling=0"]
    for k, v in PARAMS.items():
        args += ["-p", f"{k}={v}"]
    vibrofeed(*args, check=True)
    with Result(out) as r:
        t, pos, vel = r.time, r.surface_position, r.surface_velocity
        dt = r.derived["dt_used"]
        params = {k: str(v) for k, v in r.parameters.items()}
    wf = dm.waveform(params)
    (x, z), (vx, vz) = wf.position(t), wf.velocity(t)
    if waveform in (2, 3):
        z = vz = np.zeros_like(t)  # in-plane waveforms
    amp = max(float(PARAMS["amp_t"]), float(PARAMS["amp_n"]))
    w = 2 * math.pi * float(PARAMS["freq"])
    # The sine plate follows LIGGGHTS' Riemann sums: O(w dt) off the analytic sine.
    tol = 2 * w * dt * amp if waveform == 0 else 1e-12
    assert np.abs(pos[:, 0] - x).max() <= tol
    assert np.abs(pos[:, 2] - z).max() <= tol
    assert np.abs(vel[:, 0] - vx).max() <= 1e-9 * w * amp
    assert np.abs(vel[:, 2] - vz).max() <= 1e-9 * w * amp
    assert np.abs(pos[:, 0]).max() > 0.5 * float(PARAMS["amp_t"])  # it does move
