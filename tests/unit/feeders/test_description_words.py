"""A description's refusals and warnings speak its words: every value by the name the user
gave it (the dotted name of the file, or the name given to -p), in one line, and never a
traceback, for every number of every shipped description set to values a slip gives."""

import re
import warnings

import pytest

from helpers import REPO
from vibrofeed.decks import Deck
from vibrofeed.errors import ParameterError
from vibrofeed.parameters import resolve

# (cad_curved.toml's STL is drawn by feeders/cad/make_curved_track.py, not kept in git)
SHIPPED = [p for p in sorted((REPO / "feeders").glob("*.toml")) if p.name != "cad_curved.toml"]
SLIPS = ("-1", "0", "1e9", "1e-12")


def heard(deck, given):
    """What resolve says of ``given``: its refusal, or its warnings."""
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            resolve(deck, given)
    except ParameterError as exc:
        return [str(exc)]
    return [str(w.message) for w in caught]


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_every_slip_is_named_as_the_user_gave_it(path):
    deck = Deck.find(path)
    # a deck's own name spelt as code (s2_amp_t, part_size) where the description has a dotted
    # one; the prose's names in general ("the two drives' amp_n") are not a value's
    spelt = sorted({own for alias, own in deck.aliases.items() if alias != own and re.search(r"[_\d]", own)},
                   key=len, reverse=True)
    leak = re.compile(r"(?<![\w.'])(?<!' )(" + "|".join(map(re.escape, spelt)) + r")(?![\w.])")
    spoken = 0
    for alias in deck.aliases:
        for value in SLIPS:
            for message in heard(deck, {alias: value}):
                assert "\n" not in message, (alias, value, message)
                assert not leak.search(message), (alias, value, message)
                spoken += 1
    assert spoken > len(deck.aliases)  # (most slips are refused or warned of)


def test_a_refusal_names_values_in_its_lists_and_advice_as_given(tmp_path):
    orient = Deck.find(REPO / "feeders" / "orient_line.toml")
    # the values to change, cited after "lower", in a list and joined by "or"
    (message,) = heard(orient, {"element.1.drive.freq": "1e9"})
    assert "lower element.1.drive.amp_n or element.1.drive.freq;" in message
    assert message.startswith("orient_line.toml: element.1.drive.amp_n=6e-05 m at "
                              "element.1.drive.freq=1e+09 Hz")
    (message,) = heard(orient, {"element.1.drive.freq": "50", "element.1.drive.amp_t": "4.4e-4",
                                "element.1.drive.amp_n": "1e-4", "element.2.step": "3e-4"})
    assert "(element.1.drive.amp_t, element.2.drive.amp_t), more than half a part" in message
    # the name in general stays as the prose has it
    (message,) = heard(orient, {"element.2.step": "1e-12"})
    assert "the two drives' amp_n and phases" in message
    # a -p name is the user's: no file name before it
    (message,) = heard(orient, {"s2_step": "1e-12"})
    assert message.startswith("s2_step=1e-12 m: the joint")


@pytest.mark.parametrize("name, words", [
    ("element.2.kind", "parameter element.2.kind is the element's kind (linear), not a number -p varies: "
                       "change it in orient_line.toml"),
    ("element.9.length", "unknown parameter element.9.length: orient_line.toml has elements 1 to 2"),
    ("element.2.drive.ampt", "unknown parameter element.2.drive.ampt for orient_line.toml (did you "
                             "mean element.2.drive.amp_t?); valid parameters: element.1.drive.freq, "),
    ("freqq", "unknown parameter freqq for orient_line.toml (did you mean freq?)"),
])
def test_a_name_the_description_does_not_have_is_refused_in_its_words(name, words):
    (message,) = heard(Deck.find(REPO / "feeders" / "orient_line.toml"), {name: "1"})
    assert message.startswith(words)
    # the list of valid names is the description's own
    assert "s2_" not in message and "part_size" not in message


def test_a_box_too_thin_to_clump_is_one_line():
    """A film of a box would be a clump of millions of spheres (numpy once ran out of memory
    building it): refused with the count, which a 1e-12 m thickness makes 4e18 by hand (spheres
    of d = T/2 at most s d apart, s = clump_spacing = 1 here: (L - d)/d + 1 = 2e9 rows along,
    1e9 across, two layers, none inside)."""
    (message,) = heard(Deck.find(REPO / "feeders" / "orient_line.toml"), {"parts.thickness": "1e-12"})
    assert message.startswith("orient_line.toml: a box of 0.001 x 0.0005 x 1e-12 m is a clump of 4e+18 "
                              "spheres of parts.thickness/2 (at most 10000")
