"""A feeder description's dotted names (``element.2.drive.amp_t``) in sweep and study files, as
``-p`` takes them: written bare (TOML reads a bare dotted key as nested tables) or quoted, in
every table that sets parameters; the line of each named in a refusal; one parameter set by both
names refused; a study runs them by the deck's own names and its report reads them back."""

from __future__ import annotations

import pytest

from helpers import REPO
from vibrofeed.errors import ParameterError
from vibrofeed.optimize.search import own_names
from vibrofeed.optimize.spec import parse as parse_study
from vibrofeed.sweep import plan as P
from vibrofeed.sweep.spec import parse

LINE = REPO / "feeders" / "three_section_line.toml"
SWEEP = f"""deck = "{LINE}"
[fixed]
run.t_end = 0.5
[grid]
element.3.drive.amp_t = [1e-4, 2e-4]
[zip.drop]
"element.2.side_drop.width" = [5e-4, 5.5e-4]
element.2.step = [5e-5, 6e-5]
[[point]]
supply.inlet_rate = 20
"""


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # generated decks go there


def test_bare_and_quoted_dotted_names_are_one_name_each_at_its_line():
    spec = parse(SWEEP, "s.toml")
    assert spec.fixed == {"run.t_end": 0.5}
    assert spec.varied == ["element.3.drive.amp_t", "element.2.side_drop.width", "element.2.step",
                           "supply.inlet_rate"]
    lines = [spec.line_of(*spec.place(n)) for n in ["run.t_end", *spec.varied]]
    assert lines == [3, 5, 7, 8, 10]


def test_a_sweep_runs_a_description_by_its_dotted_names_as_by_the_decks():
    dotted = P.plan(parse(SWEEP, "s.toml"))
    own = P.plan(parse(SWEEP.replace("run.t_end", "t_end").replace("element.3.drive.amp_t", "s3_amp_t")
                       .replace('"element.2.side_drop.width"', "s2_drop_width")
                       .replace("element.2.step", "s2_step").replace("supply.inlet_rate", "inlet_rate"),
                       "s.toml"))
    assert len(dotted) == len(own) == 4
    assert [j.values for j in dotted] == [j.values for j in own]
    # the grid varies slowest: the zip's two settings at 1e-4, then at 2e-4
    assert [j.values["s3_amp_t"] for j in dotted] == ["0.0001", "0.0001", "0.0002", "0.0002"]
    assert [j.values["s2_step"] for j in dotted] == ["5e-05", "6e-05"] * 2
    assert dotted[0].values["t_end"] == "0.5" and dotted[0].values["inlet_rate"] == "20"


def test_a_sweeps_slips_with_dotted_names_name_them():
    typo = SWEEP.replace("element.3.drive.amp_t", "element.3.drive.amp_tt")
    said = (r"^s.toml:5: unknown parameter element.3.drive.amp_tt for deck three_section_line "
            r"\(did you mean element.3.drive.amp_t\?\)")
    with pytest.raises(ParameterError, match=said):
        P.plan(parse(typo, "s.toml"))
    twice = SWEEP.replace("run.t_end = 0.5", "run.t_end = 0.5\nt_end = 0.6")
    with pytest.raises(ParameterError, match="parameter t_end given twice, as run.t_end and as t_end"):
        P.plan(parse(twice, "s.toml"))


STUDY = f"""deck = "{LINE}"
[fixed]
run.t_end = 0.5
[variables]
element.3.drive.amp_t = {{ low = 1e-4, high = 2e-4 }}
"element.2.drive.phase" = {{ low = -60, high = 0 }}
[robustness]
parts.mu = [0.4, 0.6]
[objective]
maximize = "parts_per_s"
"""


def test_a_study_reads_dotted_names_and_runs_them_by_the_decks_own():
    from vibrofeed.sweep.plan import find_deck

    spec = parse_study(STUDY, "st.toml")
    assert [v.name for v in spec.variables] == ["element.3.drive.amp_t", "element.2.drive.phase"]
    assert (spec.variables[0].low, spec.variables[0].high) == (1e-4, 2e-4)
    own = own_names(spec, find_deck(spec))
    assert [v.name for v in own.variables] == ["s3_amp_t", "s2_phase"]
    assert own.fixed == {"t_end": 0.5} and own.robustness == {"mu": [0.4, 0.6]}
    assert own.where("variables", "s3_amp_t") == "st.toml:5" and own.where("robustness", "mu") == "st.toml:8"
    # the report re-reads the file as it ran, and the study file's renaming
    assert [v.name for v in spec.renamed(own.renames).variables] == ["s3_amp_t", "s2_phase"]


def test_a_study_setting_one_parameter_by_both_names_is_refused_at_its_line():
    from vibrofeed.sweep.plan import find_deck

    spec = parse_study(STUDY.replace("[variables]", "[variables]\ns3_amp_t = { low = 1e-4, high = 3e-4 }"),
                       "st.toml")
    with pytest.raises(ParameterError, match=r"^st.toml:6: parameter s3_amp_t is set twice, as s3_amp_t and "
                                             r"as element.3.drive.amp_t"):
        own_names(spec, find_deck(spec))
    spec = parse_study(STUDY.replace("parts.mu", "s3_amp_t"), "st.toml")
    with pytest.raises(ParameterError, match=r"^st.toml:8: s3_amp_t is a design variable"):
        own_names(spec, find_deck(spec))
