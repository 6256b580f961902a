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
from vibrofeed.results.writer import Recording, ResultWriter


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
        assert f[f"{L.PARTS}/box/edges/value"].shape == (0, 3)  # the box's edges: one row per frame
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


# -- feeder lines (further sections, track sections, line counts) and rotating surfaces ------
def test_a_line_records_each_further_sections_motion_under_its_own_observable(tmp_path):
    """Three sections, each with its own motion, all frames in one batch: section k's
    (position, velocity) read back from surface_path(k), none swapped or shifted."""
    path = tmp_path / "line.h5"
    w = new_writer(path, max_delay=60.0, recording=Recording(sections=3),
                   variables={"sections": ("3", "", "sections", "1")})

    def motion(k, j):  # section k at frame j: values no other (section, frame) shares
        return [k, j, 1e-6 * (10 * k + j)], [-k, -j, -1e-3 * (10 * k + j)]

    for j in range(3):
        w.write_frame(j, 0.1 * j, parts([1], [[0, 0, 0]]), *motion(1, j),
                      section_surfaces=[motion(2, j), motion(3, j)])
    w.finish()
    with Result(path) as r:
        assert r.n_sections == 3
        for k in (1, 2, 3):
            pos, vel = r.section_surface(k)
            assert pos.tolist() == [motion(k, j)[0] for j in range(3)], k
            assert vel.tolist() == [motion(k, j)[1] for j in range(3)], k
    with h5py.File(path, "r") as f:
        step = f[f"{L.PARTS}/position/step"]
        for k in (2, 3):   # H5MD time series of their own, sampled with the parts
            for name, (_, _, unit) in L.SURFACE_ELEMENTS.items():
                assert f[f"{L.surface_path(k)}/{name}/step"] == step
                assert f[f"{L.surface_path(k)}/{name}/value"].attrs["unit"] == unit
        assert f"{L.SURFACE}_s4" not in f


@pytest.mark.parametrize("given", [0, 1, 3])
def test_a_frame_with_the_wrong_number_of_further_sections_is_refused_whole(tmp_path, given):
    w = new_writer(tmp_path / "n.h5", recording=Recording(sections=3))
    further = [([0, 0, 0], [0, 0, 0])] * given
    with pytest.raises(ValueError, match=rf"records 3 section\(s\): give the motion of 2 further "
                                         rf"section\(s\), got {given}$"):
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0], section_surfaces=further)
    assert w.frames == 0 and w.slots.capacity == 0   # nothing of the frame was taken
    w.close()


def test_a_further_sections_motion_must_be_three_components(tmp_path):
    w = new_writer(tmp_path / "c.h5", recording=Recording(sections=2))
    for p, v in (([0, 0], [0, 0, 0]), ([0, 0, 0], [0, 0, 0, 0])):
        with pytest.raises(ValueError):
            w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0],
                          section_surfaces=[(p, v)])
    assert w.frames == 0
    w.close()


# a track of 4 vertices and 2 triangles: a vertex count the triangle count cannot stand in for
_VERTICES = np.array([[0, -1e-3, 0], [0.01, -1e-3, 0], [0.01, 1e-3, 0], [0, 1e-3, 0.0]])
_TRIANGLES = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)


def test_track_sections_from_1_to_the_last_recorded_section_are_stored(tmp_path):
    w = new_writer(tmp_path / "s.h5", recording=Recording(sections=2), track=(_VERTICES, _TRIANGLES),
                   track_sections=np.array([1, 1, 2, 2]))   # both ends of 1..sections
    w.finish()
    with Result(tmp_path / "s.h5") as r:
        assert r.track_sections.tolist() == [1, 1, 2, 2]
    with h5py.File(tmp_path / "s.h5", "r") as f:
        assert f[L.TRACK_SECTION].dtype == np.int32


@pytest.mark.parametrize("sections, match", [
    ([0, 1, 2, 2], r"lie in 1\.\.2"),            # below the first section
    ([1, 1, 2, 3], r"lie in 1\.\.2"),            # one past the last recorded section
    ([1, 2], r"must be \(4,\) integers"),        # one per triangle, not per vertex
    ([1, 1, 2, 2, 2], r"must be \(4,\) integers"),
    ([1.0, 1.0, 2.0, 2.0], r"must be \(4,\) integers"),
])
def test_track_sections_outside_the_recorded_sections_or_not_one_per_vertex_are_refused(
        tmp_path, sections, match):
    with pytest.raises(ValueError, match=match):
        new_writer(tmp_path / "s.h5", recording=Recording(sections=2), track=(_VERTICES, _TRIANGLES),
                   track_sections=np.array(sections))


def test_track_sections_need_a_track(tmp_path):
    with pytest.raises(ValueError, match="without a track"):
        new_writer(tmp_path / "s.h5", recording=Recording(sections=2), track_sections=np.array([1, 2]))


@pytest.mark.parametrize("returns", [False, True])
def test_a_line_counts_its_rejects_and_a_recirculating_one_its_returns(tmp_path, returns):
    names = L.RETURN_COUNTS if returns else L.LINE_COUNTS
    counts = {name: 10 + j for j, name in enumerate(names)}   # one value per name, told apart
    w = new_writer(tmp_path / "l.h5", recording=Recording(sections=2, rejects=True, returns=returns))
    w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0], counts=counts,
                  section_surfaces=[([0, 0, 0], [0, 0, 0])])
    w.finish()
    with Result(tmp_path / "l.h5") as r:
        assert {k: v.tolist() for k, v in r.mass_balance.items()} == {k: [v] for k, v in counts.items()}
    with h5py.File(tmp_path / "l.h5", "r") as f:
        assert L.REJECTS in f and set(f[L.MASS_BALANCE]) == set(names)


def test_a_line_without_returns_does_not_ask_for_them_and_one_with_them_does(tmp_path):
    line_counts = {name: 0 for name in L.LINE_COUNTS}   # no "returned"
    w = new_writer(tmp_path / "a.h5", recording=Recording(sections=2, rejects=True))
    w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0], counts=line_counts,
                  section_surfaces=[([0, 0, 0], [0, 0, 0])])
    assert w.frames == 1
    w.close()
    w = new_writer(tmp_path / "b.h5", recording=Recording(sections=2, rejects=True, returns=True))
    with pytest.raises(ValueError, match="counts lacks returned"):
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0], counts=line_counts,
                      section_surfaces=[([0, 0, 0], [0, 0, 0])])
    w.close()
    with pytest.raises(ValueError, match="returns without a line"):
        new_writer(tmp_path / "c.h5", recording=Recording(returns=True))


def test_a_rotating_surface_records_its_angle_and_rate_in_section_1(tmp_path):
    """Batched frames: each frame's angle and angular velocity land in SURFACE's angle and
    angular_velocity, not swapped (the rate differs from the angle at every frame)."""
    path = tmp_path / "bowl.h5"
    w = new_writer(path, max_delay=60.0, recording=Recording(rotating=True))
    angles = [[0, 0, 0.25 * j] for j in range(3)]
    rates = [[0, 0, 2.0 + j] for j in range(3)]
    for j in range(3):
        w.write_frame(j, 0.1 * j, parts([1], [[0, 0, 0]]), [0, 0, 1e-6 * j], [0, 0, 1e-3 * j],
                      surface_rotation=(angles[j], rates[j]))
    w.finish()
    with Result(path) as r:
        assert r.read("surface_angle").tolist() == angles
        assert r.read("surface_angular_velocity").tolist() == rates
        assert r.read("surface_position")[:, 2].tolist() == [1e-6 * j for j in range(3)]
    with h5py.File(path, "r") as f:
        step = f[f"{L.PARTS}/position/step"]
        for name, (_, _, unit) in L.ROTATION_ELEMENTS.items():  # FORMAT.md: value[frames][3]
            ds = f[f"{L.SURFACE}/{name}/value"]
            assert ds.shape == (3, 3) and ds.attrs["unit"] == unit, name
            assert f[f"{L.SURFACE}/{name}/step"] == step


def test_a_rotating_surface_needs_its_rotation_at_every_frame_and_no_other_takes_one(tmp_path):
    w = new_writer(tmp_path / "r.h5", recording=Recording(rotating=True))
    with pytest.raises(ValueError, match="needs surface_rotation"):
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
    w.close()
    w = new_writer(tmp_path / "s.h5")
    with pytest.raises(ValueError, match="does not rotate"):
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0],
                      surface_rotation=([0, 0, 0], [0, 0, 0]))
    assert w.frames == 0
    w.finish()
    with h5py.File(tmp_path / "s.h5", "r") as f:   # a surface that does not turn has no rotation
        assert not set(L.ROTATION_ELEMENTS) & set(f[L.SURFACE])


@pytest.mark.parametrize("sections", [0, -1])
def test_a_writer_of_fewer_than_one_section_is_refused(tmp_path, sections):
    with pytest.raises(ValueError, match=f"sections must be >= 1, got {sections}"):
        new_writer(tmp_path / "s.h5", recording=Recording(sections=sections))


def test_a_lines_rejects_record_one_section_number_per_event(tmp_path):
    """FORMAT.md: the reject table is the outlet's plus ``section`` (E,), int32."""
    w = new_writer(tmp_path / "r.h5", recording=Recording(sections=2, rejects=True))
    w.write_events({"time": [0.1, 0.2], "id": [7, 9], "position": np.zeros((2, 3)),
                    "velocity": np.zeros((2, 3)), "section": [2, 1]}, L.REJECTS)
    w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0],
                  counts={name: 0 for name in L.LINE_COUNTS}, section_surfaces=[([0, 0, 0], [0, 0, 0])])
    w.finish()
    with h5py.File(tmp_path / "r.h5", "r") as f:
        section = f[L.REJECTS]["section"]
        assert section.shape == (2,) and section.dtype == np.int32 and section[()].tolist() == [2, 1]
        assert f[L.REJECTS]["id"][()].tolist() == [7, 9]
