"""The bulk feeder deck under LIGGGHTS: by hand after `vibrofeed prepare`, and through
`vibrofeed run` on 1 and 2 ranks (a few tens of parts near the outlet for a short time:
the mass balance holds with nothing lost, parts move forward, some leave over the edge)."""

import re
import shlex
import subprocess

import numpy as np
import pytest

from helpers import DECKS, vibrofeed
from vibrofeed.results.reader import Result

# 30 spheres settled near the outlet of a short track, then 0.06 s of hopping (Gamma_n 2,
# ~20 mm/s): the front reaches the edge within a few periods.
SHORT = {"n_parts": "30", "track_length": "0.006", "fill_from": "0.5", "fill_to": "0.95",
         "t_settle": "0.01", "t_end": "0.06", "output_dt": "0.005"}


def params(values):
    return [a for k, v in values.items() for a in ("-p", f"{k}={v}")]


def test_by_hand_after_prepare(tmp_path):
    given = {**SHORT, "t_end": "0.01", "shape": "chip"}
    proc = vibrofeed("prepare", "bulk_feeder", *params(given), "-o", tmp_path / "m", check=True)
    line = proc.stdout.strip().splitlines()[-1]
    assert line.startswith("liggghts -in ") and "-var mesh_dir" in line and "-var shape 1" in line
    subprocess.run(shlex.split(line) + ["-log", "log", "-nocite"], cwd=tmp_path, check=True,
                   capture_output=True, timeout=600)
    log = (tmp_path / "log").read_text()
    assert "ERROR" not in log
    # the settle stage, then the vibration from step 0, with the timestep checks and the counts
    assert len(re.findall(r"Loop time of .* for \d+ steps", log)) == 2
    header = next(h for h in re.findall(r"^\s*Step .*$", log, re.M) if "n_insert" in h)
    assert "ts[1]" in header and "ts[2]" in header
    rows = [line.split() for line in log.splitlines() if re.match(r"^\s+\d+\s+[-0-9.e]+\s+\d+\s", line)]
    step0 = next(r for r in rows if r[0] == "0" and len(r) == len(header.split()))
    assert step0[1] == "0" and int(step0[2]) == 30 * 9  # t = 0 at the start; 9 spheres a chip
    assert float(step0[-2]) == 30  # n_inserted
    assert (tmp_path / "outlet.txt").exists() and (tmp_path / "bulk_feeder.dump").exists()
    # the neighbour skin, as LIGGGHTS took it: 0.4 of the chip's smallest sphere by default
    smallest = min(float(row.split()[3]) for row in (tmp_path / "m" / "chip.multisphere").read_text()
                   .splitlines() if not row.startswith("#"))
    assert neighbour_skin(log) == pytest.approx(0.4 * smallest, rel=1e-12)


def neighbour_skin(log: str) -> float:
    """The skin of the log's `neighbor` command, as LIGGGHTS echoed it after substitution."""
    (skin,) = re.findall(r"^neighbor\s+([-0-9.e+]+) bin$", log, re.M)
    return float(skin)


def test_a_given_neighbour_skin_is_the_one_run(tmp_path):
    """skin [m] (0: derived) reaches LIGGGHTS as given: a run by hand after prepare."""
    given = {**SHORT, "t_end": "0.005", "shape": "chip", "skin": "1.25e-4"}
    proc = vibrofeed("prepare", "bulk_feeder", *params(given), "-o", tmp_path / "m", check=True)
    line = proc.stdout.strip().splitlines()[-1]
    assert "-var skin 1.25e-4" in line
    subprocess.run(shlex.split(line) + ["-log", "log", "-nocite"], cwd=tmp_path, check=True,
                   capture_output=True, timeout=600)
    log = (tmp_path / "log").read_text()
    assert "ERROR" not in log
    assert neighbour_skin(log) == pytest.approx(1.25e-4, rel=1e-12)


@pytest.mark.parametrize("given, says", [
    # any other value than those vibrofeed checked (prepared.in; the deck repeats no rule)
    ({"gate_width": "1e-4"}, "Invalid gate_width: mesh_dir was checked and written for gate_width=0.0; "
                             "run vibrofeed prepare again"),
    # the returns are the driver's: by hand, a run that would silently drop them is refused
    ({"sections": "2", "recirculate": "1"}, "Invalid recirculate: vibrofeed run returns the rejects"),
])
def test_a_bad_combination_is_refused_in_one_line_by_hand(tmp_path, given, says):
    line = [a for k, v in given.items() if k == "sections" for a in ("-p", f"{k}={v}")]
    vibrofeed("prepare", "bulk_feeder", "-o", tmp_path / "m", *line, check=True)
    args = [a for k, v in given.items() for a in ("-var", k, v)]
    proc = subprocess.run(["liggghts", "-in", str(DECKS / "bulk_feeder.liggghts"), "-var", "deck_dir",
                           str(DECKS), "-var", "mesh_dir", str(tmp_path / "m"), *args,
                           "-log", "none", "-nocite"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert says in proc.stdout
    assert "Loop time" not in proc.stdout


@pytest.mark.parametrize("ranks", [1, 2])
def test_vibrofeed_run_keeps_the_mass_balance(tmp_path, ranks):
    out = tmp_path / "bulk.h5"
    proc = vibrofeed("run", "bulk_feeder", *params(SHORT), "-n", ranks, "-q", "-o", out)
    assert proc.returncode == 0, proc.stderr
    with Result(out) as r:
        counts = r.mass_balance
        assert counts is not None
        assert np.all(counts["inserted"] == 30)  # the pre-fill, no inlet
        assert np.all(counts["lost"] == 0)
        assert np.all(counts["on_track"] + counts["exited"] <= counts["inserted"])
        events = r.outlet
        assert counts["exited"][-1] > 0 and len(events["time"]) == counts["exited"][-1]
        assert np.all(events["position"][:, 0] > 0.006)  # beyond the outlet edge
        assert np.all(np.diff(counts["exited"]) >= 0)
        # the recorded derived constants: the outlet contract, the timestep and cohesion records
        d = r.derived
        assert d["outlet_x"] == pytest.approx(0.006, rel=1e-12) and d["body_spheres"] == 1
        assert d["catch_z"] < -5e-5 and 0 < d["dt_hertz_fraction"] <= 0.02
        assert d["k_pp"] == 0 and d["pulloff_pw"] == 0
        # forward motion: the parts present in the first and the last frame moved towards +x
        first, last = r.frame(0), r.frame(r.n_frames - 1)
        common = np.intersect1d(first.ids, last.ids)
        assert len(common) > 0
        x0 = first["position"][np.isin(first.ids, common), 0].mean()
        x1 = last["position"][np.isin(last.ids, common), 0].mean()
        assert x1 > x0 + 1e-4
        vertices, triangles = r.track_mesh
        assert vertices[:, 0].max() == pytest.approx(0.006, abs=1e-12) and len(triangles) > 0  # m: 1 pm
