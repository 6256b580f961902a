"""Run parameters are checked against physical limits before anything starts."""

import math

import pytest

from helpers import DECKS, vibrofeed
from vibrofeed.decks import Deck
from vibrofeed.parameters import ParameterError, parse_assignments, resolve


@pytest.fixture(scope="module")
def deck():
    return Deck(DECKS / "single_part.liggghts")


def test_defaults_are_the_deck_defaults(deck):
    values = resolve(deck, {})
    assert values["freq"] == deck.variables["freq"].default
    assert set(values) == set(deck.tunables)
    assert "driver" not in values  # reserved, set by vibrofeed


def test_override_replaces_default(deck):
    assert resolve(deck, {"freq": "60"})["freq"] == "60"


@pytest.mark.parametrize("name, value, fragment", [
    ("freq", "0", "must be > 0"),
    ("freq", "-3", "must be > 0"),
    ("radius", "0", "must be > 0"),
    ("amp_n", "-1e-4", "must be in [0, 0.01]"),
    ("amp_t", "-1e-4", "must be in [0, 0.01]"),
    ("restitution", "0.05", "(0.05, 1]"),
    ("restitution", "1.2", "(0.05, 1]"),
    ("poisson", "0.6", "(-1, 0.5]"),
    ("youngs", "1e6", "5e+06"),
    ("incline", "91", "[-90, 90]"),
    ("rolling", "2", "one of 0, 1"),
    ("seed", "1.5", "integer"),
    ("mu", "-0.1", ">= 0"),
    ("t_end", "0", "> 0"),
    ("freq", "abc", "not a number"),
    ("freq", "nan", "not finite"),
])
def test_non_physical_values_are_refused(deck, name, value, fragment):
    with pytest.raises(ParameterError) as err:
        resolve(deck, {name: value})
    assert name in str(err.value) and fragment in str(err.value)


@pytest.mark.parametrize("name, value", [
    ("restitution", "1"), ("restitution", "0.06"), ("poisson", "0.5"), ("amp_n", "0"),
    ("incline", "-30"), ("rolling", "1"), ("phase", "-270"), ("mu", "0"),
])
def test_limit_values_that_are_physical_pass(deck, name, value):
    assert resolve(deck, {name: value})[name] == value


def test_unknown_parameter_lists_valid_ones_and_suggests(deck):
    with pytest.raises(ParameterError) as err:
        resolve(deck, {"fre": "50"})
    text = str(err.value)
    assert "unknown parameter fre " in text and "did you mean freq?" in text
    for name in deck.tunables:
        assert name in text


def test_reserved_parameter_is_refused(deck):
    with pytest.raises(ParameterError, match="set by vibrofeed"):
        resolve(deck, {"driver": "0"})


def test_output_interval_shorter_than_timestep(deck):
    with pytest.raises(ParameterError, match="shorter than the timestep"):
        resolve(deck, {"dt": "1e-4", "output_dt": "1e-5"})


def test_output_interval_longer_than_run(deck):
    with pytest.raises(ParameterError, match="longer than the run"):
        resolve(deck, {"t_end": "0.01", "output_dt": "0.02"})


def test_too_many_frames_is_refused(deck):
    # 0.01 s at 1 ns would be 1e7 frames and, with the automatic timestep, 1e7 steps
    with pytest.raises(ParameterError, match="would write 1e\\+07 frames"):
        resolve(deck, {"t_end": "0.01", "output_dt": "1e-9"})
    resolve(deck, {"t_end": "0.01", "output_dt": "1e-8"})  # 1e6 frames: allowed


def test_parse_assignments():
    assert parse_assignments(["a=1", " b = x "]) == {"a": "1", "b": "x"}
    for bad in (["a"], ["=1"], ["a="]):
        with pytest.raises(ParameterError, match="name=value"):
            parse_assignments(bad)


# -- one volume by shape, one rule for section 1 and section 2 --------------------------------
@pytest.mark.parametrize("shape, size, thickness, volume", [
    (0, 3e-4, None, 4 / 3 * 3.141592653589793 * 1.5e-4 ** 3),   # a sphere of radius 150 um
    (1, 5e-4, 1e-4, 5e-4 * 5e-4 * 1e-4),                       # a chip: its box
    (2, 5e-4, 1e-4, 3.141592653589793 * 2.5e-4 ** 2 * 1e-4),    # a disc: its cylinder
])
def test_part_volume_by_shape_and_the_mass_the_models_weigh(shape, size, thickness, volume):
    from vibrofeed.models.deck import mass
    from vibrofeed.parameters import part_volume

    assert part_volume(shape, size, thickness) == pytest.approx(volume, rel=1e-12, abs=0)  # m^3, from 1e-11
    p = {"shape": shape, "part_size": size, "part_thickness": thickness or size, "density": 2330.0}
    assert part_volume(shape, size, thickness) * 2330.0 == pytest.approx(mass(p), rel=1e-12, abs=0)
    with pytest.raises(ParameterError, match="shape=3"):
        part_volume(3, size, thickness)


def test_the_pile_check_takes_the_parts_volume():
    """n_parts settle into n V / (0.6 fill length width): just under the walls passes, just
    over is refused, for chips (the volume their box, not a sphere's)."""
    from vibrofeed.decks import Deck

    bulk = Deck.find("bulk_feeder")
    size, thickness, width, length, walls = 4e-4, 1e-4, 2e-3, 0.02, 1e-3
    fill = 0.9  # fill_to - fill_from
    per_part = size * size * thickness / (0.6 * fill * length * width)  # m of pile per part
    fits = int(walls / per_part)
    given = {"shape": "chip", "part_size": repr(size), "part_thickness": repr(thickness),
             "track_width": repr(width), "track_length": repr(length), "wall_height": repr(walls),
             "fill_from": "0", "fill_to": repr(fill), "gate_width": "0"}
    resolve(bulk, {**given, "n_parts": str(fits)})
    with pytest.raises(ParameterError, match=f"n_parts={fits + 1} settle"):
        resolve(bulk, {**given, "n_parts": str(fits + 1)})


@pytest.mark.parametrize("twin, value", [
    ("amp_t", "0.02"), ("amp_n", "-1e-6"), ("freq", "0"), ("track_length", "0"), ("track_width", "-1"),
    ("wall_height", "0"), ("cross_tilt", "46"),
])
def test_section_2_takes_the_limits_of_its_section_1_twin(twin, value):
    from vibrofeed.parameters import RULES

    twin_2 = "s2_" + ({"track_length": "length", "track_width": "width"}.get(twin, twin))
    assert RULES[twin_2](float(value)) == RULES[twin](float(value)) is not None


def _warnings_of(deck, given):
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        resolve(deck, given)
    return caught


def test_an_idle_parameter_left_at_its_default_is_not_worth_a_word(deck):
    # dt_unchecked has no effect with the automatic dt (dt=0, the default): said only when moved
    assert _warnings_of(deck, {"dt_unchecked": "0"}) == []
    moved = _warnings_of(deck, {"dt_unchecked": "1"})
    assert [str(w.message) for w in moved] == [
        "parameter dt_unchecked has no effect: it allows a fixed dt beyond the contact's limits: "
        "dt=0 is automatic"]


def test_warnings_point_at_the_caller_of_resolve(deck):
    import warnings

    # both the plausibility advice and the insisted-on contact step name the line that called
    # resolve (here, not a helper's or pytest's frame): resolve is called right in this body
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        resolve(deck, {"dt_unchecked": "1"})
        resolve(deck, {"dt": "1e-4", "dt_unchecked": "1"})
    assert "run as dt_unchecked=1 asks" in str(caught[-1].message)
    assert [w.filename for w in caught] == [__file__] * 2


# -- a modulus in GPa, and the slip behind a refused relation ---------------------------------
YOUNGS_REFUSED = ("parameter youngs={} Pa must be in (5e+06, inf) (LIGGGHTS' Hertz model needs "
                  "youngsModulus > 5e6 Pa)")
GPA_HINT = "; a modulus in GPa? (moduli are in Pa: silicon 1.3e11)"


@pytest.mark.parametrize("value, hinted", [
    ("0.8", True), ("1", True), ("130", True), ("9999.5", True),  # under 1e4 Pa: a modulus in GPa
    ("1e4", False), ("0", False), ("-0.5", False),  # the hint's bounds are open: 0 < x < 1e4
    ("1e5", False),  # refused, but 1e5 GPa is no material either: no hint
])
def test_a_youngs_modulus_in_gpa_is_named_as_a_likely_slip(deck, value, hinted):
    with pytest.raises(ParameterError) as err:
        resolve(deck, {"youngs": value})
    assert str(err.value) == YOUNGS_REFUSED.format(value) + (GPA_HINT if hinted else "")


def test_a_refused_relation_names_the_slip_of_a_value_it_names(deck):
    # freq typed in rad/s (2 pi x 100 Hz): 1 mm at 628.3 Hz moves the surface at
    # 2 pi 628.3 1e-3 = 4 pi^2 0.1 = 3.95 m/s, past the 2 m/s limit; the refusal comes before
    # the warning would, so it names the rad/s slip of freq itself. The density in g/cm^3 is a
    # slip too, but the refusal does not name density: it stays a warning's business.
    omega = repr(2 * math.pi * 100)
    with pytest.raises(ParameterError) as err:
        resolve(deck, {"freq": omega, "amp_n": "1e-3", "amp_t": "0", "density": "2.33"})
    assert str(err.value) == (
        "amp_n=0.001 m at freq=628.319 Hz moves the surface at 3.95 m/s peak (limit 2 m/s: real "
        "feeders stay below 0.5 m/s); lower amp_n or freq; parameter freq=628.319 Hz is 2 pi x 100: "
        "an angular frequency in rad/s? (freq is in Hz)")


def test_a_modulus_beyond_any_solid_with_a_fixed_dt_is_refused_in_one_line(deck):
    # youngs has no upper limit (a rigid contact); past ~2.4e154 Pa the square of E* overflowed
    # a float and a fixed dt ended in an OverflowError instead of a refusal. The Hertz time of
    # the 0.5 mm sphere at 1e160 Pa is ~1e-70 s: any fixed dt is far beyond its tenth.
    assert resolve(deck, {"youngs": "1e160"})["youngs"] == "1e160"  # automatic dt: no limit
    with pytest.raises(ParameterError, match=r"^dt=1e-07 s is \d+% of the Rayleigh time \(limit "
                                             r"20%\) and \d+% of the Hertz time \(limit 10%\): "):
        resolve(deck, {"youngs": "1e160", "dt": "1e-7"})


# -- a value the engine would read otherwise than Python (issue 36) ----------------------------
@pytest.mark.parametrize("deck, name, text, engine", [
    ("single_part", "freq", "５０", "50.0"),          # full-width digits: LIGGGHTS reads 0
    ("single_part", "freq", "٥٠", "50.0"),            # Arabic-Indic digits
    ("single_part", "amp_n", "1_0e-5", "0.0001"),     # an underscore: C's atof stops at it
    ("single_part", "t_end", "\u20030.1", "0.1"),     # a blank Python skips (an em space)
    ("single_part", "seed", "1e2", "100"),            # an integer parameter in float notation
    ("single_part", "seed", "7.0", "7"),
    ("bulk_feeder", "n_parts", "2e1", "20"),
    ("bulk_feeder", "sections", "２", "2"),
])
def test_a_value_the_engine_would_read_otherwise_reaches_it_as_python_read_it(deck, name, text, engine):
    values = resolve(Deck.find(deck), {name: text})
    assert values[name] == engine
    assert float(values[name]) == float(text)


@pytest.mark.parametrize("name, text", [("freq", "50"), ("amp_n", "1.5e-4"), ("amp_n", "2E-05"),
                                        ("phase", "-30"), ("phase", "+.5"), ("t_end", "5."),
                                        ("seed", "12"), ("seed", "+3")])
def test_a_plain_value_reaches_the_engine_as_written(name, text):
    # (the run id of an existing result hashes it: rewriting it would make every run new)
    assert resolve(Deck.find("single_part"), {name: text})[name] == text


def test_the_run_by_hand_gets_the_value_python_read(tmp_path):
    proc = vibrofeed("prepare", "single_part", "-p", "freq=５０", "-o", tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "-var freq 50.0" in proc.stdout and "５" not in proc.stdout
