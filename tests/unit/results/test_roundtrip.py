"""H5MD result files: writer, reader and `vibrofeed check` on small hand-made runs."""

import h5py
import numpy as np
import pytest

from helpers import parts, write_conveyor, write_result
from vibrofeed import errors
from vibrofeed.results import layout as L
from vibrofeed.results import reader
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import IncompleteResult, Result, ResultError
from vibrofeed.results.writer import SlotMap


def three_frames(tmp_path, **kw):
    """Particle 1 throughout (at 0.1 m/s: a physical result, see check's speed limit); 2
    leaves after frame 0; 3 arrives at frame 2 and reuses 2's slot."""
    frames = [
        (0, 0.0, parts([1, 2], [[0, 0, 1], [1, 0, 1]])),
        (10, 1.0, parts([1], [[0.1, 0, 1]])),
        (20, 2.0, parts([3, 1], [[5, 0, 1], [0.2, 0, 1]])),
    ]
    surface = [([0, 0, k * 1e-6], [0, 0, 1e-3]) for k in range(3)]
    return write_result(tmp_path / "r.h5", frames, surface, **kw)


def test_roundtrip_with_varying_particle_number(tmp_path):
    path = three_frames(tmp_path)
    with Result(path) as r:
        assert r.n_frames == 3
        assert list(r.step) == [0, 10, 20] and r.time.tolist() == [0.0, 1.0, 2.0]
        # slot 0 is particle 1, slot 1 held 2, was empty, then holds 3
        assert r.ids.tolist() == [[1, 2], [1, -1], [1, 3]]
        assert np.isnan(r.position[1, 1]).all()
        assert np.isnan(r.radius[1, 1]) and r.species[1, 1] == -1  # FORMAT.md: species fill -1
        t, x = r.track(3)
        assert t.tolist() == [2.0] and x.tolist() == [[5, 0, 1]]
        t, x = r.track(1)
        assert np.allclose(x[:, 0], [0, 0.1, 0.2], rtol=0, atol=1e-15)  # m: float64 round trip
        assert r.part_ids.tolist() == [1, 2, 3]
        assert r.present().tolist() == [2, 1, 2]
        assert np.allclose(r.surface_position[:, 2], [0, 1e-6, 2e-6], rtol=0, atol=1e-18)  # m: 1 um steps
        assert r.parameters == {"freq": 50.0}
        assert r.units("freq") == "Hz"
        assert "LIGGGHTS" in r.liggghts_version and r.seed == 1
    assert check_file(path).ok


def test_h5md_metadata_and_hard_links(tmp_path):
    path = three_frames(tmp_path)
    with h5py.File(path, "r") as f:
        assert list(f["h5md"].attrs["version"]) == [1, 1]
        assert f["h5md/creator"].attrs["name"] == b"vibrofeed"
        assert f["h5md/author"].attrs["name"]
        # units module: variable-length strings, read back by h5py as str
        assert f[f"{L.PARTS}/position/value"].attrs["unit"] == "m"
        assert f[f"{L.PARTS}/velocity/value"].attrs["unit"] == "m s-1"
        assert f[f"{L.PARTS}/position/time"].attrs["unit"] == "s"
        # one step/time dataset shared by every element (H5MD hard links)
        ref = f[f"{L.PARTS}/position/step"]
        for name in ("velocity", "id", "radius"):
            assert f[f"{L.PARTS}/{name}/step"] == ref
        assert f[f"{L.SURFACE}/position/step"] == ref
        assert f[f"{L.PARTS}/id/value"].fillvalue == -1
        assert f[f"{L.PARTS}/species/value"].fillvalue == -1


def test_slot_map_reuses_lowest_free_slot():
    s = SlotMap()
    assert s.assign(np.array([7, 8, 9])).tolist() == [0, 1, 2]
    assert s.assign(np.array([9])).tolist() == [2]            # 7 and 8 leave
    assert s.assign(np.array([9, 4, 5])).tolist() == [2, 0, 1]  # reuse 0 then 1
    assert s.assign(np.array([6, 9, 4, 5])).tolist() == [3, 2, 0, 1]
    assert s.capacity == 4


def test_duplicate_ids_in_a_frame_are_refused(tmp_path):
    with pytest.raises(ValueError, match="duplicate"):
        write_result(tmp_path / "d.h5", [(0, 0.0, parts([1, 1], [[0, 0, 0], [1, 1, 1]]))])


def test_incomplete_run_needs_explicit_consent(tmp_path):
    path = three_frames(tmp_path, status=None)  # never finished: "running"
    with pytest.raises(IncompleteResult, match="running"):
        Result(path)
    with Result(path, allow_incomplete=True) as r:
        assert r.n_frames == 3 and r.status == "running"
    report = check_file(path)
    assert not report.ok and "killed" in str(report.problems[0])
    assert check_file(path, allow_incomplete=True).ok


def test_not_a_result(tmp_path):
    p = tmp_path / "x.h5"
    with h5py.File(p, "w") as f:
        f.create_group("foo")
    with pytest.raises(ResultError, match="not a vibrofeed result"):
        Result(p)
    (tmp_path / "y.h5").write_text("not hdf5")
    with pytest.raises(ResultError, match="cannot open"):
        Result(tmp_path / "y.h5")
    assert not check_file(tmp_path / "y.h5").ok


# Each corruption must be caught by the checker, with the path it concerns.
def _del_version(f):
    del f["h5md"].attrs["version"]


def _bad_unit(f):
    f[f"{L.PARTS}/velocity/value"].attrs["unit"] = np.bytes_(b"mm/s")


def _step_backwards(f):
    f[f"{L.PARTS}/position/step"][2] = 5


def _value_in_empty_slot(f):
    f[f"{L.PARTS}/position/value"][1, 1] = [0, 0, 0]


def _duplicate_id(f):
    f[f"{L.PARTS}/id/value"][0, 1] = 1


def _short_surface(f):
    f[f"{L.SURFACE}/velocity/value"].resize(2, axis=0)


def _no_seed(f):
    del f[f"{L.PARAMETERS}/seed"]


def _no_deck(f):
    del f[f"{L.PARAMETERS}/deck"]


def _missing_velocity(f):
    del f[f"{L.PARTS}/velocity"]


def _unknown_status(f):
    f[L.RUN].attrs["status"] = "maybe"


def _wrong_rank(f):
    del f[f"{L.SURFACE}/position/value"]
    f[f"{L.SURFACE}/position"].create_dataset("value", data=np.zeros(3))


@pytest.mark.parametrize("corrupt, where", [
    (_del_version, "h5md"), (_bad_unit, "velocity/value"), (_step_backwards, "position/step"),
    (_value_in_empty_slot, "position/value"), (_duplicate_id, "id/value"),
    (_short_surface, "surface/velocity"), (_no_seed, "seed"), (_no_deck, "deck"),
    (_missing_velocity, "velocity"), (_unknown_status, "run"), (_wrong_rank, "surface/position"),
])
def test_check_catches_corruption(tmp_path, corrupt, where):
    path = three_frames(tmp_path)
    with h5py.File(path, "r+") as f:
        corrupt(f)
    report = check_file(path)
    assert not report.ok
    assert any(where in p.where and p.level == "error" for p in report.problems), report.problems


def test_frames_reach_the_disk_within_the_delay_even_when_none_follow(tmp_path):
    import subprocess
    import sys
    import time

    from vibrofeed.results.writer import ResultWriter

    w = ResultWriter(tmp_path / "d.h5", deck_name="d", deck_path="d", deck_text="d", variables={},
                     derived={}, engine_version="LIGGGHTS", seed=1, max_delay=0.2)
    try:
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        w.write_frame(1, 1e-5, parts([1], [[0, 0, 1]]), [0, 0, 0], [0, 0, 0])
        time.sleep(0.6)  # no further frame: the writer's own thread must flush
        # Read from another process, as a user would while the run goes.
        code = ("import h5py, sys; f = h5py.File(sys.argv[1], 'r', locking=False); "
                f"print(len(f['{L.PARTS}/position/step']))")
        out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "d.h5")],
                             capture_output=True, text=True, check=True).stdout
        assert out.strip() == "2"
    finally:
        w.finish()
    with Result(tmp_path / "d.h5") as r:
        assert r.n_frames == 2 and r.position[1, 0, 2] == 1


def test_batched_frames_with_a_growing_particle_axis(tmp_path):
    from vibrofeed.results.writer import ResultWriter

    w = ResultWriter(tmp_path / "g.h5", deck_name="d", deck_path="d", deck_text="d",
                     variables={"freq": ("50", "Hz", "f", "50")},
                     derived={}, engine_version="LIGGGHTS", seed=1, max_delay=60)
    for k in range(5):  # one more particle each frame, all in one batch
        ids = list(range(1, k + 2))
        w.write_frame(k, k * 1e-3, parts(ids, [[i, 0, 0] for i in ids]), [0, 0, 0], [0, 0, 0])
    w.finish()
    with Result(tmp_path / "g.h5") as r:
        assert r.ids.shape == (5, 5)
        assert r.ids[0].tolist() == [1, -1, -1, -1, -1]
        assert r.ids[4].tolist() == [1, 2, 3, 4, 5]
        assert np.isnan(r.position[2, 3:]).all() and r.position[2, 2, 0] == 3
    assert check_file(tmp_path / "g.h5").ok


def test_reader_errors_come_from_the_error_tree():
    assert ResultError is errors.ResultError and IncompleteResult is errors.IncompleteResult


# -- reading by window -----------------------------------------------------------------
def conveyor(tmp_path, n_parts=30, n_frames=60, seed=5):
    """Parts entering and leaving, slots reused (see helpers.write_conveyor)."""
    rng = np.random.default_rng(seed)
    first = rng.integers(0, n_frames - 1, n_parts)
    last = np.minimum(first + rng.integers(0, n_frames, n_parts), n_frames - 1)
    lifetimes = np.column_stack([first, last])
    times = np.arange(n_frames) * 1e-4
    return write_conveyor(tmp_path / "many.h5", times, lifetimes, rng.uniform(0, 0.01, n_parts),
                          amp=1e-4)


FRAME_SELECTIONS = [None, 7, -1, slice(3, 40, 5), slice(None, None, -3), slice(50, 10),
                    [40, 2, 2, 17], np.array([0, 59]), np.arange(60) % 7 == 0, [], [5],
                    [4, 4, 4]]   # one frame repeated: evenly spaced by 0, no slice of step 0


@pytest.mark.parametrize("dense", [0.0, 2.0])  # scattered frames read as one block / point by point
def test_window_reads_match_whole_reads(tmp_path, monkeypatch, dense):
    monkeypatch.setattr(reader, "_DENSE", dense)
    path = conveyor(tmp_path)
    with Result(path) as whole, Result(path) as r:
        assert whole.ids.shape[1] == r.n_slots < 30  # slots were reused
        for name in Result.FIELDS:
            full = whole.read(name)
            for frames in FRAME_SELECTIONS:
                expected = (full if frames is None else full[np.array(frames, int)]
                            if isinstance(frames, list) else full[frames])
                got = r.read(name, frames=frames)
                assert got.shape == expected.shape, (name, frames)
                assert np.array_equal(got, expected, equal_nan=True), (name, frames)
        pos = whole.position
        for frames, slots, expected in [
                (None, 3, pos[:, 3]), (11, slice(1, None, 2), pos[11, 1::2]),
                ([30, 1], [4, 0, 4], pos[[30, 1]][:, [4, 0, 4]]), (None, [2, 5], pos[:, [2, 5]]),
                (slice(5, 9), 0, pos[5:9, 0]), (7, [1], pos[7, [1]])]:
            got = r.read("position", frames=frames, slots=slots)
            assert np.array_equal(got, expected, equal_nan=True), (frames, slots)
        assert np.array_equal(r.read("ids", frames=2), whole.ids[2])
        with pytest.raises(KeyError, match="no field"):
            r.read("temperature")
        with pytest.raises(IndexError):
            r.read("time", frames=60)
        with pytest.raises(IndexError):
            r.read("surface_position", slots=0)
        assert not {"ids", "position", "time"} & set(vars(r))  # nothing read whole


def test_tracks_and_frames_read_only_what_they_need(tmp_path, monkeypatch):
    monkeypatch.setattr(reader, "_BLOCK_VALUES", 200)  # scan the ids a few frames at a time
    path = conveyor(tmp_path)
    with Result(path) as whole, Result(path) as r:
        ids = whole.ids
        full = {q: whole.read(q) for q in ("position", "radius")}
        assert r.part_ids.tolist() == np.unique(ids[ids >= 0]).tolist()
        assert np.array_equal(r.present(), whole.present())
        assert np.array_equal(r.present(slice(5, 20, 3)), whole.present()[5:20:3])
        for pid in r.part_ids:
            frames, slots = np.nonzero(ids == pid)
            assert [a.tolist() for a in r.locate(pid)] == [frames.tolist(), slots.tolist()]
            for q in ("position", "radius"):
                t, v = r.track(pid, q)
                assert np.array_equal(t, whole.time[frames])
                assert np.array_equal(v, full[q][frames, slots])
            keep = frames % 2 == 1
            t, v = r.track(pid, "position", frames=slice(1, None, 2))
            assert np.array_equal(t, whole.time[frames[keep]])
            assert np.array_equal(v, whole.position[frames[keep], slots[keep]])
        with pytest.raises(KeyError, match="does not appear"):
            r.track(999)
        # arbitrary (frame, slot) pairs, slot changing between them
        fr, sl = np.array([0, 1, 2, 2, 9, 9, 30]), np.array([0, 0, 1, 0, 0, 2, 2])
        assert np.array_equal(r.gather("position", fr, sl), whole.position[fr, sl], equal_nan=True)
        assert r.gather("position", [], []).shape == (0, 3)
        # the slot one lower at the next frame is another part: a new run, not slot 1's
        k = next(k for k in range(59) if (ids[k + 1, :2] >= 0).all())
        fr, sl = np.array([k, k + 1]), np.array([1, 0])
        assert np.array_equal(r.gather("position", fr, sl), whole.position[fr, sl], equal_nan=True)
        frame = r.frame(-1, fields=("position", "mass", "surface_position"))
        present = np.nonzero(ids[-1] >= 0)[0]
        assert frame.index == 59 and frame.time == whole.time[-1] and frame.step == whole.step[-1]
        assert frame.ids.tolist() == ids[-1, present].tolist() and len(frame) == len(present)
        assert np.array_equal(frame["position"], whole.position[-1, present])
        assert np.array_equal(frame["surface_position"], whole.surface_position[-1])
        seen = [(f.index, f.ids.tolist()) for f in r.iter_frames(slice(0, None, 7), fields=())]
        assert seen == [(j, ids[j][ids[j] >= 0].tolist()) for j in range(0, 60, 7)]
        assert not {"ids", "position", "velocity"} & set(vars(r))


class _Reads:
    """An h5py dataset that records the frames each read takes (its first index)."""

    def __init__(self, ds, log):
        self.ds, self.log, self.shape, self.dtype = ds, log, ds.shape, ds.dtype

    def __getitem__(self, key):
        first = key[0] if isinstance(key, tuple) else key
        frames = range(*first.indices(self.shape[0])) if isinstance(first, slice) else first
        self.log.append(np.atleast_1d(frames).tolist())
        return self.ds[key]


@pytest.mark.parametrize("frames, reads", [
    ([50, 3, 20], [[3, 20, 50]]),       # 3 of the 48 frames spanned: those 3 only, sorted
    ([5, 3, 4, 7], [[3, 4, 5, 6, 7]]),  # 4 of 5 (at least a quarter): the span, in one read
])
def test_scattered_frames_are_read_alone_unless_they_fill_a_quarter_of_their_span(
        tmp_path, monkeypatch, frames, reads):
    """read() reads only the selected frames, except that a selection covering at least
    _DENSE = 1/4 of the frames it spans is read as that span at once."""
    log, dataset = [], Result._dataset

    def spied(self, name):
        ds, per_part = dataset(self, name)
        return _Reads(ds, log), per_part

    monkeypatch.setattr(Result, "_dataset", spied)
    path = conveyor(tmp_path)
    with h5py.File(path, "r") as f:
        expected = f[f"{L.PARTS}/position/value"][()][frames]
    with Result(path) as r:
        assert np.array_equal(r.read("position", frames=frames), expected, equal_nan=True)
    assert log == reads


def test_recorded_is_true_for_a_file_without_parts(tmp_path):
    """No frame holds a part to judge by: a float field is taken as recorded."""
    path = write_result(tmp_path / "empty.h5", [(k, k * 1e-3, parts([], np.zeros((0, 3)))) for k in range(2)])
    with Result(path) as r:
        assert r.n_frames == 2 and r.part_ids.tolist() == []
        assert r.recorded("force") and r.recorded("velocity")


def test_a_file_that_does_not_record_its_format_is_of_format_1_0(tmp_path):
    """The first files had no format_version: they are format 1.0."""
    path = three_frames(tmp_path)
    with h5py.File(path, "r+") as f:
        del f[L.PARAMETERS].attrs["format_version"]
    with Result(path) as r:
        assert r.format_version == (1, 0)


def test_check_warns_about_a_missing_run_id(tmp_path):
    from vibrofeed.results.check import check_file
    from vibrofeed.results.writer import ResultWriter

    path = tmp_path / "old.h5"
    w = ResultWriter(path, deck_name="d", deck_path="d.liggghts", deck_text="# d\n",
                     variables={"freq": ("50", "Hz", "f", "50")}, derived={}, seed=1,
                     engine_version="LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0)")  # no run_id
    w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
    w.finish()
    report = check_file(path)
    assert report.ok  # a warning, not an error: format 1.0 files had no id
    assert [p.level for p in report.problems] == ["warning"]
    assert "'id'" in report.problems[0].message


# -- bulk feeders: orientation, outlet events, mass balance, track mesh (FORMAT.md) --------------
def _quat(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.r_[np.cos(angle / 2), np.sin(angle / 2) * axis]


def bulk_file(tmp_path, name="b.h5", **kw):
    """Three parts: 2 leaves the track (event) and stays one frame as it falls, then is gone;
    4 is inserted at frame 1 and grows the slot axis."""
    from helpers import write_bulk_result

    q1, q2 = _quat([0, 0, 1], 0.3), _quat([1, 1, 0], 2.0)
    ident = [1.0, 0, 0, 0]

    def with_q(p, qs):
        p["orientation"] = np.asarray(qs, float)
        return p

    frames = [
        (0, 0.0, with_q(parts([1, 2, 3], [[0, 0, 1e-4], [19e-3, 0, 1e-4], [5e-3, 0, 1e-4]]),
                        [q1, q2, ident])),
        (10, 0.01, with_q(parts([3, 2, 1, 4], [[6e-3, 0, 1e-4], [20.5e-3, 0, -4e-4],
                                              [1e-3, 0, 1e-4], [0, 1e-3, 1e-4]]),
                          [ident, q2, q1, ident])),
        (20, 0.02, with_q(parts([1, 3, 4], [[2e-3, 0, 1e-4], [7e-3, 0, 1e-4], [1e-3, 1e-3, 1e-4]]),
                          [q1, ident, ident])),
    ]
    counts = [dict(inserted=3, on_track=3, exited=0, lost=0),
              dict(inserted=4, on_track=3, exited=1, lost=0),
              dict(inserted=4, on_track=3, exited=1, lost=0)]
    events = {"time": [0.0071], "id": [2], "position": [[20.2e-3, 0, -3e-4]],
              "velocity": [[0.04, 0, -0.05]], "orientation": [q2]}
    vertices = np.array([[0, -1e-3, 0], [0.02, -1e-3, 0], [0.02, 1e-3, 0], [0, 1e-3, 0.0]])
    triangles = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)
    template = np.array([[-1e-4, 0, 0, 7.5e-5], [0, 0, 0, 7.5e-5], [1e-4, 0, 0, 7.5e-5]])
    args = dict(events=events, counts=counts, track=(vertices, triangles), body_template=template)
    args.update(kw)
    path = write_bulk_result(tmp_path / name, frames, **args)
    return path, dict(q1=q1, q2=q2, events=events, vertices=vertices, triangles=triangles,
                      template=template)


def test_bulk_roundtrip(tmp_path):
    path, known = bulk_file(tmp_path)
    with Result(path) as r:
        assert r.ids.tolist() == [[1, 2, 3, -1], [1, 2, 3, 4], [1, -1, 3, 4]]
        q = r.read("orientation")
        assert q.shape == (3, 4, 4)
        # (quaternions: float64 round trip)
        assert np.allclose(q[0, 0], known["q1"], rtol=0, atol=1e-15)
        assert np.allclose(q[1, 1], known["q2"], rtol=0, atol=1e-15)
        assert np.isnan(q[0, 3]).all() and np.isnan(q[2, 1]).all()
        assert np.allclose(r.orientation[2, 0], known["q1"], rtol=0, atol=1e-15)  # whole-array attribute
        t, qs = r.track(2, "orientation")
        assert t.tolist() == [0.0, 0.01] and np.allclose(qs, known["q2"], rtol=0, atol=1e-15)
        f = r.frame(1, fields=("position", "orientation"))
        assert np.allclose(f["orientation"][f.ids.tolist().index(2)], known["q2"], rtol=0, atol=1e-15)
        out = r.outlet
        assert out["id"].tolist() == [2] and out["time"].tolist() == [0.0071]
        assert out["position"].shape == (1, 3)
        assert np.allclose(out["orientation"][0], known["q2"], rtol=0, atol=1e-15)
        assert r.outlet_plane == {"outlet_x": 0.02, "catch_z": -3e-4, "method": "synthetic"}
        mb = r.mass_balance
        assert mb["inserted"].tolist() == [3, 4, 4] and mb["exited"].tolist() == [0, 1, 1]
        assert mb["lost"].dtype == np.int64 and mb["on_track"].tolist() == [3, 3, 3]
        v, tri = r.track_mesh
        assert np.array_equal(v, known["vertices"]) and tri.dtype == np.int32
        assert np.array_equal(tri, known["triangles"])
        assert np.array_equal(r.body_template, known["template"])
    with h5py.File(path, "r") as f:  # step/time hard links, as for every time series
        ref = f[f"{L.PARTS}/position/step"]
        assert f[f"{L.MASS_BALANCE}/lost/step"] == ref and f[f"{L.PARTS}/orientation/step"] == ref
    report = check_file(path)
    assert report.ok, [str(p) for p in report.problems]


def test_files_without_bulk_data_read_defaults_and_stay_valid(tmp_path):
    path = three_frames(tmp_path)
    with h5py.File(path, "r") as f:
        for absent in (f"{L.PARTS}/orientation", L.OUTLET, L.MASS_BALANCE, L.TRACK, L.BODY_TEMPLATE):
            assert absent not in f
    with Result(path) as r:
        q = r.read("orientation")  # identity where a part is, NaN in empty slots
        assert q.shape == (3, 2, 4)
        assert q[0, 0].tolist() == [1, 0, 0, 0] and np.isnan(q[1, 1]).all()
        assert r.read("orientation", frames=2, slots=1).tolist() == [1, 0, 0, 0]
        assert r.track(1, "orientation")[1].tolist() == [[1, 0, 0, 0]] * 3
        assert r.outlet["id"].shape == (0,) and r.outlet["position"].shape == (0, 3)
        assert r.outlet_plane is None and r.mass_balance is None
        assert r.track_mesh is None and r.body_template is None
    assert check_file(path).ok


def test_outlet_table_exists_without_events(tmp_path):
    from helpers import write_bulk_result

    path = write_bulk_result(tmp_path / "e.h5", [(0, 0.0, parts([1], [[0, 0, 0]]))],
                             counts=[dict(inserted=1, on_track=1, exited=0, lost=0)],
                             outlet={"outlet_x": 0.02, "catch_z": -1e-3, "method": "ballistic"})
    with Result(path) as r:
        assert r.outlet["time"].shape == (0,) and r.outlet_plane["method"] == "ballistic"
    assert check_file(path).ok


def test_orientation_and_counts_appearing_late_read_fill_values_before(tmp_path):
    from vibrofeed.results.writer import ResultWriter

    path = tmp_path / "late.h5"
    w = ResultWriter(path, deck_name="x", deck_path="x", deck_text="x",
                     variables={"a": ("1", "", "", "1")}, derived={}, engine_version="LIGGGHTS x",
                     seed=1, max_delay=0)
    w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])  # on disk at once
    p = parts([1, 2], [[0, 0, 0], [1, 1, 1]])
    p["orientation"] = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
    w.write_frame(1, 0.1, p, [0, 0, 0], [0, 0, 0],
                  counts=dict(inserted=2, on_track=2, exited=0, lost=0))
    w.finish()
    with Result(path) as r:
        q = r.read("orientation")
        assert np.isnan(q[0]).all() and q[1].tolist() == [[1, 0, 0, 0], [0, 1, 0, 0]]
        assert r.mass_balance["inserted"].tolist() == [-1, 2]
    report = check_file(path)  # a frame without counts is an error in a mass balance
    assert not report.ok and any("negative counts" in str(p) for p in report.problems)


@pytest.mark.parametrize("change, message", [
    (dict(counts=[dict(inserted=3, on_track=3, exited=0, lost=0),
                  dict(inserted=4, on_track=3, exited=0, lost=1),
                  dict(inserted=4, on_track=3, exited=0, lost=1)]), "lost"),
    (dict(events={"time": [0.007, 0.008], "id": [2, 2], "position": np.zeros((2, 3)),
                  "velocity": np.zeros((2, 3)), "orientation": [[1.0, 0, 0, 0]] * 2}),
     "more than once"),
    (dict(events={"time": [0.007], "id": [2], "position": np.zeros((1, 3)),
                  "velocity": np.zeros((1, 3)), "orientation": [[0.5, 0, 0, 0]]}), "unit quaternion"),
    (dict(track=(np.zeros((3, 3)), np.array([[0, 1, 3]], np.int32))), "vertex that does not exist"),
    (dict(counts=[dict(inserted=3, on_track=3, exited=0, lost=0),
                  dict(inserted=4, on_track=3, exited=1, lost=0),
                  dict(inserted=4, on_track=1, exited=1, lost=2)]), "parts present"),
    (dict(counts=[dict(inserted=3, on_track=3, exited=0, lost=0),
                  dict(inserted=4, on_track=3, exited=1, lost=0),
                  dict(inserted=5, on_track=3, exited=1, lost=0)]), "on_track + exited + lost"),
    (dict(events={"time": [0.007, 0.008], "id": [2, 5], "position": np.zeros((2, 3)),
                  "velocity": np.zeros((2, 3)), "orientation": [[1.0, 0, 0, 0]] * 2}),
     "outlet events"),
])
def test_check_catches_bulk_problems(tmp_path, change, message):
    path, _ = bulk_file(tmp_path, **change)
    report = check_file(path)
    assert not report.ok
    assert any(message in str(p) for p in report.problems), [str(p) for p in report.problems]


def test_vectorised_slot_map_matches_the_rule(tmp_path):
    """Lowest free slot first, in the order new ids come; a reference loop decides."""
    rng = np.random.default_rng(3)
    s, ref, free, cap = SlotMap(), {}, [], 0
    pool = np.arange(1, 200)
    for _ in range(60):
        ids = rng.permutation(rng.choice(pool, size=rng.integers(0, 80), replace=False))
        for gone in [i for i in ref if i not in set(ids.tolist())]:
            free.append(ref.pop(gone))
        free.sort()
        want = []
        for i in ids.tolist():
            if i not in ref:
                ref[i] = free.pop(0) if free else cap
                cap += ref[i] == cap
            want.append(ref[i])
        assert s.assign(ids).tolist() == want
        assert s.capacity == cap and s.slot_of == ref


def test_the_writer_thread_flushes_within_the_delay(tmp_path):
    """Frames handed over reach the disk max_delay (+ a quarter of it) later, without help."""
    import time

    from vibrofeed.results.writer import ResultWriter

    w = ResultWriter(tmp_path / "t.h5", deck_name="d", deck_path="d", deck_text="d", variables={},
                     derived={}, engine_version="LIGGGHTS", seed=1, max_delay=0.4)
    try:
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
        assert w.written == 0  # batched, not yet due
        time.sleep(0.9)        # due at 0.4 s, seen by the thread by 0.5 s
        assert w.written == 1
    finally:
        w.finish()


def test_run_record_defaults_and_status_of_a_missing_file(tmp_path):
    import h5py

    from vibrofeed.results.writer import mark_file_status

    path = three_frames(tmp_path)
    with h5py.File(path, "r") as f:
        run = f[L.RUN].attrs
        assert run["ranks"] == 1 and run["status"] == "complete" and run["message"] == ""
        assert f[f"{L.PARAMETERS}/seed"][()] == 1
    assert mark_file_status(path, "failed", "boom") is True
    with Result(path, allow_incomplete=True) as r:
        assert r.status == "failed" and r.message == "boom"
    assert mark_file_status(tmp_path / "missing.h5", "failed") is False
    (tmp_path / "text.h5").write_text("not hdf5")
    assert mark_file_status(tmp_path / "text.h5", "failed") is False
    with h5py.File(tmp_path / "bare.h5", "w"):
        pass
    assert mark_file_status(tmp_path / "bare.h5", "failed") is False


def test_author_is_unknown_when_the_user_cannot_be_named(tmp_path, monkeypatch):
    import getpass

    import h5py

    def nobody():
        raise KeyError("uid not in passwd")

    monkeypatch.setattr(getpass, "getuser", nobody)
    path = three_frames(tmp_path)
    with h5py.File(path, "r") as f:
        assert f["h5md/author"].attrs["name"] == b"unknown"


def test_format_version_is_the_one_format_md_documents(tmp_path):
    import re

    import h5py

    from helpers import REPO

    text = (REPO / "FORMAT.md").read_text()
    documented = [int(v) for v in re.search(r"\+format_version = \[(\d+), (\d+)\]", text).groups()]
    with h5py.File(three_frames(tmp_path), "r") as f:
        assert f[L.PARAMETERS].attrs["format_version"].tolist() == documented
        assert f[L.PARAMETERS].attrs["format"] == b"vibrofeed-result"
        assert f["h5md"].attrs["version"].tolist() == [1, 1]  # H5MD 1.1


def test_included_files_are_stored_verbatim(tmp_path):
    from vibrofeed.results.writer import ResultWriter

    includes = {"include/contact.liggghts": "pair_style gran\n", "include/motion.liggghts": "fix m\n"}
    w = ResultWriter(tmp_path / "i.h5", deck_name="d", deck_path="d", deck_text="include x\n",
                     includes=includes, variables={}, derived={}, engine_version="LIGGGHTS", seed=1)
    w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
    w.write_frame(1, 1e-3, parts([1], [[0, 0, 1]]), [0, 0, 0], [0, 0, 0])
    assert w.frames == 2
    w.finish()
    with Result(tmp_path / "i.h5") as r:
        assert r.deck_includes == includes and r.deck_text == "include x\n"
        assert r.n_frames == 2


def test_writer_as_a_context_manager_records_how_the_run_ended(tmp_path):
    from vibrofeed.results.writer import ResultWriter

    def writer(name):
        return ResultWriter(tmp_path / name, deck_name="d", deck_path="d", deck_text="d",
                            variables={}, derived={}, engine_version="LIGGGHTS", seed=None)

    with writer("ok.h5") as w:
        assert w.max_delay == 0.25  # the documented default
        w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 1e-6], [0, 0, 2e-3])
    with pytest.raises(RuntimeError):
        with writer("bad.h5") as w:
            w.write_frame(0, 0.0, parts([1], [[0, 0, 0]]), [0, 0, 0], [0, 0, 0])
            raise RuntimeError("engine died")
    with Result(tmp_path / "ok.h5") as r:
        assert r.status == "complete" and r.seed == -1  # no seed: -1
        assert r.read("surface_position")[0].tolist() == [0, 0, 1e-6]
        assert r.read("surface_velocity")[0].tolist() == [0, 0, 2e-3]
    with Result(tmp_path / "bad.h5", allow_incomplete=True) as r:
        assert r.status == "failed" and r.message == "RuntimeError: engine died"


def test_duplicate_ids_anywhere_in_a_frame_are_refused(tmp_path):
    for k, ids in enumerate(([1, 2, 2], [3, 1, 3], [5, 6, 7, 8, 6])):
        with pytest.raises(ValueError, match="duplicate"):
            write_result(tmp_path / f"d{k}.h5", [(0, 0.0, parts(ids, np.zeros((len(ids), 3))))])


@pytest.mark.parametrize("frames, slots", [
    ([3], None), ([0, 3], None), ([-4], None), (np.array([True, False]), None),  # 3 frames
    (None, [2]), (None, [-3]), (1, [0, 2]), (slice(None), [1, 2])])               # 2 slots
def test_a_selection_beyond_the_file_is_an_index_error(tmp_path, frames, slots):
    """Indices past either end (negative ones count from the end) are refused, not clipped
    as h5py would clip them."""
    with Result(three_frames(tmp_path)) as r:
        assert (r.n_frames, r.n_slots) == (3, 2)
        with pytest.raises(IndexError, match="out of range|boolean selection"):
            r.read("position", frames=frames, slots=slots)


def test_a_run_that_wrote_no_frame_reads_as_no_parts(tmp_path):
    from vibrofeed.results.writer import ResultWriter

    path = tmp_path / "none.h5"
    ResultWriter(path, deck_name="d", deck_path="d", deck_text="d", variables={}, derived={},
                 engine_version="LIGGGHTS", seed=1).finish("failed", "died before the first frame")
    with Result(path, allow_incomplete=True) as r:
        assert r.n_frames == 0 and r.part_ids.tolist() == [] and r.part_ids.dtype.kind == "i"
        present = r.present()
        assert present.shape == (0,) and present.dtype.kind == "i"
        assert [a.tolist() for a in r.locate(1)] == [[], []]
        assert list(r.iter_frames()) == []
        with pytest.raises(KeyError, match="does not appear"):
            r.track(1)


# -- layout: the box, section names and the versions FORMAT.md documents ---------------------------
def test_the_open_box_has_zero_edges_at_every_frame_sampled_with_the_positions(tmp_path):
    """FORMAT.md: box edges are placeholders (0), hard-linked to the positions' step and time."""
    with h5py.File(three_frames(tmp_path), "r") as f:
        box = f[f"{L.PARTS}/box"]
        assert [b.decode() for b in box.attrs["boundary"]] == ["none"] * 3
        edges = box["edges/value"]
        assert edges.shape == (3, 3) and edges.attrs["unit"] == "m"
        assert not edges[()].any()
        assert box["edges/step"] == f[f"{L.PARTS}/position/step"]
        assert box["edges/time"] == f[f"{L.PARTS}/position/time"]


def test_section_1_keeps_the_single_tracks_names_and_further_ones_take_their_number():
    # section 1 is what every deck defines (DECK_CONTRACT); section k the s<k>_ names
    assert L.surface_variables(1) == (("surface_x", "surface_y", "surface_z"),
                                      ("surface_vx", "surface_vy", "surface_vz"))
    assert set(sum(L.surface_variables(1), ())) <= set(L.DECK_CONTRACT)
    for k in (2, 3):
        assert L.surface_variables(k) == (tuple(f"s{k}_surface_{c}" for c in "xyz"),
                                          tuple(f"s{k}_surface_v{c}" for c in "xyz"))
        assert L.surface_path(k) == f"{L.SURFACE}_s{k}"
    assert L.surface_path(1) == L.SURFACE
    with pytest.raises(ValueError, match="count from 1"):
        L.surface_path(0)


def test_the_rotation_and_sections_arrive_in_the_formats_format_md_names():
    import re

    from helpers import REPO

    text = (REPO / "FORMAT.md").read_text()

    def since(what):
        return tuple(int(v) for v in re.search(rf"Format (\d+)\.(\d+) records {what}", text).groups())

    assert L.ROTATION_SINCE == since("a rotating surface's rotation")
    assert L.SECTIONS_SINCE == since("a feeder line's section 2 motion")
    assert L.SECTIONS_SINCE < L.ROTATION_SINCE <= L.FORMAT_VERSION
