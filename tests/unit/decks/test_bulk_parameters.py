"""The bulk feeder's parameters: the one-line refusals, named shapes, and the deck's own
derived formulas (sjkr cohesion from the surface energy, timestep, outlet and box floor),
evaluated from decks/bulk_feeder.liggghts as LIGGGHTS would."""

import math
import re

import numpy as np
import pytest

from vibrofeed.decks import Deck
from vibrofeed.errors import ParameterError
from vibrofeed.geometry import chip_template, disc_template
from vibrofeed.parameters import resolve

DECK = Deck.find("bulk_feeder")
_FUNCTIONS = {"sqrt": math.sqrt, "abs": abs, "ceil": math.ceil, "floor": math.floor,
              "round": round, "sin": math.sin, "cos": math.cos, "tan": math.tan,
              "pi": math.pi}


def derived(**given):
    """The deck's equal-style constants for parameters ``given``, evaluated in Python
    (LIGGGHTS' ^ as **), with what its ``if`` lines and prepared.in set."""
    values = {k: float(v) for k, v in resolve(DECK, {k: str(v) for k, v in given.items()}).items()
              if k in DECK.variables and DECK.variables[k].is_numeric}
    shape = int(values["shape"])
    size, thick = values["part_size"], values["part_thickness"]
    env = dict(values)
    clumps = {1: chip_template, 2: disc_template}
    env["body_spheres"] = len(clumps[shape](size, thick)) if shape else 1
    # prepared.in's box and stl-part variables (vibrofeed.geometry): 0 for other shapes
    env.update({f"{n}_{kind}": 0.0 for kind in ("box", "stl")
                for n in ("n_sph", "r_sph", "r_min", "r_ext", "m")})
    if env["youngs_track"] <= 0:
        env["youngs_track"] = env["youngs"] * 70 / 130
    cache = {}

    def value(name):
        if name in env:
            return env[name]
        if name not in cache:
            formula = DECK.formulas[name].replace("^", "**").replace("PI", "pi")
            formula = re.sub(r"\bv_(\w+)", r"V('\1')", formula)
            cache[name] = float(eval(formula, {"V": value, **_FUNCTIONS}))
        return cache[name]

    return value


def sjkr_pulloff(k, r_star, e_star):
    """The largest tension of Hertz + sjkr, F = 4/3 E* sqrt(R*) d^1.5 - k 2 pi R* d, over the
    overlap d (sjkr's contact area 2 pi R* d), found numerically."""
    d_min = (math.pi * k * math.sqrt(r_star) / e_star) ** 2  # the minimum, for the grid's scale
    d = np.linspace(0, 4 * d_min, 400_001)
    force = 4 / 3 * e_star * math.sqrt(r_star) * d**1.5 - 2 * math.pi * k * r_star * d
    return -force.min()


@pytest.mark.parametrize("youngs", ["5e7", "1e9", "1.3e11"])
@pytest.mark.parametrize("shape", ["sphere", "chip"])
def test_sjkr_energy_density_gives_the_jkr_pulloff(youngs, shape):
    v = derived(youngs=youngs, shape=shape, surface_energy=0.05, surface_energy_pp=0.02)
    for pair, gamma in (("pp", 0.02), ("pw", 0.05)):
        k, rs, es = v(f"k_{pair}"), v(f"Rs_{pair}"), v(f"E_star_{pair}")
        jkr = 1.5 * math.pi * gamma * rs
        assert v(f"pulloff_{pair}") == pytest.approx(jkr, rel=1e-12, abs=0)  # ~1e-5 N: rounding only
        # the closed form of the measured relation, and the force law's minimum itself
        assert 2 / 3 * math.pi**3 * k**3 * rs**2 / es**2 == pytest.approx(jkr, rel=1e-12, abs=0)
        assert sjkr_pulloff(k, rs, es) == pytest.approx(jkr, rel=1e-6)
    # R*: the contact sphere (the part, or one sphere of a clump), halved between two parts
    r = 1.5e-4 if shape == "sphere" else 0.75e-4
    assert (v("Rs_pp"), v("Rs_pw")) == pytest.approx((r / 2, r), rel=1e-12, abs=0)


def test_track_material_follows_the_parts_softening():
    v = derived(youngs="5e7")
    assert v("E_track") == pytest.approx(5e7 * 70 / 130, rel=1e-12)
    e = 1 / ((1 - 0.28**2) / 5e7 + (1 - 0.33**2) / (5e7 * 70 / 130))
    assert v("E_star_pw") == pytest.approx(e, rel=1e-12)
    assert derived(youngs_track="2e8")("E_track") == pytest.approx(2e8, rel=1e-12)
    assert derived()("k_pp") == 0 and derived()("k_pw") == 0  # no cohesion by default


def test_timestep_from_the_hertz_time_with_both_fractions():
    v = derived()
    assert v("t_hertz") == pytest.approx(min(v("t_hertz_pp"), v("t_hertz_pw")), rel=1e-12, abs=0)
    steps = v("output_dt") / v("dt_used")
    assert steps == pytest.approx(round(steps), rel=1e-9)  # whole steps per frame
    assert 1 / 50 * (1 - 1 / steps) <= v("dt_hertz_fraction") <= 1 / 50
    assert v("dt_rayleigh_fraction") == pytest.approx(v("dt_used") / v("t_rayleigh"), rel=1e-12)
    assert v("dt_rayleigh_fraction") < 0.2  # LIGGGHTS' check/timestep/gran warns beyond 0.2
    # a size spread: the smallest sphere sets the contact time
    assert derived(size_spread=0.2)("t_hertz") == pytest.approx(0.8 * v("t_hertz"), rel=1e-9, abs=0)


@pytest.mark.parametrize("given", [{}, {"shape": "chip"}, {"amp_n": "2e-4", "output_dt": "0.02"},
                                   {"incline": "10"}, {"cross_tilt": "10"}])
def test_outlet_catch_plane_and_box_floor(given):
    v = derived(**given)
    assert v("outlet_x") == v("track_length")
    # below catch_z a part's top is under the lowest floor position (-amp_n, and the cross
    # tilt's drop to the -y wall), with room to spare
    lowest = -v("amp_n") - v("track_width") * math.tan(math.radians(v("cross_tilt")))
    assert v("catch_z") + v("r_ext") < lowest
    # the contract's floor rule
    odt, g = v("output_dt"), v("g")
    fall = v("v_max") * odt + g / 2 * odt**2 + 2 * v("part_size")
    assert v("fall_depth") == pytest.approx(fall, rel=1e-12, abs=0)
    assert v("box_zlo") <= v("catch_z") - fall * (1 - 1e-12)
    assert v("v_max") >= 2 * v("v_peak") + math.sqrt(2 * g * (v("box_zhi") - v("catch_z")))
    assert v("box_xhi") > v("outlet_x") + v("catch_size")


@pytest.mark.parametrize("given, fragment", [
    ({"n_parts": "0", "inlet_rate": "0"}, "n_parts=0 and inlet_rate=0"),
    ({"shape": "chip", "part_thickness": "4e-4"}, "part_thickness=0.0004"),
    ({"track_width": "2e-4"}, "track_width=0.0002 m is narrower than a part"),
    ({"size_spread": "0.5", "track_width": "4e-4"}, "track_width=0.0004 m is narrower"),
    ({"gate_width": "1e-4"}, "gate_width=0.0001 m is narrower than a part"),
    ({"gate_width": "2e-3"}, "gate_width=0.002 m must be narrower than track_width"),
    ({"gate_width": "8e-4", "gate_at": "0.99", "fill_to": "0.5"}, "gate_at=0.99"),
    ({"gate_width": "8e-4"}, "fill_to=0.9 reaches into the gate"),
    ({"fill_from": "0.5", "fill_to": "0.5"}, "fill_from=0.5 must be below fill_to"),
    ({"shape": "disc", "size_spread": "0.1"}, "size_spread=0.1 applies to spheres only"),
    ({"wall_height": "1e-4"}, "wall_height=0.0001 m is no higher than a part's centre"),
    ({"n_parts": "5000"}, "n_parts=5000 settle"),
    ({"shape": "cube"}, "shape=cube must be one of sphere (0), chip (1), disc (2)"),
    ({"shape": "5"}, "shape=5 must be one of 0, 1, 2, 3, 4"),
    ({"shape": "4"}, "an stl part (shape 4) needs its STL: part_file"),
    ({"size_spread": "1"}, "size_spread=1"),
    ({"youngs_track": "1e6"}, "youngs_track=1e6"),
    ({"restitution_pp": "0.01"}, "restitution_pp=0.01"),
    ({"surface_energy": "-0.1"}, "surface_energy=-0.1"),
    ({"n_parts": "10.5"}, "n_parts=10.5"),
    ({"mesh_dir": "x"}, "set by vibrofeed itself"),
])
def test_bad_bulk_parameters_are_refused_in_one_line(given, fragment):
    with pytest.raises(ParameterError) as info:
        resolve(DECK, given)
    assert fragment in str(info.value)
    assert "\n" not in str(info.value)


def test_valid_combinations_resolve():
    assert resolve(DECK, {"shape": "chip"})["shape"] == "1"
    assert resolve(DECK, {"shape": "Disc", "part_thickness": "1e-4"})["shape"] == "2"
    resolve(DECK, {"n_parts": "0", "inlet_rate": "200"})
    resolve(DECK, {"gate_width": "8e-4", "fill_to": "0.6"})
    resolve(DECK, {"size_spread": "0.2", "youngs_track": "0"})


def test_deck_declares_its_prepare_hook_and_generated_include():
    assert DECK.prepare_target == "vibrofeed.geometry:prepare_bulk_feeder"
    assert DECK.generated == ["${mesh_dir}/prepared.in", "${mesh_dir}/line_derived.in",
                              "${mesh_dir}/line_meshes.in", "${mesh_dir}/line_catch.in",
                              "${mesh_dir}/line_motion.in"]
    assert "mesh_dir" not in DECK.tunables and "outlet_file" not in DECK.tunables
    for name in ("outlet_x", "catch_z", "body_spheres", "k_pp", "k_pw", "pulloff_pp", "pulloff_pw",
                 "dt_hertz_fraction", "dt_rayleigh_fraction", "fall_depth", "n_prefilled"):
        assert name in DECK.constants, name
    assert "parts_present" not in DECK.constants  # follows `atoms`


def test_the_bulk_feeder_refuses_contacts_softer_than_its_validated_range():
    from vibrofeed.decks import Deck
    from vibrofeed.errors import ParameterError
    from vibrofeed.parameters import BULK_MIN_YOUNGS, resolve

    deck = Deck.find("bulk_feeder")
    assert resolve(deck, {"youngs": repr(BULK_MIN_YOUNGS)})["youngs"] == repr(BULK_MIN_YOUNGS)
    assert float(deck.variables["youngs"].default) >= BULK_MIN_YOUNGS  # the default is inside
    with pytest.raises(ParameterError, match="youngs=1.9e\\+07 Pa is softer"):
        resolve(deck, {"youngs": "1.9e7"})
    # the single-part deck keeps LIGGGHTS' own limit only
    assert resolve(Deck.find("single_part"), {"youngs": "1e7"})["youngs"] == "1e7"


def test_a_surface_speed_of_exactly_2_m_per_s_is_allowed():
    # README: the peak surface speed 2 pi freq amp is refused *above* 2 m/s
    freq = 2.0 / (2 * math.pi * 0.005)
    assert 2 * math.pi * freq * 0.005 == 2.0  # exactly on the limit (checked, not assumed)
    for amp, other in (("amp_n", "amp_t"), ("amp_t", "amp_n")):
        assert resolve(DECK, {amp: "0.005", other: "0", "freq": repr(freq)})["freq"] == repr(freq)
        with pytest.raises(ParameterError, match=f"{amp}=0.005 m at freq="):
            resolve(DECK, {amp: "0.005", other: "0", "freq": repr(freq * (1 + 1e-12))})


@pytest.mark.parametrize("shape, n, size, thickness, length", [
    ("sphere", 300, 3e-4, 1.5e-4, 0.02), ("disc", 40, 3e-4, 1.5e-4, 0.005),
    ("chip", 1, 1e-3, 1e-4, 1e-3),  # a single part already piles above the walls
])
def test_a_pre_fill_exactly_as_high_as_the_walls_is_allowed(shape, n, size, thickness, length):
    """The settled pre-fill's height n V / (0.6 (fill_to - fill_from) track_length track_width),
    V the part's volume, may reach the walls' top but not pass it."""
    volume = {"sphere": math.pi / 6 * size**3, "chip": size**2 * thickness,
              "disc": math.pi / 4 * size**2 * thickness}[shape]
    pile = n * volume / (0.6 * (0.9 - 0.1) * length * 2e-3)  # the default fill 0.1-0.9, width 2 mm
    given = {"shape": shape, "n_parts": str(n), "part_size": repr(size), "part_thickness": repr(thickness),
             "track_length": repr(length), "fill_from": "0.1", "fill_to": "0.9", "track_width": "2e-3"}
    assert resolve(DECK, {**given, "wall_height": repr(pile)})["wall_height"] == repr(pile)
    with pytest.raises(ParameterError, match=f"n_parts={n} settle .* above the walls"):
        resolve(DECK, {**given, "wall_height": repr(math.nextafter(pile, 0))})


def test_the_softest_validated_contact_is_2e7_pa():
    # README "Decks": the feed rate was measured independent of youngs from 2e7 to 1e9 Pa
    assert resolve(DECK, {"youngs": "2e7"})["youngs"] == "2e7"
    with pytest.raises(ParameterError, match=r"youngs=2e\+07 Pa is softer .* from 2e\+07 to 1e9 Pa"):
        resolve(DECK, {"youngs": repr(math.nextafter(2e7, 0))})


def own_deck(tmp_path, **defaults):
    """A deck of one's own declaring only ``defaults`` (the checks apply to what it declares)."""
    path = tmp_path / "own.liggghts"
    path.write_text("".join(f"variable {k} index {v} # [-] {k}\n" for k, v in defaults.items()))
    return Deck(path)


def test_a_deck_with_part_of_the_vocabulary_is_checked_on_what_it_declares(tmp_path):
    # vibrating normal to the track only (no amp_t): the speed limit still holds for amp_n
    normal_only = own_deck(tmp_path, freq=100, amp_n=1e-4)
    assert resolve(normal_only, {})["amp_n"] == "0.0001"
    with pytest.raises(ParameterError, match="amp_n=0.005 m at freq=100 Hz"):
        resolve(normal_only, {"amp_n": "0.005"})
    # an open track (no wall_height): no pre-fill is too high
    open_track = own_deck(tmp_path, part_size=3e-4, track_width=2e-3, track_length=0.02, n_parts=300)
    assert resolve(open_track, {"n_parts": "100000"})["n_parts"] == "100000"
    # a gate without gate_at sits at 0.7 of the track, as in the bulk feeder, and says so
    gate = own_deck(tmp_path, part_size=3e-4, track_width=2e-3, track_length=0.02, gate_width=8e-4,
                    fill_to=0.6)
    assert resolve(gate, {"fill_to": "0.7"})["fill_to"] == "0.7"
    with pytest.raises(ParameterError, match=r"fill_to=0.71 reaches into the gate \(gate_at=0.7\)"):
        resolve(gate, {"fill_to": "0.71"})


# Contact times, written out independently of vibrofeed.parameters:
# Hertz contact time t = 2.87 (m*^2 / (R* E*^2 v))^(1/5) (Johnson, Contact Mechanics, 11.2);
# E* = 1 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2); Rayleigh time
# T_R = pi R sqrt(rho / G) / (0.1631 nu + 0.8766), G = E / (2 (1 + nu)).
def hertz_time(m_star, r_star, e_star, speed):
    return 2.87 * (m_star ** 2 / (r_star * e_star ** 2 * speed)) ** 0.2


def e_star(e1, nu1, e2, nu2):
    return 1 / ((1 - nu1 ** 2) / e1 + (1 - nu2 ** 2) / e2)


def rayleigh_time(r, rho, youngs, nu):
    return math.pi * r * math.sqrt(rho / (youngs / (2 * (1 + nu)))) / (0.1631 * nu + 0.8766)


SILICON = {"density": 2330.0, "youngs": 1.3e11, "poisson": 0.28}
DRIVE = {"freq": 100.0, "amp_t": 3e-5, "amp_n": 4e-5}  # peak speed 2 pi 100 5e-5 = 0.0314 m/s
V_DRIVE = 2 * math.pi * 100 * 5e-5


def test_single_part_contact_times_are_a_sphere_on_a_plate_of_its_material():
    from vibrofeed.parameters import contact_times

    r = 5e-4
    m = 4 / 3 * math.pi * r ** 3 * 2330  # the plate does not move: m* = m, R* = r
    times = contact_times({**SILICON, **DRIVE, "radius": r})
    e = e_star(1.3e11, 0.28, 1.3e11, 0.28)
    assert times["hertz"] == pytest.approx(hertz_time(m, r, e, V_DRIVE), rel=1e-12)
    assert times["rayleigh"] == pytest.approx(rayleigh_time(r, 2330, 1.3e11, 0.28), rel=1e-12)


def test_bulk_contact_time_of_the_smallest_sphere_part_against_part():
    from vibrofeed.parameters import contact_times

    r = 2e-4 * (1 - 0.2)  # the smallest sphere of a 20 % spread
    m = 4 / 3 * math.pi * r ** 3 * 2330
    times = contact_times({**SILICON, **DRIVE, "part_size": 4e-4, "shape": 0, "size_spread": 0.2})
    # the track defaults to aluminium softened as the parts (E 70/130): part-part is shorter
    pp = hertz_time(m / 2, r / 2, e_star(1.3e11, 0.28, 1.3e11, 0.28), V_DRIVE)
    pw = hertz_time(m, r, e_star(1.3e11, 0.28, 7e10, 0.28), V_DRIVE)
    assert pp < pw
    assert times["hertz"] == pytest.approx(pp, rel=1e-12)
    assert times["rayleigh"] == pytest.approx(rayleigh_time(r, 2330, 1.3e11, 0.28), rel=1e-12)
    # a sphere is one sphere: part_thickness (of chips and discs) does not split its mass
    thin = contact_times({**SILICON, **DRIVE, "part_size": 4e-4, "shape": 0, "size_spread": 0.2,
                          "part_thickness": 1e-4})
    assert thin["hertz"] == pytest.approx(pp, rel=1e-12)


def test_bulk_contact_time_part_against_a_track_of_nearly_incompressible_poisson():
    from vibrofeed.parameters import contact_times

    # poisson_track -0.99 makes the track nearly rigid in E*: part-track is then the shorter
    r, size = 1.5e-4, 3e-4
    m = 4 / 3 * math.pi * r ** 3 * 2330
    p = {**SILICON, **DRIVE, "part_size": size, "poisson_track": -0.99}  # (no youngs_track: E 70/130)
    pp = hertz_time(m / 2, r / 2, e_star(1.3e11, 0.28, 1.3e11, 0.28), V_DRIVE)
    pw = hertz_time(m, r, e_star(1.3e11, 0.28, 1.3e11 * 70 / 130, -0.99), V_DRIVE)
    assert pw < pp
    assert contact_times(p)["hertz"] == pytest.approx(pw, rel=1e-12)
    # a track given its own modulus; 0 means the default
    pw_own = hertz_time(m, r, e_star(1.3e11, 0.28, 2e12, -0.99), V_DRIVE)
    assert contact_times({**p, "youngs_track": 2e12})["hertz"] == pytest.approx(pw_own, rel=1e-12)
    assert contact_times({**p, "youngs_track": 0.0})["hertz"] == pytest.approx(pw, rel=1e-12)


@pytest.mark.parametrize("shape, template", [(1, chip_template), (2, disc_template)])
def test_a_clumps_spheres_share_its_mass(shape, template):
    from vibrofeed.parameters import contact_times

    size, thick = 4e-4, 1e-4
    volume = size ** 2 * thick if shape == 1 else math.pi / 4 * size ** 2 * thick
    m = volume * 2330 / len(template(size, thick))  # one sphere's share
    r = thick / 2
    times = contact_times({**SILICON, **DRIVE, "part_size": size, "part_thickness": thick, "shape": shape})
    pp = hertz_time(m / 2, r / 2, e_star(1.3e11, 0.28, 1.3e11, 0.28), V_DRIVE)
    assert times["hertz"] == pytest.approx(pp, rel=1e-12)


def test_pulloff_contacts_are_timed_at_1_cm_per_s():
    from vibrofeed.parameters import contact_times

    r = 1.5e-4
    m = 4 / 3 * math.pi * r ** 3 * 2330
    pp = hertz_time(m / 2, r / 2, e_star(1.3e11, 0.28, 1.3e11, 0.28), 0.01)
    # "pair" marks the pulloff deck: nothing vibrates, whatever a drive says
    times = contact_times({**SILICON, **DRIVE, "part_size": 3e-4, "pair": 0})
    assert times["hertz"] == pytest.approx(pp, rel=1e-12)
    # without a drive the bulk deck also takes 1 cm/s
    assert contact_times({**SILICON, "part_size": 3e-4})["hertz"] == pytest.approx(pp, rel=1e-12)
    still = contact_times({**SILICON, "part_size": 3e-4, "freq": 100.0})
    assert still["hertz"] == pytest.approx(pp, rel=1e-12)


def test_without_a_part_there_is_no_contact_time():
    from vibrofeed.parameters import contact_times

    assert contact_times(SILICON) is None
    assert contact_times({"density": 2330.0, "youngs": 1.3e11, "radius": 1e-4}) is None


def test_a_fixed_dt_is_held_to_a_tenth_of_the_hertz_and_a_fifth_of_the_rayleigh_time():
    from vibrofeed.parameters import contact_times, step_beyond_contact

    p = {**SILICON, "youngs": 5e7, "part_size": 3e-4, "pair": 0}  # the decks' softened silicon
    r = 1.5e-4
    m = 4 / 3 * math.pi * r ** 3 * 2330
    hertz = hertz_time(m / 2, r / 2, e_star(5e7, 0.28, 5e7, 0.28), 0.01)
    rayleigh = rayleigh_time(r, 2330, 5e7, 0.28)
    # 0.2 T_R lies between the automatic dt (t_H / 50) and 0.1 t_H
    assert hertz / 50 < 0.2 * rayleigh < 0.1 * hertz
    assert step_beyond_contact({**p, "dt": 0.0}) is None  # automatic
    assert step_beyond_contact({**p, "dt": hertz / 50 * 0.999}) is None  # shorter than automatic
    assert step_beyond_contact({**p, "dt": 0.2 * rayleigh * 0.999}) is None
    past_rayleigh = step_beyond_contact({**p, "dt": 0.2 * rayleigh * 1.001})
    assert "of the Rayleigh time (limit 20%)" in past_rayleigh and "Hertz" not in past_rayleigh
    both = step_beyond_contact({**p, "dt": 0.1 * hertz * 1.001})
    assert "of the Hertz time (limit 10%)" in both and "of the Rayleigh time (limit 20%)" in both
    assert "Hertz" not in step_beyond_contact({**p, "dt": 0.1 * hertz * 0.999})
    # exactly at a limit is allowed (the limits are "beyond"): the times as the check takes them
    times = contact_times(p)
    assert times["hertz"] == pytest.approx(hertz, rel=1e-12)
    assert step_beyond_contact({**p, "dt": 0.2 * times["rayleigh"]}) is None
    assert "Hertz" not in step_beyond_contact({**p, "dt": 0.1 * times["hertz"]})


@pytest.mark.parametrize("value, hinted", [
    ("0.5", True), ("9999.5", True),  # under 1e4 Pa: a modulus in GPa
    ("1e4", False), ("-0.5", False),  # the hint's bounds are open: 0 < x < 1e4
])
def test_a_track_modulus_in_gpa_is_named_as_a_likely_slip(value, hinted):
    with pytest.raises(ParameterError, match=f"youngs_track={value} Pa must be 0") as info:
        resolve(DECK, {"youngs_track": value})
    assert ("a modulus in GPa? (moduli are in Pa: aluminium 7e10)" in str(info.value)) == hinted


def test_without_a_pre_fill_its_place_is_not_checked():
    # n_parts=0: only the inlet feeds, fill_from/fill_to place nothing (a word, no refusal)
    resolve(DECK, {"n_parts": "0", "inlet_rate": "200", "gate_width": "8e-4", "fill_to": "0.9"})
    resolve(DECK, {"n_parts": "0", "inlet_rate": "200", "fill_from": "0.5", "fill_to": "0.5"})
    with pytest.raises(ParameterError, match="fill_to=0.9 reaches into the gate"):
        resolve(DECK, {"n_parts": "1", "inlet_rate": "200", "gate_width": "8e-4", "fill_to": "0.9"})
    with pytest.raises(ParameterError, match="fill_from=0.5 must be below fill_to=0.5"):
        resolve(DECK, {"n_parts": "1", "fill_from": "0.5", "fill_to": "0.5"})


# -- the fixed dt against the contact: the fractions users read, the automatic dt's edge --------
PULLOFF = Deck.find("pulloff")


def pulloff_times(youngs):
    """The pull-off deck's contact times by the closed forms above: its 0.3 mm silicon
    spheres (density 2330, poisson 0.28) at 1 cm/s, part-part or part-track (aluminium's
    poisson 0.33, E x 70/130), the shorter Hertz time."""
    r = 1.5e-4
    m = 4 / 3 * math.pi * r ** 3 * 2330
    pp = hertz_time(m / 2, r / 2, e_star(youngs, 0.28, youngs, 0.28), 0.01)
    pw = hertz_time(m, r, e_star(youngs, 0.28, youngs * 70 / 130, 0.33), 0.01)
    return min(pp, pw), rayleigh_time(r, 2330, youngs, 0.28)


def whole_percent(fraction):
    """``fraction`` in whole percent, as the message rounds it (asserted away from a rounding edge)."""
    pct = round(100 * fraction)
    assert abs(100 * fraction - pct) < 0.4
    return pct


def test_a_step_past_both_limits_is_refused_with_its_fractions_of_both_times():
    hertz, rayleigh = pulloff_times(5e7)  # the deck's softened silicon
    dt = 0.15 * hertz  # 15 % of the Hertz time (limit 10 %); and 0.15 t_H / T_R of the Rayleigh time
    with pytest.raises(ParameterError) as err:
        resolve(PULLOFF, {"dt": repr(dt)})
    assert str(err.value) == (
        f"dt={dt:g} s is {whole_percent(0.15 * hertz / rayleigh)}% of the Rayleigh time (limit 20%) "
        "and 15% of the Hertz time (limit 10%): contacts would last a few steps and parts gain energy; "
        "lower dt or set dt=0 (automatic); to run it anyway add -p dt_unchecked=1 (the run then "
        "fails, as vibrofeed check rejects its result, with its frames kept)")


def test_the_automatic_step_is_allowed_even_past_a_fifth_of_the_rayleigh_time():
    from vibrofeed.parameters import contact_times

    # unsoftened silicon: t_H / 50 (the decks' automatic dt) lies past 0.2 T_R; a fixed dt that
    # long is still allowed, one a bit longer is beyond the Rayleigh limit (not the Hertz one)
    hertz, rayleigh = pulloff_times(1.3e11)
    assert 0.2 * rayleigh < hertz / 50 < 0.1 * hertz
    given = {"youngs": "1.3e11"}
    times = contact_times({k: float(v) for k, v in resolve(PULLOFF, given).items()})
    assert times["hertz"] == pytest.approx(hertz, rel=1e-12)
    assert times["rayleigh"] == pytest.approx(rayleigh, rel=1e-12)
    automatic = times["hertz"] / 50  # as the check takes it, to the last bit
    assert resolve(PULLOFF, {**given, "dt": repr(automatic)})["dt"] == repr(automatic)
    longer = math.nextafter(automatic, math.inf)
    with pytest.raises(ParameterError) as err:
        resolve(PULLOFF, {**given, "dt": repr(longer)})
    assert str(err.value).startswith(f"dt={longer:g} s is {whole_percent(hertz / 50 / rayleigh)}% "
                                     "of the Rayleigh time (limit 20%): contacts would last")


def test_a_stroke_without_a_frequency_is_no_drive():
    from vibrofeed.parameters import contact_times

    # a deck of one's own may declare a stroke but no freq: nothing moves it, so the contact is
    # timed at 1 cm/s as without a stroke (5 mm at 1 Hz would be 2 pi 5e-3 = 3.1 cm/s)
    r = 1.5e-4
    m = 4 / 3 * math.pi * r ** 3 * 2330
    pp = hertz_time(m / 2, r / 2, e_star(1.3e11, 0.28, 1.3e11, 0.28), 0.01)
    times = contact_times({**SILICON, "part_size": 3e-4, "amp_t": 5e-3, "amp_n": 5e-3})
    assert times["hertz"] == pytest.approx(pp, rel=1e-12)


def test_a_deck_without_dt_unchecked_refuses_a_step_beyond_the_contact(tmp_path):
    # a deck of one's own with a contact and a fixed dt but no dt_unchecked: nobody insisted
    own = own_deck(tmp_path, radius=5e-4, density=2330, youngs=5e7, poisson=0.3, dt=0)
    m = 4 / 3 * math.pi * 5e-4 ** 3 * 2330  # a sphere on a plate of its material, at 1 cm/s
    hertz = hertz_time(m, 5e-4, e_star(5e7, 0.3, 5e7, 0.3), 0.01)
    assert resolve(own, {"dt": repr(hertz / 100)})["dt"] == repr(hertz / 100)
    with pytest.raises(ParameterError, match=r"20% of the Hertz time \(limit 10%\): contacts would") as e:
        resolve(own, {"dt": repr(0.2 * hertz)})
    # and it is not told to add a parameter its deck does not declare
    assert str(e.value).endswith("lower dt or set dt=0 (automatic)")


def test_a_pre_fill_place_is_checked_where_a_deck_declares_one(tmp_path):
    # a gate on a deck that declares no pre-fill place (no fill_to): nothing reaches into it
    gate_only = own_deck(tmp_path, part_size=3e-4, track_width=2e-3, track_length=0.02, gate_width=8e-4)
    assert resolve(gate_only, {})["gate_width"] == "0.0008"
    # a pre-fill place without n_parts (the deck's own count, as the gate deck above): checked
    place = own_deck(tmp_path, part_size=3e-4, track_width=2e-3, fill_from=0.1, fill_to=0.9)
    assert resolve(place, {"fill_from": "0.4", "fill_to": "0.5"})["fill_from"] == "0.4"
    with pytest.raises(ParameterError, match=r"^fill_from=0.5 must be below fill_to=0.5$"):
        resolve(place, {"fill_from": "0.5", "fill_to": "0.5"})


def test_a_bowl_fed_only_along_its_track_resolves():
    # the bowl has no inlet (no inlet_rate): with n_parts=0 its n_track parts along the track
    # are its feed; only both at 0 is no feed, in the bowl's words
    bowl = Deck.find("bowl_feeder")
    assert "inlet_rate" not in bowl.tunables
    assert resolve(bowl, {"n_parts": "0"})["n_parts"] == "0"
    with pytest.raises(ParameterError, match="^n_parts=0 and n_track=0: no part in the bowl"):
        resolve(bowl, {"n_parts": "0", "n_track": "0"})


def test_a_deck_of_ones_own_without_n_parts_is_not_refused_for_no_inlet(tmp_path):
    # parts put on its track some other way (no n_parts declared): inlet_rate=0 is no refusal
    own = own_deck(tmp_path, part_size=3e-4, track_width=2e-3, inlet_rate=10)
    assert resolve(own, {"inlet_rate": "0"})["inlet_rate"] == "0"
    # with n_parts declared and 0, no part would ever come
    both = own_deck(tmp_path, part_size=3e-4, track_width=2e-3, inlet_rate=10, n_parts=0)
    with pytest.raises(ParameterError, match=r"^n_parts=0 and inlet_rate=0: no part would ever be fed"):
        resolve(both, {"inlet_rate": "0"})


def test_a_pile_on_a_deck_without_a_fill_place_spreads_over_the_whole_track(tmp_path):
    # no fill_from/fill_to declared: the pre-fill lies along the whole track (0 .. 1 of it).
    # 300 um spheres, 2 mm x 20 mm track, packed at 0.6: n parts pile n V / (0.6 L W) high
    d, W, L, wall = 3e-4, 2e-3, 0.02, 1e-3
    per_part = math.pi / 6 * d ** 3 / (0.6 * L * W)        # m of pile per part
    n_high = math.ceil(1.5 * wall / per_part)               # 1.5 x the wall: refused
    n_low = math.floor(0.9 * wall / per_part)               # 0.9 x the wall: fits
    own = own_deck(tmp_path, part_size=d, track_width=W, track_length=L, wall_height=wall, n_parts=10)
    assert resolve(own, {"n_parts": str(n_low)})["n_parts"] == str(n_low)
    with pytest.raises(ParameterError, match=rf"^n_parts={n_high} settle 0\.0015\d* m high, above the walls"):
        resolve(own, {"n_parts": str(n_high)})
