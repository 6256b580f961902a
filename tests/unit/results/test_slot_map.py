"""The writer's slot bookkeeping for any sequence of particles entering and leaving.

FORMAT.md promises: a particle keeps its slot (column) while it exists, a slot
freed by a particle is reused (the lowest free one first), and the particle
axis is as wide as the most particles present at once. Checked on random
insert/delete sequences, for SlotMap alone and through a written file.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers import parts, write_result
from vibrofeed.results import layout as L
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import SlotMap

# A run: frames, each the list of particle ids present (in the order handed over).
ids = st.integers(min_value=0, max_value=40)
frame = st.lists(ids, unique=True, max_size=12)
runs = st.lists(frame, min_size=1, max_size=25)


def reference_slots(run):
    """Slots as FORMAT.md describes them, computed independently of SlotMap."""
    slot_of: dict[int, int] = {}
    out = []
    for present in run:
        slot_of = {i: s for i, s in slot_of.items() if i in present}
        row = []
        for i in present:
            if i not in slot_of:
                used = set(slot_of.values())
                slot_of[i] = min(s for s in range(len(used) + 1) if s not in used)
            row.append(slot_of[i])
        out.append(row)
    return out


@settings(max_examples=200, deadline=None)
@given(run=runs)
def test_slots_follow_the_format(run):
    s = SlotMap()
    previous: dict[int, int] = {}
    for present, expected in zip(run, reference_slots(run)):
        got = s.assign(np.array(present, dtype=np.int64)).tolist()
        assert got == expected
        assert len(set(got)) == len(got)  # one particle per slot
        now = dict(zip(present, got))
        for pid in set(now) & set(previous):  # a particle keeps its slot while present
            assert now[pid] == previous[pid]
        previous = now
    assert s.capacity == max(len(p) for p in run)  # as wide as the most present at once


@settings(max_examples=25, deadline=None)
@given(run=runs, shuffle_seed=st.integers(0, 2**16))
def test_written_file_tracks_every_particle(tmp_path_factory, run, shuffle_seed):
    rng = np.random.default_rng(shuffle_seed)
    frames = []
    for k, present in enumerate(run):
        present = list(rng.permutation(present)) if present else []
        pos = [[pid + 0.001 * k, -pid, k] for pid in present]
        frames.append((10 * k, 1e-3 * k, parts(present, pos) if present else parts([], [])))
    path = write_result(tmp_path_factory.mktemp("slots") / "r.h5", frames)
    with Result(path) as r:
        assert r.n_frames == len(run)
        assert r.n_slots == max(len(p) for p in run)
        ids = r.ids
        assert ids.shape == (len(run), r.n_slots)
        for k, present in enumerate(run):
            row = ids[k]
            assert sorted(row[row >= 0].tolist()) == sorted(present)
            free = row == L.ID_FILL
            assert np.isnan(r.position[k][free]).all()
            assert (r.species[k][free] == -1).all()  # FORMAT.md: species fill -1
        for pid in {p for f in run for p in f}:
            where, slots = r.locate(pid)
            assert where.tolist() == [k for k, f in enumerate(run) if pid in f]
            t, x = r.track(pid)
            # synthetic positions (m, up to 40) read back: float64, exact up to rounding
            assert np.allclose(x[:, 1], -pid, rtol=0, atol=1e-12)
            assert np.allclose(x[:, 2], where, rtol=0, atol=1e-12)
            assert np.allclose(x[:, 0], pid + 0.001 * where, rtol=0, atol=1e-12)
