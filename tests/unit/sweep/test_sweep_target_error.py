"""A sweep's target_error: every job stops at that relative feed-rate error (run_deck's
target_error), its run id says so, and a deck without an outlet is refused naming the line."""

import pytest

from vibrofeed.engine.runner import run_id
from vibrofeed.errors import InputError
from vibrofeed.sweep.plan import plan
from vibrofeed.sweep.spec import parse

BULK = 'deck = "bulk_feeder"\ntarget_error = 0.05\n[grid]\namp_n = [5e-5, 7e-5]\n'


def test_every_job_carries_the_target_and_its_run_id_says_so():
    jobs = plan(parse(BULK, "s.toml"))
    assert [j.target_error for j in jobs] == [0.05, 0.05]
    from vibrofeed.sweep.plan import find_deck

    deck = find_deck(parse(BULK, "s.toml"))
    for j in jobs:
        assert j.run_id == run_id(deck, j.values, target_error=0.05)
        assert j.run_id != run_id(deck, j.values)  # another computation than the run to t_end
    assert all(j.target_error is None for j in plan(parse(BULK.replace("target_error = 0.05\n", ""), "s")))


@pytest.mark.parametrize("text, words", [
    ('deck = "single_part"\ntarget_error = 0.05\n[grid]\nphase = [0, 30]\n', "s.toml:2: target error: deck "
                                                                              "single_part has no outlet"),
    (BULK.replace("0.05", "1.5"), "s.toml:2: target_error must be a number in (0, 1)"),
])
def test_a_target_that_cannot_be_met_is_refused_naming_its_line(text, words):
    with pytest.raises(InputError) as err:
        plan(parse(text, "s.toml"))
    assert words in str(err.value) and "\n" not in str(err.value)
