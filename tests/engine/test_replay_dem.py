"""The DEM engine of `vibrofeed replay` agrees with the model on the same inputs.

Target (issue): mean |z_DEM - z_model| <= 0.02 mm. The DEM plays the
platform's spline on a near-rigid, exactly Coulomb wall (validation/replay/dem.py).
"""

import json

import numpy as np

from helpers import vibrofeed, write_trial
from vibrofeed.validation.replay.dem import replay_dem
from vibrofeed.validation.replay.fit import MEASURED_NORMAL_FORCE_MG, prepare, replay
from vibrofeed.validation.replay.trials import load_trials, read_trial

MASS, G, MU = 0.009, 9.81, 0.6


def compare(trial, force, tmp_path):
    prep = prepare(trial)
    model = replay(prep, MASS, force, MU, MU)
    dem = replay_dem(prep, MASS, force, MU, tmp_path / f"{trial.name}.h5")
    assert len(dem.t) == len(model.t)
    assert np.abs(dem.t - model.t).max() < 1e-5  # frames at the trial's times
    return model, dem, float(np.mean(np.abs(dem.predicted_mm - model.predicted_mm)))


def test_synthetic_stick_slip_trial(tmp_path):
    # Platform up to ~2.7 g; a grasp of 3 m g (stick band -2.8 g .. +0.8 g)
    # makes the part stick and slip every period (and slide down overall).
    trial = read_trial(write_trial(tmp_path / "trial_9.csv", n=200))
    model, dem, diff = compare(trial, 3 * MASS * G, tmp_path)
    assert 0.2 < model.stuck_fraction < 0.9  # it does stick and slip
    assert diff <= 0.02
    assert abs(dem.final_predicted_mm - model.final_predicted_mm) <= 0.02


def test_cli_dem_engine(tmp_path):
    path = write_trial(tmp_path / "trial_9.csv", n=120)
    common = [path, "--mass", MASS, "--normal-force", 2 * MASS * G, "--mu-s", MU, "--mu-k", MU, "--json"]
    dem = json.loads(vibrofeed("replay", *common, "--engine", "dem", "-o", tmp_path / "out",
                               check=True).stdout)
    model = json.loads(vibrofeed("replay", *common, check=True).stdout)
    assert dem["engine"] == "dem" and (tmp_path / "out" / "trial_9.h5").is_file()
    assert abs(dem["final_predicted_mm"] - model["final_predicted_mm"]) <= 0.02
    assert abs(dem["mean_abs_error_mm"] - model["mean_abs_error_mm"]) <= 0.02


def test_measured_trial_5(tmp_path, measured_trials_dir):
    trial = next(t for t in load_trials(measured_trials_dir) if t.number == 5)  # low grasp, long slips
    model, dem, diff = compare(trial, MEASURED_NORMAL_FORCE_MG[5] * MASS * G, tmp_path)
    assert diff <= 0.02
