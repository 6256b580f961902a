"""`vibrofeed feedrate` and `vibrofeed singulation` as a user runs them."""

import json
import subprocess
import sys

import numpy as np
import pytest

from bulk_synthetic import feeder
from helpers import REPO, parts, vibrofeed, write_result
from vibrofeed.postproc import FeedRate, Singulation
from vibrofeed.results.reader import Result

FEED_KEYS = {"parts_per_s", "parts_per_s_err", "mass_per_s", "mean_velocity", "steady_from",
             "inserted", "exited", "on_track", "lost"}
SINGULATION_KEYS = {"cv_interarrival", "doubles_rate", "singulated_fraction", "mean_gap",
                    "cluster_sizes"}
# A hopping vibration in the deck vocabulary, for the dilute-limit model.
VIBRATION = {"amp_t": ("4.97e-5", "m", "", "0"), "amp_n": ("4.97e-5", "m", "", "0"),
             "phase": ("0", "deg", "", "0"), "mu": ("0.5", "", "", "0.5"),
             "restitution": ("0.3", "", "", "0.3"), "incline": ("0", "deg", "", "0")}


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    exits = 0.2 + np.arange(240) / 300.0
    lanes = np.arange(240) % 4 * 1e-3
    path = tmp_path_factory.mktemp("bulk") / "bulk.h5"
    return feeder(path, np.arange(0, 1.0 + 1e-9, 0.01), exits, speed=0.05, amp=4e-5, lanes=lanes,
                  variables=VIBRATION)


def test_feedrate_prints_a_table_and_json_with_the_contract_keys(run_file):
    table = vibrofeed("feedrate", run_file, "--no-model", check=True).stdout
    assert "parts/s" in table and "steady window" in table and "mass balance" in table
    out = vibrofeed("feedrate", run_file, "--json", check=True).stdout
    figures = json.loads(out)
    assert FEED_KEYS <= set(figures)
    with Result(run_file) as r:
        fr = FeedRate(r).run().results
    # the same analysis, through json (which keeps every digit): equal up to rounding
    assert figures["parts_per_s"] == pytest.approx(fr.parts_per_s, rel=1e-12)
    assert figures["steady_from"] == pytest.approx(fr.steady_from, rel=1e-12)
    assert figures["lost"] == 0 and figures["exited"] == 240
    # the dilute limit: the single-part model of the same vibration
    from vibrofeed.models import deck as dm
    from vibrofeed.models.part_on_surface import PartParams, mean_velocity

    params = {k: float(v[0]) for k, v in VIBRATION.items()} | {"freq": 100.0}
    model = mean_velocity(dm.waveform(params), PartParams(0.5, 0.5, 0.3)).velocity
    assert figures["model_velocity"] == pytest.approx(model, rel=1e-9)
    assert figures["velocity_ratio"] == pytest.approx(0.05 / model, rel=1e-6)


def test_singulation_prints_a_table_and_json_with_the_contract_keys(run_file):
    table = vibrofeed("singulation", run_file, check=True).stdout
    assert "CV" in table and "doubles" in table and "clusters" in table
    figures = json.loads(vibrofeed("singulation", run_file, "--json", "--gap", "1e-3",
                                   check=True).stdout)
    assert SINGULATION_KEYS <= set(figures)
    with Result(run_file) as r:
        sg = Singulation(r, gap=1e-3).run().results
    assert figures["doubles_rate"] == pytest.approx(sg.doubles_rate, rel=1e-12, abs=1e-12)  # a fraction
    assert figures["cluster_sizes"] == {str(k): v for k, v in sg.cluster_sizes.items()}
    assert figures["cv_interarrival"] == pytest.approx(0.0, abs=1e-9)


def test_plots_land_in_the_folder(run_file, tmp_path):
    out = tmp_path / "figures"
    res = vibrofeed("feedrate", run_file, "--no-model", "--plot", out, check=True)
    vibrofeed("singulation", run_file, "--plot", out, check=True)
    names = sorted(p.name for p in out.iterdir())
    assert names == ["feedrate_cumulative.png", "feedrate_velocity_profile.png",
                     "singulation_clusters.png", "singulation_interarrival.png"]
    assert all((out / n).stat().st_size > 5000 for n in names)   # drawn, not empty
    assert f"figure: {out}" in res.stdout
    # a mistyped parent folder is refused before any work, not created
    bad = vibrofeed("feedrate", run_file, "--plot", tmp_path / "no" / "such")
    assert bad.returncode == 2 and not (tmp_path / "no").exists()
    assert bad.stderr.count("\n") == 1 and "does not exist" in bad.stderr


def test_a_result_without_outlet_data_is_one_line(tmp_path):
    one = write_result(tmp_path / "single.h5", [(k, k * 0.01, parts([1], [[0, 0, 0]])) for k in range(4)])
    for command in ("feedrate", "singulation"):
        res = vibrofeed(command, one)
        assert res.returncode == 2
        assert res.stderr.startswith("vibrofeed: error:") and res.stderr.count("\n") == 1
        assert "no outlet data" in res.stderr and "bulk_feeder" in res.stderr
    res = vibrofeed("feedrate", tmp_path / "missing.h5")
    assert res.returncode == 1 and res.stderr.count("\n") == 1


def test_no_plotting_library_without_plot(run_file):
    code = ("import sys\nfrom vibrofeed.cli import main\n"
            f"main(['feedrate', {str(run_file)!r}, '--json', '--no-model'])\n"
            f"main(['singulation', {str(run_file)!r}, '--json'])\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('matplotlib', 'pyvista') "
            "or m.startswith('vibrofeed.validation')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO,
                         check=True).stdout
    assert out.strip().splitlines()[-1] == "[]"
