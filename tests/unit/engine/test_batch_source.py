"""The executor takes its items lazily (vibrofeed.engine.batch): a generator decides the next
item from the answers so far and may yield WAIT until one finishes; a list runs as before."""

import threading

import pytest

from vibrofeed.engine import batch


def test_a_list_runs_every_item_workers_at_a_time():
    lock, running, most, answers = threading.Lock(), [0], [0], {}

    def work(item):
        with lock:
            running[0] += 1
            most[0] = max(most[0], running[0])
        threading.Event().wait(0.02)
        with lock:
            running[0] -= 1
        return item * item

    batch.run_local(range(6), 2, work, finished=answers.__setitem__)
    assert answers == {k: k * k for k in range(6)} and most[0] == 2


def test_a_generator_decides_from_the_answers_and_waits_for_them():
    answers: dict = {}

    def source():
        yield 1
        yield 2
        while len(answers) < 2:  # the third item depends on both answers
            yield batch.WAIT
        yield answers[1] + answers[2]

    pulled_while_running = []
    batch.run_local(source(), 2, lambda item: item * 10,
                    started=pulled_while_running.append, finished=answers.__setitem__)
    assert pulled_while_running == [1, 2, 30] and answers == {1: 10, 2: 20, 30: 300}


def test_a_source_that_waits_with_nothing_running_is_an_error_not_a_hang():
    def source():
        yield batch.WAIT

    with pytest.raises(RuntimeError, match="wait forever"):
        batch.run_local(source(), 1, lambda item: item)
