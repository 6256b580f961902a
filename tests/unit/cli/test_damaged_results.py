"""A damaged result file is one line naming the file, in every command that reads results.

The damage is made by hand in a synthetic result: the signature of the B-tree that indexes
the chunks of one dataset is overwritten ("wrong B-tree signature" to HDF5, as a disk error
or a copy cut and patched would leave it), or the file is cut in half.
"""

from __future__ import annotations

import struct

import h5py
import numpy as np
import pytest

from bulk_synthetic import feeder
from helpers import vibrofeed
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result, ResultError

FRAMES = np.linspace(0.0, 1.0, 21)
EXITS = np.array([0.12, 0.33, 0.41, 0.55, 0.62, 0.9, 1.4, 1.9])
POSITION = "/particles/parts/position/value"
DAMAGED = "the file is damaged or was not written whole"


def break_chunk_index(path, dataset: str) -> None:
    """Overwrite the signature ("TREE") of the B-tree node that points at the first chunk of
    ``dataset``: its data can no longer be found, the rest of the file reads."""
    with h5py.File(path, "r") as f:
        address = f[dataset].id.get_chunk_info(0).byte_offset
    data = bytearray(path.read_bytes())
    at = 0
    while (at := data.find(b"TREE", at)) >= 0:
        # a version-1 B-tree node of chunks (type 1) whose keys hold the chunk's address
        if data[at + 4] == 1 and struct.pack("<Q", address) in data[at:at + 2048]:
            data[at:at + 4] = b"XXXX"
            path.write_bytes(bytes(data))
            return
        at += 4
    raise AssertionError(f"no B-tree node points at {dataset}'s first chunk")


@pytest.fixture
def good(tmp_path):
    return feeder(tmp_path / "good.h5", FRAMES, EXITS, speed=0.03, amp=2e-5)


@pytest.fixture
def damaged(tmp_path, good):
    path = tmp_path / "damaged.h5"
    path.write_bytes(good.read_bytes())
    break_chunk_index(path, POSITION)
    with h5py.File(path, "r") as f, pytest.raises(OSError, match="wrong B-tree signature"):
        f[POSITION][()]  # the damage is what the tests below meet
    return path


def one_error_line(proc, path) -> str:
    assert proc.returncode == 1, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vibrofeed: error: "), proc.stderr
    assert str(path) in lines[0] and "Traceback" not in proc.stderr
    return lines[0]


@pytest.mark.parametrize("command", [
    ("feedrate",), ("singulation",), ("render", "-o", "{tmp}/x.png"), ("export", "-o", "{tmp}/pv"),
    ("export", "--format", "h5md-md", "-o", "{tmp}/md")], ids=lambda c: " ".join(c[:3]))
def test_every_command_reading_a_damaged_result_names_the_file_and_what_it_could_not_read(
        damaged, tmp_path, command):
    command = [word.format(tmp=tmp_path) for word in command]
    line = one_error_line(vibrofeed(command[0], damaged, *command[1:]), damaged)
    assert line == (f"vibrofeed: error: {damaged}: cannot read {POSITION} (wrong B-tree signature): "
                    f"{DAMAGED}")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["damaged.h5", "good.h5"]  # nothing written


def test_a_cut_result_is_one_line_naming_the_file(good, tmp_path):
    cut = tmp_path / "cut.h5"
    data = good.read_bytes()
    cut.write_bytes(data[:len(data) // 2])
    line = one_error_line(vibrofeed("feedrate", cut), cut)
    assert line == (f"vibrofeed: error: {cut}: cannot open as HDF5 (truncated file: eof = {len(data) // 2}, "
                    f"sblock->base_addr = 0, stored_eof = {len(data)})")
    assert one_error_line(vibrofeed("render", tmp_path / "none.h5", "-o", tmp_path / "x.png"),
                          tmp_path / "none.h5").endswith("none.h5: no such file")


def test_check_checks_every_file_and_fails_if_any_is_damaged(damaged, good, tmp_path):
    cut = tmp_path / "cut.h5"
    cut.write_bytes(good.read_bytes()[:1000])
    proc = vibrofeed("check", damaged, cut, good)
    assert proc.returncode == 1 and proc.stderr == ""
    out = proc.stdout.splitlines()
    assert out[0].startswith(f"INVALID: {damaged}: ")
    assert out[1] == f"  error: {POSITION}: cannot read (wrong B-tree signature): {DAMAGED}"
    assert out[2].startswith(f"INVALID: {cut}: ") and "truncated file" in out[3]
    assert out[4].startswith(f"OK: {good}: 21 frames")
    # the library's check, alike: a report, not an exception
    report = check_file(damaged)
    assert not report.ok and [p.where for p in report.problems if p.level == "error"] == [POSITION[1:]]


def test_a_result_read_by_the_library_raises_result_error_naming_the_file(damaged):
    with pytest.raises(ResultError, match=f"^{damaged}: cannot read {POSITION} "), Result(damaged) as r:
        r.read("position")


def test_errors_that_are_not_the_file_s_pass_through(good):
    with pytest.raises(KeyError, match="no_such_field"), Result(good):
        {}["no_such_field"]
    with pytest.raises(OSError, match="disk"), Result(good):
        raise OSError(28, "no room on the disk")


def test_a_run_that_did_not_complete_names_the_option_only_where_the_command_has_it(good, tmp_path):
    with h5py.File(good, "r+") as f:
        f["parameters/run"].attrs["status"] = "interrupted"
        f["parameters/run"].attrs["message"] = "Ctrl-C"
    with pytest.raises(ResultError) as info:
        Result(good)
    assert str(info.value) == f"{good}: the run that wrote it did not complete (status interrupted: Ctrl-C)"
    assert "allow_incomplete" not in str(info.value)
    line = one_error_line(vibrofeed("feedrate", good), good)
    assert "--allow-incomplete" not in line  # feedrate has no such option
    line = one_error_line(vibrofeed("render", good, "-o", tmp_path / "x.png"), good)
    assert line.endswith("(status interrupted: Ctrl-C); --allow-incomplete reads the frames it holds")
