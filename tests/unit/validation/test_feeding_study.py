"""The micro-scale feeding study's analysis (validation/studies/feeding.py, README "Micro-scale
forces in the feeder"): Bond numbers worked out by hand, the sticking part's model speed as
the model under a heavier gravity, and a sweep folder of synthetic results whose feed rates
and speeds are known by construction, grouped over replicates over the study's window."""

import json
import math

import numpy as np
import pytest

from bulk_synthetic import feeder
from vibrofeed.models import deck as dm
from vibrofeed.models.constants import G
from vibrofeed.models.part_on_surface import PartParams, mean_velocity
from vibrofeed.sweep import summary as S
from vibrofeed.validation.studies import feeding as mc

DIE = {"shape": "chip", "part_size": 3e-4, "part_thickness": 2e-4, "density": 2330.0}


@pytest.mark.parametrize("hamaker, roughness, bond", [
    # the sweep file's table: A a^2 / (6 pi s^3) / (a^2 t rho g), s = 0.2 nm + roughness
    (1e-19, 2e-7, 1e-19 / (6 * math.pi * 2.002e-7 ** 3) / (2e-4 * 2330 * 9.81)),
    (4e-19, 1e-7, 4e-19 / (6 * math.pi * 1.002e-7 ** 3) / (2e-4 * 2330 * 9.81)),
])
def test_the_bond_number_of_a_die_is_its_face_pulloff_over_its_weight(hamaker, roughness, bond):
    got = mc.bond_number({**DIE, "hamaker": hamaker, "roughness": roughness})
    assert got == pytest.approx(bond * 9.81 / G, rel=1e-12)
    assert mc.bond_number({**DIE, "hamaker": 0, "roughness": roughness}) == 0.0


def test_the_bond_number_of_a_sphere_and_of_a_disc():
    sphere = {"shape": 0, "part_size": 3e-4, "density": 2330.0, "hamaker": 1e-19, "roughness": 3e-9}
    pull = 1e-19 * 1.5e-4 / (6 * 3.2e-9 ** 2)
    assert mc.bond_number(sphere) == pytest.approx(pull / (math.pi / 6 * 3e-4 ** 3 * 2330 * G), rel=1e-12)
    disc = {**DIE, "shape": "disc", "hamaker": 1e-19, "roughness": 2e-7}
    area = math.pi * 1.5e-4 ** 2
    pull = 1e-19 * area / (6 * math.pi * 2.002e-7 ** 3)
    assert mc.bond_number(disc) == pytest.approx(pull / (area * 2e-4 * 2330 * G), rel=1e-12)


DECK = {"freq": 100.0, "amp_t": 4.9698e-5, "amp_n": 1.98792e-5, "phase": 0.0, "waveform": 0, "duty": 0.5,
        "incline": 0.0, "mu": 0.5, "restitution": 0.1}


def test_a_part_that_never_leaves_moves_as_under_a_heavier_gravity():
    bond = 0.58
    got = mc.sticky_model_speed(DECK, bond)
    want = mean_velocity(dm.waveform(DECK), PartParams(mu_s=0.5, mu_k=0.5, e=0.1), g=G * (1 + bond)).velocity
    assert got == pytest.approx(want, rel=1e-12)
    # adhesion slows the sliding part: more normal load, less slip
    assert 0 < got < mc.sticky_model_speed(DECK, 0.0)
    # one that would hop (Gamma_n 2 > 1 + Bo) has no such model, nor another waveform
    assert mc.sticky_model_speed({**DECK, "amp_n": 4.9698e-5}, 0.5) is None
    assert mc.sticky_model_speed({**DECK, "amp_n": 4.9698e-5}, 1.5) is not None
    assert mc.sticky_model_speed({**DECK, "waveform": 2}, 0.5) is None


def sweep_folder(folder, settings, t_end=0.4):
    """A finished sweep of synthetic bulk results: ``settings`` maps a hamaker value to
    one (exit interval [s], speed [m/s]) per replicate; exits are periodic from t = 0."""
    (folder / "jobs").mkdir(parents=True)
    frames = np.round(np.arange(0, t_end + 1e-9, 0.01), 10)
    rows, job = [], 0
    for hamaker, replicates in settings.items():
        for rep, (interval, speed) in enumerate(replicates):
            exits = np.arange(interval / 2, 0.6, interval)
            name = f"jobs/job-{job:04d}.h5"
            feeder(folder / name, frames, exits, speed=speed, freq=100.0, seed=job,
                   variables={"hamaker": (repr(hamaker), "J", "Hamaker constant", "0")})
            rows.append({"job": job, "replicate": rep, "seed": 1 + rep, "hamaker": hamaker,
                         "status": "done", "error": "", "file": name, "run_id": "x", "wall_s": 1.0})
            job += 1
    S.write(folder, rows, ["seed", "hamaker"], {"varied": json.dumps(["hamaker", "seed"])})
    (folder / "sweep.json").write_text(json.dumps({"spec": {"fixed": {"shape": "chip"}}}))


def test_settings_are_the_replicates_means_over_the_study_window(tmp_path):
    # two settings, two replicates each: 100 and 120 parts/s at 20 and 22 mm/s; 25 parts/s
    # at 10 mm/s twice
    sweep_folder(tmp_path, {0.0: [(0.01, 0.020), (1 / 120, 0.022)], 1e-19: [(0.04, 0.010), (0.04, 0.010)]})
    entries = {e["parameters"]["hamaker"]: e for e in mc._settings(tmp_path, start=0.05)}
    free, sticky = entries[0.0], entries[1e-19]
    assert free["parameters"]["shape"] == "chip" and free["runs"] == 2
    count = 1 / 0.35  # a count of periodic exits over the 0.35 s window is within one exit
    assert free["parts_per_s"] == pytest.approx(110, abs=count)
    assert free["parts_per_s_err"] == pytest.approx(10, abs=count)  # |120 - 100| / 2
    assert free["mean_velocity"] == pytest.approx(0.021, rel=1e-6)
    assert free["mean_velocity_err"] == pytest.approx(0.001, rel=1e-4)
    assert sticky["parts_per_s"] == pytest.approx(25, abs=count)
    assert sticky["mean_velocity"] == pytest.approx(0.010, rel=1e-6)
    assert sticky["mean_velocity_err"] == pytest.approx(0.0, abs=1e-9)
    # one lane, parts of 0.3 mm: 0.2 and 0.18 mm apart (centres) they overlap along the track,
    # 0.4 mm apart they leave 0.1 mm of clear track between them
    # (fractions of the parts: exact up to rounding)
    assert free["doubles_rate"] == pytest.approx(1.0, abs=1e-12)
    assert free["singulated_fraction"] == pytest.approx(0.0, abs=1e-12)
    assert sticky["doubles_rate"] == pytest.approx(0.0, abs=1e-12)
    assert sticky["singulated_fraction"] == pytest.approx(1.0, abs=1e-12)
    assert sticky["track_singulated_fraction"] == pytest.approx(1.0, abs=1e-12)
    assert sticky["deck_parameters"]["hamaker"] == 1e-19


def test_a_sweep_without_a_finished_job_is_refused(tmp_path):
    (tmp_path / "jobs").mkdir()
    S.write(tmp_path, [{"job": 0, "replicate": 0, "seed": 1, "hamaker": 0.0, "status": "failed",
                        "error": "boom", "file": "", "run_id": "", "wall_s": 1.0}],
            ["seed", "hamaker"], {"varied": json.dumps(["hamaker", "seed"])})
    (tmp_path / "sweep.json").write_text(json.dumps({"spec": {"fixed": {}}}))
    with pytest.raises(mc.CaseError, match="no finished job"):
        mc._settings(tmp_path)
