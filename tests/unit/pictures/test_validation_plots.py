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


def test_a_reference_case_is_drawn_one_panel_per_compared_quantity(tmp_path):
    """plot_reference takes its quantities (name -> error key, unit) and draws the ones
    the case compares (stiffness_independence's figure, which once crashed validate)."""
    from pathlib import Path

    from vibrofeed.validation.cases import find
    from vibrofeed.validation.crosscheck import REFERENCE_QUANTITIES
    from vibrofeed.validation.outcome import Run
    from vibrofeed.validation.plots import plot_reference

    case = find("stiffness_independence")
    axis = next(iter(case.sweep))
    runs = [Run(label=f"r{k}", values={axis: v}, params={}, output=Path("x.h5"))
            for k, v in enumerate(case.sweep[axis])]
    figures = {r.label: {q: 1.0 + 0.01 * k for q in REFERENCE_QUANTITIES}
               | {REFERENCE_QUANTITIES[q][0]: 0.01 for q in REFERENCE_QUANTITIES}
               for k, r in enumerate(runs)}
    path = plot_reference(case, runs, figures, runs[1], REFERENCE_QUANTITIES, tmp_path / "ref.png")
    assert path.stat().st_size > 10_000
