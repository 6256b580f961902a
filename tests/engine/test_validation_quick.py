"""Short DEM cross-checks for the default suite (the full set: ctest -L validation).

Each runs a validation case, or one sweep point of it, through `vibrofeed validate`, with
the case file's own parameters and tolerances: a hopping part's lift-off, landings and
flight times, the conveying speed of a hopping part, a box's free rocking, its rocking
onset and its tipping or sliding on an incline.
"""

import json
import re

import pytest

from helpers import vibrofeed
from vibrofeed.validation.cases import CASES_DIR


def one_point(tmp_path, name, key, value):
    """A copy of case `name` whose sweep is the single value `key = value`."""
    text = (CASES_DIR / f"{name}.toml").read_text()
    text, n = re.subn(r"(?ms)^\[sweep\]\n.*?(?=^\[)", f"[sweep]\n{key} = [{value}]\n\n", text)
    assert n == 1
    text = text.replace("zip = true\n", "")
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("name, key, value", [
    ("hop_flights", "gamma", 2.0),
    ("hop_speed", "gamma", 1.5),
])
def test_quick_cross_check(tmp_path, name, key, value):
    case = one_point(tmp_path, name, key, value)
    if name == "hop_speed":  # its sweep moves both amplitudes: pin the tangential one
        case.write_text(case.read_text().replace("[parameters]\n", f"[parameters]\ngamma_t = {value}\n"))
    proc = vibrofeed("validate", case, "-o", tmp_path / "out", "--json")
    rows = json.loads(proc.stdout)
    assert rows, proc.stderr
    for row in rows:
        assert set(row) >= {"case", "quantity", "model", "dem", "rel_diff", "tolerance", "passed"}
    failed = [r for r in rows if not r["passed"]]
    assert not failed, failed
    assert proc.returncode == 0
    assert list((tmp_path / "out" / name).glob("*.png")), "the overlay figure is written"


def test_quick_free_rocking(tmp_path):
    """A box released tilted on its end: the impact speed and Housner's ratio (one run, ~7 s)."""
    proc = vibrofeed("validate", "free_rocking", "-o", tmp_path / "out", "--json")
    rows = json.loads(proc.stdout)
    assert {r["quantity"].split("[")[0] for r in rows} == {"impact_speed", "impact_ratio"}, proc.stderr
    assert all(r["passed"] for r in rows), rows
    assert proc.returncode == 0


@pytest.mark.parametrize("name, quantity", [("rocking_onset", "rocks"), ("tip_or_slide", "regime")])
def test_quick_rocking_and_tipping(tmp_path, name, quantity):
    """Housner's onset (two aspect ratios, 0.85x and 1.15x the threshold) and tipping or sliding
    on an incline (both sides of both boundaries): every run's regime equals the closed form's,
    the case file's tolerance (abs 0), four short single-box runs each."""
    proc = vibrofeed("validate", name, "-j", "2", "-o", tmp_path / "out", "--json")
    rows = json.loads(proc.stdout)
    assert len(rows) == 4 and {r["quantity"].split("[")[0] for r in rows} == {quantity}, proc.stderr
    assert all(r["passed"] for r in rows), rows
    assert proc.returncode == 0
