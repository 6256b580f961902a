"""The micro-scale surface forces in the bulk feeder (decks/bulk_feeder.liggghts with
decks/include/surface_forces.liggghts).

* Off (hamaker = air_viscosity = 0, the defaults) the block changes nothing: spheres
  with a size spread and discs run bit for bit as the deck without it.
* On, the z-force LIGGGHTS applies to an airborne sphere is the models' law
  (vibrofeed/models/adhesion.py, squeeze_film.py) at that sphere's own radius, gap
  and velocity relative to the floor, to 1e-6; past the outlet edge it is gravity alone.
* A chip's or disc's clump spheres each carry 1/n of the face's law (flat-flat vdW,
  Stefan's film for a disc or a square) at their own gap and velocity.
* The step limit the deck derives is vibrofeed.parameters' and the models', the
  automatic dt obeys it, and a requested dt above it is refused.
"""

import math
import re

import numpy as np
import pytest

from helpers import DECKS, liggghts_text, lying_flat, vibrofeed
from vibrofeed.models import adhesion as ad
from vibrofeed.models import squeeze_film as sf
from vibrofeed.models.constants import G
from vibrofeed.parameters import surface_forces_step_limit
from vibrofeed.results.reader import Result

DECK = DECKS / "bulk_feeder.liggghts"
SHAPES = {"sphere": 0, "chip": 1, "disc": 2}
# a few parts far apart on a wide track, settled briefly
FEW = {"n_parts": 3, "track_length": 0.01, "track_width": 4e-3, "fill_from": 0.1, "fill_to": 0.9,
       "t_settle": 0.005}


def params(values):
    return [a for k, v in values.items() for a in ("-p", f"{k}={v}")]


def by_hand(deck_text, folder, given, unchecked=None):
    """`vibrofeed prepare` for ``given``, then the deck text run by liggghts in ``folder`` with
    ``given`` and ``unchecked`` (values vibrofeed would refuse); returns (output, dump text)."""
    folder.mkdir(parents=True, exist_ok=True)
    vibrofeed("prepare", "bulk_feeder", *params(given), "-o", folder / "m", check=True)
    values = {name: SHAPES.get(value, value) for name, value in {**given, **(unchecked or {})}.items()}
    return liggghts_text(deck_text, folder, values, "bulk_feeder.dump",
                         extra=("-var", "mesh_dir", folder / "m"))


def without_surface_forces(text):
    """The deck with the block taken out: no include, no compute or fix, the Hertz step alone."""
    text, n1 = re.subn(r"(?m)^include\s+\$\{deck_dir\}/include/surface_forces\.liggghts\n",
                       "variable dt_surface_forces equal 1e30\n", text)
    text, n2 = re.subn(r"(?m)^if \"(\$\{sf_on\} == 1|\(\$\{sf_on\} == 1\) && \(\$\{sf_atom_radius\} == 1\))\""
                       r".*\n", "", text)
    assert (n1, n2) == (1, 2)
    return text


@pytest.mark.parametrize("given", [
    {"n_parts": 30, "track_length": 0.006, "fill_from": 0.5, "fill_to": 0.95, "t_settle": 0.01,
     "t_end": 0.02, "output_dt": 0.005, "size_spread": 0.2, "roughness": 1e-6},   # roughness alone: nothing
    {**FEW, "shape": "disc", "t_end": 0.01, "output_dt": 0.005},
], ids=["spheres", "discs"])
def test_forces_off_leave_the_run_unchanged(tmp_path, given):
    text = DECK.read_text()
    out_on, dump_on = by_hand(text, tmp_path / "block", given)
    out_off, dump_off = by_hand(without_surface_forces(text), tmp_path / "plain", given)
    assert dump_on and dump_on == dump_off, out_on[-2000:]


def apart(position, radius, half_width):
    """Spheres touching neither another sphere nor a side wall (1 um to spare)."""
    d = np.linalg.norm(position[:, None, :] - position[None, :, :], axis=2)
    reach = radius[:, None] + radius[None, :] + 1e-6
    np.fill_diagonal(d, np.inf)
    clear_of_walls = np.abs(position[:, 1]) + radius < half_width - 1e-6
    return np.all(d > reach, axis=1) & clear_of_walls


def test_the_force_on_a_sphere_is_the_models_law_at_its_own_radius(tmp_path):
    # six spheres of three radii (size spread 0.3: 105, 150, 195 um) hopping at Gamma 2.5;
    # those settled near the outlet edge fall off it
    given = {**FEW, "n_parts": 6, "fill_from": 0.9, "fill_to": 0.99, "size_spread": 0.3, "amp_n": 6.2e-5,
             "amp_t": 6.2e-5, "hamaker": 1e-19, "roughness": 3e-9, "air_viscosity": sf.AIR_VISCOSITY,
             "t_end": 0.04, "output_dt": 1e-5}
    out = tmp_path / "spheres.h5"
    vibrofeed("run", "bulk_feeder", "-q", *params(given), "-o", out, check=True)
    got, want, beyond, radii = [], [], [], set()
    with Result(out) as r:
        d = r.derived
        dt, edge, half_w = d["dt_used"], d["outlet_x"], given["track_width"] / 2
        fields = ("position", "velocity", "force", "radius", "mass", "surface_position", "surface_velocity")
        for frame in r.iter_frames(fields=fields):
            if frame.step == 0:  # the force of the settle's last step: the forces start after it
                continue
            x, v, f = frame["position"], frame["velocity"], frame["force"]
            radius, mass = frame["radius"], frame["mass"]
            xs, zs = frame["surface_position"][[0, 2]]
            vs = frame["surface_velocity"][2]
            free = apart(x, radius, half_w)
            gap = x[:, 2] - radius - zs
            over = x[:, 0] - xs < edge
            for i in np.nonzero(free & over & (gap > 1e-9))[0]:
                adh = ad.Adhesion(given["hamaker"], given["roughness"], radius=radius[i])
                film = sf.Film(given["air_viscosity"], radius[i], sf.clearance(given["roughness"]),
                               flat=False)
                # the force acts on the half-step velocity, v(t) - f dt / (2 m)
                v_half = v[i, 2] - f[i, 2] * dt / (2 * mass[i])
                surface = -adh.force(gap[i]) + film.force(gap[i], v_half - vs)
                got.append(f[i, 2])
                want.append((surface - mass[i] * G, surface, mass[i] * G))
                radii.add(round(radius[i] * 1e6))
            # past the edge (centre beyond it, clear of the track): gravity alone
            for i in np.nonzero(free & (x[:, 0] - xs > edge + radius) & (gap < -2 * radius))[0]:
                beyond.append(f[i, 2] / (mass[i] * G))
    want = np.array(want)
    assert len(got) > 500 and radii == {105, 150, 195}
    np.testing.assert_allclose(got, want[:, 0], rtol=1e-6, atol=1e-12 * want[:, 2].max())
    # both forces matter: the surface force reaches a tenth of the weight and beyond
    assert np.max(np.abs(want[:, 1]) / want[:, 2]) > 0.1
    assert len(beyond) > 10
    np.testing.assert_allclose(beyond, -1.0, rtol=1e-12)


def detailed(text):
    """The deck run by hand with a full-precision dump of every sphere's z-force and velocity
    and the surface's z and vz."""
    block = re.search(r'(?ms)^if "\$\{driver\} == 0" then &\n  "dump parts.*?"run \$\{n_steps\}"\n', text)
    assert block
    columns = "id mol type radius x y z vx vy vz fz v_sz v_svz"
    form = " ".join(["%d"] * 3 + ["%.17g"] * 10)
    new = ("variable sz atom v_surface_z\nvariable svz atom v_surface_vz\n"
           f"dump parts all custom ${{output_every}} ${{dump_file}} {columns}\n"
           f'dump_modify parts format "{form}"\nrun ${{n_steps}}\n')
    return text[:block.start()] + new + text[block.end():]


def frames_of(dump):
    out = []
    for chunk in dump.split("ITEM: TIMESTEP\n")[1:]:
        lines = chunk.splitlines()
        out.append((int(lines[0]), np.array([[float(x) for x in line.split()] for line in lines[8:]])))
    return out


SIZE, THICK, RHO = 3e-4, 1.5e-4, 2330.0  # the deck's defaults


@pytest.mark.parametrize("shape, surface", [
    ("disc", {"hamaker": 1e-19, "roughness": 2e-7, "air_viscosity": 0, "amp_n": 5e-5}),        # flat-flat vdW
    ("disc", {"hamaker": 0, "roughness": 5e-6, "air_viscosity": sf.AIR_VISCOSITY, "amp_n": 1.24e-4}),
    ("chip", {"hamaker": 1e-19, "roughness": 5e-6, "air_viscosity": sf.AIR_VISCOSITY, "amp_n": 1.24e-4}),
], ids=["disc vdW", "disc film", "chip film"])
def test_a_clumps_spheres_share_the_faces_law(tmp_path, shape, surface):
    # three parts far apart, the track vibrating normal to itself only: they hop lying flat
    given = {**FEW, "shape": shape, "amp_t": 0, "t_end": 0.01, "output_dt": 1e-5, **surface}
    out, dump = by_hand(detailed(DECK.read_text()), tmp_path, given)
    frames = frames_of(dump)
    assert len(frames) == 1001, out[-2000:]
    n = 7 if shape == "disc" else 9
    mass, adh, film = lying_flat(shape, SIZE, THICK, RHO, surface["hamaker"], surface["roughness"],
                                 surface["air_viscosity"])
    dt = given["output_dt"] / (frames[1][0] - frames[0][0])
    got, want = [], []
    for _, rows in frames:
        bodies = rows[:, 1].astype(int)
        for body in np.unique(bodies):
            b = rows[bodies == body]
            gap = b[:, 6] - THICK / 2 - b[:, 11]
            if len(b) != n or gap.min() <= 1e-9:
                continue
            # in flight a clump sphere's f holds its share alone (gravity acts on the body);
            # the force acts on the half-step velocity
            accel = (b[:, 10].sum() - mass * G) / mass
            v_half = b[:, 9] - accel * dt / 2
            share = (np.array([-adh.force(g) for g in gap]) + film.force(gap, v_half - b[:, 12])) / n
            got.append(b[:, 10])
            want.append(share)
    got, want = np.concatenate(got), np.concatenate(want)
    assert len(got) > 100 * n
    scale = np.abs(want).max()
    assert scale > 0.1 * mass * G / n  # the forces are felt: a tenth of a sphere's share of the weight
    np.testing.assert_allclose(got, want, rtol=1e-6, atol=1e-6 * scale)


@pytest.mark.parametrize("shape, surface", [
    ("sphere", {"size_spread": 0.3, "hamaker": 1e-19, "roughness": 1e-9, "air_viscosity": sf.AIR_VISCOSITY}),
    ("chip", {"hamaker": 1e-19, "roughness": 2e-8, "air_viscosity": 0}),
    ("disc", {"hamaker": 4e-19, "roughness": 1.5e-6, "air_viscosity": sf.AIR_VISCOSITY}),
])
def test_the_step_limit_joins_the_automatic_timestep(tmp_path, shape, surface):
    given = {**FEW, "shape": shape, "t_settle": 1e-3, "t_end": 1e-3, "output_dt": 5e-4, **surface}
    out = tmp_path / "dt.h5"
    vibrofeed("run", "bulk_feeder", "-q", *params(given), "-o", out, check=True)
    with Result(out) as r:
        d, p = r.derived, r.parameters
    limit = d["dt_surface_forces"]
    assert limit == pytest.approx(surface_forces_step_limit(p), rel=1e-12)
    assert limit == pytest.approx(min(d["dt_vdw"], d["dt_film"]), rel=1e-12)
    hamaker, rough, mu = surface["hamaker"], surface["roughness"], surface["air_viscosity"]
    if shape == "sphere":
        r_min = SIZE / 2 * (1 - surface["size_spread"])
        mass = 4 / 3 * math.pi * r_min ** 3 * RHO
        adh = ad.Adhesion(hamaker, rough, radius=r_min)
        film = sf.Film(mu, r_min, sf.clearance(rough), flat=False)
    else:
        mass, adh, film = lying_flat(shape, SIZE, THICK, RHO, hamaker, rough, mu)
    assert d["dt_vdw"] == pytest.approx(ad.vdw_step_limit(adh, mass), rel=1e-12)
    if mu > 0:
        assert d["dt_film"] == pytest.approx(sf.film_step_limit(film, mass), rel=1e-12)
    assert d["sf_pulloff"] == pytest.approx(adh.pulloff, rel=1e-12)
    hertz = d["t_hertz"] / 50
    step = min(limit, hertz)
    assert limit < hertz  # each case is chosen so that the surface forces set the step
    assert step / (1 + step / p["output_dt"]) < d["dt_used"] <= step


def test_a_timestep_above_the_limit_is_refused(tmp_path):
    given = {**FEW, "hamaker": 1e-19, "roughness": 1e-9}
    too_long = {"dt": 1e-6}  # the limit: 2.1e-7 s
    proc = vibrofeed("run", "bulk_feeder", *params({**given, **too_long}), "-o", tmp_path / "x.h5")
    assert proc.returncode == 2
    assert "surface forces need" in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    out, dump = by_hand(DECK.read_text(), tmp_path / "hand", given, too_long)
    # by hand the prepared folder holds the run to the dt vibrofeed checked (the automatic one)
    assert "Invalid dt: mesh_dir was checked and written for dt=0.0" in out and not dump
