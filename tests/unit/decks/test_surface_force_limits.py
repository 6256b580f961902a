"""The surface forces' step limit and refusals in both decks' vocabularies
(vibrofeed/parameters.py; decks/include/surface_forces.liggghts derives the same):
the limit is the models' (vibrofeed/models/adhesion.py, squeeze_film.py) for the
part it binds -- a single part, the smallest sphere of a bulk size spread, a chip's
square face, a disc's round one -- and bad combinations are refused in one line."""

import math

import pytest

from helpers import lying_flat
from vibrofeed.decks import Deck
from vibrofeed.errors import ParameterError
from vibrofeed.models import adhesion as ad
from vibrofeed.models import squeeze_film as sf
from vibrofeed.parameters import resolve, surface_forces_part, surface_forces_step_limit

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
    assert surface_forces_step_limit(p) == pytest.approx(want, rel=1e-12, abs=0)
    # the smallest sphere binds: the nominal one allows a longer step
    assert surface_forces_step_limit({**p, "size_spread": 0.0}) > want


@pytest.mark.parametrize("shape", [1, 2], ids=["chip", "disc"])
@pytest.mark.parametrize("hamaker, roughness, mu", [(1e-19, 2e-8, 0.0), (0.0, 2e-6, MU), (1e-19, 5e-6, MU)])
def test_a_clump_takes_its_whole_face_and_mass(shape, hamaker, roughness, mu):
    p = {**BULK, "shape": shape, "hamaker": hamaker, "roughness": roughness, "air_viscosity": mu}
    a, t = 3e-4, 1.5e-4
    mass, adh, film = lying_flat(shape, a, t, RHO, hamaker, roughness, mu)
    assert surface_forces_step_limit(p) == pytest.approx(models_limit(adh, film, mass), rel=1e-12, abs=0)


def test_the_single_part_vocabulary_is_unchanged():
    p = {"density": RHO, "radius": 5e-4, "face_radius": 2e-4, "hamaker": 1e-19, "roughness": 1e-7,
         "air_viscosity": MU}
    mass = 4 / 3 * math.pi * 5e-4 ** 3 * RHO
    want = models_limit(ad.Adhesion(1e-19, 1e-7, radius=5e-4, face_radius=2e-4),
                        sf.Film(MU, 2e-4, sf.clearance(1e-7)), mass)
    assert surface_forces_step_limit(p) == pytest.approx(want, rel=1e-12, abs=0)


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


# -- the part description (surface_forces_part), each field against its closed form

def test_a_single_part_is_a_sphere_unless_it_lies_on_a_face():
    r, f = 5e-4, 2e-4
    sphere = {"mass": 4 / 3 * math.pi * r ** 3 * RHO, "radius": r}
    # no face_radius (or 0): a sphere, without the flat face's area, Stefan constant or drag;
    # abs=0 throughout: the masses, areas and Stefan constants (1e-15..1e-6) are far below the
    # default abs=1e-12 of pytest.approx, which would pass any of them for another
    assert surface_forces_part({"density": RHO, "radius": r}) == pytest.approx(sphere, rel=1e-12, abs=0)
    assert surface_forces_part({"density": RHO, "radius": r, "face_radius": 0.0}) == pytest.approx(
        sphere, rel=1e-12, abs=0)
    film = sf.Film(MU, f, sf.MEAN_FREE_PATH)  # a disc face: Stefan 1.5 pi f^4, drag 16 mu f
    assert surface_forces_part({"density": RHO, "radius": r, "face_radius": f}) == pytest.approx(
        {**sphere, "area": math.pi * f ** 2, "stefan": film.stefan_constant,
         "drag": film.free_coefficient / MU}, rel=1e-12, abs=0)


@pytest.mark.parametrize("shape", [0, 1, 2], ids=["sphere", "chip", "disc"])
def test_a_bulk_part_is_its_sphere_or_its_whole_clump_on_its_face(shape):
    a, t = 3e-4, 1.5e-4
    p = {"density": RHO, "part_size": a, "part_thickness": t, "shape": shape}  # no size_spread: 0
    if shape == 0:
        want = {"mass": 4 / 3 * math.pi * (a / 2) ** 3 * RHO, "radius": a / 2}
    else:
        if shape == 1:  # a square face of side a
            area, film = a * a, sf.Film(MU, 0.0, sf.MEAN_FREE_PATH, side=a)
        else:  # a round face of diameter a
            area, film = math.pi * (a / 2) ** 2, sf.Film(MU, a / 2, sf.MEAN_FREE_PATH)
        # radius: the clump's spheres, of diameter part_thickness (the deck's r_sph)
        want = {"mass": area * t * RHO, "radius": t / 2, "area": area, "stefan": film.stefan_constant,
                "drag": film.free_coefficient / MU}
    assert surface_forces_part(p) == pytest.approx(want, rel=1e-12, abs=0)


# -- the step limit: each force alone, and the cases that need no limit

@pytest.mark.parametrize("roughness", [None, 1e-6], ids=["smooth-by-default", "rough"])
def test_van_der_waals_alone_gives_the_adhesion_models_limit(roughness):
    """Also on a rough track, where the vdW spring is far below 1 N/m (the limit is still finite)."""
    rough = {} if roughness is None else {"roughness": roughness}
    s = roughness or 0.0
    r, f, a, t = 5e-4, 2e-4, 3e-4, 1.5e-4
    ball, chip = 4 / 3 * math.pi * r ** 3 * RHO, a * a * t * RHO
    cases = [  # (parameters, the model's adhesion, mass)
        ({"radius": r}, ad.Adhesion(1e-19, s, radius=r), ball),
        ({"radius": r, "face_radius": f}, ad.Adhesion(1e-19, s, face_radius=f), ball),
        ({"part_size": a, "part_thickness": t, "shape": 1}, ad.Adhesion(1e-19, s, face_side=a), chip),
    ]
    for given, adhesion, mass in cases:
        if roughness:
            assert adhesion.stiffness < 1.0  # N/m: a soft spring, yet one to resolve
        p = {"density": RHO, "hamaker": 1e-19, **rough, **given}
        assert surface_forces_step_limit(p) == pytest.approx(ad.vdw_step_limit(adhesion, mass),
                                                             rel=1e-12, abs=0)  # s, from 1e-11


def test_without_either_force_no_part_is_even_described():
    # parts far too large for a float's mass: with hamaker = air_viscosity = 0 nothing is computed
    for part in ({"part_size": 1e300}, {"radius": 1e300}, {"part_size": 1e300, "shape": 1}):
        for off in ({}, {"hamaker": 0.0, "air_viscosity": 0.0, "roughness": 0.0}):
            assert surface_forces_step_limit({"density": RHO, **part, **off}) == math.inf


def test_a_limit_exactly_at_the_smallest_timestep_is_accepted():
    """The deck refuses limits *below* 1e-9 s: a chip on a 0.27 um rough track with air, its
    density chosen (next to the closed form's) so that the limit is exactly 1e-9 s."""
    a, t, h = 3e-4, 1.5e-4, 2.7e-7
    film = sf.Film(MU, 0.0, h, side=a)
    rho = 1e-9 * 10 * film.coefficient(h) / (a * a * t)  # m / (10 c) = 1e-9 s
    p = {"density": rho, "part_size": a, "part_thickness": t, "shape": 1, "air_viscosity": MU,
         "roughness": h}
    for _ in range(100):  # a few ulps of rounding apart
        limit = surface_forces_step_limit({**p, "density": rho})
        if limit == 1e-9:
            break
        rho = math.nextafter(rho, math.inf if limit < 1e-9 else 0.0)
    assert limit == 1e-9 and rho == pytest.approx(p["density"], rel=1e-12)
    given = {"shape": "chip", "air_viscosity": repr(MU), "roughness": repr(h)}
    assert resolve(BULK_DECK, {**given, "density": repr(rho)})["density"] == repr(rho)
    while surface_forces_step_limit({**p, "density": rho}) == 1e-9:
        rho = math.nextafter(rho, 0.0)
    assert "below 1e-09 s" in refusal(**given, density=repr(rho))


def test_a_timestep_exactly_at_the_limit_is_accepted():
    given = {"hamaker": "1e-19", "roughness": "1e-9"}
    p = {k: float(v) for k, v in resolve(BULK_DECK, given).items()
         if k in BULK_DECK.variables and BULK_DECK.variables[k].is_numeric}
    limit = surface_forces_step_limit(p)
    r = 1.5e-4  # the default 300 um sphere
    mass = 4 / 3 * math.pi * r ** 3 * RHO
    assert limit == pytest.approx(ad.vdw_step_limit(ad.Adhesion(1e-19, 1e-9, radius=r), mass),
                                  rel=1e-12, abs=0)  # s, ~2e-7
    assert resolve(BULK_DECK, {**given, "dt": repr(limit)})["dt"] == repr(limit)
    assert "is longer than" in refusal(**given, dt=repr(math.nextafter(limit, math.inf)))


# -- a deck of one's own declaring only some of the forces' parameters: the others are off (0)

def own_deck(tmp_path, **defaults):
    path = tmp_path / "own.liggghts"
    path.write_text("".join(f"variable {k} index {v} # [-] {k}\n" for k, v in defaults.items()))
    return Deck(path)


def test_a_deck_without_some_force_parameters_reports_them_as_zero(tmp_path):
    # a face lying flat on a smooth track: too stiff for either force alone
    part = {"radius": 5e-4, "face_radius": 2e-4, "density": RHO}
    with pytest.raises(ParameterError) as err:
        resolve(own_deck(tmp_path, **part, hamaker=1e-19), {})
    assert "hamaker=1e-19 J, air_viscosity=0 Pa s with roughness=0 m need a timestep" in str(err.value)
    with pytest.raises(ParameterError) as err:
        resolve(own_deck(tmp_path, **part, air_viscosity=MU), {})
    assert f"hamaker=0 J, air_viscosity={MU:g} Pa s with roughness=0 m need" in str(err.value)


@pytest.mark.parametrize("force", [{"air_viscosity": repr(MU)}, {"hamaker": "1e-19"}])
def test_a_tilted_floor_refuses_either_surface_force(force):
    with pytest.raises(ParameterError, match=r"cross_tilt: the surface forces .* act on a level floor"):
        resolve(Deck.find("bulk_feeder"), {"cross_tilt": "5", **force})
    resolve(Deck.find("bulk_feeder"), {"cross_tilt": "0", **force})


def test_a_tilted_bowl_without_surface_forces_resolves():
    # the bowl declares neither hamaker nor air_viscosity: an absent force is off
    bowl = Deck.find("bowl_feeder")
    assert "hamaker" not in bowl.tunables and "air_viscosity" not in bowl.tunables
    assert resolve(bowl, {"cross_tilt": "3"})["cross_tilt"] == "3"
