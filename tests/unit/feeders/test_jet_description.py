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
    assert "variable s2_jet_on atom 0" in motion
    assert "fix s2_jet s2_jet_parts addforce 0 v_s2_jet_fy" in motion
    assert "group s2_jet_parts subtract all all" in motion  # ideal: empty until it fires
    assert "inactive in a run by hand" in motion


@pytest.mark.parametrize("change, words", [
    ('keep = "up, lengthwise, lead +x"', "element.2.jet.keep: no state named 'sideways'"),
    ('mode = "ideal"', 'element.2.jet.mode = "gentle" must be "region" or "ideal"'),
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


FILL = {"fill_to": "0.5", "n_parts": "20"}  # a fill that fits section 1


def test_a_jets_throw_is_bounded_by_its_block_and_duration(tmp_path):
    """Blowing straight across (angle 0, no cross tilt) the bound is hand-computable: the whole
    force for the duration or across the block (the far wall to two part sizes beyond the near
    one), then a fall from the block's top to a part below its bottom."""
    values = resolve(Deck.find(described(tmp_path, JET.replace("mode = ", "angle = 0\nmode = "))), FILL)
    feeder = Feeder.from_values(values)
    s2, part = feeder.elements[1], feeder.part
    rho, g = float(values["density"]), 9.81
    mass = rho * 3e-4 ** 2 * 1.5e-4  # a chip: size^2 x thickness
    across = 4.5e-4 + 2 * 3e-4  # the far wall to the block's side, two part sizes past the wall
    height = 6e-4 + 2 * 2e-5 + 2 * 3e-4  # the walls, the normal stroke both ways, a part each way
    push = 2e-6 / mass
    speed = min(push * 0.02, (2 * push * across) ** 0.5)
    fall = (2 * g * (height + 3e-4)) ** 0.5 / g
    got = s2.jet_throw(part, mass, g)
    assert got[0] == pytest.approx(speed, rel=1e-12)
    assert got[1] == pytest.approx(2 * 3e-4 + speed * fall, rel=1e-12)


def test_a_jet_that_would_throw_parts_past_what_check_accepts_is_warned_of(tmp_path):
    from vibrofeed.errors import ParameterWarning

    # a chip of 3.1e-8 kg (3.1e-7 N); the block 1.05 mm across: 65 weights throw it 0.16 m (check: 0.028 m)
    path = described(tmp_path, JET.replace("force = 2e-6", "force = 2e-5"))
    weights = 2e-5 / (2330 * 3e-4 ** 2 * 1.5e-4 * 9.81)
    said = rf"^jet.toml: element.2.jet.force=2e-05 N \({weights:.3g} times the part's weight\) may throw"
    with pytest.warns(ParameterWarning, match=said):
        resolve(Deck.find(path), FILL)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", ParameterWarning)  # three weights blow it off, no farther
        resolve(Deck.find(path), {**FILL, "element.2.jet.force": "9.5e-7"})


def test_a_jet_mode_given_to_p_is_refused_in_the_users_words(tmp_path):
    path = described(tmp_path, JET)
    with pytest.raises(ParameterError, match=r"^s2_jet_mode=Gentle must be region or ideal$"):
        resolve(Deck.find(path), {**FILL, "s2_jet_mode": "Gentle"})
