"""What "correctly oriented" means is said once, for the part (the parameter ``correct``,
``[parts] correct`` of a description): resolved and checked as a parameter, the part's, and
every air jet's without a keep of its own."""

import pytest

from vibrofeed.decks import Deck
from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.description import read
from vibrofeed.orientation import CORRECT, Correct, parse_correct, run_correct
from vibrofeed.parameters import checked_value, resolve

LINE = """
[parts]
shape = "chip"
size = 3e-4
thickness = 1.5e-4
correct = "up|down, lead +x"
[[element]]
kind = "linear"
length = 0.004
width = 1.2e-3
gate = { width = 4.5e-4, at = 0.9 }
[[element]]
kind = "linear"
length = 0.003
width = 4.5e-4
wall_height = 6e-4
step = 5e-5
drive = { freq = 100, amp_t = 6e-5, amp_n = 2e-5, phase = -30 }
jet = { force = 2e-6, at = 0.4 }
"""
RUN = {"fill_to": "0.5", "n_parts": "20"}
BULK = Deck.find("bulk_feeder")


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


def described(tmp_path, text=LINE):
    path = tmp_path / "line.toml"
    path.write_text(text)
    return path


def one_line(info, *words):
    text = str(info.value)
    assert "\n" not in text and all(w in text for w in words), text


def test_the_descriptions_correct_is_the_parts_and_its_jet_keeps_it(tmp_path):
    path = described(tmp_path)
    assert read(path).values["correct"] == "up|down,lengthwise,lead+x"
    deck = Deck.find(path)
    assert deck.tunables["correct"].default == "up|down,lengthwise,lead+x"
    assert deck.tunables["s2_jet_keep"].default == "correct"   # the jet names no state of its own
    values = resolve(deck, RUN)
    assert values["correct"] == "up|down,lengthwise,lead+x"    # recorded as every parameter is
    feeder = Feeder.from_values(values)
    said = parse_correct("up|down, lead +x")
    assert feeder.part.correct == said
    jet = feeder.elements[1].jet
    assert jet.keep == said and jet.keeps_correct


def test_a_run_overrides_it_like_any_parameter_and_an_explicit_keep_still_wins(tmp_path):
    deck = Deck.find(described(tmp_path))
    values = resolve(deck, {**RUN, "parts.correct": "side, any-direction"})
    assert values["correct"] == "side,any-direction"          # the deck's word: no blank
    feeder = Feeder.from_values(values)
    assert feeder.elements[1].jet.keep == Correct(states=("side",), lengthwise=False)
    values = resolve(deck, {**RUN, "s2_jet_keep": "up, any-direction"})
    jet = Feeder.from_values(values).elements[1].jet
    assert jet.keep == Correct(states=("up",), lengthwise=False) and not jet.keeps_correct
    assert Feeder.from_values(values).part.correct == parse_correct("up|down, lead +x")
    kept = read(described(tmp_path, LINE.replace("at = 0.4 }", 'at = 0.4, keep = "down" }')))
    assert kept.values["s2_jet_keep"] == "down,lengthwise"


def test_the_decks_default_is_up_lengthwise_and_a_result_without_correct_reads_so():
    assert BULK.tunables["correct"].default == CORRECT == "up,lengthwise"
    assert Deck.find("bowl_feeder").tunables["correct"].default == CORRECT
    assert resolve(BULK, {"shape": "chip"})["correct"] == CORRECT
    assert run_correct({}) == run_correct({"correct": CORRECT}) == Correct()


def test_a_state_that_does_not_exist_is_one_line_naming_the_parameter(tmp_path):
    with pytest.raises(ParameterError) as info:
        resolve(BULK, {"shape": "chip", "correct": "upside"})
    one_line(info, "correct: no state named 'upside'")
    with pytest.raises(ParameterError) as info:
        checked_value(BULK, "correct", "up, sideways")           # a study's [fixed] value
    one_line(info, "correct: 'sideways' is not a state condition")
    with pytest.raises(ParameterError) as info:
        resolve(BULK, {"shape": "chip", "correct": "correct"})    # (a jet's word, not a state)
    one_line(info, "correct: no state named 'correct'")
    with pytest.raises(ParameterError) as info:
        read(described(tmp_path, LINE.replace('"up|down, lead +x"', '"up|upside"')))
    one_line(info, "line.toml: parts.correct: no state named 'upside'")
    with pytest.raises(ParameterError) as info:
        read(described(tmp_path, LINE.replace('"up|down, lead +x"', "1")))
    one_line(info, "parts.correct = 1 must be text")


def test_spheres_refuse_a_correct_given_but_run_at_the_default():
    with pytest.raises(ParameterError) as info:
        resolve(BULK, {"correct": "up"})                           # shape 0: spheres
    one_line(info, "parameter correct=up: spheres (shape 0) have no orientation")
    assert resolve(BULK, {})["correct"] == CORRECT                 # unsaid: no refusal


def test_a_sphere_description_that_says_correct_is_refused(tmp_path):
    text = LINE.replace('shape = "chip"\n', 'shape = "sphere"\n').replace("thickness = 1.5e-4\n", "")
    with pytest.raises(ParameterError) as info:
        read(described(tmp_path, text.replace("jet = { force = 2e-6, at = 0.4 }\n", "")))
    one_line(info, "parts.correct: spheres have no orientation")


def test_a_jet_keeping_a_correct_of_every_state_names_correct(tmp_path):
    deck = Deck.find(described(tmp_path))
    with pytest.raises(ParameterError) as info:
        resolve(deck, {**RUN, "correct": "up|down|side|end, any-direction"})
    one_line(info, 'correct="up|down|side|end" counts every state correct', "element.2.jet.keep")


def test_correct_in_words_reads_back_as_itself():
    # (a deck holds the words: "up, any-direction" once came back as "up", i.e. lengthwise)
    for text in ("up", "up, any-direction", "down|side, lead -x", "end", "up|end",
                 "side, any-direction, lead +x"):
        c = parse_correct(text)
        assert parse_correct(str(c)) == c, text


def test_values_resolved_once_resolve_again_for_spheres():
    """A validation case's runs resolve the values the case resolved: the deck's default correct
    is then among them, for spheres too, and is no choice to refuse."""
    from helpers import DECKS
    from vibrofeed.decks import Deck
    from vibrofeed.parameters import resolve

    deck = Deck(DECKS / "bulk_feeder.liggghts")
    once = resolve(deck, {})
    assert once["shape"] == "0" and resolve(deck, once) == once
