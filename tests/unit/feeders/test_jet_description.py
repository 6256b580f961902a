"""A jet in a feeder description: its keys, the deck's words and names, the generated line
file, and its slips as one line naming the key."""

import pytest

from vibrofeed.decks import Deck
from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.deck import line_files
from vibrofeed.feeders.description import read
from vibrofeed.parameters import resolve

JET = """
[parts]
shape = "chip"
size = 3e-4
thickness = 1.5e-4
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
[element.jet]
at = 0.4
keep = "up, lengthwise, lead +x"
delay = 0.01
duration = 0.02
force = 2e-6
mode = "ideal"
"""


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


def described(tmp_path, text):
    path = tmp_path / "jet.toml"
    path.write_text(text)
    return path


def test_a_jet_is_described_by_its_keys_and_the_deck_declares_its_words(tmp_path):
    path = described(tmp_path, JET)
    d = read(path)
    assert d.values["s2_jet_keep"] == "up,lengthwise,lead+x" and d.values["s2_jet_mode"] == "ideal"
    assert d.aliases["element.2.jet.force"] == "s2_jet_force"
    deck = Deck.find(path)
    assert deck.tunables["s2_jet_keep"].default == "up,lengthwise,lead+x"
    assert deck.tunables["s2_jet_force"].unit == "N"
    values = resolve(deck, {"fill_to": "0.5", "n_parts": "20"})
    feeder = Feeder.from_values(values)
    j = feeder.elements[1].jet
    assert (j.at, j.delay, j.duration, j.force, j.mode, j.keep.lead) == (0.4, 0.01, 0.02, 2e-6, "ideal", 1)
    motion = line_files(feeder)["line_motion.in"]
    assert "variable s2_jet_on atom 0" in motion and "fix s2_jet all addforce 0 v_s2_jet_fy" in motion
    assert "inactive in a run by hand" in motion


@pytest.mark.parametrize("change, words", [
    ('keep = "up, lengthwise, lead +x"', "element.2.jet.keep: no state named 'sideways'"),
    ('mode = "ideal"', "element.2.jet.mode = 'gentle' must be 'region' or 'ideal'"),
    ("force = 2e-6\n", "element 2's jet has no force"),
])
def test_a_jets_slip_is_one_line_naming_the_key(tmp_path, change, words):
    wrong = {'keep = "up, lengthwise, lead +x"': 'keep = "sideways"', 'mode = "ideal"': 'mode = "gentle"',
             "force = 2e-6\n": ""}[change]
    with pytest.raises(ParameterError) as info:
        read(described(tmp_path, JET.replace(change, wrong)))
    assert words in str(info.value) and "\n" not in str(info.value)


def test_a_jet_on_the_first_section_is_refused(tmp_path):
    text = JET.replace('gate = { width = 4.5e-4, at = 0.9 }', 'jet = { force = 1e-6 }', 1)
    with pytest.raises(ParameterError, match="a jet is built on the second section on"):
        read(described(tmp_path, text))
