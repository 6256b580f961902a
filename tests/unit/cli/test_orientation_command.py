"""`vibrofeed orientation` as a user runs it: its table, its JSON, its figure, what it refuses
and what it warns about (results of tests/bulk_synthetic.py, box-like clumps)."""

import json

import numpy as np
import pytest

from bulk_synthetic import feeder
from helpers import vibrofeed
from vibrofeed.postproc import Orientation
from vibrofeed.results.reader import Result

BOX = np.array([[x, y, 0.0, 5e-5] for x in (-2e-4, -1e-4, 0.0, 1e-4, 2e-4) for y in (-5e-5, 5e-5)])
UP, CROSS = [1.0, 0, 0, 0], [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)]   # lengthwise, crosswise
GATE = {"gate_width": ("6e-4", "m", "", "0"), "gate_at": ("0.5", "-", "", "0.7"),
        "track_width": ("1.2e-3", "m", "", "1e-3")}
KEYS = {"correct", "correct_source", "run_correct", "within", "n_delivered", "state_fractions",
        "lengthwise_fraction", "correct_fraction", "correct_rate", "correct_rate_err", "oriented_rate",
        "oriented_rate_err", "singulated_fraction", "parts_per_s", "parts_per_s_err",
        "recirculation_per_s", "recirculation_per_s_err", "recirculation_source", "stations", "census_x",
        "census_fractions", "census_correct", "census_count", "steady_from", "steady_to", "reason"}


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    # 60 parts, one every 10 ms from 0.4 s; every other one crosswise until the gate turns it
    n = 60
    exits = 0.403 + 0.01 * np.arange(n)
    before = np.array([UP if k % 2 else CROSS for k in range(n)])
    path = tmp_path_factory.mktemp("orient") / "boxes.h5"
    return feeder(path, np.arange(0, 1.2 + 1e-9, 0.01), exits, speed=0.05, orientations=before,
                  turn=(0.0101, np.tile(UP, (n, 1))), body_template=BOX, lanes=np.arange(n) % 6 * 1e-3,
                  variables=GATE)


def test_json_holds_the_analysis_figures(run_file):
    figures = json.loads(vibrofeed("orientation", run_file, "--json", check=True).stdout)
    assert set(figures) == KEYS
    with Result(run_file) as r:
        o = Orientation(r).run().results
    assert figures["oriented_rate"] == pytest.approx(o.oriented_rate, rel=1e-12)
    assert figures["correct_fraction"] == 1.0                   # all turned lengthwise by the gate
    (gate,) = figures["stations"]
    assert gate["name"] == "s1.gate" and gate["efficiency"] == pytest.approx(2.0, rel=0.2)
    assert set(figures["census_fractions"]) == {"up", "down", "side", "end"}


def test_the_table_and_the_figure(run_file, tmp_path):
    png = tmp_path / "states.png"
    proc = vibrofeed("orientation", run_file, "--correct", "up|down, lengthwise", "--plot", png, check=True)
    assert "oriented rate" in proc.stdout and "parts/s correct and single" in proc.stdout
    assert "s1.gate" in proc.stdout and "recirculation" in proc.stdout
    assert f"figure: {png}" in proc.stdout and png.stat().st_size > 0
    assert proc.stderr == ""


def test_an_angle_that_looks_like_radians_is_warned_about(run_file):
    proc = vibrofeed("orientation", run_file, "--within", "0.3", "--json")
    lines = proc.stderr.splitlines()
    assert lines[0] == ("vibrofeed: warning: --within 0.3 deg looks like radians (0.3 rad is 17.2 deg; "
                        "--within is in degrees)")
    assert json.loads(proc.stdout)["within"] == 0.3               # it goes on, as told


def test_a_state_that_does_not_exist_and_spheres_are_refused_in_one_line(run_file, tmp_path):
    proc = vibrofeed("orientation", run_file, "--correct", "upright")
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr == ("vibrofeed: error: --correct: no state named 'upright'; the states are up, "
                           "down, side, end\n")
    spheres = feeder(tmp_path / "spheres.h5", np.arange(0, 0.5, 0.01), [0.1, 0.2])
    proc = vibrofeed("orientation", spheres)
    assert proc.returncode == 2 and len(proc.stderr.splitlines()) == 1
    assert "spheres have no orientation" in proc.stderr


def test_the_runs_own_correct_is_the_default_and_correct_overrides_it_saying_so(tmp_path):
    # the run says "down, any-direction": its parts, all face up, are none of them correct
    path = feeder(tmp_path / "down.h5", np.arange(0, 1.2 + 1e-9, 0.01), 0.403 + 0.01 * np.arange(30),
                  speed=0.05, orientations=np.tile(UP, (30, 1)), body_template=BOX,
                  lanes=np.arange(30) % 6 * 1e-3,
                  variables={"correct": ("down,any-direction", "-", "", "up,lengthwise")})
    own = vibrofeed("orientation", path, check=True).stdout
    assert "correct        down, any-direction (the run's parameter correct;" in own
    assert "correct 0.0 %" in own
    told = vibrofeed("orientation", path, "--correct", "up", "--json", check=True).stdout
    figures = json.loads(told)
    assert (figures["correct"], figures["correct_source"]) == ("up, lengthwise", "given")
    assert figures["run_correct"] == "down, any-direction" and figures["correct_fraction"] == 1.0
    table = vibrofeed("orientation", path, "--correct", "up", check=True).stdout
    assert "(--correct, overriding the run's down, any-direction;" in table


def test_an_angle_beyond_a_right_angle_is_refused_naming_the_option(run_file):
    proc = vibrofeed("orientation", run_file, "--within", "200")
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr == ("vibrofeed: error: orientation: argument --within: must be <= 90, got 200 "
                           "(see vibrofeed orientation --help)\n")
