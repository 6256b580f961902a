"""`vibrofeed replay` with the model engine: figures, plot, fit, and bad input."""

import json

import pytest

from helpers import vibrofeed, write_trial
from vibrofeed.models.constants import G

MASS = 0.009
KEYS = {"mean_abs_error_mm", "max_displacement_mm", "final_measured_mm", "final_predicted_mm",
        "stuck_fraction"}


@pytest.fixture
def trial(tmp_path):
    # The synthetic part rides on the platform (2 mm above it): with a grasp of
    # 40 m g (stick band +-28 g) it never slips, and the model must say so.
    return write_trial(tmp_path / "trial_7.csv")


def test_replay_reports_the_figures_as_json(trial):
    proc = vibrofeed("replay", trial, "--mass", MASS, "--normal-force", 40 * MASS * G,
                     "--mu-s", 0.72, "--mu-k", 0.6, "--json", check=True)
    out = json.loads(proc.stdout)
    assert KEYS <= set(out) and out["trial"] == "trial_7" and out["engine"] == "model"
    # Part stuck to the platform: prediction = platform motion = measured part
    # motion, up to the 5 um tracking noise of the synthetic file.
    assert out["stuck_fraction"] > 0.99
    assert out["mean_abs_error_mm"] < 0.02
    assert abs(out["final_predicted_mm"] - out["final_measured_mm"]) < 0.03
    assert out["max_displacement_mm"] > 0.3  # the platform moves 0.4 mm


def test_replay_text_and_plot(trial, tmp_path):
    png = tmp_path / "r.png"
    proc = vibrofeed("replay", trial, trial, "--mass", MASS, "--normal-force", 40 * MASS * G,
                     "--mu-s", 0.72, "--mu-k", 0.6, "--plot", png, check=True)
    assert proc.stdout.count("trial_7 (model): mean abs error") == 2
    assert png.stat().st_size > 10_000


def test_fit_finds_forces_that_keep_the_part_stuck(trial, tmp_path):
    other = write_trial(tmp_path / "trial_8.csv", seed=3)
    proc = vibrofeed("replay", "--fit", trial, other, "--mass", MASS, "--mu-s", 0.72, "--json",
                     check=True)
    out = json.loads(proc.stdout)
    assert {t["trial"] for t in out["trials"]} == {"trial_7", "trial_8"}
    assert 0 < out["mu_k"] <= 0.72
    assert out["mean_abs_error_mm"] < 0.02
    for t in out["trials"]:
        assert t["normal_force"] == pytest.approx(t["normal_force_mg"] * MASS * G, rel=1e-12)  # N, ~0.9


@pytest.mark.parametrize("args, fragment", [
    (["--normal-force", "1", "--mu-s", "0.5", "--mu-k", "0.5"], "--mass is required"),
    (["--mass", "0.009", "--mu-s", "0.5", "--mu-k", "0.5"], "--normal-force is required"),
    (["--mass", "-1", "--normal-force", "1", "--mu-s", "0.5", "--mu-k", "0.5"], "--mass: must be > 0"),
    (["--mass", "0.009", "--normal-force", "1", "--mu-s", "0.5", "--mu-k", "0.6"], "cannot exceed"),
    (["--mass", "0.009", "--normal-force", "1", "--mu-s", "0.7", "--mu-k", "0.5", "--engine", "dem"],
     "one friction coefficient"),
])
def test_bad_arguments(trial, args, fragment):
    proc = vibrofeed("replay", trial, *args)
    assert proc.returncode == 2 and fragment in proc.stderr and "Traceback" not in proc.stderr


def test_a_file_that_is_not_a_trial_is_named(tmp_path):
    bad = tmp_path / "notes.csv"
    bad.write_text("a,b\n1,2\n")
    proc = vibrofeed("replay", bad, "--mass", MASS, "--normal-force", 1, "--mu-s", 0.5, "--mu-k", 0.5)
    assert proc.returncode == 2 and "notes.csv" in proc.stderr and "missing columns" in proc.stderr


def test_plot_into_a_missing_folder_is_refused_before_any_work(trial, tmp_path):
    """A mistyped folder is a usage error (exit 2), not created silently."""
    target = tmp_path / "no" / "such" / "dir" / "x.png"
    proc = vibrofeed("replay", trial, "--mass", MASS, "--normal-force", 40 * MASS * G,
                     "--mu-s", 0.72, "--mu-k", 0.6, "--plot", target)
    assert proc.returncode == 2 and "does not exist" in proc.stderr
    assert not (tmp_path / "no").exists() and proc.stdout == ""
