"""The study file (vibrofeed.optimize.spec): what it accepts, and every refusal in one line
naming the line of the file; inequalities evaluated as written."""

import textwrap

import pytest

from vibrofeed.errors import InputError
from vibrofeed.optimize.spec import parse

GOOD = textwrap.dedent("""\
    deck = "bulk_feeder"
    seed = 11

    [fixed]
    sections = 2
    amp_t = 3.5e-5

    [variables]
    s2_amp_t = { low = 6e-5, high = 2.4e-4 }
    freq = { low = 50, high = 200, log = true }
    inlet_batch = { low = 1, high = 4, type = "int" }
    shape = { choices = [0, 1] }

    [constraints]
    max_acceleration = 6.0
    frequency = [50, 200]
    require = ["s2_amp_t >= 2 * amp_t", "abs(s2_amp_t - amp_t) < 2e-4"]

    [objective]
    maximize = "singulated_rate"
    at_least = { parts_per_s = 25 }

    [budget]
    runs = 12
    seeds = 4

    [robustness]
    mu = [0.4, 0.6]
    """)


def test_a_good_study_reads_as_written():
    s = parse(GOOD, "study.toml")
    assert s.deck == "bulk_feeder" and s.seed == 11 and s.fixed == {"sections": 2, "amp_t": 3.5e-5}
    kinds = {v.name: (v.kind, v.low, v.high, v.log, v.choices) for v in s.variables}
    assert kinds == {"s2_amp_t": ("float", 6e-5, 2.4e-4, False, []), "freq": ("float", 50, 200, True, []),
                     "inlet_batch": ("int", 1, 4, False, []), "shape": ("choice", None, None, False, [0, 1])}
    assert s.maximize == ["singulated_rate"] and not s.multi and s.at_least == {"parts_per_s": 25}
    assert s.budget == {"runs": 12, "seeds": 4, "screen": 256, "confirm": 3, "replicates": 3}
    assert s.robustness == {"mu": [0.4, 0.6]}
    assert s.parameters == ["sections", "amp_t", "s2_amp_t", "freq", "inlet_batch", "shape"]
    # the fingerprint follows the content, not the layout
    assert parse(GOOD.replace("seed = 11", "seed  =  11  # the sampler's"), "x").fingerprint == s.fingerprint
    assert parse(GOOD.replace("seed = 11", "seed = 12"), "x").fingerprint != s.fingerprint


def test_inequalities_hold_and_break_by_their_margin():
    s = parse(GOOD, "study.toml")
    ratio, spread = s.inequalities
    assert ratio.holds({"s2_amp_t": 7e-5, "amp_t": 3.5e-5})  # exactly 2x: >= holds
    assert not ratio.holds({"s2_amp_t": 6.9e-5, "amp_t": 3.5e-5})
    assert ratio.margin({"s2_amp_t": 6e-5, "amp_t": 3.5e-5}) == pytest.approx(1e-5, rel=1e-9)
    assert not spread.holds({"s2_amp_t": 2.4e-4, "amp_t": 3.5e-5})  # 2.05e-4: < fails
    assert spread.margin({"s2_amp_t": 1e-4, "amp_t": 3.5e-5}) == pytest.approx(-1.35e-4, rel=1e-9)


@pytest.mark.parametrize("change, line, words", [
    (("[budget]", "[budget]\nflights = 3"), 24, "unknown key flights in [budget]"),
    (('maximize = "singulated_rate"', 'maximize = "speed"'), 20, "unknown metric speed"),
    (('maximize = "singulated_rate"', 'maximize = ["parts_per_s", "parts_per_s"]'), 20, "the same metric"),
    (("freq = { low = 50, high = 200, log = true }", "freq = { low = 200, high = 50 }"), 10,
     "needs numbers low < high"),
    (("freq = { low = 50, high = 200, log = true }", "freq = { low = 0, high = 50, log = true }"), 10,
     "log scale needs low > 0"),
    (("inlet_batch = { low = 1, high = 4, type = \"int\" }", "inlet_batch = { low = 1, high = 4.5, "
      "type = \"int\" }"), 11, "whole bounds"),
    (("shape = { choices = [0, 1] }", "shape = { choices = [0, 0] }"), 12, "listed twice"),
    (('"s2_amp_t >= 2 * amp_t"', '"__import__(1) > 0"'), 17, "calls something other"),
    (('"s2_amp_t >= 2 * amp_t"', '"s2_amp_t == amp_t"'), 17, "one comparison"),
    (("max_acceleration = 6.0", "max_acceleration = -1"), 15, "must be a number > 0"),
    (("frequency = [50, 200]", "frequency = [200, 50]"), 16, "0 < low < high"),
    (("runs = 12", "runs = 3"), 25, "seeds (4) exceeds runs (3)"),
    (("mu = [0.4, 0.6]", "freq = [60, 80]"), 28, "freq is a design variable"),
    (("amp_t = 3.5e-5", "s2_amp_t = 1e-4"), 9, "s2_amp_t is set twice"),
    (("[objective]", "[objectives]"), 19, "unknown key objectives"),
    (("seed = 11", "seed = 11\ntarget_error = 1.5"), 3, "target_error must be a number in (0, 1)"),
])
def test_refusals_name_the_line(change, line, words):
    text = GOOD.replace(*change)
    assert text != GOOD
    with pytest.raises(InputError) as err:
        parse(text, "study.toml")
    message = str(err.value)
    assert words in message and "\n" not in message
    assert message.startswith(f"study.toml:{line}:"), message


def test_a_study_needs_variables_and_an_objective():
    with pytest.raises(InputError, match="no design variables"):
        parse('deck = "bulk_feeder"\n[objective]\nmaximize = "parts_per_s"\n', "s.toml")
    with pytest.raises(InputError, match="maximize must name a metric"):
        parse('deck = "bulk_feeder"\n[variables]\nfreq = { low = 50, high = 60 }\n', "s.toml")


FREQ = "freq = { low = 50, high = 200, log = true }"


@pytest.mark.parametrize("change, words", [
    (('require = ["s2_amp_t >= 2 * amp_t", "abs(s2_amp_t - amp_t) < 2e-4"]', 'require = "s2_amp_t > 0"'),
     "require must list inequalities as strings"),
    (('"s2_amp_t >= 2 * amp_t"', '"s2_amp_t >= >= 2"'), "is not an inequality"),
    ((FREQ, "freq = { low = 50, high = inf }"), "needs numbers low < high"),
    ((FREQ, "freq = { low = nan, high = 200 }"), "needs numbers low < high"),
    (("max_acceleration = 6.0", "max_acceleration = 0"), "must be a number > 0"),
    (('maximize = "singulated_rate"', 'maximize = ["parts_per_s", "singulated_fraction", "doubles_rate"]'),
     "or two (a Pareto front)"),
    (("seeds = 4", "seeds = -1"), "seeds must be a whole number >= 0"),
    (("seed = 11", "seed = 11\nranks_per_run = 0"), "ranks_per_run must be a whole number >= 1"),
])
def test_more_refusals_at_their_boundaries(change, words):
    text = GOOD.replace(*change)
    assert text != GOOD
    with pytest.raises(InputError) as err:
        parse(text, "study.toml")
    assert words in str(err.value) and "\n" not in str(err.value)


def test_defaults_and_two_objectives():
    s = parse('deck = "bulk_feeder"\n[variables]\nfreq = { low = 50, high = 60 }\n[objective]\n'
              'maximize = ["parts_per_s", "singulated_fraction"]\n', "s.toml")
    assert s.multi and s.maximize == ["parts_per_s", "singulated_fraction"]
    assert s.budget == {"runs": 20, "seeds": 6, "screen": 256, "confirm": 3, "replicates": 3}
    assert s.seed == 5489 and s.ranks_per_run == 1 and s.target_error is None and s.at_least == {}
    # zero is a bound a study may state (0 <= seeds, confirm)
    s0 = parse(GOOD.replace("seeds = 4", "seeds = 0"), "s.toml")
    assert s0.budget["seeds"] == 0


@pytest.mark.parametrize("change, words", [
    # each bound exactly at its limit is refused where the rule is strict
    ((FREQ, "freq = { low = 50, high = 50 }"), "needs numbers low < high"),
    (("frequency = [50, 200]", "frequency = [0, 200]"), "0 < low < high"),
    (("frequency = [50, 200]", "frequency = [100, 100]"), "0 < low < high"),
    (("seed = 11", "seed = -1"), "seed must be a whole number >= 0"),
    (("seed = 11", "seed = 1.5"), "seed must be a whole number >= 0"),
    (("seed = 11", "seed = true"), "seed must be a whole number >= 0"),
    (('deck = "bulk_feeder"', 'deck = "   "'), "deck must be a deck name or file"),
    # section numbers start at 1; a boolean is not a section; one number is not a list
    (("max_acceleration = 6.0", "no_hopping = [0]"), "no_hopping must list section numbers"),
    (("max_acceleration = 6.0", "no_hopping = [true]"), "no_hopping must list section numbers"),
    (("max_acceleration = 6.0", "no_hopping = 2"), "no_hopping must list section numbers"),
    # one choice is no choice; a choice is a scalar
    (("shape = { choices = [0, 1] }", "shape = { choices = [0] }"), "choices must list two or more"),
    (("shape = { choices = [0, 1] }", "shape = { choices = [[0], 1] }"), "choices must list two or more"),
    (("shape = { choices = [0, 1] }", "shape = { choices = 0 }"), "choices must list two or more"),
    (("at_least = { parts_per_s = 25 }", "at_least = { speed = 25 }"), "at_least: speed = 25 must be"),
    (("at_least = { parts_per_s = 25 }", 'at_least = { parts_per_s = "many" }'), "must be a known metric"),
    (('maximize = "singulated_rate"', "maximize = []"), "maximize must name a metric"),
    (("seeds = 4", "seeds = 4\nreplicates = 0"), "replicates must be a whole number >= 1"),
    (("seeds = 4", "seeds = 4\nreplicates = 2.5"), "replicates must be a whole number >= 1"),
    (("seeds = 4", "seeds = 4\nconfirm = true"), "confirm must be a whole number >= 0"),
    (("seeds = 4", "seeds = 4\nscreen = 3"), "screen (3) must be at least seeds (4)"),
    # screen = 1000000000 ended in a memory traceback (and would have screened for years)
    (("seeds = 4", "seeds = 4\nscreen = 10001"), "screen = 10001 is more settings than the models "
                                                 "screen in reasonable time: at most 10000"),
    (("seeds = 4", "seeds = 4\nscreen = 1000000000"), "at most 10000 (about 90 ms a setting"),
    (("mu = [0.4, 0.6]", "mu = []"), "robustness mu must list the values to try"),
    (("mu = [0.4, 0.6]", "mu = 0.4"), "robustness mu must list the values to try"),
    (("mu = [0.4, 0.6]", "mu = [[0.4]]"), "robustness mu must list the values to try"),
])
def test_refusals_at_and_just_past_each_limit(change, words):
    text = GOOD.replace(*change)
    assert text != GOOD
    with pytest.raises(InputError) as err:
        parse(text, "study.toml")
    assert words in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("key", ["fixed", "variables", "constraints", "objective", "budget", "robustness"])
def test_each_section_must_be_a_table(key):
    text = f'deck = "bulk_feeder"\n{key} = 3\n'
    with pytest.raises(InputError, match=rf"^s\.toml:2: {key} must be a table \[{key}\]$"):
        parse(text, "s.toml")


@pytest.mark.parametrize("change, check", [
    # the lowest values each rule allows are accepted as given
    (("seed = 11", "seed = 0"), lambda s: s.seed == 0),
    (("frequency = [50, 200]", "frequency = [0.5, 200]"), lambda s: s.constraints["frequency"] == [0.5, 200]),
    (("max_acceleration = 6.0", "no_hopping = [1, 2]"), lambda s: s.constraints["no_hopping"] == [1, 2]),
    (("runs = 12", "runs = 4"), lambda s: s.budget["runs"] == s.budget["seeds"] == 4),  # seeds == runs
    (("seeds = 4", "seeds = 4\nscreen = 4"), lambda s: s.budget["screen"] == 4),  # screen == seeds
    (("seeds = 4", "seeds = 4\nscreen = 10000"), lambda s: s.budget["screen"] == 10_000),
    (("runs = 12\nseeds = 4", "runs = 1\nseeds = 1\nscreen = 1\nconfirm = 0\nreplicates = 1"),
     lambda s: s.budget == {"runs": 1, "seeds": 1, "screen": 1, "confirm": 0, "replicates": 1}),
    (("mu = [0.4, 0.6]", 'mu = [0.5]\nmesh = ["chip.stl"]'),
     lambda s: s.robustness == {"mu": [0.5], "mesh": ["chip.stl"]}),
])
def test_values_at_each_limit_are_accepted(change, check):
    text = GOOD.replace(*change)
    assert text != GOOD
    assert check(parse(text, "study.toml"))


def study_with(require: str):
    return parse(GOOD.replace('["s2_amp_t >= 2 * amp_t", "abs(s2_amp_t - amp_t) < 2e-4"]', require), "s.toml")


def test_strict_inequalities_fail_at_equality_and_others_hold_by_any_amount():
    spec = study_with('["amp_t < s2_amp_t", "amp_t > s2_amp_t", "amp_t <= s2_amp_t"]')
    less, more, at_most = spec.inequalities
    equal = {"amp_t": 5e-5, "s2_amp_t": 5e-5}
    assert less.margin(equal) == 0.0 and not less.holds(equal) and not more.holds(equal)
    assert at_most.holds(equal)
    # a margin well inside (-1, 0) still holds: the sign decides, not the size
    small = {"amp_t": 5e-5, "s2_amp_t": 6e-5}
    assert less.margin(small) == pytest.approx(-1e-5, rel=1e-9) and less.holds(small)
    assert more.margin(small) == pytest.approx(1e-5, rel=1e-9) and not more.holds(small)


def test_signs_in_an_inequality_are_evaluated():
    neg, pos = study_with('["-amp_t > -2 * s2_amp_t", "+amp_t <= s2_amp_t"]').inequalities
    values = {"amp_t": 3.5e-5, "s2_amp_t": 1e-4}
    # > : margin = right - left = -2 * 1e-4 - (-3.5e-5)
    assert neg.margin(values) == pytest.approx(3.5e-5 - 2e-4, rel=1e-9) and neg.holds(values)
    # unary plus changes nothing: 3.5e-5 - 1e-4
    assert pos.margin(values) == pytest.approx(3.5e-5 - 1e-4, rel=1e-9)


@pytest.mark.parametrize("key", ["confirm", "replicates"])
def test_confirmation_runs_fit_their_job_numbers(key):
    # confirmation runs are jobs 10000 + 100 x rank + replicate (rows of the ledger by job):
    # a 101st rank or replicate would take another run's number
    assert parse(GOOD.replace("seeds = 4", f"seeds = 4\n{key} = 100"), "s.toml").budget[key] == 100
    with pytest.raises(InputError) as err:
        parse(GOOD.replace("seeds = 4", f"seeds = 4\n{key} = 101"), "study.toml")
    assert str(err.value).startswith(f"study.toml:26: {key} must be at most 100")
    assert "\n" not in str(err.value)
