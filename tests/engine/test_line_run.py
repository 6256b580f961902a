"""A short two-section feeder line through the driver, on 1 and 2 ranks: a bed of spheres
near section 1's end crosses the joint onto a faster section 2 whose side drop (a ledge
narrower than the bed, open on one side) throws off every part not against its wall. By
construction some parts fall off the drop and some leave over the outlet edge; the mass
balance is exact at every frame (inserted = on_track + exited + rejected, nothing lost),
each reject fell off the drop's open side, and the result stores both sections' meshes."""

import numpy as np
import pytest

from helpers import vibrofeed
from vibrofeed.line import section_from
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result

LINE = {"sections": 2, "n_parts": 30, "track_length": 0.004, "track_width": 1.2e-3,
        "fill_from": 0.5, "fill_to": 0.97, "s2_length": 0.003, "s2_width": 1.2e-3,
        "s2_amp_t": 1e-4, "s2_phase": -30, "s2_drop_from": 0.1, "s2_drop_to": 0.9,
        "s2_drop_width": 4e-4, "t_end": 0.2, "output_dt": 0.005, "part_size": 3e-4}


@pytest.mark.parametrize("ranks", [1, 2])
def test_two_sections_mass_balance_is_exact(tmp_path, ranks):
    out = tmp_path / f"line{ranks}.h5"
    args = [a for k, v in LINE.items() for a in ("-p", f"{k}={v}")]
    vibrofeed("run", "bulk_feeder", "-q", "-o", out, "-n", ranks, *args, check=True)
    report = check_file(out)
    assert report.ok, [str(p) for p in report.problems]
    with Result(out) as r:
        mb, ev, rej, plane = r.mass_balance, r.outlet, r.rejects, r.outlet_plane
        assert (mb["lost"] == 0).all()
        assert (mb["inserted"] == mb["on_track"] + mb["exited"] + mb["rejected"]).all()
        assert mb["inserted"][-1] == 30
        assert len(ev["id"]) == mb["exited"][-1] > 0 and len(rej["id"]) == mb["rejected"][-1] > 0
        assert not set(ev["id"]) & set(rej["id"])  # a part leaves once, one way
        assert plane["outlet_x"] == pytest.approx(0.007, abs=1e-12)  # the outlet is section 2's end
        # every reject fell off section 2 over the drop's open side (+y, past the ledge), a
        # part's size around the stretch at most (it is timed where it crossed the catch plane)
        s = section_from({k: str(v) for k, v in LINE.items()} | {"s2_wall_height": "1e-3",
                                                                    "s2_step": "5e-5"})
        a, b = s.drop_x
        assert (rej["section"] == 2).all()
        assert (rej["position"][:, 0] > a - 3e-4).all() and (rej["position"][:, 0] < b + 3e-4).all()
        assert (rej["position"][:, 1] > -s.width / 2 + s.drop_width).all()
        assert np.abs(rej["position"][:, 2] - plane["catch_z"]).max() < 1e-12
        # both sections' meshes, at rest: section 2 below section 1 and reaching the outlet
        v, _ = r.track_mesh
        assert v[:, 0].max() == pytest.approx(0.007, abs=1e-12)
        assert v[:, 2].min() == pytest.approx(-5e-5, abs=1e-12)  # no cross tilt: the step
