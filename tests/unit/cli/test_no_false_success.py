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


# ----------------------------------------------------------------- steps beyond the contact
@pytest.mark.parametrize("deck", ["single_part", "bulk_feeder", "pulloff"])
def test_a_step_beyond_the_contact_is_refused_unless_insisted(deck):
    from vibrofeed.decks import Deck
    from vibrofeed.errors import ParameterError
    from vibrofeed.parameters import (
        MAX_HERTZ_FRACTION,
        MAX_RAYLEIGH_FRACTION,
        ParameterWarning,
        contact_times,
        resolve,
    )

    d = Deck.find(deck)
    p = {k: float(v.default) for k, v in d.tunables.items() if v.is_numeric}
    times = contact_times(p)
    # the decks' own derivation of the Rayleigh time, written out: pi r sqrt(rho / G) / (...)
    r = p["radius"] if deck == "single_part" else p["part_size"] / 2
    shear = p["youngs"] / (2 * (1 + p["poisson"]))
    rayleigh = np.pi * r * np.sqrt(p["density"] / shear) / (0.1631 * p["poisson"] + 0.8766)
    assert times["rayleigh"] == pytest.approx(rayleigh, rel=1e-12, abs=0)
    limit = min(MAX_RAYLEIGH_FRACTION * times["rayleigh"], MAX_HERTZ_FRACTION * times["hertz"])
    limit = max(limit, times["hertz"] / 50)
    run = {"t_end": "0.01", "output_dt": "0.01"}
    resolve(d, {**run, "dt": repr(limit)})  # at the limit: accepted
    too_long = repr(limit * 1.01)
    with pytest.raises(ParameterError, match=r"dt=.* s is \d+% of the (Rayleigh|Hertz) time"):
        resolve(d, {**run, "dt": too_long})
    with pytest.warns(ParameterWarning, match="vibrofeed check rejects the result, so the run fails"):
        assert resolve(d, {**run, "dt": too_long, "dt_unchecked": "1"})["dt"] == too_long


def test_the_bulk_feeders_step_of_issue_19_is_refused_in_one_line():
    proc = vibrofeed("run", "bulk_feeder", "-p", "dt=1e-4")
    one_line_error(proc, 2, "dt=0.0001 s is 1792% of the Rayleigh time (limit 20%)", "dt_unchecked=1")


# ----------------------------------------------------------------- check: what cannot be physical
def _problems(path):
    from vibrofeed.results.check import check_file

    return [str(p) for p in check_file(path).problems if p.level == "error"]


def _conveyed(tmp_path, name="ok.h5", speed=0.02, **kw):
    from bulk_synthetic import feeder

    frames = np.arange(0, 0.2 + 1e-9, 0.01)
    variables = {"amp_t": ("5e-5", "m", "amplitude", "5e-5"), "amp_n": ("5e-5", "m", "amplitude", "5e-5")}
    return feeder(tmp_path / name, frames, 0.05 + 0.1 * np.arange(20) / 20, speed=speed,
                  amp=5e-5, variables=variables, **kw)


def _rewrite(path, element, change):
    """Change one particle element of a written result in place: change(values) -> values."""
    import h5py

    with h5py.File(path, "r+") as f:
        ds = f[f"particles/parts/{element}/value"]
        ds[...] = change(ds[()])


def test_check_passes_a_physical_bulk_result(tmp_path):
    assert _problems(_conveyed(tmp_path)) == []


def test_check_fails_a_part_faster_than_the_drive_can_make_it(tmp_path):
    # surface peak speed 2 pi 100 Hz 7.07e-5 m = 0.0444 m/s: the limit is 100 x that + free fall
    path = _conveyed(tmp_path)

    def fling(v):
        v[5, 0] = [30.0, 0.0, 0.0]
        return v

    _rewrite(path, "velocity", fling)
    v_surface = 2 * np.pi * 100 * np.hypot(5e-5, 5e-5)
    height = 1.5e-4  # the first frame's parts (centres at their radius) above the track (z = 0)
    limit = 100 * v_surface + np.sqrt(2 * 9.81 * height)
    problems = _problems(path)
    assert any(f"moves at 30 m/s at frame 5 (t = 0.05 s), beyond the {limit:.3g} m/s" in p
               for p in problems), problems


def test_check_fails_a_part_of_negative_mass(tmp_path):
    path = _conveyed(tmp_path)

    def negative(m):  # one part's mass turned negative at frame 7 (no faster, no farther)
        m[7, np.flatnonzero(np.isfinite(m[7]) & (m[7] > 0))[0]] *= -1
        return m

    _rewrite(path, "mass", negative)
    problems = _problems(path)
    assert len(problems) == 1 and "at frame 7 (t = 0.07 s): a part's mass is finite and positive" \
        in problems[0], problems


def test_check_fails_a_part_a_metre_away(tmp_path):
    track = (np.array([[0, -1e-3, 0], [0.02, -1e-3, 0], [0.02, 1e-3, 0]], float),
             np.array([[0, 1, 2]], np.int32))
    path = _conveyed(tmp_path, track=track)
    assert _problems(path) == []

    import h5py

    with h5py.File(path, "r+") as f:  # a part on the track at frames 9 and 10 jumps a metre up
        ids, x = f["particles/parts/id/value"][()], f["particles/parts/position/value"]
        slot = int(np.nonzero((ids[9] == ids[10]) & (ids[9] != -1))[0][0])
        moved = x[10]
        moved[slot, 2] += 1.0
        x[10] = moved
    problems = _problems(path)
    assert any("far outside the track" in p and "frame 10" in p for p in problems), problems
    assert any("moves 1 m between frames 9 and 10" in p for p in problems), problems


def test_check_fails_a_step_beyond_the_contact(tmp_path):
    from helpers import parts, write_result

    single = {"radius": ("5e-4", "m", "", "5e-4"), "density": ("2330", "kg/m^3", "", "2330"),
              "youngs": ("5e7", "Pa", "", "5e7"), "poisson": ("0.3", "-", "", "0.3"),
              "freq": ("50", "Hz", "", "50"), "dt": ("1e-4", "s", "", "0")}
    frames = [(k, k * 1e-3, parts([1], [[0, 0, 5e-4]])) for k in range(3)]
    bad = write_result(tmp_path / "dt.h5", frames, variables=single)
    assert any("/parameters/variables/dt" in p and "535% of the Rayleigh time" in p
               for p in _problems(bad)), _problems(bad)
    insisted = write_result(tmp_path / "insisted.h5", frames,
                            variables={**single, "dt_unchecked": ("1", "-", "", "0")})
    assert any("(run with dt_unchecked=1)" in p for p in _problems(insisted))
    fine = write_result(tmp_path / "fine.h5", frames, variables={**single, "dt": ("1e-6", "s", "", "0")})
    assert _problems(fine) == []


def test_check_fails_a_nan_position_a_lost_part_and_a_balance_that_does_not_close(tmp_path):
    import h5py

    nan = _conveyed(tmp_path, "nan.h5")
    with h5py.File(nan, "r+") as f:
        ids, x = f["particles/parts/id/value"][()], f["particles/parts/position/value"]
        row = x[4]
        row[int(np.nonzero(ids[4] != -1)[0][0])] = np.nan
        x[4] = row
    assert any("non-finite position" in p for p in _problems(nan)), _problems(nan)
    for name, change, words in (("lost.h5", {"lost": 1}, "part(s) lost at frame 6"),
                                ("open.h5", {"inserted": 1}, "inserted differs from on_track + exited")):
        path = _conveyed(tmp_path, name)
        with h5py.File(path, "r+") as f:
            for count, extra in change.items():
                ds = f[f"observables/mass_balance/{count}/value"]
                values = ds[()]
                values[6:] += extra
                ds[...] = values
        assert any(words in p for p in _problems(path)), _problems(path)
