"""The feeder-line study's figure reads the sweep's summary: the speed ratio is the DEM's
v2/v1 per job, unmeasured or failed jobs are left out, and chips carry their yield."""

import json
import math

import pytest

from vibrofeed.errors import CaseError
from vibrofeed.sweep import summary as S
from vibrofeed.validation.studies.line_singulation import line_figure, study_rows

PARAMETERS = ["s2_amp_t", "s2_drop_width", "shape"]


def job(k, stroke, shape, v1, v2, rate, singulated, status="done", yield_=math.nan):
    return {"job": k, "replicate": 0, "seed": 5489, "s2_amp_t": stroke, "s2_drop_width": 4e-4,
            "shape": shape, "status": status, "parts_per_s": rate, "parts_per_s_err": 1.5,
            "speed_1": v1, "speed_2": v2, "singulated_fraction": singulated, "orientation_yield": yield_,
            "doubles_rate": 0.1, "reject_rate_2": 0.0, "n_arrivals": 50}


def write(folder, rows):
    S.write(folder, rows, PARAMETERS, {"varied": json.dumps(PARAMETERS), "deck": "bulk_feeder"})


def test_the_ratio_is_the_measured_speeds_and_unmeasured_jobs_are_left_out(tmp_path):
    write(tmp_path, [job(0, 1e-4, 0, 0.0136, 0.0463, 28.9, 0.969),
                     job(1, 6e-5, 0, 0.016, 0.0232, math.nan, math.nan),  # too few exits
                     job(2, 6e-5, 1, 0.016, 0.018, 25.9, 0.509, yield_=0.614),
                     job(3, 1.4e-4, 0, 0.015, 0.05, 30.0, 0.9, status="failed")])
    rows = study_rows(tmp_path)
    assert [(r["shape"], r["stroke"]) for r in rows] == [(0, 1e-4), (1, 6e-5)]
    assert rows[0]["ratio"] == pytest.approx(0.0463 / 0.0136, rel=1e-12)
    assert rows[0]["yield"] is None and rows[1]["yield"] == pytest.approx(0.614, rel=1e-12)
    assert line_figure(tmp_path, tmp_path / "f.png").stat().st_size > 10_000


def test_a_sweep_with_nothing_measured_says_so(tmp_path):
    write(tmp_path, [job(0, 6e-5, 0, 0.016, 0.0232, math.nan, math.nan)])
    with pytest.raises(CaseError, match="no finished, measured job"):
        study_rows(tmp_path)
