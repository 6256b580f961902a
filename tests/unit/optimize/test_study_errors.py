"""A study's errors in the user's words: a study refused before its first run leaves nothing
behind, the budget is named as the user gave it, a damaged study folder is one line."""

from __future__ import annotations

import json

from helpers import vibrofeed

STUDY = """deck = "bulk_feeder"
[fixed]
freq = 100
[variables]
amp_n = { low = 1e-5, high = 1e-4 }
[constraints]
max_acceleration = LIMIT
[objective]
maximize = "parts_per_s"
[budget]
runs = RUNS
seeds = 2
screen = 8
"""


def study(tmp_path, limit=8.0, runs=4):
    path = tmp_path / "s.toml"
    path.write_text(STUDY.replace("LIMIT", str(limit)).replace("RUNS", str(runs)))
    return path


def one_line(proc, code=2) -> str:
    assert proc.returncode == code, proc.stderr
    lines = [line for line in proc.stderr.strip().splitlines() if not line.startswith("optimize: ")]
    assert len(lines) == 1 and lines[0].startswith("vibrofeed: error: ") and "Traceback" not in proc.stderr
    return lines[0].removeprefix("vibrofeed: error: ")  # (after the screen's progress line, if any)


def test_a_study_the_screen_refuses_leaves_no_files_and_its_correction_is_not_another_study(tmp_path):
    # peak acceleration of amp_n at 100 Hz: (2 pi 100)^2 x 1e-5 / 9.81 = 0.40 g at the least,
    # above a limit of 0.001 g for every setting screened
    out = tmp_path / "out"
    line = one_line(vibrofeed("optimize", study(tmp_path, limit=0.001), "-o", out))
    assert line == ("no setting of the design space passes the checks and the models (section 1: peak "
                    "acceleration [g] rules out 8); widen the bounds or loosen [constraints]")
    assert not out.exists()
    out.mkdir()  # an empty folder given: left empty
    one_line(vibrofeed("optimize", study(tmp_path, limit=0.001), "-o", out))
    assert list(out.iterdir()) == []
    # the corrected file is checked as a new study (refused here for its budget, named as given)
    line = one_line(vibrofeed("optimize", study(tmp_path, runs=10_000), "-o", out))
    assert line == f"{tmp_path / 's.toml'}:11: runs = 10000: give 1 to 9999 DEM runs"
    line = one_line(vibrofeed("optimize", study(tmp_path), "-o", out, "--budget", "10000"))
    assert line == "--budget 10000: give 1 to 9999 DEM runs"
    assert list(out.iterdir()) == []


def test_optimize_report_on_a_damaged_study_json_is_one_line(tmp_path):
    path = tmp_path / "study.json"
    for text, why in (("{bad", "not readable at line 1"), ('{"format": "vibrofeed-study"}',
                                                             "holds no study (its spec_text)"),
                      ("[1]", "holds no study (its spec_text)")):
        path.write_text(text)
        line = one_line(vibrofeed("optimize-report", tmp_path))
        assert line == f"{path}: {why}: damaged, or not a file vibrofeed optimize wrote"
    path.write_bytes(b"\xff\xfe\x00")
    assert one_line(vibrofeed("optimize-report", tmp_path)) == (
        f"{path}: not readable: damaged, or not a file vibrofeed optimize wrote")


def test_optimize_report_of_a_study_stopped_before_its_search_says_so(tmp_path):
    """study.json written, the journal empty (killed before its first trial): no runs, no traceback."""
    (tmp_path / "study.json").write_text(json.dumps({
        "format": "vibrofeed-study", "fingerprint": "x", "source": "s.toml",
        "spec_text": study(tmp_path).read_text()}))
    (tmp_path / "optuna.journal").write_text("")
    proc = vibrofeed("optimize-report", tmp_path)
    assert proc.returncode == 0 and proc.stderr == ""
    assert proc.stdout.splitlines() == [
        "study s.toml: 0 search runs, 0 proposals ruled out by the models without a DEM run",
        "no confirmed design"]


def test_a_robustness_value_run_refuses_is_refused_before_the_first_run(tmp_path):
    """[robustness] mu = [-1, 0.5] was refused by the robustness run, after the search's and
    the confirmation's DEM runs."""
    path = study(tmp_path)
    path.write_text(path.read_text() + "[robustness]\nmu = [-1, 0.5]\n")
    out = tmp_path / "out"
    line = one_line(vibrofeed("optimize", path, "-o", out))
    assert line == f"{path}:15: robustness mu: parameter mu=-1 must be >= 0"
    assert not out.exists()


def checked(tmp_path, text: str) -> str | None:
    from vibrofeed.errors import VibrofeedError
    from vibrofeed.optimize.search import check_values
    from vibrofeed.optimize.spec import parse
    from vibrofeed.sweep.plan import find_deck

    spec = parse(text, tmp_path / "s.toml")
    try:
        check_values(spec, find_deck(spec))
    except VibrofeedError as exc:
        return str(exc)
    return None


SINGLE = """deck = "single_part"
[fixed]
FIXED
[variables]
phase = { low = 0, high = 90 }
[objective]
maximize = GOAL
"""


def test_an_objective_the_deck_never_measures_is_refused_before_the_first_run(tmp_path):
    """maximize = "parts_per_s" on single_part spent its runs, then said nothing measured it."""
    s = tmp_path / "s.toml"
    single = SINGLE.replace("FIXED", "")
    assert checked(tmp_path, single.replace("GOAL", '"mean_velocity"')) is None
    assert checked(tmp_path, single.replace("GOAL", '"parts_per_s"')) == (
        f"{s}:7: parts_per_s: deck single_part has no outlet (it is not a bulk feeder), so its runs "
        "measure mean_velocity only")
    targets = single.replace("GOAL", '"mean_velocity"') + "at_least = { singulated_fraction = 0.5 }\n"
    assert checked(tmp_path, targets).startswith(
        f"{s}:8: singulated_fraction: deck single_part has no outlet")
    bulk = STUDY.replace("LIMIT", "8").replace("RUNS", "4")
    for goal, shape, refused in (("orientation_yield", "", True), ("oriented_rate", "shape = 0", True),
                                 ("oriented_rate", 'shape = "sphere"', True),
                                 ("correct_fraction", "shape = 0", True),
                                 ("correct_fraction", "shape = 1", False),
                                 ("orientation_yield", "shape = 1", False),
                                 ("orientation_yield", 'shape = "disc"', False),
                                 ("parts_per_s", "", False)):
        text = bulk.replace('"parts_per_s"', f'"{goal}"').replace("freq = 100", f"freq = 100\n{shape}")
        answer = checked(tmp_path, text)
        assert (answer is not None and "the study's parts are spheres, which have no orientation"
                in answer) == refused, (goal, shape, answer)
    chosen = bulk.replace('"parts_per_s"', '"orientation_yield"').replace(
        "[variables]", "[variables]\nshape = { choices = [0, 1] }")
    assert checked(tmp_path, chosen) is None


def test_fixed_values_and_choices_run_refuses_are_named_at_their_line(tmp_path):
    s = tmp_path / "s.toml"
    single = SINGLE.replace("GOAL", '"mean_velocity"')
    assert checked(tmp_path, single.replace("FIXED", "restitution = 0.01")) == (
        f"{s}:3: parameter restitution=0.01 must be in (0.05, 1] (LIGGGHTS needs "
        "coefficientRestitution > 0.05)")
    choices = single.replace("FIXED", "").replace("[variables]",
                                                  "[variables]\nwaveform = { choices = [0, 7] }")
    assert checked(tmp_path, choices) == (f"{s}:5: variable waveform: a choice: parameter waveform=7 must "
                                          "be one of 0, 1, 2, 3, 4")


def test_a_studys_correct_is_checked_at_its_line(tmp_path):
    s = tmp_path / "s.toml"
    bulk = STUDY.replace("LIMIT", "8").replace("RUNS", "4").replace('"parts_per_s"', '"oriented_rate"')
    chips = bulk.replace("freq = 100", 'freq = 100\nshape = 1\ncorrect = "CORRECT"')
    assert checked(tmp_path, chips.replace("CORRECT", "up|down, lengthwise")) is None
    assert checked(tmp_path, chips.replace("CORRECT", "upside")) == (
        f"{s}:5: correct: no state named 'upside'; the states are up, down, side, end")
    spheres = bulk.replace("freq = 100", 'freq = 100\ncorrect = "up"')
    answer = checked(tmp_path, spheres)
    assert answer.startswith(f"{s}:4: ") and "spheres" in answer and "correct is for chips" in answer
