"""The main job: `vibrofeed demo` runs the bulk feeder and reports feed rate and
singulation, with the result, a picture and the plots in one folder."""

import json

from helpers import vibrofeed
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result

# A small, short version of the default case: 40 parts close to the outlet so
# that some leave within 0.2 s (the default fill conveys for ~0.1 s first).
SMALL = ["-p", "n_parts=40", "-p", "fill_from=0.6", "-p", "fill_to=0.95", "-p", "t_end=0.2",
         "-p", "output_dt=0.005", "-q"]


def test_demo_writes_the_report_the_result_the_picture_and_the_plots(tmp_path):
    out = tmp_path / "results"
    proc = vibrofeed("demo", "-o", out, *SMALL, check=True)
    text = proc.stdout
    for heading in ("Feed rate", "Singulation", "feed rate", "mass balance", "inter-arrival"):
        assert heading in text
    result = out / "bulk_feeder.h5"
    assert check_file(result).ok
    with Result(result) as r:
        mb = {k: int(v[-1]) for k, v in r.mass_balance.items()}
        events = r.outlet
    assert mb["lost"] == 0 and mb["inserted"] == 40
    assert mb["inserted"] == mb["on_track"] + mb["exited"]
    assert mb["exited"] == len(events["time"]) > 0  # parts reached the outlet
    assert f"exited {mb['exited']}, lost 0" in text
    picture = out / "bulk_feeder.png"
    assert picture.stat().st_size > 10_000
    plots = sorted(p.name for p in (out / "plots").glob("*.png"))
    assert len(plots) >= 3
    # The same numbers through the analysis commands, as JSON.
    fr = json.loads(vibrofeed("feedrate", result, "--json", check=True).stdout)
    assert fr["exited"] == mb["exited"] and fr["lost"] == 0


def test_demo_refuses_a_bad_parameter_before_running(tmp_path):
    proc = vibrofeed("demo", "-o", tmp_path / "r", "-p", "n_parts=-3")
    assert proc.returncode == 2 and proc.stderr.startswith("vibrofeed: error: ")
    assert not (tmp_path / "r" / "bulk_feeder.h5").exists()
