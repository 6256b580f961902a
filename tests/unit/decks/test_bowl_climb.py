"""A bowl whose helix is steeper than its drive can climb: `vibrofeed run` warns before
anything runs (the single-part model's speed up the helix is not positive)."""

import warnings

import pytest

from vibrofeed.bowl import bowl_from, climb_advice, track_drive
from vibrofeed.decks import Deck
from vibrofeed.models.deck import transport
from vibrofeed.parameters import ParameterWarning, resolve

DECK = Deck.find("bowl_feeder")


def warned(given: dict) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        resolve(DECK, given)
    return [str(w.message) for w in caught if issubclass(w.category, ParameterWarning)]


@pytest.mark.parametrize("helix, climbs", [(3.0, True), (6.0, True), (10.0, False), (15.0, False)])
def test_the_warning_follows_the_models_speed_up_the_helix(helix, climbs):
    given = {"shape": "1", "helix_angle": repr(helix)}
    values = {k: float(v) for k, v in resolve(DECK, given).items()
              if k in DECK.variables and DECK.variables[k].is_numeric}
    d = track_drive(values["amp_t"], values["amp_n"], values["phase"], values["freq"], helix,
                    bowl_from(values).r_mid)
    speed = transport({**values, "amp_t": d.amp_t, "amp_n": d.amp_n, "phase": d.phase,
                       "incline": d.incline}).velocity
    assert (speed > 0) is climbs  # the model itself: 8 deg is about this drive's limit
    lines = [w for w in warned(given) if "do not climb" in w]
    if climbs:
        assert lines == []
    else:
        assert len(lines) == 1 and lines[0].startswith(f"helix_angle={helix:g} deg")
        assert f"({speed * 1e3:.3g} mm/s" in lines[0]


def test_no_model_for_a_deck_that_is_not_a_bowl_or_lacks_a_value():
    assert climb_advice({"freq": 100.0, "amp_t": 5e-5}) == []
    assert climb_advice({"bowl_diameter": 0.02, "track_width": 1.2e-3}) == []


def test_a_bowl_that_does_not_move_its_parts_is_warned_of_too():
    """No vibration: the model's speed is exactly 0 (the part rests), not positive: the parts
    do not climb, and the warning says so (a part that stays is not fed)."""
    p = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "freq": 100.0, "amp_t": 0.0,
         "amp_n": 0.0, "phase": 0.0, "mu": 0.5, "restitution": 0.3, "part_size": 3e-4, "turns": 1.5,
         "wall_height": 1e-3}
    (text,) = climb_advice(p)
    assert "do not climb" in text and "(0 mm/s up its centre line)" in text


@pytest.mark.parametrize("change", [{"mu": None}, {"restitution": None}, {"waveform": 7.0}])
def test_a_bowl_the_model_cannot_judge_gets_no_warning(change):
    """A value the model needs left unset (None: the model's KeyError) or one it does not know
    (a waveform past 3: its ValueError): no judgement, so no warning, and no error either; the
    same bowl with the values set is judged (the steep helix does not climb)."""
    p = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 15.0, "freq": 100.0, "amp_t": 5e-5,
         "amp_n": 3e-5, "phase": -20.0, "mu": 0.5, "restitution": 0.3, "part_size": 3e-4, "turns": 1.5,
         "wall_height": 1e-3}
    assert len(climb_advice(p)) == 1
    assert climb_advice({**p, **change}) == []
