"""Run parameters are checked against physical limits before anything starts."""

import pytest

from helpers import DECKS
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
    assert "unknown parameter 'fre'" in text and "did you mean 'freq'" in text
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
