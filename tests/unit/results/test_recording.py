"""What a run records of its feeder (vibrofeed.results.writer.Recording): one record the writer
takes, the rejects, their return and an air jet's firings from the feeder, the sections' motion
and the rotation as the deck defines them; and the files it makes."""

import h5py
import pytest
from feeder_values import BOWL, BOWL_LINE, LINE, TRACK

from vibrofeed.feeders import Feeder
from vibrofeed.results import layout as L
from vibrofeed.results.writer import Recording, ResultWriter


@pytest.mark.parametrize("values, sections, rotating, want", [
    (None, 1, False, Recording()),                      # a deck without the feeders' vocabulary
    (TRACK, 1, False, Recording()),
    (LINE, 2, False, Recording(sections=2, rejects=True)),
    ({**LINE, "recirculate": 1}, 2, False, Recording(sections=2, rejects=True, returns=True)),
    ({**LINE, "s2_jet_force": 1e-6, "s2_jet_at": 0.25}, 2, False,
     Recording(sections=2, rejects=True, jet=True)),
    (BOWL, 1, True, Recording(rotating=True)),
    (BOWL_LINE, 2, True, Recording(sections=2, rotating=True, rejects=True)),
])
def test_a_feeders_recording(values, sections, rotating, want):
    feeder = Feeder.from_values(values) if values is not None else None
    assert Recording.of(feeder, sections, rotating) == want


def test_a_deck_of_ones_own_records_the_motion_it_defines():
    assert Recording.of(None, 3, True) == Recording(sections=3, rotating=True)


def test_what_the_writer_creates_of_each(tmp_path):
    def made(recording):
        path = tmp_path / f"r{len(list(tmp_path.iterdir()))}.h5"
        w = ResultWriter(path, deck_name="d", deck_path="d", deck_text="d", variables={}, derived={},
                         engine_version="LIGGGHTS", seed=1, recording=recording)
        w.close()
        with h5py.File(path, "r") as f:
            return (L.REJECTS in f, L.JET in f, L.surface_path(2) in f,
                    "angle" in f[L.SURFACE])

    assert made(Recording()) == (False, False, False, False)
    assert made(Recording(sections=2, rejects=True, jet=True)) == (True, True, True, False)
    assert made(Recording(rotating=True)) == (False, False, False, True)


def test_a_recording_refuses_what_no_run_records():
    with pytest.raises(ValueError, match="returns without a line"):
        Recording(returns=True)
    with pytest.raises(ValueError, match="sections must be >= 1, got 0"):
        Recording(sections=0)
