"""The model screen (vibrofeed.optimize.screen) against closed forms of a sine drive, the
constraints' margins, the objective values and errors (vibrofeed.optimize.objective), and
the pieces of the search that rank and confirm (vibrofeed.optimize.search)."""

import math

import numpy as np
import pytest

from vibrofeed.models.constants import G
from vibrofeed.optimize import objective as O
from vibrofeed.optimize.screen import drive, screen
from vibrofeed.optimize.search import (
    _confirmed,
    _mean_and_error,
    from_unit,
    setting_index,
    target_margins,
    to_unit,
)
from vibrofeed.optimize.spec import parse

SINE = {"freq": 100.0, "amp_t": 5e-5, "amp_n": 5e-5, "phase": 0.0, "waveform": 0, "mu": 0.5,
        "restitution": 0.3, "incline": 0.0}


def study(extra: str = "", variables: str = 'amp_n = { low = 1e-5, high = 1e-4 }') -> object:
    return parse('deck = "bulk_feeder"\n[variables]\n' + variables + '\n[objective]\n'
                 'maximize = "parts_per_s"\n' + extra, "s.toml")


def test_a_sines_peaks_are_its_closed_forms():
    w = 2 * math.pi * 100.0
    # in phase: |a| peaks at w^2 sqrt(at^2 + an^2); 90 degrees apart: at w^2 max(at, an)
    d = drive(SINE, 1, with_model=False)
    assert d.peak_acceleration == pytest.approx(w * w * math.hypot(5e-5, 5e-5) / G, rel=1e-4)
    assert d.peak_displacement == pytest.approx(5e-5, rel=1e-4)
    d = drive({**SINE, "amp_n": 2e-5, "phase": 90.0}, 1, with_model=False)
    assert d.peak_acceleration == pytest.approx(w * w * 5e-5 / G, rel=1e-4)
    # hopping: Gamma_n = an w^2 / g above 1 (here 2.01) hops, below (0.4) does not
    assert drive(SINE, 1, with_model=False).hops
    assert not drive({**SINE, "amp_n": 1e-5}, 1, with_model=False).hops
    # an incline shares gravity: g cos(beta) must be beaten (Gamma_n 0.9 hops at 30 degrees
    # only if 0.9 > cos 30 = 0.866)
    an = 0.9 * G / (w * w)
    assert drive({**SINE, "amp_n": an, "incline": 30.0}, 1, with_model=False).hops
    assert not drive({**SINE, "amp_n": an, "incline": 20.0}, 1, with_model=False).hops


def test_section_two_has_its_own_drive_and_the_model_speed():
    p = {**SINE, "sections": 2, "s2_freq": 150.0, "s2_amp_t": 1e-4, "s2_amp_n": 2e-5, "s2_phase": -30.0}
    d2 = drive(p, 2)
    w2 = 2 * math.pi * 150.0
    assert d2.freq == 150.0 and d2.peak_displacement == pytest.approx(1e-4, rel=1e-4)
    assert d2.peak_acceleration <= w2 * w2 * math.hypot(1e-4, 2e-5) / G * (1 + 1e-9)
    assert d2.peak_acceleration >= w2 * w2 * 1e-4 / G * (1 - 1e-4)
    from vibrofeed.models.deck import transport

    expected = transport({**p, "freq": 150.0, "amp_t": 1e-4, "amp_n": 2e-5, "phase": -30.0}).velocity
    assert d2.speed == pytest.approx(expected, rel=1e-12) and d2.speed > 0


def test_margins_say_what_breaks_and_by_how_much():
    s = study('[constraints]\nmax_acceleration = 2.5\nmax_displacement = 4e-5\nfrequency = [120, 200]\n'
              'no_hopping = [1]\nrequire = ["amp_n <= 2 * amp_t"]\n')
    sc = screen(s, {**SINE, "sections": 1})
    w = 2 * math.pi * 100.0
    m = sc.margins
    assert m["section 1: peak acceleration [g]"] == pytest.approx(w * w * math.hypot(5e-5, 5e-5) / G - 2.5,
                                                                  rel=1e-4)
    assert m["section 1: peak displacement [m]"] == pytest.approx(1e-5, rel=1e-3)
    assert m["section 1: frequency [Hz]"] == pytest.approx(20.0, abs=1e-12)
    assert m["section 1: hops"] == 1.0
    assert m["amp_n <= 2 * amp_t"] <= 0  # holds
    assert not sc.feasible and set(sc.broken) == {k for k in m if k != "amp_n <= 2 * amp_t"}
    ok = screen(s, {**SINE, "sections": 1, "freq": 150.0, "amp_t": 1e-5, "amp_n": 1e-5})
    assert ok.feasible and ok.broken == []


def test_a_drive_the_model_gives_no_speed_for_is_ruled_out_when_speed_is_asked():
    s = study("[constraints]\nmin_model_speed = 1e-3\n")
    sc = screen(s, {**SINE, "sections": 1, "amp_t": 0.0})  # no tangential stroke: no conveying
    assert sc.margins["section 1: model speed [m/s]"] == pytest.approx(1e-3, abs=1e-6)
    assert not sc.feasible


def test_objective_values_and_errors():
    row = {"parts_per_s": 20.0, "parts_per_s_err": 1.0, "singulated_fraction": 0.9, "n_arrivals": 100,
           "orientation_yield": None}
    v, e = O.value_and_error(row, "singulated_fraction")
    assert v == 0.9 and e == pytest.approx(math.sqrt(0.9 * 0.1 / 100), rel=1e-12)  # binomial
    v, e = O.value_and_error(row, "singulated_rate")
    assert v == pytest.approx(18.0, rel=1e-12)
    assert e == pytest.approx(math.hypot(1.0 * 0.9, 0.03 * 20.0), rel=1e-12)  # relative errors in quadrature
    assert O.value_and_error(row, "oriented_rate") == (None, None)  # not measured: no number
    # correctly oriented single parts: counted part by part, with their own batch-means error
    oriented = {**row, "oriented_rate": 14.0, "oriented_rate_err": 0.7, "correct_fraction": 0.75}
    assert O.value_and_error(oriented, "oriented_rate") == (14.0, 0.7)
    v, e = O.value_and_error(oriented, "correct_fraction")
    assert v == 0.75 and e == pytest.approx(math.sqrt(0.75 * 0.25 / 100), rel=1e-12)  # binomial
    assert O.value_and_error({"parts_per_s": float("nan")}, "parts_per_s") == (None, None)
    assert O.cautious(18.0, 0.5, "singulated_rate") == 17.5 and O.cautious(0.3, 0.1, "cv_interarrival") == 0.4
    assert O.better(0.2, 0.3, "doubles_rate") and O.better(3.0, 2.0, "parts_per_s")


def test_targets_are_relative_shortfalls():
    s = study('[objective.at_least]\nparts_per_s = 25\n'.replace("[objective.at_least]", "at_least = "
                                                                 "{ parts_per_s = 25 }\n[x]")
              .split("[x]")[0])
    assert target_margins(s, {"parts_per_s": 20.0}) == [pytest.approx(0.2, rel=1e-12)]
    assert target_margins(s, {"parts_per_s": 30.0}) == [pytest.approx(-0.2, rel=1e-12)]
    assert target_margins(s, {"parts_per_s": None}) == [1.0]


def test_unit_cube_round_trip_and_seed_offsets():
    s = study(variables='amp_n = { low = 1e-5, high = 1e-4, log = true }\nfreq = { low = 50, high = 150 }\n'
                        'inlet_batch = { low = 1, high = 4, type = "int" }\nshape = { choices = [0, 1, 2] }')
    setting = from_unit(s, np.array([0.5, 0.25, 1.0, 0.0]))
    assert setting["amp_n"] == pytest.approx(math.sqrt(1e-5 * 1e-4), rel=1e-12)  # log midpoint
    assert setting["freq"] == pytest.approx(75.0, rel=1e-12) and setting["inlet_batch"] == 4
    assert setting["shape"] == 0 and type(setting["freq"]) is float
    assert from_unit(s, np.array([0.0, 0.0, 0.0, 0.999]))["shape"] == 2
    u = to_unit(s, setting)
    assert u[:3] == pytest.approx([0.5, 0.25, 1.0], abs=1e-12) and u[3] == pytest.approx(1 / 6, abs=1e-12)
    assert setting_index(setting) == setting_index(dict(reversed(list(setting.items()))))
    assert setting_index(setting) != setting_index({**setting, "freq": 75.000001})
    assert 0 <= setting_index(setting) < 1_000_000


def test_replicates_mean_and_error():
    mean, err = _mean_and_error([10.0, 12.0, 14.0], [0.1, 0.1, 0.1])
    assert mean == 12.0 and err == pytest.approx(2.0 / math.sqrt(3), rel=1e-12)  # the scatter wins
    mean, err = _mean_and_error([10.0, 10.0], [1.0, 1.0])
    assert err == pytest.approx(math.sqrt(2.0) / 2, rel=1e-12)  # the runs' own errors win
    assert _mean_and_error([5.0], [None]) == (5.0, None)


def test_confirmation_ranks_by_the_fresh_runs_one_error_towards_worse():
    s = study()
    rows = [  # setting 0: mean 20 +- 4 (cautious ~16); setting 1: 18 +- 0.1 (cautious ~17.9)
        {"job": 10000, "stage": "confirm", "objective": 16.0, "objective_err": 0.1},
        {"job": 10001, "stage": "confirm", "objective": 24.0, "objective_err": 0.1},
        {"job": 10100, "stage": "confirm", "objective": 18.0, "objective_err": 0.1},
        {"job": 10101, "stage": "confirm", "objective": 18.0, "objective_err": 0.1},
        {"job": 5, "stage": "search", "objective": 99.0, "objective_err": 0.1},  # not a confirmation
    ]
    out = _confirmed(s, [{"amp_n": 1e-5}, {"amp_n": 2e-5}], rows)
    assert [c["setting"]["amp_n"] for c in out] == [2e-5, 1e-5]
    assert out[1]["parts_per_s"] == (20.0, pytest.approx(4.0, rel=1e-12)) and out[0]["runs"] == 2


def test_the_screens_reasons_group_refusals_without_their_numbers():
    from vibrofeed.optimize.search import _kind

    a = _kind("the joint opens by up to 0.000204 m along the track (amp_t, s2_amp_t), more than half")
    b = _kind("the joint opens by up to 1.7e-4 m along the track (amp_t, s2_amp_t), more than half")
    assert a == b == ("parameter check: the joint opens by up to # m along the track (amp_t, s2_amp_t), "
                      "more than half")
    assert _kind("parameter s2_step=-2e-05 m: must step down; also this") == \
        "parameter check: parameter s2_step=# m: must step down"


def test_objective_columns_and_a_target_of_zero():
    from vibrofeed.optimize.search import objective_keys

    assert objective_keys(study()) == ["objective"]
    s2 = parse('deck = "bulk_feeder"\n[variables]\namp_n = { low = 1e-5, high = 1e-4 }\n[objective]\n'
               'maximize = ["parts_per_s", "singulated_fraction"]\n', "s.toml")
    assert objective_keys(s2) == ["objective", "objective_2"]
    zero = parse('deck = "bulk_feeder"\n[variables]\namp_n = { low = 1e-5, high = 1e-4 }\n[objective]\n'
                 'maximize = "parts_per_s"\nat_least = { cv_interarrival = 0 }\n', "s.toml")
    # a target of 0 has no scale of its own: the shortfall is absolute
    assert target_margins(zero, {"cv_interarrival": 0.3}) == [pytest.approx(-0.3, rel=1e-12)]


def test_skewed_replicates_mean_is_not_their_median():
    mean, err = _mean_and_error([10.0, 10.0, 16.0], [None, None, None])
    assert mean == pytest.approx(12.0, rel=1e-12)  # the median would be 10
    assert err == pytest.approx(math.sqrt(12.0) / math.sqrt(3), rel=1e-12)


def test_confirmation_reports_the_targets_mean_too():
    s = parse('deck = "bulk_feeder"\n[variables]\namp_n = { low = 1e-5, high = 1e-4 }\n[objective]\n'
              'maximize = "singulated_rate"\nat_least = { parts_per_s = 25 }\n', "s.toml")
    rows = [{"job": 10000, "stage": "confirm", "objective": 20.0, "objective_err": 1.0, "parts_per_s": 28.0},
            {"job": 10001, "stage": "confirm", "objective": 22.0, "objective_err": 1.0, "parts_per_s": 30.0}]
    (entry,) = _confirmed(s, [{"amp_n": 1e-5}], rows)
    assert entry["parts_per_s"][0] == pytest.approx(29.0, rel=1e-12)
    assert entry["parts_per_s"][1] == pytest.approx(1.0, rel=1e-12)  # the scatter: sd 1.414 / sqrt 2


def test_an_unreadable_study_file_says_why(tmp_path):
    from vibrofeed.errors import InputError
    from vibrofeed.optimize.spec import load

    with pytest.raises(InputError) as err:
        load(tmp_path / "missing.toml")
    assert str(err.value) == f"cannot read study file {tmp_path / 'missing.toml'}: No such file or directory"


def test_hopping_starts_strictly_above_gravity():
    from vibrofeed.models.deck import waveform
    from vibrofeed.optimize.screen import SAMPLES

    # the normal amplitude whose sampled floor acceleration bottoms out at exactly -g (found on
    # the model itself, as the screen samples it): the part only just keeps contact, no hop
    t = np.arange(SAMPLES) / (SAMPLES * 100.0)

    def lowest(an):
        return float(np.min(waveform({**SINE, "amp_n": an}).acceleration(t)[1]))

    an = -G / lowest(1.0)  # within an ulp or two of the limit: step onto it
    for _ in range(8):
        if lowest(an) == -G:
            break
        an = math.nextafter(an, 0.0) if lowest(an) < -G else math.nextafter(an, 1.0)
    assert lowest(an) == -G
    assert not drive({**SINE, "amp_n": an}, 1, with_model=False).hops
    above = an * (1 + 1e-9)
    assert lowest(above) < -G and drive({**SINE, "amp_n": above}, 1, with_model=False).hops


def test_a_deck_without_an_incline_is_level():
    # Gamma_n = 0.99993: below 1, so no hop on a level track, but above cos(1 deg) = 0.99985,
    # so a default incline of even one degree either way would make it hop
    w = 2 * math.pi * 100.0
    level = {k: v for k, v in SINE.items() if k != "incline"}
    assert not drive({**level, "amp_n": 0.99993 * G / (w * w)}, 1, with_model=False).hops
    assert drive({**SINE, "amp_n": 0.99993 * G / (w * w), "incline": 1.0}, 1, with_model=False).hops


def test_a_deck_without_sections_has_one():
    from vibrofeed.optimize.screen import sections

    assert sections({}) == 1 and sections({"sections": "2"}) == 2
    sc = screen(study("[constraints]\nmax_acceleration = 2.5\n"), dict(SINE))  # no "sections" key
    assert [d.section for d in sc.drives] == [1] and list(sc.margins) == ["section 1: peak acceleration [g]"]


def test_the_model_speed_margin_and_notes():
    from vibrofeed.models.deck import transport

    s = study("[constraints]\nmin_model_speed = 1e-3\n")
    fast = screen(s, {**SINE, "sections": 1})
    v = transport(SINE).velocity
    assert v > 1e-3 and fast.drives[0].note == ""  # converged: nothing to say
    assert fast.margins["section 1: model speed [m/s]"] == pytest.approx(1e-3 - v, rel=1e-12)
    assert fast.feasible
    # the model cannot say (a parameter missing, KeyError; a value it refuses, ValueError):
    # no speed, so the setting cannot show it conveys: broken by an unbounded amount
    for values in ({k: x for k, x in SINE.items() if k != "mu"}, {**SINE, "mu": -1.0}):
        sc = screen(s, {**values, "sections": 1})
        d = sc.drives[0]
        assert d.speed is None and d.note.startswith("model not applicable (")
        assert sc.margins["section 1: model speed [m/s]"] == math.inf and not sc.feasible


def test_values_that_are_not_numbers_pass_through_the_screen():
    # resolved deck values hold strings (a mesh file) and may hold None: neither is a number,
    # neither stops the screen
    s = study('[constraints]\nmax_acceleration = 2.5\nrequire = ["amp_n <= 2 * amp_t"]\n')
    plain = screen(s, {**SINE, "sections": 1})
    extra = screen(s, {**SINE, "sections": "1", "freq": "100.0", "mesh": "tray.stl", "label": None})
    assert extra.margins == plain.margins


def test_the_screens_margins_are_the_amounts_broken_or_to_spare():
    s = study('[constraints]\nno_hopping = [1]\nrequire = ["amp_n <= 2 * amp_t"]\n')
    ok = screen(s, {**SINE, "sections": 1, "freq": 150.0, "amp_t": 1e-4, "amp_n": 1e-5})
    assert ok.margins["section 1: hops"] == 0.0  # no hop: broken by nothing
    # holds with 2e-4 - 1e-5 to spare; broken by 5e-5 - 2e-5
    assert ok.margins["amp_n <= 2 * amp_t"] == pytest.approx(1e-5 - 2e-4, rel=1e-9) and ok.feasible
    bad = screen(s, {**SINE, "sections": 1, "freq": 150.0, "amp_t": 1e-5, "amp_n": 5e-5})
    assert bad.margins["amp_n <= 2 * amp_t"] == pytest.approx(3e-5, rel=1e-9)
    assert "amp_n <= 2 * amp_t" in bad.broken


def test_ties_are_not_better_and_no_error_is_no_caution():
    assert not O.better(0.3, 0.3, "doubles_rate") and not O.better(2.0, 2.0, "parts_per_s")
    assert O.cautious(18.0, None, "singulated_rate") == 18.0
    assert O.cautious(0.3, None, "cv_interarrival") == 0.3
    assert O.cautious(18.0, 0.0, "singulated_rate") == 18.0


def test_a_product_with_one_error_unknown_has_no_error():
    # the rate's error missing, the fraction's known (and the other way round): no error
    row = {"parts_per_s": 20.0, "singulated_fraction": 0.9, "n_arrivals": 100}
    v, e = O.value_and_error(row, "singulated_rate")
    assert v == pytest.approx(18.0, rel=1e-12) and e is None
    row = {"parts_per_s": 20.0, "parts_per_s_err": 1.0, "singulated_fraction": 0.9}
    assert O.value_and_error(row, "singulated_rate") == (pytest.approx(18.0, rel=1e-12), None)


def test_a_fraction_rounded_past_one_has_no_error_rather_than_a_crash():
    above = math.nextafter(1.0, 2.0)  # f (1 - f) is then -2.2e-16: clamped to 0
    row = {"singulated_fraction": above, "n_arrivals": 10}
    assert O.value_and_error(row, "singulated_fraction") == (above, 0.0)


def test_the_unit_cube_edges_and_a_choice_before_other_variables():
    s = study(variables='shape = { choices = [0, 1, 2] }\nfreq = { low = 50, high = 150 }')
    # u = 1 is the top edge of the last choice's bin, and the upper bound
    assert from_unit(s, np.array([1.0, 1.0])) == {"shape": 2, "freq": 150.0}
    assert from_unit(s, np.array([0.34, 0.5])) == {"shape": 1, "freq": pytest.approx(100.0, rel=1e-12)}


def test_replicates_own_errors_add_in_quadrature():
    # no scatter; own errors 2 and 2: sqrt(4 + 4) / 2
    mean, err = _mean_and_error([10.0, 10.0], [2.0, 2.0])
    assert mean == 10.0 and err == pytest.approx(math.sqrt(8.0) / 2, rel=1e-12)


def test_the_seed_offset_is_a_fixed_hash_of_the_setting():
    import hashlib

    # every search run's seed is the study's seed plus this offset: a study (and the benchmark
    # docs/optimize.md quotes) reproduces only while the derivation stays the same: the first
    # 32 bits of the SHA-256 of the setting as sorted JSON of deck strings, modulo 10^6
    text = '{"freq": "75.0", "shape": "1"}'
    expected = int(hashlib.sha256(text.encode()).hexdigest()[:8], 16) % 1_000_000
    assert setting_index({"shape": 1, "freq": 75.0}) == expected
    # spread over the whole range, not bunched at its bottom
    offsets = [setting_index({"freq": 50.0 + i}) for i in range(100)]
    assert max(offsets) > 900_000 and min(offsets) < 100_000 and len(set(offsets)) == 100


def test_confirmation_groups_replicates_by_their_job_numbers():
    # job 10000 + 100 x rank + replicate: the 100th replicate of the first (10099) is its own
    s = study()
    rows = [{"job": 10000, "stage": "confirm", "objective": 10.0, "objective_err": 1.0},
            {"job": 10099, "stage": "confirm", "objective": 12.0, "objective_err": 1.0},
            {"job": 10100, "stage": "confirm", "objective": 5.0, "objective_err": 1.0},
            {"job": 10200, "stage": "confirm", "objective": 99.0, "objective_err": 1.0}]  # a third rank's
    out = _confirmed(s, [{"amp_n": 1e-5}, {"amp_n": 2e-5}], rows)
    assert [(c["setting"]["amp_n"], c["runs"]) for c in out] == [(1e-5, 2), (2e-5, 1)]
    assert out[0]["parts_per_s"][0] == 11.0 and out[1]["parts_per_s"] == (5.0, pytest.approx(1.0, rel=1e-12))


def test_a_confirmed_value_without_an_error_still_counts():
    (entry,) = _confirmed(study(), [{"amp_n": 1e-5}], [{"job": 10000, "stage": "confirm", "objective": 5.0}])
    assert entry["parts_per_s"] == (5.0, None) and entry["parts_per_s_measured"] == 1


def test_two_objectives_are_confirmed_in_the_first_ones_order():
    s = parse('deck = "bulk_feeder"\n[variables]\namp_n = { low = 1e-5, high = 1e-4 }\n[objective]\n'
              'maximize = ["parts_per_s", "singulated_fraction"]\n', "s.toml")
    rows = [{"job": 10000, "stage": "confirm", "objective": 20.0, "objective_2": 0.5},
            {"job": 10100, "stage": "confirm", "objective": 10.0, "objective_2": 0.9}]
    out = _confirmed(s, [{"amp_n": 1e-5}, {"amp_n": 2e-5}], rows)
    assert [c["setting"]["amp_n"] for c in out] == [1e-5, 2e-5]  # 20 > 10, though 0.5 < 0.9
    assert out[1]["singulated_fraction"] == (0.9, None)


def test_a_strict_inequality_met_with_equality_rules_the_setting_out():
    # amp_n < amp_t at amp_n == amp_t is broken (Inequality.holds says so) by no amount: the
    # screen must still count it broken (feasible: every margin <= 0), or a setting the study
    # excludes is sent to DEM; <= at equality holds
    s = study('[constraints]\nrequire = ["amp_n < amp_t", "amp_n <= amp_t"]\n')
    sc = screen(s, {**SINE, "sections": 1})  # amp_n == amp_t == 5e-5
    assert 0.0 < sc.margins["amp_n < amp_t"] < 1e-300  # broken, by a vanishing amount
    assert sc.margins["amp_n <= amp_t"] == 0.0
    assert not sc.feasible and sc.broken == ["amp_n < amp_t"]
