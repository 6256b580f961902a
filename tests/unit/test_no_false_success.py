"""No false success from input or analysis (issue 19): what the commands refuse,
and what they say instead of a traceback or a result that is not one."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from helpers import REPO, vibrofeed

SWEEP = """deck = "single_part"
[fixed]
t_end = 0.01
[grid]
freq = [40, 50]
"""


def one_line_error(proc, code: int, *words: str) -> None:
    assert proc.returncode == code, proc.stderr
    assert proc.stderr.startswith("vibrofeed: error: ") and proc.stderr.count("\n") == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    for word in words:
        assert word in proc.stderr, proc.stderr


def test_a_corrupt_sweep_summary_is_named_in_one_line(tmp_path):
    from vibrofeed.sweep import folder as F
    from vibrofeed.sweep.execute import find_deck
    from vibrofeed.sweep.plan import plan
    from vibrofeed.sweep.spec import load

    spec_path = tmp_path / "s.toml"
    spec_path.write_text(SWEEP)
    spec = load(spec_path)
    deck = find_deck(spec)
    out = tmp_path / "out"
    out.mkdir()
    F.write_manifest(out, spec, plan(spec, deck), str(deck.path))
    summary = out / "summary.h5"
    summary.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 40)  # a truncated HDF5 file
    one_line_error(vibrofeed("sweep-report", out), 1, str(summary))
    one_line_error(vibrofeed("sweep", spec_path, "-o", out, "--dry-run"), 1, str(summary))


def test_json_listings_are_json():
    listed = json.loads(vibrofeed("validate", "--list", "--json", check=True).stdout)
    assert len(listed) == len(list((REPO / "validation" / "cases").glob("*.toml")))


# Every command that writes, with a destination it cannot write: a file where a
# folder is wanted, a folder where a file is, a folder that takes no file (/proc).
def _writers(result, folder, trial):
    return {
        "render": (["render", result, "-o"], "x.png"),
        "export": (["export", result, "-o"], "x"),
        "feedrate": (["feedrate", result, "--plot"], "x"),
        "singulation": (["singulation", result, "--plot"], "x"),
        "sweep-report": (["sweep-report", folder, "--plot"], "x"),
        "replay": (["replay", trial, "--mass", "1e-3", "--mu-s", "0.7", "--mu-k", "0.6",
                    "--normal-force", "0.1", "--plot"], "x.png"),
        "run": (["run", "single_part", "-o"], "x.h5"),
        "demo": (["demo", "-o"], "x"),
        "prepare": (["prepare", "bulk_feeder", "-o"], "x"),
        "validate": (["validate", "hop_flights", "-o"], "x"),
        "sweep": (["sweep", REPO / "sweeps" / "example.toml", "--dry-run", "-o"], "x"),
    }


def test_every_command_refuses_a_destination_it_cannot_write_before_any_work(tmp_path):
    from helpers import parts, write_result, write_trial

    result = write_result(tmp_path / "r.h5", [(0, 0.0, parts([1], [[0, 0, 0]]))])
    trial = write_trial(tmp_path / "trial.csv")
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    for name, (args, leaf) in _writers(result, tmp_path, trial).items():
        folder_wanted = leaf.count(".") == 0
        bad = [Path("/proc") / leaf, a_file / leaf]
        if folder_wanted:
            bad.append(a_file)
        else:
            (tmp_path / leaf).mkdir(exist_ok=True)  # a folder named like the file
            bad.append(tmp_path / leaf)
        for path in bad:
            proc = vibrofeed(*args, path, timeout=60)
            one_line_error(proc, 2, str(path))
            assert not proc.stdout, (name, proc.stdout)


def test_a_file_reported_is_a_file_that_holds_something(tmp_path):
    from vibrofeed.cli.outputs import written
    from vibrofeed.errors import OutputError

    with pytest.raises(OutputError, match="was not written"):
        written(tmp_path / "none.png")
    with pytest.raises(OutputError, match="was not written"):
        written(tmp_path)
    (tmp_path / "empty.png").write_bytes(b"")
    with pytest.raises(OutputError, match="written empty"):
        written(tmp_path / "empty.png")
    (tmp_path / "full.png").write_bytes(b"\x89PNG")
    assert written(tmp_path / "full.png") == tmp_path / "full.png"


def _feeder(tmp_path, exits, name="feed.h5"):
    from bulk_synthetic import feeder

    frames = np.arange(0, 0.2 + 1e-9, 0.01)
    return feeder(tmp_path / name, frames, np.asarray(exits, dtype=float), freq=100.0)


def test_too_few_exits_measure_no_rate(tmp_path):
    few = _feeder(tmp_path, [0.05, 0.12, 0.15])  # 3 exits in a 0.2 s run
    proc = vibrofeed("feedrate", few, "--no-model")
    assert proc.returncode == 1 and "0 ± 0" not in proc.stdout
    assert "too few exits to measure (3 in the window; need ≥ 10)" in proc.stdout
    one_line_error(proc, 1, str(few), "too few exits")
    figures = json.loads(vibrofeed("feedrate", few, "--no-model", "--json").stdout)
    assert figures["parts_per_s"] is None and figures["mass_per_s"] is None
    assert figures["reason"].startswith("too few exits") and figures["n_events"] == 3
    proc = vibrofeed("singulation", few, "--json")
    figures = json.loads(proc.stdout)
    assert proc.returncode == 1 and figures["cv_interarrival"] is None and figures["n_arrivals"] == 3
    # enough exits: a rate, exit 0, no reason
    many = _feeder(tmp_path, 0.02 + 0.15 * np.arange(40) / 40, "many.h5")
    figures = json.loads(vibrofeed("feedrate", many, "--no-model", "--json", check=True).stdout)
    assert figures["reason"] is None and figures["parts_per_s"] > 0


def test_analysis_windows_and_options_that_mean_nothing_are_refused(tmp_path):
    run = _feeder(tmp_path, 0.02 + 0.15 * np.arange(40) / 40)
    for command in ("feedrate", "singulation"):
        for option, value, words in (("--end", "50", "window end 50 s is outside the run (0 .. 0.2 s)"),
                                     ("--start", "-1", "window start -1 s is outside the run"),
                                     ("--start", "nan", "--start: must be a finite number"),
                                     ("--end", "inf", "--end: must be a finite number")):
            one_line_error(vibrofeed(command, run, option, value), 2, words)
    for command, option, value in (("feedrate", "--bins", "0"), ("feedrate", "--batches", "1"),
                                   ("singulation", "--gap", "-1"), ("singulation", "--gap", "nan"),
                                   ("singulation", "--gap-distance", "-1e-6"),
                                   ("singulation", "--tolerance", "-1e-6"),
                                   ("singulation", "--cluster-frames", "0"),
                                   ("render", "--fps", "nan"), ("render", "--every", "0"),
                                   ("export", "--every", "0"), ("render", "--frame", "21")):
        proc = vibrofeed(command, run, option, value, "-o" if command in ("render", "export") else "--json",
                         *((tmp_path / f"x{option}.png",) if command == "render" else
                           (tmp_path / "x",) if command == "export" else ()))
        one_line_error(proc, 2, option if command != "render" or option != "--frame" else "frame 21")
