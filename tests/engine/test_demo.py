"""The main job: `vibrofeed demo` runs the feeder line and reports feed rate per section,
singulation and rejects, with the result, a picture and the plots in one folder."""

import json

from helpers import vibrofeed
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result

# A short version of the default line: the supply doubled so that enough parts exit
# within 0.6 s (the first reach the outlet after ~0.3 s).
SMALL = ["-p", "inlet_rate=60", "-p", "t_end=0.6", "-q"]


def test_demo_writes_the_report_the_result_the_picture_and_the_plots(tmp_path):
    out = tmp_path / "results"
    proc = vibrofeed("demo", "-o", out, *SMALL, check=True)
    text = proc.stdout
    for heading in ("Feed rate", "Singulation", "feed rate", "sections", "continuity", "rejects",
                    "mass balance", "inter-arrival"):
        assert heading in text
    result = out / "feeder_line.h5"
    assert check_file(result).ok
    with Result(result) as r:
        mb = {k: int(v[-1]) for k, v in r.mass_balance.items()}
        events, rejects = r.outlet, r.rejects
        assert r.n_sections == 2
    assert mb["lost"] == 0 and mb["inserted"] > 0
    assert mb["inserted"] == mb["on_track"] + mb["exited"] + mb["rejected"]
    assert mb["exited"] == len(events["time"]) > 0 and mb["rejected"] == len(rejects["time"])
    assert f"exited {mb['exited']}, rejected {mb['rejected']}, lost 0" in text
    picture = out / "feeder_line.png"
    assert picture.stat().st_size > 10_000
    plots = sorted(p.name for p in (out / "plots").glob("*.png"))
    assert len(plots) >= 3
    # The same numbers through the analysis commands, as JSON.
    fr = json.loads(vibrofeed("feedrate", result, "--json", check=True).stdout)
    assert fr["exited"] == mb["exited"] and fr["lost"] == 0
    assert [s["section"] for s in fr["sections"]] == [1, 2]


def test_demo_refuses_a_bad_parameter_before_running(tmp_path):
    proc = vibrofeed("demo", "-o", tmp_path / "r", "-p", "n_parts=-3")
    assert proc.returncode == 2 and proc.stderr.startswith("vibrofeed: error: ")
    assert not (tmp_path / "r" / "feeder_line.h5").exists()


def test_the_bowl_case_runs_the_bowl_with_its_dies(tmp_path):
    """`vibrofeed demo --case bowl`, cut short (a few dies, 0.03 s: none leaves yet): the bowl
    deck with the case's parameters runs, its result is complete, and the demo fails saying
    why it measured nothing (never a feed rate of 0 reported as a success)."""
    out = tmp_path / "results"
    proc = vibrofeed("demo", "--case", "bowl", "-o", out, "-q", "--no-pictures", "-p", "t_settle=0.003",
                     "-p", "t_end=0.03", "-p", "n_parts=2", "-p", "n_track=10", "-p", "output_dt=0.0025")
    assert proc.returncode == 1
    assert "too few exits to measure" in proc.stderr and "bowl_feeder.h5" in proc.stderr
    with Result(out / "bowl_feeder.h5") as r:
        assert r.deck_name == "bowl_feeder" and r.status == "complete"
        assert r.parameters["shape"] == 1 and r.parameters["freq"] == 75  # the case's dies and drive
        assert r.holds("surface_angle")
        mb = {k: int(v[-1]) for k, v in r.mass_balance.items()}
    assert mb["inserted"] == 12 and mb["lost"] == 0 and mb["inserted"] == mb["on_track"] + mb["exited"]
    assert "Feed rate" in proc.stdout and "Singulation" in proc.stdout
