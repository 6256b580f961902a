"""Options that would do nothing are said to (issue 19): one warning line naming the option,
the rest of the request carried out; or a refusal where the option would be silently
replaced. And an option `vibrofeed` does not know is named, not taken for a missing command."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from helpers import REPO, vibrofeed, write_trial
from vibrofeed.models.constants import G

MASS = 0.009


def warnings_of(proc) -> list[str]:
    return [line for line in proc.stderr.splitlines() if line.startswith("vibrofeed: warning: ")]


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    from bulk_synthetic import feeder

    folder = tmp_path_factory.mktemp("r")
    return feeder(folder / "run.h5", np.arange(0, 0.2 + 1e-9, 0.01), 0.02 + 0.15 * np.arange(40) / 40,
                  freq=100.0)


# ----------------------------------------------------------------- render
def test_movie_options_with_a_png_are_named(run_file, tmp_path):
    out = tmp_path / "a.png"
    proc = vibrofeed("render", run_file, "-o", out, "--fps", "10", "--every", "2", check=True)
    assert warnings_of(proc) == [
        f"vibrofeed: warning: {option} has no effect: a PNG (a.png) is one frame; {option} is for a "
        "movie (.mp4)" for option in ("--every", "--fps")]
    assert proc.stdout.startswith(f"wrote {out} (1 frame")
    # their defaults given by nobody: nothing said
    assert warnings_of(vibrofeed("render", run_file, "-o", out, "--frame", "3", check=True)) == []


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="needs ffmpeg")
def test_a_frame_with_a_movie_is_named(run_file, tmp_path):
    proc = vibrofeed("render", run_file, "-o", tmp_path / "m.mp4", "--frame", "3", "--every", "5",
                     "--size", "160x96", check=True)
    assert [w for w in warnings_of(proc) if "--frame" in w] == [
        "vibrofeed: warning: --frame has no effect: a movie (m.mp4) draws every frame; --frame picks a PNG's"]
    assert len(warnings_of(proc)) == 1 and "5 frames" in proc.stdout


# ----------------------------------------------------------------- replay
@pytest.fixture
def trial(tmp_path):
    return write_trial(tmp_path / "trial_7.csv")


def test_dem_options_with_the_model_engine_are_named(trial, tmp_path):
    proc = vibrofeed("replay", trial, "--mass", MASS, "--normal-force", 40 * MASS * G, "--mu-s", 0.72,
                     "--mu-k", 0.6, "-n", "2", "-o", tmp_path / "dem", "--json", check=True)
    assert warnings_of(proc) == [
        "vibrofeed: warning: -o has no effect: the model engine runs no LIGGGHTS; -o is for --engine dem",
        "vibrofeed: warning: -n has no effect: the model engine runs no LIGGGHTS; -n is for --engine dem"]
    assert json.loads(proc.stdout)["engine"] == "model" and not (tmp_path / "dem").exists()


@pytest.mark.parametrize("extra, words", [
    (["--mu-k", "0.5"], "--mu-k: --fit fits the kinetic friction shared by the trials; drop --mu-k"),
    (["--normal-force", "1"], "--normal-force: --fit fits a normal force per trial; drop --normal-force"),
    (["--engine", "dem", "--mu-k", "0.72"], "--mu-k: --fit fits"),
    (["--engine", "dem"], "--engine dem: --fit fits the model of Yako et al."),
])
def test_what_the_fit_would_replace_is_refused(trial, extra, words):
    proc = vibrofeed("replay", "--fit", trial, "--mass", MASS, "--mu-s", 0.72, *extra)
    assert proc.returncode == 2 and proc.stderr.startswith("vibrofeed: error: ")
    assert words in proc.stderr and proc.stderr.count("\n") == 1 and proc.stdout == ""


def test_the_fit_names_dem_options_it_does_not_use(trial):
    proc = vibrofeed("replay", "--fit", trial, "--mass", MASS, "--mu-s", 0.72, "-n", "2", "--json",
                     check=True)
    assert warnings_of(proc) == ["vibrofeed: warning: -n has no effect: the model engine of --fit runs "
                                 "no LIGGGHTS; -n is for --engine dem"]
    assert 0 < json.loads(proc.stdout)["mu_k"] <= 0.72


# ----------------------------------------------------------------- validate --list
def test_run_options_with_a_listing_are_named():
    proc = vibrofeed("validate", "--list", "-j", "3", "-n", "2", "--reuse", "hop_flights", check=True)
    assert warnings_of(proc) == [
        "vibrofeed: warning: CASE has no effect: --list lists every case; hop_flights would pick cases "
        "to run",
        "vibrofeed: warning: -j has no effect: --list only lists the cases; it runs none",
        "vibrofeed: warning: -n has no effect: --list only lists the cases; it runs none",
        "vibrofeed: warning: --reuse has no effect: --list only lists the cases; it runs none"]
    cases = sorted(p.stem for p in (REPO / "validation" / "cases").glob("*.toml"))
    assert [line.split()[0] for line in proc.stdout.splitlines()] == cases
    assert warnings_of(vibrofeed("validate", "--list", check=True)) == []


# ----------------------------------------------------------------- vibrofeed --bogus
@pytest.mark.parametrize("args", [["--bogus"], ["--bogus", "decks"], ["-x", "run", "single_part"]])
def test_an_unknown_option_before_the_command_is_named(args):
    proc = vibrofeed(*args)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr == (f"vibrofeed: error: unrecognized option {args[0]} (see vibrofeed --help)\n")


def test_the_options_vibrofeed_takes_still_work():
    assert vibrofeed("--vers", check=True).stdout.startswith("vibrofeed ")  # a prefix, as argparse allows
    assert "usage: vibrofeed" in vibrofeed("-h", check=True).stdout
    assert "required: COMMAND" in vibrofeed().stderr  # nothing at all: the command is what is missing
