"""The micro-scale surface forces of the single-part deck (decks/include/surface_forces.liggghts).

* Off (hamaker = air_viscosity = 0, the defaults) the block changes nothing: the
  trajectory is bit for bit that of the deck without it.
* On, the force LIGGGHTS applies to an airborne part is the models' law
  (vibrofeed/models/adhesion.py, squeeze_film.py) at the recorded gap and
  relative velocity, to round-off, for a sphere and for a flat face.
* The timestep obeys the step limits the models and vibrofeed.parameters
  derive, and a requested dt above them is refused by vibrofeed and by the
  deck run by hand.
* One point each of the validation cases vdw_pulloff and squeeze_launch.
"""

import json
import math
import re

import numpy as np
import pytest

from helpers import DECKS, liggghts_text, vibrofeed
from vibrofeed.models import adhesion as ad
from vibrofeed.models import squeeze_film as sf
from vibrofeed.models.constants import G
from vibrofeed.parameters import surface_forces_step_limit
from vibrofeed.results.reader import Result
from vibrofeed.validation.cases import CASES_DIR

DECK = DECKS / "single_part.liggghts"


def by_hand(deck_text, folder, *variables):
    """Run a deck text with liggghts in ``folder``; returns (stdout, dump text)."""
    return liggghts_text(deck_text, folder, dict(variables), "single_part.dump", timeout=300)


def without_surface_forces(text):
    """The deck with the block taken out: no include, no fix, the Hertz step alone."""
    text, n1 = re.subn(r"(?m)^include\s+\$\{deck_dir\}/include/surface_forces\.liggghts\n",
                       "variable dt_surface_forces equal 1e30\n", text)
    text, n2 = re.subn(r"(?m)^if \"\$\{sf_on\} == 1\".*\n", "", text)
    assert n1 == n2 == 1
    return text


@pytest.mark.parametrize("variables", [
    [("t_end", 0.03), ("amp_n", 2e-4)],                                     # hopping sine
    [("t_end", 0.03), ("amp_n", 0), ("waveform", 2)],                      # stick-slip
    [("t_end", 0.03), ("roughness", 1e-6)],                                # roughness alone: nothing
])
def test_forces_off_leave_the_trajectory_unchanged(tmp_path, variables):
    text = DECK.read_text()
    out_on, dump_on = by_hand(text, tmp_path / "block", *variables)
    out_off, dump_off = by_hand(without_surface_forces(text), tmp_path / "plain", *variables)
    assert dump_on and dump_on == dump_off, out_on[-2000:]


def run(tmp_path, name, **params):
    out = tmp_path / f"{name}.h5"
    args = ["run", "single_part", "-q", "-o", out]
    for k, v in params.items():
        args += ["-p", f"{k}={v}"]
    vibrofeed(*args, check=True)
    return out


# A flat face's vdW pull and its air film need very different clearances to be
# felt without holding the part down (flat-flat vdW falls as 1/s^3, Stefan's
# film as 1/h^3 from a much larger prefactor): one each.
SPHERE = dict(radius=1.5e-4, hamaker=1e-19, roughness=3e-9, air_viscosity=sf.AIR_VISCOSITY)
FLAT_VDW = dict(radius=1.817121e-4, face_radius=2e-4, hamaker=1e-19, roughness=1e-7, air_viscosity=0)
FLAT_FILM = dict(radius=1.817121e-4, face_radius=2e-4, hamaker=0, roughness=5e-6,
                 air_viscosity=sf.AIR_VISCOSITY)


@pytest.mark.parametrize("part", [SPHERE, FLAT_VDW, FLAT_FILM], ids=["sphere", "flat vdW", "flat film"])
def test_the_applied_force_is_the_models_law(tmp_path, part):
    freq, gamma = 100.0, 5.0
    out = run(tmp_path, "f", freq=freq, amp_t=0, amp_n=repr(gamma * G / (2 * math.pi * freq) ** 2),
              t_end=0.008, output_dt=1e-5, **part)
    with Result(out) as r:
        t, x = r.track(1)
        _, v = r.track(1, "velocity")
        _, f = r.track(1, "force")
        zs, vs = r.surface_position[:, 2], r.surface_velocity[:, 2]
        dt, mass = r.derived["dt_used"], r.derived["mass"]
    face = part.get("face_radius", 0.0)
    adh = ad.Adhesion(part["hamaker"], part["roughness"], radius=part["radius"], face_radius=face)
    film = sf.Film(part["air_viscosity"], face or part["radius"], sf.clearance(part["roughness"]),
                   flat=face > 0)
    gap = x[:, 2] - part["radius"] - zs
    airborne = gap > 1e-9
    assert airborne.sum() > 100 and gap.max() > 1e-5  # from nanometres to tens of microns
    # LIGGGHTS computes the force at the end of a step with the half-step velocity,
    # v(t) - f dt / (2 m); the recorded f is the total force (gravity included).
    v_half = v[:, 2] - f[:, 2] * dt / (2 * mass)
    surface = np.array([-adh.force(g) for g in gap]) + film.force(gap, v_half - vs)
    want = surface - mass * G
    got = f[:, 2]
    np.testing.assert_allclose(got[airborne], want[airborne], rtol=1e-7, atol=1e-12 * mass * G)
    # each force that is on matters: the recorded force is not gravity's alone
    for on, one in ((part["hamaker"] > 0, -np.array([adh.force(g) for g in gap])),
                    (part["air_viscosity"] > 0, film.force(gap, v_half - vs))):
        if on:
            assert np.max(np.abs(one[airborne])) > 1e-3 * mass * G


def test_timestep_obeys_the_step_limits(tmp_path):
    # a smooth surface: the vdW force is the stiffest, and sets the step
    params = dict(hamaker=1e-19, roughness=0, air_viscosity=sf.AIR_VISCOSITY, t_end=1e-3)
    out = run(tmp_path, "dt", **params)
    with Result(out) as r:
        d, p = r.derived, r.parameters
    mass = d["mass"]
    adh = ad.Adhesion(1e-19, 0.0, radius=p["radius"])
    film = sf.Film(sf.AIR_VISCOSITY, p["radius"], sf.clearance(0.0), flat=False)
    assert d["dt_vdw"] == pytest.approx(ad.vdw_step_limit(adh, mass), rel=1e-12)
    assert d["dt_film"] == pytest.approx(sf.film_step_limit(film, mass), rel=1e-12)
    assert d["sf_pulloff"] == pytest.approx(adh.pulloff, rel=1e-12)
    limit = d["dt_surface_forces"]
    assert limit == pytest.approx(surface_forces_step_limit({**p, "roughness": 0.0}), rel=1e-12)
    assert limit == pytest.approx(min(d["dt_vdw"], d["dt_film"]), rel=1e-12)
    assert limit < d["dt_hertz"]
    # the automatic step: the limit rounded down to a whole number of steps per frame
    assert limit / (1 + limit / p["output_dt"]) < d["dt_used"] <= limit


def test_a_timestep_above_the_limit_is_refused(tmp_path):
    proc = vibrofeed("run", "single_part", "-p", "hamaker=1e-19", "-p", "dt=1e-5", "-o", tmp_path / "x.h5")
    assert proc.returncode == 2
    assert "surface forces need" in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    out, dump = by_hand(DECK.read_text(), tmp_path / "hand", ("hamaker", 1e-19), ("dt", 1e-5))
    assert "Invalid dt: the surface forces need dt <=" in out and not dump


def one_point(tmp_path, name, sweep):
    """A copy of case ``name`` with the single sweep point ``sweep`` (a dict)."""
    text = (CASES_DIR / f"{name}.toml").read_text().replace("zip = true\n", "")
    lines = "".join(f"{k} = [{v}]\n" for k, v in sweep.items())
    text, n = re.subn(r"(?ms)^\[sweep\]\n.*?(?=^\[|\Z)", f"[sweep]\n{lines}\n", text)
    assert n == 1
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("name, sweep", [
    ("vdw_pulloff", {"hamaker": 1e-19, "roughness": 3e-9, "face_radius": 0, "gamma": 2.633}),
    ("squeeze_launch", {"freq": 300, "roughness": 5e-6}),
])
def test_quick_cross_check(tmp_path, name, sweep):
    proc = vibrofeed("validate", one_point(tmp_path, name, sweep), "-o", tmp_path / "out", "--json")
    rows = json.loads(proc.stdout)
    assert rows, proc.stderr
    failed = [r for r in rows if not r["passed"]]
    assert not failed, failed
    assert proc.returncode == 0
    assert list((tmp_path / "out" / name).glob("*.png"))
