"""The surface forces' step limit and refusals in both decks' vocabularies
(vibrofeed/parameters.py; decks/include/surface_forces.liggghts derives the same):
the limit is the models' (validation/models/adhesion.py, squeeze_film.py) for the
part it binds -- a single part, the smallest sphere of a bulk size spread, a chip's
square face, a disc's round one -- and bad combinations are refused in one line."""

import math

import pytest

from vibrofeed.decks import Deck
from vibrofeed.errors import ParameterError
from vibrofeed.parameters import resolve, surface_forces_step_limit
from vibrofeed.validation.models import adhesion as ad
from vibrofeed.validation.models import squeeze_film as sf

MU = sf.AIR_VISCOSITY
RHO = 2330.0
BULK = {"density": RHO, "part_size": 3e-4, "part_thickness": 1.5e-4, "size_spread": 0.0}


def models_limit(adhesion, film, mass):
    return min(ad.vdw_step_limit(adhesion, mass), sf.film_step_limit(film, mass))


@pytest.mark.parametrize("hamaker, roughness, mu", [(1e-19, 0.0, MU), (4e-19, 2e-9, 0.0), (0.0, 1e-6, MU)])
def test_bulk_spheres_take_the_smallest_sphere_of_the_spread(hamaker, roughness, mu):
    p = {**BULK, "shape": 0, "size_spread": 0.3, "hamaker": hamaker, "roughness": roughness,
         "air_viscosity": mu}
    r = 1.5e-4 * 0.7
    mass = 4 / 3 * math.pi * r ** 3 * RHO
    want = models_limit(ad.Adhesion(hamaker, roughness, radius=r),
                        sf.Film(mu, r, sf.clearance(roughness), flat=False), mass)
    assert surface_forces_step_limit(p) == pytest.approx(want, rel=1e-12)
    # the smallest sphere binds: the nominal one allows a longer step
    assert surface_forces_step_limit({**p, "size_spread": 0.0}) > want


@pytest.mark.parametrize("shape", [1, 2], ids=["chip", "disc"])
@pytest.mark.parametrize("hamaker, roughness, mu", [(1e-19, 2e-8, 0.0), (0.0, 2e-6, MU), (1e-19, 5e-6, MU)])
def test_a_clump_takes_its_whole_face_and_mass(shape, hamaker, roughness, mu):
    p = {**BULK, "shape": shape, "hamaker": hamaker, "roughness": roughness, "air_viscosity": mu}
    a, t = 3e-4, 1.5e-4
    if shape == 1:
        mass = a * a * t * RHO
        adh = ad.Adhesion(hamaker, roughness, face_side=a)
        film = sf.Film(mu, 0.0, sf.clearance(roughness), side=a)
    else:
        mass = math.pi * (a / 2) ** 2 * t * RHO
        adh = ad.Adhesion(hamaker, roughness, face_radius=a / 2)
        film = sf.Film(mu, a / 2, sf.clearance(roughness))
    assert surface_forces_step_limit(p) == pytest.approx(models_limit(adh, film, mass), rel=1e-12)


def test_the_single_part_vocabulary_is_unchanged():
    p = {"density": RHO, "radius": 5e-4, "face_radius": 2e-4, "hamaker": 1e-19, "roughness": 1e-7,
         "air_viscosity": MU}
    mass = 4 / 3 * math.pi * 5e-4 ** 3 * RHO
    want = models_limit(ad.Adhesion(1e-19, 1e-7, radius=5e-4, face_radius=2e-4),
                        sf.Film(MU, 2e-4, sf.clearance(1e-7)), mass)
    assert surface_forces_step_limit(p) == pytest.approx(want, rel=1e-12)


def test_no_limit_when_both_forces_are_off_or_without_a_part():
    assert surface_forces_step_limit({**BULK, "shape": 1, "roughness": 1e-9}) == math.inf
    assert surface_forces_step_limit({"hamaker": 1e-19}) == math.inf


BULK_DECK = Deck.find("bulk_feeder")


def refusal(**given):
    with pytest.raises(ParameterError) as err:
        resolve(BULK_DECK, {k: str(v) for k, v in given.items()})
    message = str(err.value)
    assert "\n" not in message
    return message


def test_the_bulk_feeder_refuses_forces_too_stiff_to_integrate():
    # a chip's smooth face with air: a film relaxing in ~1e-11 s
    message = refusal(shape="chip", hamaker=1e-19, air_viscosity=MU)
    assert "below 1e-09 s" in message and "raise roughness" in message
    # the same with 5 um of roughness runs
    assert resolve(BULK_DECK, {"shape": "chip", "hamaker": "1e-19", "air_viscosity": str(MU),
                               "roughness": "5e-6"})["roughness"] == "5e-6"


def test_the_bulk_feeder_refuses_a_timestep_above_the_limit():
    limit = surface_forces_step_limit({**BULK, "shape": 0, "hamaker": 1e-19, "roughness": 1e-9})
    assert 1e-7 < limit < 1e-6
    message = refusal(hamaker=1e-19, roughness=1e-9, dt=1e-6)
    assert "dt=1e-06 s is longer than" in message and "set dt=0" in message
    resolve(BULK_DECK, {"hamaker": "1e-19", "roughness": "1e-9", "dt": "1e-7"})  # below: accepted
    resolve(BULK_DECK, {"roughness": "1e-9", "dt": "1e-6"})  # forces off: no limit


def test_bad_surface_force_values_are_refused_in_the_bulk_feeder_too():
    assert "hamaker=1e-15" in refusal(hamaker=1e-15)
    assert "roughness=-1e-09" in refusal(roughness=-1e-9)
    assert "air_viscosity=1" in refusal(air_viscosity=1)
