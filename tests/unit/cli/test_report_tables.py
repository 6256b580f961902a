"""What `vibrofeed feedrate` and `vibrofeed singulation` print, line by line, from summaries
written by hand (no result file, no analysis): the units each figure is scaled to, the
columns of a line's and a bowl's sections, the continuity at each joint, the n/a cells of an
unmeasured run, and the numeric options' limits (vibrofeed.cli.numbers).

Every expected string is written out from the inputs here. Figures that a scale factor
multiplies sit just beside a rounding boundary (e.g. 0.24565001 mg/s, printed 0.2457), so that
the scale off by one part in a million (1e6 -> 999999) or a thousand (1e3 -> 999) changes the
printed digits: each such site is printed once just above a boundary and once just below.
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
import types

import numpy as np
import pytest

from vibrofeed.cli import feedrate, singulation
from vibrofeed.cli.feedrate import _pm, section_name, section_table, single_part, unmeasured_sections
from vibrofeed.cli.numbers import real, whole
from vibrofeed.values import duration, fmt, to_json

SLIDING = "a sliding block's speed: spheres roll, so for them a reference, not a prediction"
INDENT = " " * 15  # a section's row starts under the header's first column
LINE_WIDTHS = (15, 22, 22, 20, 15)  # x, out, speed, hold-up, density; the rejects run on
BOWL_WIDTHS = (22, 22, 22, 20, 15)  # a bowl's first column holds "helix: a .. b"


def row(widths, *cells):
    """A table row as written here: each cell but the last left-aligned in its width."""
    *aligned, last = cells
    return INDENT + "".join(f"{c:<{w}}" for c, w in zip(aligned, widths)) + last


# -- the summaries ------------------------------------------------------------------------------
# Just above and just below a rounding boundary, for the figures a scale multiplies. Parts of
# 1e-9 kg, so ~245.65 parts/s are 2.4565e-7 kg/s = 0.24565 mg/s: 0.24565001 -> "0.2457"
# (999999/1e6 of it, 0.24564976, -> "0.2456"), 0.24564999 -> "0.2456" (1000001/1e6 of it,
# 0.24565024, -> "0.2457"); the same for 0.00325 mg/s at 2 figures and 0.455 mm/s.
SIDES = {
    "above": {"mass_per_s": 2.4565001e-7, "mass_per_s_err": 3.2500003e-9, "mean_velocity_err": 4.550001e-4,
              "shown": ("0.2457", "0.0033", "0.46")},
    "below": {"mass_per_s": 2.4564999e-7, "mass_per_s_err": 3.2499997e-9, "mean_velocity_err": 4.549999e-4,
              "shown": ("0.2456", "0.0032", "0.45")},
}


def track(side="above", **changes):
    """A single track's summary: no sections, spheres, the model compared."""
    s = {"parts_per_s": 245.6, "parts_per_s_err": 3.21,
         "mass_per_s": SIDES[side]["mass_per_s"], "mass_per_s_err": SIDES[side]["mass_per_s_err"],
         "mean_velocity": 0.01234, "mean_velocity_err": SIDES[side]["mean_velocity_err"],
         "steady_from": 0.2, "steady_to": 1.0, "unsteady": None, "n_events": 240, "velocity_lag": 7,
         "inserted": 300, "exited": 240, "on_track": 45, "lost": 2,
         "model_velocity": 0.01836, "model_note": "", "velocity_ratio": 0.6721, "shape": 0, "reason": None}
    return s | changes


def line_sections():
    """Three sections of a line. x: 124.5001 mm prints 125 (a scale 999/1e3 gives 124.38 -> 124),
    275.4999 mm prints 275 (1001/1e3: 275.78 -> 276); the speed errors likewise sit beside
    0.455 mm/s."""
    return [
        {"section": 1, "x_from": 0.0, "x_to": 0.1245001, "joint_flux": 50.0, "joint_flux_error": 0.3,
         "reject_rate": 2.5, "reject_rate_error": 0.5, "rejects_in_window": 5, "speed": 0.01234,
         "speed_error": 4.550001e-4, "hold_up": 6.5, "hold_up_error": 0.25, "line_density": 52.2},
        {"section": 2, "x_from": 0.1245001, "x_to": 0.2754999, "joint_flux": 42.0, "joint_flux_error": 0.4,
         "reject_rate": 6.0, "reject_rate_error": 1.2, "rejects_in_window": 12, "speed": 0.02468,
         "speed_error": 4.549999e-4, "hold_up": 9.75, "hold_up_error": 0.5, "line_density": 65.0},
        {"section": 3, "x_from": 0.2754999, "x_to": 0.4, "joint_flux": 40.0, "joint_flux_error": 0.8,
         "reject_rate": 1.5, "reject_rate_error": 0.8, "rejects_in_window": 3, "speed": 0.03579,
         "speed_error": 1.2e-3, "hold_up": 5.0, "hold_up_error": 0.15, "line_density": 40.0},
    ]


def line_tooling():
    return {"side_drop": None,  # this line has none: the tools after it are still listed
            "wiper": {"per_s": 4.0, "per_s_error": 0.9, "in_window": 16, "total": 40},
            "other": {"per_s": 6.0, "per_s_error": 1.1, "in_window": 24, "total": 55}}


def line(**changes):
    s = track(sections=line_sections(), rejects_by_tooling=line_tooling(), rejected=13, returned=None)
    return s | changes


LINE_HEADER = ("sections       x [mm]" + " " * 9 + "out [parts/s]" + " " * 9  # 6 + 9 = 15, 13 + 9 = 22
               + "speed [mm/s]" + " " * 10 + "hold-up [parts]" + " " * 5  # 12 + 10 = 22, 15 + 5 = 20
               + "density [/mm]" + " " * 2 + "rejects [/s]")  # 13 + 2 = 15
# speed x1e3 [mm/s]; line density x1e-3 [/mm]: 52.2 /m = 0.0522 /mm
LINE_ROWS = [row(LINE_WIDTHS, "1: 0 .. 125", "joint 50 ± 0.3", "12.34 ± 0.46", "6.5 ± 0.25", "0.0522",
                 "2.5 ± 0.5"),
             row(LINE_WIDTHS, "2: 125 .. 275", "joint 42 ± 0.4", "24.68 ± 0.45", "9.75 ± 0.5", "0.065",
                 "6 ± 1.2"),
             row(LINE_WIDTHS, "3: 275 .. 400", "outlet 40 ± 0.8", "35.79 ± 1.2", "5 ± 0.15", "0.04",
                 "1.5 ± 0.8")]
LINE_TOOLING = ("rejects        side drop: none on the line; wiper 4 ± 0.9 /s (16 in the window, 40 in all); "
                "other 6 ± 1.1 /s (24 in the window, 55 in all)")
# joint k: section k's flux in = section k+1's flux out + section k+1's rejects; the spread is
# the root sum of squares of the three errors.
LINE_CONTINUITY = [
    # 50 - 42 - 6 = 2; sqrt(0.3^2 + 0.4^2 + 1.2^2) = sqrt(0.09 + 0.16 + 1.44) = sqrt(1.69) = 1.3
    "continuity     joint 1: 50 /s in = 42 through joint 2 + 6 rejected /s (in - out 2 ± 1.3)",
    # 42 - 40 - 1.5 = 0.5; sqrt(0.4^2 + 0.8^2 + 0.8^2) = sqrt(0.16 + 0.64 + 0.64) = sqrt(1.44) = 1.2
    "continuity     joint 2: 42 /s in = 40 through the outlet + 1.5 rejected /s (in - out 0.5 ± 1.2)",
]


def bowl():
    """A bowl: its helix and chute along the path, falls back into the bowl, chips."""
    sections = [
        {"section": 1, "name": "helix", "along": "path", "x_from": 0.0, "x_to": 0.15, "joint_flux": 12.0,
         "joint_flux_error": 0.6,
         "reject_rate": 3.0, "reject_rate_error": 0.4, "rejects_in_window": 12, "speed": 0.0105,
         "speed_error": 3e-4, "hold_up": 20.0, "hold_up_error": 1.5, "line_density": 133.3,
         "model_speed": 0.01502, "model_note": "", "speed_ratio": 0.6991},
        {"section": 2, "name": "chute", "along": "path", "x_from": 0.15, "x_to": 0.18, "joint_flux": 8.0,
         "joint_flux_error": 0.5,
         "reject_rate": 1.0, "reject_rate_error": 0.2, "rejects_in_window": 4, "speed": 0.02,
         "speed_error": 1e-3, "hold_up": 3.0, "hold_up_error": 0.2, "line_density": 100.0,
         "model_speed": None, "model_note": "the drive throws the part", "speed_ratio": None},
    ]
    tooling = {"side_drop": None, "wiper": None,
               "other": {"per_s": 3.0, "per_s_error": 0.4, "in_window": 12, "total": 30}}
    return track(sections=sections, rejects_by_tooling=tooling, fell=12, fell_per_s=3.0, fell_per_s_err=0.4,
                 shape=1)


# -- vibrofeed feedrate: a single track ----------------------------------------------------------
@pytest.mark.parametrize("side", SIDES)
def test_a_single_tracks_table_line_by_line_in_mg_per_s_and_mm_per_s(side):
    mass, mass_err, v_err = SIDES[side]["shown"]
    assert feedrate.table(track(side)).split("\n") == [
        f"feed rate      245.6 ± 3.2 parts/s, {mass} ± {mass_err} mg/s",  # kg/s x 1e6
        "steady window  0.2 .. 1 s (240 exits in the run analysed)",
        # m/s x 1e3
        f"conveying      12.34 ± {v_err} mm/s (whole-period displacement, 7 frames per interval)",
        f"single part    18.36 mm/s (model, dilute limit); bulk / model = 0.672; {SLIDING}",
        "mass balance   inserted 300, on track 45, exited 240, lost 2 (last frame)",
    ]


def test_a_reason_replaces_the_rate_even_where_figures_remain():
    text = feedrate.table(track(reason="too few exits (3) for a rate"))
    assert text.split("\n")[0] == "feed rate      too few exits (3) for a rate"
    assert "parts/s" not in text and "continuity" not in text


def test_the_figures_run_unmeasured_prints_n_a_in_their_cells():
    s = track(**dict.fromkeys(feedrate.RATE_KEYS), reason="too few exits (3) for a rate",
              mean_velocity=None, mean_velocity_err=None, steady_to=None)
    lines = feedrate.table(s).split("\n")
    assert lines[1] == "steady window  0.2 .. n/a s (240 exits in the run analysed)"
    assert lines[2] == "conveying      n/a ± n/a mm/s (whole-period displacement, 7 frames per interval)"


def test_no_model_line_and_no_mass_balance_when_the_summary_has_neither():
    s = track()
    for key in ("model_velocity", "model_note", "velocity_ratio", "inserted"):
        del s[key]
    assert feedrate.table(s).split("\n")[3:] == []  # rate, window, conveying only


@pytest.mark.parametrize("changes, tail", [
    ({"rejected": 13}, ", rejected 13, lost 2 (last frame)"),
    ({"rejected": 0}, ", rejected 0, lost 2 (last frame)"),  # none rejected is still said
    ({"rejected": 13, "returned": 4}, ", rejected 13 (returned to the inlet 4, counted in inserted), lost 2 "
                                      "(last frame)"),
    ({"rejected": 0, "returned": 0}, ", rejected 0 (returned to the inlet 0, counted in inserted), lost 2 "
                                     "(last frame)"),
    ({"rejected": None, "returned": None}, ", lost 2 (last frame)"),
])
def test_the_mass_balance_names_rejects_and_returns_when_the_line_has_them(changes, tail):
    last = feedrate.table(track(**changes)).split("\n")[-1]
    assert last == "mass balance   inserted 300, on track 45, exited 240" + tail


# -- the single-part line ------------------------------------------------------------------------
def test_the_model_line_of_a_chip_gives_the_models_note_and_no_sphere_caveat():
    s = {"model_velocity": 0.01836, "velocity_ratio": 0.6721, "model_note": "slides: no flights", "shape": 1}
    # 0.01836 m/s = 18.36 mm/s; ratio to 3 decimals
    assert single_part(s) == ("single part    18.36 mm/s (model, dilute limit); bulk / model = 0.672; "
                              "slides: no flights")


def test_a_summary_without_a_shape_is_of_spheres():
    s = {"model_velocity": 0.01836, "velocity_ratio": 0.6721, "model_note": ""}  # the decks' default
    assert single_part(s).endswith(f"= 0.672; {SLIDING}")


def test_no_model_is_n_a_with_why():
    s = {"model_velocity": None, "velocity_ratio": None, "model_note": "the result lacks mu", "shape": 0}
    assert single_part(s) == "single part    n/a (the result lacks mu)"


def test_each_sections_model_and_n_a_for_a_section_without_one():
    s = {"model_velocity": 0.01834, "velocity_ratio": 0.6729, "model_note": "", "shape": 0, "sections": [
        {"section": 1, "model_speed": 0.01834, "model_note": "", "speed_ratio": 0.6729},
        {"section": 2, "model_speed": None, "model_note": "the drive throws the part", "speed_ratio": None}]}
    assert single_part(s) == ("single part    model, dilute limit, each section's drive: 1: 18.34 mm/s "
                              "(DEM / model 0.673), 2: n/a (the drive throws the part); " + SLIDING)
    # sections without a model of their own: the track's line
    s["sections"] = [{"section": 1}, {"section": 2}]
    assert single_part(s) == ("single part    18.34 mm/s (model, dilute limit); bulk / model = 0.673; "
                              + SLIDING)


# -- a feeder line's sections ----------------------------------------------------------------------
def test_a_lines_sections_in_columns_with_their_joints_outlet_tooling_and_continuity():
    assert section_table(line()) == [LINE_HEADER, *LINE_ROWS, LINE_TOOLING, *LINE_CONTINUITY]
    # the columns: 15 for "sections" and its padding, then x's 15, out's 22, speed's 22
    assert LINE_HEADER.index("out [parts/s]") == 30 and LINE_HEADER.index("speed [mm/s]") == 52
    assert LINE_ROWS[0].index("joint 50") == 30 and LINE_ROWS[0].index("12.34") == 52


def test_a_cell_as_wide_as_its_column_is_still_set_apart_from_the_next():
    """"2: 12.5 .. 30.4" is 15 characters, the x column's width: one space still follows it,
    and the other columns start where a full cell would have put them, one further on."""
    s = line(sections=[dict(sec) for sec in line_sections()[:2]])
    s["sections"][0] |= {"x_from": 0.0, "x_to": 0.0125}
    s["sections"][1] |= {"x_from": 0.0125, "x_to": 0.0304}
    second = section_table(s)[2]
    assert second.startswith(INDENT + "2: 12.5 .. 30.4 outlet 42 ± 0.4"), second
    # the cells after it shift by one: outlet's cell starts at 31, the speed at 31 + 22
    assert second.index("24.68") == 53


def test_a_lines_whole_table_puts_the_sections_after_the_conveying_speed():
    lines = feedrate.table(line()).split("\n")
    assert lines[3:8] == [LINE_HEADER, *LINE_ROWS, LINE_TOOLING]
    assert lines[8:10] == LINE_CONTINUITY
    assert lines[10].startswith("single part    18.36 mm/s")
    assert lines[11] == ("mass balance   inserted 300, on track 45, exited 240, rejected 13, lost 2 "
                         "(last frame)")
    assert len(lines) == 12  # no "fell back" line: not a bowl


def test_an_unmeasured_line_says_n_a_for_every_rate_and_gives_no_continuity():
    # the figures kept in the dict: the reason alone decides
    lines = section_table(line(reason="not steady: the hold-up of section 2 drifts"))
    assert lines == [
        LINE_HEADER,
        row(LINE_WIDTHS, "1: 0 .. 125", "joint n/a", "12.34 ± 0.46", "6.5 ± 0.25", "0.0522", "n/a"),
        row(LINE_WIDTHS, "2: 125 .. 275", "joint n/a", "24.68 ± 0.45", "9.75 ± 0.5", "0.065", "n/a"),
        row(LINE_WIDTHS, "3: 275 .. 400", "outlet n/a", "35.79 ± 1.2", "5 ± 0.15", "0.04", "n/a"),
        "rejects        side drop: none on the line; wiper n/a (16 in the window, 40 in all); "
        "other n/a (24 in the window, 55 in all)",
    ]


def test_a_joint_whose_figures_are_missing_reads_n_a_in_its_continuity():
    first, second = line_sections()[:2]
    second["reject_rate_error"] = None  # (NaN in the analysis, None once JSON-ready)
    lines = section_table(line(sections=[first, second], rejects_by_tooling=None))
    assert lines[-1] == ("continuity     joint 1: 50 /s in = 42 through the outlet + 6 rejected /s "
                         "(in - out 2 ± n/a)")
    second["joint_flux"] = None
    lines = section_table(line(sections=[first, second], rejects_by_tooling=None))
    assert lines[-1] == "continuity     joint 1: 50 /s in = n/a through the outlet + 6 rejected /s " \
                        "(in - out n/a ± n/a)"
    assert len(lines) == 1 + 2 + 1  # header, rows, one joint: no tooling line


def test_a_single_track_has_no_section_lines():
    assert section_table(track()) == [] and section_table(track(sections=[])) == []


# -- a bowl ------------------------------------------------------------------------------------------
BOWL_HEADER = ("sections       path [mm]" + " " * 13 + "out [parts/s]" + " " * 9  # 9 + 13 = 22, 13 + 9 = 22
               + "speed [mm/s]" + " " * 10 + "hold-up [parts]" + " " * 5  # 12 + 10 = 22, 15 + 5 = 20
               + "density [/mm]" + " " * 2 + "fell back [/s]")  # 13 + 2 = 15


def test_a_bowls_table_names_its_helix_and_chute_and_what_fell_back():
    assert feedrate.table(bowl()).split("\n") == [
        "feed rate      245.6 ± 3.2 parts/s, 0.2457 ± 0.0033 mg/s",
        "steady window  0.2 .. 1 s (240 exits in the run analysed)",
        "conveying      12.34 ± 0.46 mm/s (whole-period displacement, 7 frames per interval)",
        BOWL_HEADER,
        row(BOWL_WIDTHS, "helix: 0 .. 150", "joint 12 ± 0.6", "10.5 ± 0.3", "20 ± 1.5", "0.1333", "3 ± 0.4"),
        row(BOWL_WIDTHS, "chute: 150 .. 180", "outlet 8 ± 0.5", "20 ± 1", "3 ± 0.2", "0.1", "1 ± 0.2"),
        "fell back by   side drop: none on the bowl; wiper: none on the bowl; other 3 ± 0.4 /s (12 in the "
        "window, 30 in all)",
        # 12 - 8 - 1 = 3; sqrt(0.6^2 + 0.5^2 + 0.2^2) = sqrt(0.36 + 0.25 + 0.04) = sqrt(0.65) = 0.806
        "continuity     joint 1: 12 /s in = 8 through the outlet + 1 rejected /s (in - out 3 ± 0.81)",
        "fell back      12 in the window, 3 ± 0.4 /s (off the track back into the bowl)",
        # chips: no sphere caveat; 0.01502 m/s = 15.02 mm/s
        "single part    model, dilute limit, each section's drive: helix: 15.02 mm/s (DEM / model 0.699), "
        "chute: n/a (the drive throws the part)",
        "mass balance   inserted 300, on track 45, exited 240, lost 2 (last frame)",
    ]
    assert BOWL_HEADER.index("out [parts/s]") == 15 + 22


def test_an_unmeasured_bowl_reads_n_a_for_its_tools_that_exist():
    s = bowl() | {"reason": "too few exits (1) for a rate"}
    lines = section_table(s)
    assert lines[-1] == ("fell back by   side drop: none on the bowl; wiper: none on the bowl; "
                         "other n/a (12 in the window, 30 in all)")
    assert lines[1].startswith(INDENT + "helix: 0 .. 150".ljust(22) + "joint n/a ")


# -- the rates a reason leaves unmeasured ----------------------------------------------------------
def test_a_reason_empties_each_sections_rates_and_each_tools_but_keeps_the_counts():
    s = line(reason="not steady: the conveying speed drifts")
    unmeasured_sections(s)
    for sec, before in zip(s["sections"], line_sections()):
        assert sec == before | dict.fromkeys(("joint_flux", "joint_flux_error", "reject_rate",
                                              "reject_rate_error"))
    assert s["rejects_by_tooling"] == {
        "side_drop": None,
        "wiper": {"per_s": None, "per_s_error": None, "in_window": 16, "total": 40},
        "other": {"per_s": None, "per_s_error": None, "in_window": 24, "total": 55}}


@pytest.mark.parametrize("reason", [None, ""])
def test_without_a_reason_the_sections_are_left_as_they_are(reason):
    s = line(reason=reason)
    unmeasured_sections(s)
    assert s == line(reason=reason)


def test_a_reason_on_a_summary_without_sections_or_tooling_changes_nothing():
    for s in (track(reason="too few exits (0) for a rate"),
              track(reason="too few exits (0) for a rate", sections=None, rejects_by_tooling=None)):
        before = copy.deepcopy(s)
        unmeasured_sections(s)
        assert s == before


# -- the small pieces ---------------------------------------------------------------------------
def test_a_value_with_its_error_to_four_and_two_figures_in_the_same_unit():
    assert _pm(12.3456, 0.01234) == "12.35 ± 0.012"
    assert _pm(0.0123456, 4.56e-4, 1e3) == "12.35 ± 0.46"  # m/s as mm/s, both
    assert _pm(None, float("nan")) == "n/a ± n/a"


def test_a_sections_name_is_its_number_or_its_name():
    assert section_name({"section": 2}) == "2"
    assert section_name({"section": 1, "name": "helix"}) == "helix"


def test_fmt_scales_then_formats_and_says_n_a_for_what_is_not_a_number():
    assert fmt(0.5) == "0.5" and fmt(1 / 3) == "0.3333"  # unscaled, 4 figures
    assert fmt(7) == "7" and fmt(np.int64(3), 2) == "6"  # integers are numbers too
    assert fmt(2.5e-3, 1e3) == "2.5" and fmt(0.123456, 100, ".1f") == "12.3"
    for missing in (None, float("nan"), float("inf"), -float("inf"), np.float64("nan")):
        assert fmt(missing) == "n/a" and fmt(missing, 1e3, ".2g") == "n/a"


@pytest.mark.parametrize("seconds, text", [
    (59, "59s"), (60, "1m00s"), (125, "2m05s"),  # minutes from 60 s
    (3599, "59m59s"), (3600, "1h00m"), (7325, "2h02m"),  # hours from 3600 s, then no seconds
])
def test_a_duration_splits_at_60_and_3600_seconds(seconds, text):
    assert duration(seconds) == text


def test_to_json_gives_plain_lists_and_numbers_and_none_for_what_is_not_finite():
    value = {1: np.array([1.5, np.nan]), "t": (np.float64(2.5), np.int64(3), float("inf")), "s": "x",
             "n": None, "f": -float("inf"), "ok": 0.25}
    out = to_json(value)
    assert out == {"1": [1.5, None], "t": [2.5, 3, None], "s": "x", "n": None, "f": None, "ok": 0.25}
    assert type(out["t"][1]) is int and type(out["t"][0]) is float
    assert json.loads(json.dumps(out, allow_nan=False)) == out  # strict JSON


# -- the numeric options ------------------------------------------------------------------------
def refused(parse, text):
    with pytest.raises(argparse.ArgumentTypeError) as caught:
        parse(text)
    return str(caught.value)


def test_a_real_is_a_finite_number():
    assert real()("-2.5") == -2.5 and real()("1e-300") == 1e-300
    assert refused(real(), "abc") == "must be a number, got abc"
    assert refused(real(), "") == "must be a number, got nothing"
    for text in ("nan", "inf", "-inf", "1e400"):  # (1e400 overflows to inf)
        assert refused(real(), text) == f"must be a finite number, got {text}"


def test_above_is_strict_and_at_least_is_not():
    assert real(above=0)("1e-300") == 1e-300
    assert refused(real(above=0), "0") == "must be > 0, got 0"
    assert refused(real(above=0.5), "0.25") == "must be > 0.5, got 0.25"
    assert real(at_least=0)("0") == 0.0
    assert refused(real(at_least=0), "-1e-300") == "must be >= 0, got -1e-300"
    assert refused(real(at_least=2.5), "2") == "must be >= 2.5, got 2"
    assert real(above=-1, at_least=0)("0") == 0.0  # both limits hold
    assert refused(real(above=0, at_least=-1), "0") == "must be > 0, got 0"


def test_a_whole_number_from_its_minimum():
    assert whole(2)("2") == 2 and whole(2)("3") == 3
    assert refused(whole(2), "1") == "must be at least 2, got 1"
    assert refused(whole(1), "0") == "must be at least 1, got 0"
    assert whole()("-3") == -3  # no minimum
    for text in ("2.5", "3.0", "x", "nan"):
        assert refused(whole(1), text) == f"must be a whole number, got {text}"


def parser(command):
    p = argparse.ArgumentParser(prog=f"vibrofeed {command.__name__.rsplit('.', 1)[-1]}")
    command.add_arguments(p)
    return p


def usage_error(p, argv, capsys):
    with pytest.raises(SystemExit) as caught:
        p.parse_args(argv)
    assert caught.value.code == 2
    return capsys.readouterr().err.strip().split("\n")[-1]


def test_feedrates_options_defaults_and_limits(capsys):
    p = parser(feedrate)
    a = p.parse_args(["run.h5"])
    assert (a.result, a.start, a.end, a.batches, a.bins, a.no_model, a.json, a.plot) == \
        ("run.h5", None, None, 10, 20, False, False, None)
    a = p.parse_args(["run.h5", "--batches", "2", "--bins", "1", "--start", "-0.5", "--end", "2"])
    assert (a.batches, a.bins, a.start, a.end) == (2, 1, -0.5, 2.0)
    assert usage_error(p, ["run.h5", "--batches", "1"], capsys).endswith(
        "argument --batches: must be at least 2, got 1")
    assert usage_error(p, ["run.h5", "--bins", "0"], capsys).endswith(
        "argument --bins: must be at least 1, got 0")
    assert usage_error(p, ["run.h5", "--start", "nan"], capsys).endswith(
        "argument --start: must be a finite number, got nan")


def test_singulations_options_defaults_and_limits(capsys):
    p = parser(singulation)
    a = p.parse_args(["run.h5"])
    assert (a.gap, a.gap_distance, a.tolerance, a.start, a.end, a.cluster_frames) == \
        (None, None, None, None, None, 20)
    a = p.parse_args(["run.h5", "--gap", "1e-9", "--gap-distance", "0", "--tolerance", "0",
                      "--cluster-frames", "1"])
    assert (a.gap, a.gap_distance, a.tolerance, a.cluster_frames) == (1e-9, 0.0, 0.0, 1)
    a = p.parse_args(["run.h5", "--gap", "0.5", "--gap-distance", "0.5", "--tolerance", "0.5"])
    assert (a.gap, a.gap_distance, a.tolerance) == (0.5, 0.5, 0.5)
    assert usage_error(p, ["run.h5", "--gap", "0"], capsys).endswith("argument --gap: must be > 0, got 0")
    for option in ("--gap-distance", "--tolerance"):
        assert usage_error(p, ["run.h5", f"{option}=-1e-6"], capsys).endswith(
            f"argument {option}: must be >= 0, got -1e-6")
    assert usage_error(p, ["run.h5", "--cluster-frames", "0"], capsys).endswith("must be at least 1, got 0")
    assert usage_error(p, ["run.h5", "--end", "inf"], capsys).endswith("must be a finite number, got inf")


# -- vibrofeed singulation ------------------------------------------------------------------------
# mean clear gap in um (m x 1e6), just above and below 12.345 um
GAPS = {"above": (12.3450025e-6, "12.35"), "below": (12.3449975e-6, "12.34")}


def spheres(side="above", **changes):
    s = {"steady_from": 0.25, "steady_to": 1.5, "n_arrivals": 120, "reason": None,
         "mean_interarrival": 0.01042, "cv_interarrival": 0.4567, "doubles_rate": 0.125, "n_doubles": 15,
         "doubles_per_s": 12.0, "gap": None, "gap_distance": None, "tolerance": 3e-6,
         "singulated_fraction": 0.8, "mean_gap": GAPS[side][0], "edge_velocity": 0.02345,
         "cluster_sizes": {1: 30.5, 2: 4.25, 3: 0.5}, "track_singulated_fraction": 0.7631,
         "face_up_fraction": None, "face_down_fraction": None, "on_edge_fraction": None,
         "aligned_fraction": None, "orientation_yield": None}
    return s | changes


@pytest.mark.parametrize("side", GAPS)
def test_singulations_table_line_by_line_in_ms_percent_and_um(side):
    assert singulation.table(spheres(side)).split("\n") == [
        "window         0.25 .. 1.5 s, 120 arrivals",
        "inter-arrival  mean 10.42 ms, CV 0.457 (1: random, 0: periodic)",  # s x 1e3
        # fractions x 100 to 1 decimal
        "doubles        12.5 % of consecutive pairs (15, 12 /s; abreast or overlapping along the track, "
        "or touching)",
        f"singulated     80.0 % of the parts at the outlet; mean clear gap {GAPS[side][1]} um "
        "(edge speed 23.45 mm/s)",
        "clusters       per frame on the track, size: number = 1: 30.5, 2: 4.25, 3: 0.5; alone 76.3 %",
    ]


@pytest.mark.parametrize("gap, gap_distance, rule", [
    (1.234e-3, None, "closer than 1.234 ms"),  # s x 1e3
    (1e-3, 12.3450025e-6, "closer than 1 ms or 12.35 um"),  # m x 1e6
    (1e-3, 12.3449975e-6, "closer than 1 ms or 12.34 um"),
    (None, 12.3450025e-6, "closer than 12.35 um of clear track"),
    (None, 12.3449975e-6, "closer than 12.34 um of clear track"),
    (None, 0.0, "abreast or overlapping along the track"),  # no clear track at all
    (None, None, "abreast or overlapping along the track"),
])
def test_the_doubles_line_says_which_rule_counted_them(gap, gap_distance, rule):
    lines = singulation.table(spheres(gap=gap, gap_distance=gap_distance)).split("\n")
    assert lines[2] == f"doubles        12.5 % of consecutive pairs (15, 12 /s; {rule}, or touching)"


@pytest.mark.parametrize("sizes, shown", [
    ({}, "none"),
    ({k: k + 0.5 for k in range(1, 9)}, "1: 1.5, 2: 2.5, 3: 3.5, 4: 4.5, 5: 5.5, 6: 6.5, 7: 7.5, 8: 8.5"),
    # past eight sizes: the first eight and the largest size (not its number, 9.5)
    ({k: k + 0.5 for k in range(1, 10)}, "1: 1.5, 2: 2.5, 3: 3.5, 4: 4.5, 5: 5.5, 6: 6.5, 7: 7.5, 8: 8.5, "
                                         "... up to 9"),
    ({1: 12.345, 12: 0.125}, "1: 12.3, 12: 0.125"),  # 3 figures
])
def test_the_cluster_sizes_are_eight_at_most(sizes, shown):
    lines = singulation.table(spheres(cluster_sizes=sizes)).split("\n")
    assert lines[4] == f"clusters       per frame on the track, size: number = {shown}; alone 76.3 %"


def test_chips_get_their_orientation_and_yield_in_percent():
    chips = spheres(face_up_fraction=0.62, face_down_fraction=0.3, on_edge_fraction=0.08,
                    aligned_fraction=0.75, orientation_yield=0.5)
    assert singulation.table(chips).split("\n")[5:] == [
        "orientation    face up 62.0 %, face down 30.0 %, on edge 8.0 %; aligned with the track 75.0 %",
        "yield          50.0 % of the parts delivered face up and aligned with the track (each part both)",
    ]
    chips["orientation_yield"] = None
    assert singulation.table(chips).split("\n")[5:] == [
        "orientation    face up 62.0 %, face down 30.0 %, on edge 8.0 %; aligned with the track 75.0 %"]


def test_too_few_arrivals_give_the_reason_and_n_a_for_their_statistics():
    s = spheres(**dict.fromkeys(singulation.ARRIVAL_KEYS), n_arrivals=1, n_doubles=0,
                reason="too few arrivals (1) for their statistics")
    assert singulation.table(s).split("\n")[:4] == [
        "window         0.25 .. 1.5 s, 1 arrivals; too few arrivals (1) for their statistics",
        "inter-arrival  mean n/a ms, CV n/a (1: random, 0: periodic)",
        "doubles        n/a % of consecutive pairs (0, n/a /s; abreast or overlapping along the track, "
        "or touching)",
        "singulated     n/a % of the parts at the outlet; mean clear gap n/a um (edge speed 23.45 mm/s)",
    ]


# -- the commands, with the analysis replaced by the summaries above ----------------------------------
class Analysis:
    """Stands for FeedRate / Singulation: records its arguments, gives ``summary``."""

    made: list = []

    def __init__(self, result, **options):
        self.made.append((result, options))

    def run(self):
        return self

    def summary(self):
        return copy.deepcopy(self.given)


class Result:
    def __init__(self, path):
        self.path = path

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


@pytest.fixture
def analysis(monkeypatch):
    """The modules `run` imports, replaced: no result file is read, no figure drawn."""
    from vibrofeed.cli import outputs

    monkeypatch.setattr(outputs, "_destinations", [])
    Analysis.made = []
    drawn = []

    def figures(name):
        def draw(analysis, folder):
            drawn.append((analysis, folder))
            path = folder / f"{name}.txt"
            path.write_text("drawn")
            return [path]
        return draw

    modules = {"vibrofeed.results.reader": {"Result": Result},
               "vibrofeed.postproc.feedrate": {"FeedRate": Analysis},
               "vibrofeed.postproc.singulation": {"Singulation": Analysis},
               "vibrofeed.pictures.plots": {"feedrate_figures": figures("feedrate"),
                                            "singulation_figures": figures("singulation")}}
    for name, names in modules.items():
        module = types.ModuleType(name)
        module.__dict__.update(names)
        monkeypatch.setitem(sys.modules, name, module)
    return drawn


def test_feedrate_prints_its_table_and_passes_the_options_on(analysis, capsys, tmp_path):
    Analysis.given = line()
    p = parser(feedrate)
    args = p.parse_args(["run.h5", "--start", "0.2", "--end", "1", "--batches", "5", "--bins", "8",
                         "--no-model"])
    assert feedrate.run(args) == 0
    (result, options), = Analysis.made
    assert result.path == "run.h5"
    assert options == {"start": 0.2, "end": 1.0, "batches": 5, "bins": 8, "model": False}
    # no --plot: nothing drawn
    assert capsys.readouterr().out == feedrate.table(line()) + "\n" and analysis == []
    # --plot DIR: drawn there and named after the table
    args = p.parse_args(["run.h5", "--plot", str(tmp_path / "figures")])
    assert feedrate.run(args) == 0
    assert Analysis.made[1][1]["model"] is True and analysis[0][1] == tmp_path / "figures"
    out = capsys.readouterr().out.split("\n")
    assert out[-2:] == [f"figure: {tmp_path / 'figures' / 'feedrate.txt'}", ""]


def test_feedrate_with_a_reason_prints_null_rates_and_fails(analysis, capsys):
    Analysis.given = line(reason="not steady: the conveying speed drifts")
    assert feedrate.run(parser(feedrate).parse_args(["run.h5", "--json"])) == 1
    out, err = capsys.readouterr()
    figures = json.loads(out)
    assert [figures[k] for k in feedrate.RATE_KEYS] == [None] * 4
    assert figures["sections"][0]["joint_flux"] is None and figures["sections"][0]["speed"] == 0.01234
    assert figures["rejects_by_tooling"]["wiper"] == {"per_s": None, "per_s_error": None, "in_window": 16,
                                                      "total": 40}
    assert err == "vibrofeed: error: run.h5: not steady: the conveying speed drifts\n"


def test_singulation_prints_its_table_and_passes_the_options_on(analysis, capsys, tmp_path):
    Analysis.given = spheres()
    p = parser(singulation)
    args = p.parse_args(["run.h5", "--gap", "1e-3", "--gap-distance", "2e-6", "--tolerance", "1e-6",
                         "--start", "0.1", "--end", "0.9", "--cluster-frames", "4"])
    assert singulation.run(args) == 0
    (result, options), = Analysis.made
    assert result.path == "run.h5"
    assert options == {"gap": 1e-3, "gap_distance": 2e-6, "tolerance": 1e-6, "start": 0.1, "end": 0.9,
                       "cluster_frames": 4}
    assert capsys.readouterr().out == singulation.table(spheres()) + "\n" and analysis == []
    assert singulation.run(p.parse_args(["run.h5", "--plot", str(tmp_path)])) == 0
    assert capsys.readouterr().out.endswith(f"\nfigure: {tmp_path / 'singulation.txt'}\n")
    # too few arrivals: their statistics null, the reason on stderr, exit 1
    Analysis.given = spheres(reason="too few arrivals (1) for their statistics")
    assert singulation.run(p.parse_args(["run.h5", "--json"])) == 1
    out, err = capsys.readouterr()
    figures = json.loads(out)
    assert [figures[k] for k in singulation.ARRIVAL_KEYS] == [None] * len(singulation.ARRIVAL_KEYS)
    assert figures["edge_velocity"] == 0.02345
    assert err == "vibrofeed: error: run.h5: too few arrivals (1) for their statistics\n"
