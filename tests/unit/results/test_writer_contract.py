"""The writer's promises that the round-trip tests do not reach: what a run that wrote no
frame leaves, when a batch is due, what close() waits for, and the inputs it refuses."""

import threading
import time

import h5py
import numpy as np
import pytest

from helpers import FakeClock, parts
from vibrofeed.results import layout as L
from vibrofeed.results import writer as writer_module
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import ResultWriter


def new_writer(path, **kw):
    args = dict(deck_name="d", deck_path="d", deck_text="d", derived={}, engine_version="LIGGGHTS",
                seed=1, variables={"freq": ("50", "Hz", "vibration frequency", "100")})
    args.update(kw)
    return ResultWriter(path, **args)


def test_a_run_that_wrote_no_frame_leaves_empty_series(tmp_path):
    w = new_writer(tmp_path / "empty.h5")
    w.finish("failed", "the engine died before the first frame")
    with h5py.File(tmp_path / "empty.h5", "r") as f:
        for name, (_, comps, _) in L.PART_ELEMENTS.items():
            assert f[f"{L.PARTS}/{name}/value"].shape == ((0, 0, comps) if comps else (0, 0)), name
        assert f[f"{L.PARTS}/position/step"].shape == (0,) and f[f"{L.PARTS}/position/time"].shape == (0,)
        for name in L.SURFACE_ELEMENTS:
            assert f[f"{L.SURFACE}/{name}/value"].shape == (0, 3), name
    report = check_file(tmp_path / "empty.h5")  # the failed status is its error, not the series
    assert not [str(p) for p in report.problems if L.PARTS in p.where]
    assert report.frames == 0


def test_variables_keep_unit_description_default_and_whether_given(tmp_path):
    variables = {"freq": ("50", "Hz", "vibration frequency", "100"),
                 "amp": ("1e-5", None, None, "1e-5"), "waveform": ("sine", "", "", "sine")}
    w = new_writer(tmp_path / "v.h5", variables=variables)
    w.finish()
    with h5py.File(tmp_path / "v.h5", "r") as f:
        freq = f[f"{L.VARIABLES}/freq"]
        assert freq[()] == 50.0
        assert freq.attrs["unit"] == "Hz" and freq.attrs["description"] == "vibration frequency"
        assert freq.attrs["default"] == "100" and bool(freq.attrs["given"]) is True
        amp = f[f"{L.VARIABLES}/amp"]
        assert amp.attrs["unit"] == "" and amp.attrs["description"] == ""  # None stored as ""
        assert bool(amp.attrs["given"]) is False
        assert f[f"{L.VARIABLES}/waveform"][()] in ("sine", b"sine")  # not a number: text


def test_events_without_orientation_are_plain_spheres(tmp_path):
    w = new_writer(tmp_path / "e.h5", outlet={"outlet_x": 0.02, "catch_z": -3e-4, "method": "m"})
    w.write_events({"time": [0.5, 0.6], "id": [3, 4], "position": np.zeros((2, 3)),
                    "velocity": np.ones((2, 3))})
    w.write_events({"time": [], "id": [], "position": np.zeros((0, 3)), "velocity": np.zeros((0, 3))})
    assert w.events == 2
    w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
    w.finish()
    with Result(tmp_path / "e.h5") as r:
        assert r.outlet["orientation"].tolist() == [[1.0, 0, 0, 0]] * 2
        assert r.outlet["id"].tolist() == [3, 4] and r.outlet["velocity"].tolist() == [[1.0] * 3] * 2
    with pytest.raises(KeyError):  # any other field is required
        new_writer(tmp_path / "f.h5").write_events({"time": [0.5], "id": [3], "position": [[0, 0, 0]]})


@pytest.mark.parametrize("vertices, triangles, what", [
    (np.zeros((4, 2)), [[0, 1, 2]], "vertices"),
    (np.zeros(12), [[0, 1, 2]], "vertices"),
    (np.zeros((4, 3)), [[0, 1]], "triangles"),
    (np.zeros((4, 3)), [0, 1, 2], "triangles"),
    (np.zeros((4, 3)), [[0.0, 1.0, 2.0]], "triangles"),
])
def test_a_malformed_track_mesh_is_refused(tmp_path, vertices, triangles, what):
    with pytest.raises(ValueError, match=f"track {what}"):
        new_writer(tmp_path / "t.h5", track=(vertices, np.asarray(triangles)))


@pytest.fixture
def clock(monkeypatch):
    fake = FakeClock()  # the writer's clock: no race with the flusher thread
    monkeypatch.setattr(writer_module, "_time", fake)
    return fake


def test_a_batch_is_due_max_delay_after_its_first_frame_whatever_follows(tmp_path, clock):
    # max_delay in the fake clock's seconds; the flusher thread polls every 25 real
    # seconds, so only write_frame's own check can flush here
    w = new_writer(tmp_path / "b.h5", max_delay=100.0)
    try:
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        clock.now = 60.0
        w.write_events({"time": [0.5], "id": [7], "position": [[0, 0, 0]], "velocity": [[0, 0, 0]]})
        w.write_frame(1, 0.1, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        assert w.written == 0                     # 60 s after the first frame: not yet
        clock.now = 100.0
        w.write_frame(2, 0.2, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        assert w.written == 3                     # 100 s after the first frame: due
        # events alone start a batch of their own
        clock.now = 150.0
        w.write_events({"time": [0.6], "id": [8], "position": [[0, 0, 0]], "velocity": [[0, 0, 0]]})
        clock.now = 249.0
        w.write_frame(3, 0.3, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        assert w.written == 3
        clock.now = 250.0
        w.write_frame(4, 0.4, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        assert w.written == 5
        # no events at all start nothing: the clock starts with the next frame
        clock.now = 300.0
        w.write_events({"time": [], "id": [], "position": np.zeros((0, 3)), "velocity": np.zeros((0, 3))})
        clock.now = 350.0
        w.write_frame(5, 0.5, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        clock.now = 449.0
        w.write_frame(6, 0.6, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        assert w.written == 5
    finally:
        w.finish()


def test_close_waits_for_the_flusher_thread(tmp_path):
    """After close() no thread of the writer touches the file: it joins its flusher."""
    finished = threading.Event()

    class SlowToStop(ResultWriter):
        def _flush_when_due(self):
            self._stop.wait()
            time.sleep(0.3)  # a flush under way when close() is called
            finished.set()

    w = SlowToStop(tmp_path / "c.h5", deck_name="d", deck_path="d", deck_text="d", variables={},
                   derived={}, engine_version="LIGGGHTS", seed=1)
    w.close()
    assert finished.is_set() and not w._flusher.is_alive()


def test_frames_without_counts_read_minus_one_in_a_batch_or_before_it(tmp_path):
    """The mass balance of a frame that gave none is -1 (never a count), however the frames
    were batched: written before the series existed, or in the batch that creates it."""
    counts = dict(inserted=2, on_track=1, exited=1, lost=0)
    for delay in (0.0, 60.0):   # each frame on disk at once / all in one batch
        path = tmp_path / f"c{delay:g}.h5"
        w = new_writer(path, max_delay=delay)
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        w.write_frame(1, 0.1, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0], counts=counts)
        w.write_frame(2, 0.2, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        w.finish()
        with Result(path) as r:
            mb = r.mass_balance
            assert {k: v.tolist() for k, v in mb.items()} == {
                "inserted": [-1, 2, -1], "on_track": [-1, 1, -1], "exited": [-1, 1, -1],
                "lost": [-1, 0, -1]}, delay


def test_a_capacity_hint_below_one_is_taken_as_one(tmp_path):
    for hint in (0, -5):   # sizes chunks only: any hint gives the same file
        w = new_writer(tmp_path / f"h{hint}.h5", capacity_hint=hint)
        w.write_frame(0, 0.0, parts([4, 9], [[0, 0, 0], [1, 2, 3]]), [0, 0, 0], [0, 0, 0])
        w.finish()
        with Result(tmp_path / f"h{hint}.h5") as r:
            assert r.ids.tolist() == [[4, 9]] and r.position[0, 1].tolist() == [1, 2, 3]


def test_a_field_with_the_wrong_number_of_rows_is_named_with_both_counts(tmp_path):
    w = new_writer(tmp_path / "rows.h5")
    p = parts([1, 2, 3], np.zeros((3, 3)))
    p["radius"] = np.full(2, 1e-4)
    with pytest.raises(ValueError, match=r"parts\['radius'\] has 2 rows, id has 3"):
        w.write_frame(0, 0.0, p, [0, 0, 0], [0, 0, 0])
    p = parts([1, 2, 3], np.zeros((3, 3)))
    p["velocity"] = np.zeros((2, 3))   # rows, not components
    with pytest.raises(ValueError, match=r"parts\['velocity'\] has 2 rows, id has 3"):
        w.write_frame(0, 0.0, p, [0, 0, 0], [0, 0, 0])
    w.close()


def test_variable_values_are_numbers_where_they_can_be_else_text():
    from vibrofeed.results.writer import _number_or_text

    assert _number_or_text("1e-5") == 1e-5 and _number_or_text(3) == 3.0
    assert _number_or_text("sine") == "sine"
    assert _number_or_text(None) == "None"   # float(None) is a TypeError, not a ValueError
    assert _number_or_text([1, 2]) == "[1, 2]"


def test_the_units_module_is_the_version_format_md_documents(tmp_path):
    import re

    from helpers import REPO

    documented = re.search(r"modules/units\s+\+version = \[(\d+), (\d+)\]",
                           (REPO / "FORMAT.md").read_text()).groups()
    new_writer(tmp_path / "u.h5").finish()
    with h5py.File(tmp_path / "u.h5", "r") as f:
        units = f["h5md/modules/units"].attrs
        assert units["version"].tolist() == [int(v) for v in documented]
        assert units["system"] == "SI"  # variable-length (units module)


@pytest.mark.parametrize("template", [np.zeros((3, 3)), np.zeros(4), np.zeros((2, 5))])
def test_a_body_template_that_is_not_n_by_4_is_refused(tmp_path, template):
    with pytest.raises(ValueError, match=r"body_template must be \(n, 4\)"):
        new_writer(tmp_path / "b.h5", body_template=template)


def test_the_flusher_thread_leaves_a_batch_alone_until_it_is_due(tmp_path):
    w = new_writer(tmp_path / "f.h5", max_delay=1.0)   # the thread looks every 0.25 s
    try:
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        time.sleep(0.6)        # the thread has looked twice: nothing is due before 1 s
        assert w.written == 0
    finally:
        w.finish()
    assert w.written == 1


def test_derived_values_are_stored_as_numbers(tmp_path):
    w = new_writer(tmp_path / "d.h5", derived={"dt_used": 2e-7, "n_steps": 5000, "t_contact": "1e-5"})
    w.finish()
    with Result(tmp_path / "d.h5") as r:
        assert r.derived == {"dt_used": 2e-7, "n_steps": 5000.0, "t_contact": 1e-5}


def test_slots_of_new_ids_equal_to_the_last_slots_are_not_taken_from_the_cache():
    from vibrofeed.results.writer import SlotMap

    s = SlotMap()
    assert s.assign([5, 6, 7]).tolist() == [0, 1, 2]
    assert s.assign([6, 7]).tolist() == [1, 2]
    # ids 1 and 2 are new (6 and 7 left): the lowest free slots, not the previous frame's [1, 2]
    assert s.assign([1, 2]).tolist() == [0, 1]
    assert s.slot_of == {1: 0, 2: 1}


def test_no_events_make_no_outlet_table_and_orientation_has_no_unit(tmp_path):
    w = new_writer(tmp_path / "n.h5", max_delay=0.0)
    w.write_events({"time": [], "id": [], "position": np.zeros((0, 3)), "velocity": np.zeros((0, 3))})
    p = parts([1], [[0, 0, 0]])
    p["orientation"] = np.array([[1.0, 0, 0, 0]])
    w.write_frame(0, 0.0, p, [0, 0, 0], [0, 0, 0])
    w.finish()
    assert w.events == 0
    with h5py.File(tmp_path / "n.h5", "r") as f:
        assert L.OUTLET not in f                     # a sphere deck's file keeps its layout
        assert "unit" not in f[f"{L.PARTS}/orientation/value"].attrs   # a quaternion has none
        assert f[f"{L.PARTS}/radius/value"].attrs["unit"] == "m"
