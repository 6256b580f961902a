"""The executor without LIGGGHTS or MPI: run_many with run_deck faked, and the MPI dispatch
and serve on a fake communicator (a fake mpi4py): which ranks lead, get items, poll how often."""

from __future__ import annotations

import sys
import threading
import time
import types
from collections import deque
from pathlib import Path
from types import SimpleNamespace

import pytest

from vibrofeed.engine import batch
from vibrofeed.errors import RunError


# ---------------------------------------------------------------- run_many
def test_run_many_gives_an_outcome_per_request_in_order_with_its_ranks(monkeypatch):
    seen = []

    def run_deck(deck, params, output, ranks, **kw):
        seen.append((output.name, ranks))
        if output.name == "bad.h5":
            raise RunError("LIGGGHTS error")
        return SimpleNamespace(reused=False)

    monkeypatch.setattr(batch, "run_deck", run_deck)
    requests = [batch.RunRequest(None, {}, Path(n)) for n in ("a.h5", "bad.h5", "c.h5")]
    outcomes = batch.run_many(requests, jobs=2)
    assert [o.request for o in outcomes] == requests
    assert [o.ok for o in outcomes] == [True, False, True]
    assert sorted(seen) == [("a.h5", 1), ("bad.h5", 1), ("c.h5", 1)]  # one rank unless told


def _most_at_once(run):
    """run(work) with a work that takes 20 ms: the most items it ran at once."""
    lock, running, most = threading.Lock(), [0], [0]

    def work(*args, **kw):
        with lock:
            running[0] += 1
            most[0] = max(most[0], running[0])
        time.sleep(0.02)
        with lock:
            running[0] -= 1
        return SimpleNamespace(reused=False)

    run(work)
    return most[0]


@pytest.mark.parametrize("workers", [0, 1])
def test_run_local_runs_one_at_a_time_for_one_worker_or_none(workers):
    assert _most_at_once(lambda work: batch.run_local(range(3), workers, work)) == 1


def test_run_many_runs_one_at_a_time_unless_told(monkeypatch):
    requests = [batch.RunRequest(None, {}, Path(f"{k}.h5")) for k in range(3)]

    def run(work):
        monkeypatch.setattr(batch, "run_deck", work)
        batch.run_many(requests)

    assert _most_at_once(run) == 1


def test_run_many_tells_each_runs_states(monkeypatch):
    monkeypatch.setattr(batch, "run_deck", lambda d, p, output, **kw: SimpleNamespace(
        reused=output.name == "old.h5"))
    states = []
    requests = [batch.RunRequest(None, {}, Path(n)) for n in ("new.h5", "old.h5")]
    batch.run_many(requests, on_state=lambda r, s: states.append((r.output.name, s)))
    assert sorted(states) == [("new.h5", "done"), ("new.h5", "running"), ("old.h5", "reused"),
                              ("old.h5", "running")]


def test_a_bug_in_one_run_is_raised_after_the_others_finished(monkeypatch):
    finished = []

    def run_deck(deck, params, output, **kw):
        if output.name == "bug.h5":
            raise KeyError("bug")
        time.sleep(0.1)
        finished.append(output.name)
        return SimpleNamespace(reused=False)

    monkeypatch.setattr(batch, "run_deck", run_deck)
    requests = [batch.RunRequest(None, {}, Path(n)) for n in ("bug.h5", "slow.h5")]
    with pytest.raises(KeyError, match="bug"):
        batch.run_many(requests, jobs=2)
    assert finished == ["slow.h5"]


# ---------------------------------------------------------------- a fake MPI
class Status:
    source = tag = None

    def Get_source(self):
        return self.source

    def Get_tag(self):
        return self.tag


@pytest.fixture
def mpi(monkeypatch):
    fake_mpi = SimpleNamespace(Status=Status, ANY_SOURCE=-1, ANY_TAG=-1, COMM_WORLD=None)
    monkeypatch.setitem(sys.modules, "mpi4py", types.SimpleNamespace(MPI=fake_mpi))
    monkeypatch.setattr(batch, "_released", False)
    return fake_mpi


class Comm:
    """Ranks 1.. of ``size``: a leader sent an item answers ``leader(item)`` at once."""

    def __init__(self, size, leader=lambda item: item * 10):
        self.size, self.leader = size, leader
        self.sent, self.answers = [], deque()

    def Get_size(self):
        return self.size

    def send(self, obj, dest, tag):
        self.sent.append((dest, tag, obj))
        if tag == batch.TAG_JOB:
            self.answers.append((dest, self.leader(obj)))

    def Iprobe(self, source, tag, status):
        if not self.answers:
            return False
        status.source = self.answers[0][0]
        return True

    def recv(self, source, tag):
        rank, answer = self.answers.popleft()
        assert rank == source
        return answer


def test_world_is_none_for_one_rank_under_a_launcher(mpi, monkeypatch):
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "1")
    mpi.COMM_WORLD = Comm(1)
    assert batch.world() is None
    mpi.COMM_WORLD = Comm(2)
    assert batch.world() is mpi.COMM_WORLD


@pytest.mark.parametrize("size, per_run, leaders", [(3, 1, {1, 2}), (5, 2, {2}), (7, 3, {3})])
def test_dispatch_hands_items_to_every_other_whole_groups_leader(mpi, size, per_run, leaders):
    comm = Comm(size)
    finished = {}
    batch.dispatch(comm, range(8), {"ranks": per_run}, lambda item: item * 10,
                   finished=finished.__setitem__)
    assert finished == {k: 10 * k for k in range(8)}
    assert {dest for dest, tag, _ in comm.sent if tag == batch.TAG_JOB} == leaders
    stops = [dest for dest, tag, _ in comm.sent if tag == batch.TAG_STOP]
    assert stops == list(range(1, size))


def test_serve_polls_often_only_as_a_leader_of_a_whole_group(mpi, monkeypatch):
    """Of 3 ranks in groups of 2, rank 2 is in no whole group: it holds no slot that runs."""
    intervals = []

    class Served:
        def __init__(self, rank):
            self.rank, self.inbox = rank, deque([(batch.TAG_SETUP, ("setup", {"ranks": 2})),
                                                  (batch.TAG_STOP, None)])

        def Get_rank(self):
            return self.rank

        def Get_size(self):
            return 3

        def recv(self, source, tag):
            assert source == 0  # every message a rank gets is rank 0's
            return self.inbox.popleft()[1]

    def wait(comm, source, tag, interval):
        intervals.append(interval)
        tag = comm.inbox[0][0]  # the next message's, as Iprobe's status says it
        return SimpleNamespace(Get_tag=lambda: tag)

    monkeypatch.setattr(batch, "_wait", wait)
    assert batch.serve(Served(2), lambda setup: None) == 0
    assert intervals == [batch.IDLE_POLL, batch.IDLE_POLL]
    intervals.clear()
    with monkeypatch.context() as m:
        m.setattr(Served, "Get_size", lambda self: 4)  # now rank 2 leads the group {2, 3}
        assert batch.serve(Served(2), lambda setup: None) == 0
    assert intervals == [batch.IDLE_POLL, batch.POLL]


def test_a_rank_told_to_exit_ends_at_once(mpi, monkeypatch):
    class Told:
        def recv(self, source, tag):
            assert (source, tag) == (0, batch.TAG_SETUP)
            return ("exit", None)

    monkeypatch.setattr(batch, "_wait", lambda comm, source, tag, interval: None)
    assert batch.serve(Told(), lambda setup: pytest.fail("no work without a setup")) == 0


def test_after_a_dispatch_release_sends_nothing_more(mpi):
    comm = Comm(3)
    batch.dispatch(comm, range(2), {"ranks": 1}, lambda item: item)
    sent = len(comm.sent)
    batch.release(comm)
    assert len(comm.sent) == sent


def test_rank_0s_own_slow_item_is_waited_for(mpi):
    comm = Comm(2)
    finished = {}

    def slow(item):
        time.sleep(0.05)
        return -item

    batch.dispatch(comm, range(3), {"ranks": 1}, slow, finished=finished.__setitem__)
    assert finished[0] == 0 and set(finished) == {0, 1, 2}
    assert all(finished[k] in (-k, 10 * k) for k in (1, 2))


def test_an_error_of_rank_0s_own_item_is_raised_and_every_rank_stopped(mpi):
    comm = Comm(3)

    def work(item):
        raise ValueError("bad item")

    with pytest.raises(ValueError, match="bad item"):
        batch.dispatch(comm, range(4), {"ranks": 1}, work)
    assert [d for d, tag, _ in comm.sent if tag == batch.TAG_STOP] == [1, 2]


def test_release_tells_every_other_rank_to_exit_once(mpi):
    comm = Comm(3)
    batch.release(comm)
    batch.release(comm)
    assert comm.sent == [(1, batch.TAG_SETUP, ("exit", None)), (2, batch.TAG_SETUP, ("exit", None))]
