"""Legal but senseless values (issue 19): unit slips are named, impossible values refused,
options that the chosen setting ignores are pointed out -- one rule per test row."""

from __future__ import annotations

import warnings

import pytest

from helpers import vibrofeed
from vibrofeed.decks import Deck
from vibrofeed.parameters import ParameterError, ParameterWarning, resolve
from vibrofeed.plausibility import advice

SINGLE, BULK, BOWL = Deck.find("single_part"), Deck.find("bulk_feeder"), Deck.find("bowl_feeder")
LINE = {"sections": "2"}  # a feeder line with the deck's section 2
STEP = {"s2_step": "1.5e-4"}  # a joint for drives of two frequencies (the floors part by 0.1 mm)


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
    (BULK, {"part_thickness": "1e-4"}, "part_thickness has no effect: it applies to chips, discs and boxes"),
    (BULK, {"gate_at": "0.5"}, "gate_at has no effect: it places the gate: gate_width=0 has none"),
    (BULK, {"sections": "2", "s2_width": "1.2e-3", "track_width": "1.2e-3", "s2_gate_at": "0.5"},
     "s2_gate_at has no effect: it places the gate: s2_gate_width=0 has none"),
    (BULK, {"fill_to": "0.8", "n_parts": "0", "inlet_rate": "100"}, "fill_to has no effect"),
    (SINGLE, {"roughness": "1e-8"}, "roughness has no effect"),
    (SINGLE, {"face_radius": "1e-4"}, "face_radius has no effect"),
    (SINGLE, {"dt_unchecked": "1"}, "dt_unchecked has no effect"),
    # a neighbour skin typed in mm: wider than the part (the bulk deck's 0.3 mm default)
    (BULK, {"skin": "0.1"}, "skin=0.1 m is wider than a part (0.0003 m): every sphere within it"),
    # a width or a wall typed in mm, which a track length would allow
    (BULK, {"track_width": "2"}, "track_width=2 m is 2 metres: a length in mm?"),
    (BULK, {"wall_height": "1"}, "wall_height=1 m is 1 metres: a length in mm?"),
    # a feeder line's section 2 as its section-1 twins
    (BULK, {**LINE, **STEP, "s2_freq": "314.159"},
     "s2_freq=314.159 Hz is 2 pi x 50: an angular frequency in rad/s? (s2_freq is in Hz)"),
    (BULK, {**LINE, **STEP, "s2_freq": "2e4", "s2_amp_t": "1e-6", "s2_amp_n": "1e-6"},
     "s2_freq=20000 Hz is beyond vibratory feeders"),
    (BULK, {**LINE, "s2_phase": "1.5708"}, "s2_phase=1.5708 deg is 0.5 pi: an angle in radians?"),
    (BULK, {**LINE, "s2_cross_tilt": "0.0872665"}, "s2_cross_tilt=0.0872665 deg is 0.02778 pi"),
    (BULK, {"cross_tilt": "0.0872665"}, "cross_tilt=0.0872665 deg is 0.02778 pi"),
    (BULK, {**LINE, "s2_length": "10"}, "s2_length=10 m is 10 metres: a length in mm?"),
    (BULK, {**LINE, "s2_width": "2"}, "s2_width=2 m is 2 metres: a length in mm?"),
    (BULK, {**LINE, "s2_wall_height": "1"}, "s2_wall_height=1 m is 1 metres: a length in mm?"),
    (BULK, {**LINE, "s2_phase": "30", "s2_amp_t": "0"}, "s2_phase has no effect: it shifts the normal"),
    # section 2's parameters without a section 2, its tooling's without the tool
    (BULK, {"s2_freq": "150"}, "s2_freq has no effect: it shapes a feeder line's section 2: sections=1 "
                               "has none"),
    (BULK, {"s2_wiper_at": "0.3"}, "s2_wiper_at has no effect: it shapes a feeder line's section 2"),
    (BULK, {**LINE, "s2_wiper_at": "0.3"}, "s2_wiper_at has no effect: it places the wiper: "
                                           "s2_wiper_height=0 has none"),
    (BULK, {**LINE, "s2_wiper_skew": "60"}, "s2_wiper_skew has no effect: it turns the wiper: "
                                             "s2_wiper_height=0 has none"),
    (BULK, {**LINE, "s2_drop_width": "1e-3"}, "s2_drop_width has no effect: it shapes the side drop: "
                                              "s2_drop_to <= s2_drop_from has none"),
    (BULK, {**LINE, "s2_drop_from": "0.2"}, "s2_drop_from has no effect: it shapes the side drop"),
    # each limit just past it (its value at the limit says nothing: see below)
    (SINGLE, {"density": "99.5"}, "density=99.5 kg/m³ is lighter than any solid"),
    (SINGLE, {"density": "25010"}, "density=25010 kg/m³ is denser than any solid"),
    (BULK, {"surface_energy": "10.01"}, "surface_energy=10.01 J/m² exceeds the surface energies of solids"),
    (SINGLE, {"mu": "2.01"}, "mu=2.01 exceeds the friction of solids"),
    # an angle of 2 pi (just below it: 6.283185 < 2 pi) is still a whole turn in radians
    (SINGLE, {"phase": "6.283185"}, "phase=6.28318 deg is 2 pi: an angle in radians?"),
    # the inlet's batches without an inlet (the deck's inlet_rate is 0)
    (BULK, {"inlet_batch": "5"}, "inlet_batch has no effect: it groups the inlet's parts: inlet_rate=0"),
    # issue 36: a return delay without returns, the normal motion of a waveform along the track
    (BULK, {"return_delay": "0.1"}, "return_delay has no effect: it delays the rejects' return to the "
                                    "inlet: recirculate=0 removes them"),
    (SINGLE, {"waveform": "2", "amp_n": "1e-4"}, "amp_n has no effect: it shapes the motion normal to "
                                                 "the track: waveform=2 moves it along the track only"),
    (BULK, {"waveform": "3", "phase": "30"}, "phase has no effect: it shapes the motion normal to the "
                                             "track: waveform=3"),
    (SINGLE, {"waveform": "1", "amp_n": "0", "phase": "30"}, "phase has no effect: it shifts the normal"),
    # the bowl's tooling without its tool, as a line's section 2
    (BOWL, {"drop_width": "4e-4"}, "drop_width has no effect: it shapes the side drop: drop_to <= "
                                   "drop_from has none"),
    (BOWL, {"wiper_at": "0.3"}, "wiper_at has no effect: it places the wiper: wiper_height=0 has none"),
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
    # a line with its tooling in effect, in metres and degrees
    (BULK, {**LINE, **STEP, "s2_freq": "150", "s2_phase": "45", "s2_cross_tilt": "2", "s2_length": "0.015",
            "s2_width": "3e-3", "s2_wall_height": "1.5e-3", "track_width": "3e-3"}),
    (BULK, {**LINE, "s2_wiper_height": "6e-4", "s2_wiper_at": "0.8"}),
    (BULK, {**LINE, "s2_drop_from": "0.2", "s2_drop_to": "0.6", "s2_drop_width": "1.5e-3"}),
    # the limits themselves are plausible
    (SINGLE, {"density": "100"}), (SINGLE, {"density": "25000"}), (BULK, {"surface_energy": "10"}),
    (SINGLE, {"mu": "2"}),
    # angles: beyond 2 pi a multiple of 5 deg in radians (73 pi/36, 3 pi) is taken as degrees
    (SINGLE, {"phase": "6.3705"}), (SINGLE, {"incline": "9.42478"}),
    # frequencies: only 2 pi x a multiple of 5 Hz reads as rad/s, not 2 pi x 3 Hz nor 15 pi
    (SINGLE, {"freq": "18.8496"}), (SINGLE, {"freq": "47.1239"}),
    (BULK, {"inlet_batch": "5", "inlet_rate": "1"}),
    (BULK, {"recirculate": "1", "return_delay": "0.1", **LINE}),
    (SINGLE, {"waveform": "2", "duty": "0.8", "amp_n": "0"}),  # a motion along the track, said so
    (BOWL, {"drop_from": "0.2", "drop_to": "0.5", "drop_width": "4e-4"}),
    (BOWL, {"wiper_height": "6e-4", "wiper_at": "0.3"}),
    (BULK, {"skin": "3e-4"}), (BOWL, {"skin": "1.05e-4"}),  # as wide as the part; three times a default
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


@pytest.mark.parametrize("given, words", [
    ({**LINE, "s2_step": "0.05"}, "s2_step=0.05 m is not a small step"),
    ({**LINE, "s2_wiper_height": "0.5"}, "s2_wiper_height=0.5 m is not below the walls"),
])
def test_a_refusal_caused_by_a_unit_slip_names_the_slip(given, words):
    # the relation refuses the value before the warning would be reached: it says it
    name = next(iter(k for k in given if k != "sections"))
    with pytest.raises(ParameterError) as err:
        resolve(BULK, given)
    assert words in str(err.value)
    assert f"parameter {name}={float(given[name]):g} m is {float(given[name]) * 1e3:g} mm: a length in mm?" \
        in str(err.value)


def test_the_command_line_prints_a_warning_as_one_line(tmp_path):
    proc = vibrofeed("prepare", "single_part", "-p", "density=2.33", "-o", tmp_path)
    assert proc.returncode == 0
    assert proc.stderr == ("vibrofeed: warning: parameter density=2.33 kg/m³ is lighter than any solid: "
                           "a density in g/cm³? (silicon: 2330 kg/m³, not 2.33)\n")


@pytest.mark.parametrize("p, name, why", [
    # no air film declared is no air film: with hamaker=0, nothing for roughness to shape
    ({"hamaker": 0.0, "roughness": 1e-8}, "roughness",
     "shapes the surface forces: hamaker=0 and air_viscosity=0 turn them off"),
    # no s2_drop_to declared is a drop to the section's end (1): from 1 on, none
    ({"s2_drop_from": 1.0, "s2_drop_width": 1e-3}, "s2_drop_from",
     "shapes the side drop: s2_drop_to <= s2_drop_from has none"),
])
def test_a_parameter_the_deck_does_not_declare_takes_its_neutral_value(p, name, why):
    assert advice(p, {name}) == [f"parameter {name} has no effect: it {why}"]


@pytest.mark.parametrize("p, name, why", [
    # a described line's sections past 2 as section 2: its tooling, and its absence
    ({"sections": 3.0, "s3_wiper_height": 0.0, "s3_wiper_at": 0.3}, "s3_wiper_at",
     "places the wiper: s3_wiper_height=0 has none"),
    ({"sections": 3.0, "s3_wiper_height": 0.0, "s3_wiper_skew": 60.0}, "s3_wiper_skew",
     "turns the wiper: s3_wiper_height=0 has none"),
    ({"sections": 3.0, "s3_drop_from": 0.5, "s3_drop_to": 0.2}, "s3_drop_from",
     "shapes the side drop: s3_drop_to <= s3_drop_from has none"),
    ({"sections": 2.0, "s3_freq": 80.0}, "s3_freq", "shapes a feeder line's section 3: sections=2 has none"),
    ({"sections": 3.0, "s3_phase": 20.0, "s3_amp_n": 0.0}, "s3_phase",
     "shifts the normal motion against the tangential one: one of them is 0"),
    ({"sections": 2.0, "s2_phase_c": 90.0, "s2_amp_c": 0.0}, "s2_phase_c",
     "shifts the cross stroke: s2_amp_c=0 has none"),
    ({"sections": 3.0, "s3_phase_c": 90.0}, "s3_phase_c", "shifts the cross stroke: s3_amp_c=0 has none"),
    ({"phase_c": 90.0}, "phase_c", "shifts the cross stroke: amp_c=0 has none"),
])
def test_a_further_sections_idle_parameters_are_named_as_section_2s(p, name, why):
    assert advice(p, {name}) == [f"parameter {name} has no effect: it {why}"]
