"""H5MD result files: writer, reader and `vibrofeed check` on small hand-made runs."""

import h5py
import numpy as np
import pytest

from vibrofeed.results import layout as L
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import IncompleteResult, Result, ResultError
from vibrofeed.results.writer import SlotMap

from helpers import parts, write_result


def three_frames(tmp_path, **kw):
    """Particle 1 throughout; 2 leaves after frame 0; 3 arrives at frame 2 and reuses 2's slot."""
    frames = [
        (0, 0.0, parts([1, 2], [[0, 0, 1], [1, 0, 1]])),
        (10, 1e-5, parts([1], [[0.1, 0, 1]])),
        (20, 2e-5, parts([3, 1], [[5, 0, 1], [0.2, 0, 1]])),
    ]
    surface = [([0, 0, k * 1e-6], [0, 0, 1e-3]) for k in range(3)]
    return write_result(tmp_path / "r.h5", frames, surface, **kw)


def test_roundtrip_with_varying_particle_number(tmp_path):
    path = three_frames(tmp_path)
    with Result(path) as r:
        assert r.n_frames == 3
        assert list(r.step) == [0, 10, 20] and np.allclose(r.time, [0, 1e-5, 2e-5])
        # slot 0 is particle 1, slot 1 held 2, was empty, then holds 3
        assert r.ids.tolist() == [[1, 2], [1, -1], [1, 3]]
        assert np.isnan(r.position[1, 1]).all()
        assert np.isnan(r.radius[1, 1]) and r.species[1, 1] == L.SPECIES_FILL
        t, x = r.track(3)
        assert t.tolist() == [2e-5] and x.tolist() == [[5, 0, 1]]
        t, x = r.track(1)
        assert np.allclose(x[:, 0], [0, 0.1, 0.2])
        assert r.part_ids.tolist() == [1, 2, 3]
        assert r.present().tolist() == [2, 1, 2]
        assert np.allclose(r.surface_position[:, 2], [0, 1e-6, 2e-6])
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
        assert f[f"{L.PARTS}/position/value"].attrs["unit"] == b"m"
        assert f[f"{L.PARTS}/velocity/value"].attrs["unit"] == b"m s-1"
        assert f[f"{L.PARTS}/position/time"].attrs["unit"] == b"s"
        # one step/time dataset shared by every element (H5MD hard links)
        ref = f[f"{L.PARTS}/position/step"]
        for name in ("velocity", "id", "radius"):
            assert f[f"{L.PARTS}/{name}/step"] == ref
        assert f[f"{L.SURFACE}/position/step"] == ref
        assert f[f"{L.PARTS}/id/value"].fillvalue == -1


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
