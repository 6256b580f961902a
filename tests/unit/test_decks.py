"""Deck files: tunables with units, commands with their lines, lookup by name."""

import pytest

from vibrofeed.decks import Deck, DeckError, available, split_commands, strip_comment

from helpers import DECKS

VOCABULARY = ["freq", "amp_t", "amp_n", "phase", "incline", "radius", "density", "youngs",
              "poisson", "restitution", "mu", "t_end", "output_dt", "dt", "seed"]


def test_every_deck_declares_the_shared_vocabulary_with_units():
    for name in available():
        deck = Deck.find(name)
        for var in VOCABULARY:
            assert var in deck.variables, f"{name} lacks {var}"
            assert deck.variables[var].unit, f"{name}: {var} has no [unit]"
            assert deck.variables[var].description, f"{name}: {var} has no description"


def test_every_deck_starts_with_a_header_and_says_how_to_run():
    for name in available():
        deck = Deck.find(name)
        assert deck.header, name
        assert "liggghts -in decks/" in deck.header, f"{name}: header must show how to run by hand"
        assert "Units" in deck.header, f"{name}: header must state units"


def test_single_part_variables_parsed(tmp_path):
    deck = Deck(DECKS / "single_part.liggghts")
    freq = deck.variables["freq"]
    assert (freq.unit, freq.default) == ("Hz", "50")
    assert "vibration frequency" in freq.description
    assert deck.variables["rolling"].default == "0"
    for name in ("n_steps", "dt_used", "t_contact", "ss_x0"):
        assert name in deck.constants
    for name in ("sin_x", "tx", "ss_x", "cp_vx"):  # follow `time`, directly or not
        assert name in deck.formulas and name not in deck.constants


def test_constants_follow_references(tmp_path):
    p = tmp_path / "c.liggghts"
    p.write_text("variable a index 1 # [m] a\n"
                 "variable b equal 2*v_a\n"
                 "variable c equal v_b+time\n"
                 "variable d equal v_c*2\n"
                 "variable e equal v_b*3  # time in a comment is not a reference\n")
    assert Deck(p).constants == ["b", "e"]


def test_split_commands_joins_continuations_and_strips_comments():
    text = 'a 1 # c\n\n# only comment\nb 2 &\n   3 &\n 4\nprint "x # not a comment"\n'
    cmds = split_commands(text)
    assert [(c.line, c.text) for c in cmds] == [(1, "a 1"), (4, "b 2 3 4"),
                                                (7, 'print "x # not a comment"')]
    assert strip_comment("x 'a#b' # c") == "x 'a#b' "


def test_find_by_name_and_by_path(tmp_path):
    assert Deck.find("single_part").path == (DECKS / "single_part.liggghts").resolve()
    assert Deck.find(str(DECKS / "single_part.liggghts")).name == "single_part"
    with pytest.raises(DeckError, match="single_part"):  # lists what exists
        Deck.find("no_such_deck")
    with pytest.raises(DeckError):
        Deck.find(tmp_path / "missing.liggghts")


def test_deck_without_tunables_is_refused(tmp_path):
    p = tmp_path / "x.liggghts"
    p.write_text("units si\n")
    with pytest.raises(DeckError, match="declares no tunables"):
        Deck(p)
