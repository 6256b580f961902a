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
    values = {k: float(v) for k, v in resolve(DECK, given).items() if k != "deck_dir" and
              k not in ("mesh_dir", "dump_file", "outlet_file")}
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
