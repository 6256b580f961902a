"""Physical smoke test: a part on a plate vibrating normal to itself.

Rigid-body theory (Khan & Sarma, §2.3, with the corrected launch condition and flight
trajectory noted in the project's sources): on a plate
moving as z_s = A sin(w t), a part in contact leaves the plate when the
plate's downward acceleration first exceeds g, at w t_l = asin(1/Gamma),
Gamma = A w^2 / g, with the plate's height and velocity there; it then flies
freely, z_p = z_s(t_l) + v_s(t_l) (t - t_l) - g (t - t_l)^2 / 2, and lands
where that parabola meets z_s. Below Gamma = 1 it never leaves.

Tolerances, from what separates the DEM from that model:
- lift-off and landing times: the soft Hertz contact releases and catches the
  part within about one contact time t_c (the deck's t_contact, ~1e-5 s here);
  the events themselves are reconstructed between frames (postproc.flights);
- launch velocity: LIGGGHTS moves the mesh by summing v(t_k) dt each step
  (right Riemann sums), an O(w dt) relative error in the plate's motion;
  allowed: 3 w dt;
- launch height: the static overlap under the part's weight, m g / k, is
  ~1e-7 m; allowed: 1e-3 A.
"""

import numpy as np
import pytest
from scipy.optimize import brentq

from helpers import vibrofeed
from vibrofeed.models.constants import G
from vibrofeed.postproc.flights import Flights
from vibrofeed.results.reader import Result

FREQ = 50.0
W = 2 * np.pi * FREQ
T = 1 / FREQ
OUTPUT_DT = 2e-5


def run_plate(tmp_path, gamma):
    amp = gamma * G / W ** 2
    out = tmp_path / f"gamma{gamma}.h5"
    vibrofeed("run", "single_part", "-q", "-o", out, "-p", f"freq={FREQ}", "-p", "amp_t=0",
              "-p", f"amp_n={amp!r}", "-p", "t_end=0.06", "-p", f"output_dt={OUTPUT_DT}",
              check=True)
    return Result(out)


def test_below_one_g_the_part_never_leaves_the_plate(tmp_path):
    with run_plate(tmp_path, 0.8) as r:
        fl = Flights(r).run().results
        # In contact the gap is minus the elastic overlap: it never turns positive.
        assert fl.gap[1:].max() <= 1e-12
        assert fl.n_hops == 0


@pytest.mark.parametrize("gamma", [1.5, 2.5])
def test_above_one_g_the_part_hops_as_free_flight_predicts(tmp_path, gamma):
    amp = gamma * G / W ** 2
    t_l = np.arcsin(1 / gamma) / W
    z_l, v_l = amp * np.sin(W * t_l), amp * W * np.cos(W * t_l)

    def gap_model(t):
        s = t - t_l
        return z_l + v_l * s - G / 2 * s ** 2 - amp * np.sin(W * t)

    grid = np.linspace(t_l + 1e-7, t_l + 3 * T, 60001)
    k = np.argmax(gap_model(grid) < 0)
    t_land = brentq(gap_model, grid[k - 1], grid[k])
    apex = gap_model(grid[:k]).max()

    with run_plate(tmp_path, gamma) as r:
        fl = Flights(r).run().results
        t_contact, dt = r.derived["t_contact"], r.derived["dt_used"]
        radius = r.parameters["radius"]
        z = r.track(1)[1][:, 2] - radius  # height of the part's lowest point

    assert fl.n_hops >= 1 and fl.kinds[0] == "lift-off"
    assert abs(fl.takeoffs[0] - t_l) < t_contact, \
        f"lift-off at {fl.takeoffs[0] / T:.5f} T, model {t_l / T:.5f} T"
    assert abs(fl.landings[0] - t_land) < t_contact, \
        f"landing at {fl.landings[0] / T:.5f} T, model {t_land / T:.5f} T"
    # Launch state: fit the free flight (z'' = -g exactly in the DEM) and
    # evaluate it at the model's launch time.
    t = fl.time
    airborne = (t > fl.takeoffs[0]) & (t < fl.landings[0]) & (fl.gap > 5e-6)
    s = t[airborne] - t_l
    v_fit, z_fit = np.polyfit(s, z[airborne] + G / 2 * s ** 2, 1)
    assert v_fit == pytest.approx(v_l, rel=3 * W * dt)
    assert z_fit == pytest.approx(z_l, abs=1e-3 * amp)
    # Apex of the first flight above the plate.
    first = t < fl.landings[0]
    assert fl.gap[first].max() == pytest.approx(apex, rel=5e-3)
