"""The validation figures' axes carry units and their headings name the case."""

from types import SimpleNamespace

from vibrofeed.decks import Deck
from vibrofeed.validation.plots import axis_label, heading


def test_swept_axes_take_the_decks_units():
    case = SimpleNamespace(deck="bulk_feeder", name="dilute_limit", title="Dilute limit")
    deck = Deck.find("bulk_feeder").variables
    assert axis_label(case, "freq") == f"freq [{deck['freq'].unit}]" == "freq [Hz]"
    assert axis_label(case, "amp_n") == "amp_n [m]"
    assert axis_label(case, "gamma").startswith("Gamma_n") and axis_label(case, "gamma").endswith("[-]")
    assert axis_label(case, "no_such_parameter") == "no_such_parameter"   # no unit invented
    assert axis_label(SimpleNamespace(deck="no_such_deck"), "freq") == "freq"
    assert heading(case) == "dilute_limit: Dilute limit"
