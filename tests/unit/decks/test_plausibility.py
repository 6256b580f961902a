"""Legal but senseless values (issue 19): unit slips are named, impossible values refused,
options that the chosen setting ignores are pointed out -- one rule per test row."""

from __future__ import annotations

import warnings

import pytest

from helpers import vibrofeed
from vibrofeed.decks import Deck
from vibrofeed.parameters import ParameterError, ParameterWarning, resolve

SINGLE, BULK = Deck.find("single_part"), Deck.find("bulk_feeder")


def said(deck, given) -> list[str]:
    """The warnings resolve issues for ``given``."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        resolve(deck, given)
    return [str(w.message) for w in caught if issubclass(w.category, ParameterWarning)]


@pytest.mark.parametrize("deck, given, words", [
    (SINGLE, {"density": "2.33"}, "density=2.33 kg/m³ is lighter than any solid: a density in g/cm³?"),
    (BULK, {"density": "50000"}, "density=50000 kg/m³ is denser than any solid"),
    (SINGLE, {"radius": "0.5"}, "radius=0.5 m is 500 mm: a length in mm or µm?"),
    (SINGLE, {"radius": "5e-7"}, "radius=5e-07 m is 500 nm: smaller than a micro-part"),
    (BULK, {"part_size": "0.02", "track_width": "0.05", "wall_height": "0.05", "n_parts": "1"},
     "part_size=0.02 m is 20 mm"),
    (BULK, {"track_length": "20"}, "track_length=20 m is 20 metres: a length in mm?"),
    (SINGLE, {"freq": "314.159"}, "freq=314.159 Hz is 2 pi x 50: an angular frequency in rad/s?"),
    (SINGLE, {"freq": "2e4", "amp_t": "1e-6", "amp_n": "1e-6"}, "freq=20000 Hz is beyond vibratory feeders"),
    (SINGLE, {"phase": "1.5708"}, "phase=1.5708 deg is 0.5 pi: an angle in radians?"),
    (SINGLE, {"incline": "0.0872665"}, "incline=0.0872665 deg is 0.02778 pi: an angle in radians?"),
    (SINGLE, {"mu": "5"}, "mu=5 exceeds the friction of solids"),
    (BULK, {"surface_energy": "50"}, "surface_energy=50 J/m² exceeds the surface energies of solids"),
    (SINGLE, {"duty": "0.5"}, "duty has no effect: it applies to waveforms 2 and 3"),
    (SINGLE, {"phase": "30", "amp_t": "0"}, "phase has no effect"),
    (BULK, {"part_thickness": "1e-4"}, "part_thickness has no effect: it applies to chips and discs"),
    (BULK, {"gate_at": "0.5"}, "gate_at has no effect: it places the gate: gate_width=0 has none"),
    (BULK, {"fill_to": "0.8", "n_parts": "0", "inlet_rate": "100"}, "fill_to has no effect"),
    (SINGLE, {"roughness": "1e-8"}, "roughness has no effect"),
    (SINGLE, {"face_radius": "1e-4"}, "face_radius has no effect"),
    (SINGLE, {"dt_unchecked": "1"}, "dt_unchecked has no effect"),
])
def test_an_implausible_value_is_named_with_its_likely_slip(deck, given, words):
    lines = said(deck, given)
    assert len(lines) == 1 and words in lines[0], lines


@pytest.mark.parametrize("deck, given", [
    (SINGLE, {"density": "2330", "freq": "50", "phase": "90", "radius": "5e-4"}),
    (SINGLE, {"duty": "0.5", "waveform": "2"}),            # the duty of a stick-slip motion
    (BULK, {"part_thickness": "1e-4", "shape": "chip"}),   # a chip's thickness
    (BULK, {"gate_at": "0.6", "gate_width": "1e-3", "fill_to": "0.5"}),
    (SINGLE, {"roughness": "1e-8", "hamaker": "1e-19"}),
    (SINGLE, {"duty": "0.7"}),  # the default, as callers that pass every value give it
    (SINGLE, {"freq": "62.5"}), (SINGLE, {"phase": "22.5"}),
])
def test_plausible_values_and_options_in_effect_say_nothing(deck, given):
    assert said(deck, given) == []


@pytest.mark.parametrize("deck, given, words", [
    (SINGLE, {"density": "1e30"}, r"density=1e30 kg/m\^3 must be <= 100000 .no material is denser"),
    (SINGLE, {"radius": "2"}, "radius=2 m must be <= 1 .a metre is no micro-part"),
    (SINGLE, {"youngs": "130"}, "a modulus in GPa?"),
    (BULK, {"youngs_track": "70"}, "a modulus in GPa?"),
])
def test_an_impossible_value_is_refused(deck, given, words):
    with pytest.raises(ParameterError, match=words.replace("?", r"\?")):
        resolve(deck, given)


def test_the_command_line_prints_a_warning_as_one_line(tmp_path):
    proc = vibrofeed("prepare", "single_part", "-p", "density=2.33", "-o", tmp_path)
    assert proc.returncode == 0
    assert proc.stderr == ("vibrofeed: warning: parameter density=2.33 kg/m³ is lighter than any solid: "
                           "a density in g/cm³? (silicon: 2330 kg/m³, not 2.33)\n")
