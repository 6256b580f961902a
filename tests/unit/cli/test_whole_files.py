"""Whether a file a command wrote is whole, and the one line an OSError becomes
(vibrofeed.cli.outputs), on bytes built by hand: the boundaries of each kind's check
(a PNG's end chunk, an MP4's box headers and sizes, a VTK XML file's closing tag), the
messages users read, and ``replaced`` keeping an older file when the new one fails."""

from __future__ import annotations

import errno
import os
import struct
import zlib
from pathlib import Path

import pytest

from vibrofeed.cli import outputs
from vibrofeed.cli.outputs import incomplete, os_error, replaced, written
from vibrofeed.errors import OutputError


# ----------------------------------------------------------------- PNG
def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def _png() -> bytes:
    """A 1x1 grey PNG: signature, IHDR, IDAT, IEND (12 bytes: an empty chunk)."""
    ihdr = struct.pack(">IIBBBBB", 1, 1, 8, 0, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", zlib.compress(b"\0\x80"))
            + _chunk(b"IEND", b""))


def test_a_png_ending_exactly_with_its_end_chunk_is_whole(tmp_path):
    p = tmp_path / "a.png"
    p.write_bytes(_png())
    assert incomplete(p) is None


@pytest.mark.parametrize("short", range(1, 5))
def test_a_png_whose_end_chunk_lost_its_crc_says_its_end_chunk_is_cut(tmp_path, short):
    # the end chunk's length and type (8 bytes) are there, 1..4 bytes of its CRC are not
    p = tmp_path / "a.png"
    p.write_bytes(_png()[:-short])
    assert incomplete(p) == "its end chunk is cut"


@pytest.mark.parametrize("short", range(5, 13))
def test_a_png_cut_before_its_end_chunks_type_stops_before_the_end_chunk(tmp_path, short):
    data = _png()[:-short]
    p = tmp_path / "a.png"
    p.write_bytes(data)
    assert incomplete(p) == f"its image data stops after {len(data)} bytes, before the end chunk"


def test_a_png_cut_inside_its_image_data_stops_before_the_end_chunk(tmp_path):
    png = _png()
    cut = png.index(b"IDAT") + 6  # inside the IDAT chunk's data
    p = tmp_path / "a.png"
    p.write_bytes(png[:cut])
    assert incomplete(p) == f"its image data stops after {cut} bytes, before the end chunk"


# ----------------------------------------------------------------- MP4 (ISO base media)
def _box(kind: bytes, payload: bytes) -> bytes:
    return struct.pack(">I", 8 + len(payload)) + kind + payload


def _box64(kind: bytes, payload: bytes) -> bytes:
    """A box with a 64-bit size: size field 1, then the 8-byte largesize after the type."""
    return struct.pack(">I", 1) + kind + struct.pack(">Q", 16 + len(payload)) + payload


FTYP = _box(b"ftyp", b"isom\0\0\2\0")  # 16 bytes
MOOV = _box(b"moov", b"\0" * 40)


def _mp4(tmp_path, data: bytes) -> str | None:
    p = tmp_path / "m.mp4"
    p.write_bytes(data)
    return incomplete(p)


@pytest.mark.parametrize("last", [False, True])
def test_an_mp4_with_a_64_bit_box_size_is_whole(tmp_path, last):
    mdat = _box64(b"mdat", bytes(range(256)) * 4)
    movie = FTYP + MOOV + mdat if last else FTYP + mdat + MOOV
    assert _mp4(tmp_path, movie) is None


def test_an_mp4_whose_64_bit_box_is_cut_stops_after_its_bytes(tmp_path):
    movie = FTYP + _box64(b"mdat", b"\1" * 100) + MOOV
    cut = len(FTYP) + 16 + 50  # inside the data of the 64-bit box
    assert _mp4(tmp_path, movie[:cut]) == f"its data stops after {cut} of {len(FTYP) + 116} bytes"


def test_an_mp4_whose_last_box_has_size_0_runs_to_the_end_and_is_whole(tmp_path):
    # size 0: the box runs to the end of the file (ffmpeg's mdat while it writes)
    mdat = struct.pack(">I", 0) + b"mdat" + b"\0" * 64 + b"\7" * 100
    assert _mp4(tmp_path, FTYP + MOOV + mdat) is None


def test_an_mp4_ending_with_an_empty_8_byte_box_is_whole(tmp_path):
    assert _mp4(tmp_path, FTYP + MOOV + _box(b"free", b"")) is None


@pytest.mark.parametrize("left", range(1, 8))
def test_an_mp4_cut_inside_a_box_header_says_where(tmp_path, left):
    movie = FTYP + MOOV + _box(b"free", b"\0" * 8)
    at = len(FTYP) + len(MOOV)
    assert _mp4(tmp_path, movie[:at + left]) == f"it stops inside a box header at byte {at}"


@pytest.mark.parametrize("left", range(8, 16))
def test_an_mp4_cut_inside_a_64_bit_box_header_is_not_whole(tmp_path, left):
    movie = FTYP + _box64(b"mdat", b"\1" * 32)
    msg = _mp4(tmp_path, movie[:len(FTYP) + left])
    assert msg is not None and msg.endswith(f" at byte {len(FTYP)}")


@pytest.mark.parametrize("size", range(2, 8))
def test_an_mp4_box_smaller_than_its_header_is_malformed(tmp_path, size):
    bad = struct.pack(">I", size) + b"free"
    assert _mp4(tmp_path, FTYP + bad + MOOV) == f"it has a malformed box at byte {len(FTYP)}"


@pytest.mark.parametrize("size", range(0, 8))
def test_an_mp4_64_bit_box_size_smaller_than_a_header_is_malformed(tmp_path, size):
    bad = struct.pack(">I", 1) + b"free" + struct.pack(">Q", size)
    assert _mp4(tmp_path, FTYP + bad + MOOV) == f"it has a malformed box at byte {len(FTYP)}"


# ----------------------------------------------------------------- VTK XML
# white space after the tag, however long: none, one line end, 54 and 55 bytes (an earlier
# check read only the last 64), and more than one 4096-byte block read back, ending exactly on
# a block's edge or the tag straddling one
@pytest.mark.parametrize("after", [b"", b"\n", b"\r\n", b" \t\n" * 3, b" " * 54, b" " * 55, b"\n" * 5000,
                                   b" " * 4096, b" " * 4091])
def test_a_vtk_xml_file_ending_with_its_closing_tag_and_white_space_is_whole(tmp_path, after):
    p = tmp_path / "r.vtp"
    p.write_bytes(b'<?xml version="1.0"?>\n<VTKFile type="PolyData">\n' + b"x" * 500 + b"\n</VTKFile>"
                  + after)
    assert incomplete(p) is None


@pytest.mark.parametrize("after", [b"", b"\n"])
def test_the_closing_tag_is_found_at_the_very_start_of_a_short_file(tmp_path, after):
    p = tmp_path / "r.pvd"
    p.write_bytes(b"</VTKFile>" + after)
    assert incomplete(p) is None


@pytest.mark.parametrize("text", [b" ", b"\n" * 6000, b"/VTKFile>", b"</VTKFile"])
def test_a_short_or_blank_file_is_not_a_whole_vtk_xml_file(tmp_path, text):
    p = tmp_path / "r.vtp"
    p.write_bytes(text)
    assert incomplete(p) == "it stops before </VTKFile>"


@pytest.mark.parametrize("tail", [b"</VTKFile", b"</VTKFile>\n<extra/>\n", b"</AppendedData>\n",
                                  b"</AppendedData>" + b" " * 5000, b"VTKFile>\n", b"\n" * 9000])
def test_a_vtk_xml_file_not_ending_with_its_closing_tag_is_not_whole(tmp_path, tail):
    p = tmp_path / "r.vtu"
    p.write_bytes(b'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid">\n' + b"y" * 300 + tail)
    assert incomplete(p) == "it stops before </VTKFile>"


# ----------------------------------------------------------------- HDF5
def test_an_hdf5_file_that_is_not_one_names_hdf5s_reason(tmp_path):
    p = tmp_path / "r.h5"
    p.write_bytes(b"these bytes are no HDF5 file\n" * 40)
    msg = incomplete(p)
    assert msg.startswith("HDF5 cannot open it (") and msg.endswith(")")
    assert "signature" in msg and "\n" not in msg  # HDF5's own reason, not a stand-in


def test_hdf5s_reason_is_its_first_line_or_damaged_when_it_gives_none(tmp_path, monkeypatch):
    import h5py

    p = tmp_path / "r.h5md"
    p.write_bytes(b"\0" * 100)
    for raised, shown in [(OSError("Unable to open file (truncated file)\nHDF5-DIAG: error stack"),
                           "Unable to open file (truncated file)"),
                          (OSError(), "damaged")]:
        def refuse(*args, exc=raised, **kwargs):
            raise exc

        monkeypatch.setattr(h5py, "File", refuse)
        assert incomplete(p) == f"HDF5 cannot open it ({shown})"


# ----------------------------------------------------------------- written, replaced
def test_written_names_what_is_missing_empty_or_cut(tmp_path):
    with pytest.raises(OutputError) as e:
        written(tmp_path / "none.png", name="shown.png")
    assert str(e.value) == "shown.png was not written"
    (tmp_path / "e.mp4").write_bytes(b"")
    with pytest.raises(OutputError) as e:
        written(tmp_path / "e.mp4")
    assert str(e.value) == f"{tmp_path / 'e.mp4'} was written empty"
    (tmp_path / "c.png").write_bytes(_png()[:-2])
    with pytest.raises(OutputError) as e:
        written(tmp_path / "c.png")
    assert str(e.value) == f"{tmp_path / 'c.png'} is incomplete: its end chunk is cut"


@pytest.mark.parametrize("exc, why", [(OSError(errno.EIO, "Input/output error"), "Input/output error"),
                                      (OSError("cannot read it"), "cannot read it")])
def test_a_file_that_cannot_be_read_is_not_reported_as_written(tmp_path, monkeypatch, exc, why):
    (tmp_path / "x.png").write_bytes(_png())

    def unreadable(path):
        raise exc

    monkeypatch.setattr(outputs, "incomplete", unreadable)
    with pytest.raises(OutputError) as e:
        written(tmp_path / "x.png")
    assert str(e.value) == f"{tmp_path / 'x.png'} is incomplete: {why}"


def test_replaced_puts_the_whole_file_under_its_name_and_leaves_nothing_else(tmp_path):
    out = tmp_path / "pic.png"
    with replaced(out) as tmp:
        assert tmp.parent == tmp_path and tmp.suffix == ".png" and tmp.name.startswith(".")
        tmp.write_bytes(_png())
    assert out.read_bytes() == _png()
    assert [p.name for p in tmp_path.iterdir()] == ["pic.png"]


def test_replaced_keeps_the_older_file_when_the_new_one_is_cut(tmp_path):
    out = tmp_path / "pic.png"
    out.write_bytes(b"older")
    with pytest.raises(OutputError) as e:
        with replaced(out) as tmp:
            tmp.write_bytes(_png()[:-20])
    assert str(e.value).startswith(f"{out} is incomplete: ")  # the name asked for, not the temporary
    assert out.read_bytes() == b"older"
    assert [p.name for p in tmp_path.iterdir()] == ["pic.png"]


def test_replaced_passes_the_writers_error_on_when_it_wrote_nothing(tmp_path):
    class WriterFailed(Exception):
        pass

    out = tmp_path / "pic.png"
    with pytest.raises(WriterFailed):
        with replaced(out):
            raise WriterFailed
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------- OSError as one line
def test_an_oserror_without_strerror_is_its_first_line_or_its_type(monkeypatch):
    monkeypatch.setattr(outputs, "_destinations", [])
    assert os_error(OSError("the plotting library failed\nat line 3\n  detail")) == (
        "the plotting library failed", 1)
    assert os_error(OSError("one line only")) == ("one line only", 1)
    assert os_error(OSError()) == ("OSError", 1)
    assert os_error(BlockingIOError()) == ("BlockingIOError", 1)


def test_a_failed_move_names_both_files(monkeypatch):
    monkeypatch.setattr(outputs, "_destinations", [Path("elsewhere")])
    assert os_error(OSError(errno.EXDEV, "Invalid cross-device link", "a.part", None, "a.png")) == (
        "cannot move a.part to a.png: Invalid cross-device link", 1)


@pytest.mark.parametrize("code, status", [
    (errno.EISDIR, 2), (errno.ENOTDIR, 2), (errno.EACCES, 2), (errno.EPERM, 2), (errno.EROFS, 2),
    (errno.ENOENT, 2), (errno.ENAMETOOLONG, 2), (errno.EEXIST, 2), (errno.ELOOP, 2),
    (errno.EIO, 1), (errno.EDQUOT, 1), (errno.EFBIG, 1), (errno.EBADF, 1),
])
def test_the_exit_status_is_2_for_a_path_that_cannot_be_written_else_1(code, status):
    assert os_error(OSError(code, os.strerror(code), "f.png")) == (f"f.png: {os.strerror(code)}", status)


def test_an_error_naming_no_file_is_placed_only_when_it_is_a_full_disk(monkeypatch, tmp_path):
    monkeypatch.setattr(outputs, "_destinations", [tmp_path / "first.png", tmp_path / "plots"])
    # not a full disk: the destination is not where it happened
    assert os_error(OSError(errno.EIO, "Input/output error")) == ("Input/output error", 1)
    # over quota: where the command was writing, its latest destination
    assert os_error(OSError(errno.EDQUOT, "Disk quota exceeded")) == (
        f"writing into {tmp_path / 'plots'}: Disk quota exceeded", 1)
    monkeypatch.setattr(outputs, "_destinations", [])
    assert os_error(OSError(errno.EIO, "Input/output error")) == ("Input/output error", 1)
    assert os_error(OSError(errno.ENOSPC, "No space left on device")) == ("No space left on device", 1)


@pytest.fixture
def mounted(tmp_path, monkeypatch):
    """tmp_path/mnt, an existing folder seen as the mount point of a file system of its own."""
    mnt = (tmp_path / "mnt").resolve()
    mnt.mkdir()
    real = os.path.ismount
    monkeypatch.setattr(os.path, "ismount", lambda p: Path(p) == mnt or real(p))
    return mnt


def test_a_full_disk_names_the_mount_of_the_file(mounted, monkeypatch):
    monkeypatch.setattr(outputs, "_destinations", [])
    (mounted / "old.png").write_bytes(b"x")
    for target in (mounted / "old.png", mounted / "new.png", mounted / "a" / "b" / "new.png", mounted):
        assert os_error(OSError(errno.ENOSPC, "No space left on device", str(target))) == (
            f"{target}: no space left on {mounted}", 1)


def test_a_full_disk_naming_no_file_names_the_latest_destination_and_its_mount(mounted, monkeypatch,
                                                                               tmp_path):
    # the latest destination, a folder not created yet: its nearest existing folder's mount
    monkeypatch.setattr(outputs, "_destinations", [tmp_path / "x.png", mounted / "results" / "run1"])
    assert os_error(OSError(errno.ENOSPC, "No space left on device")) == (
        f"writing into {mounted / 'results' / 'run1'}: no space left on {mounted}", 1)


def test_a_full_disk_behind_a_symbolic_link_names_the_mount_it_leads_to(mounted, monkeypatch, tmp_path):
    # -o link.png, a link to a file not written yet on another file system: the file goes there
    monkeypatch.setattr(outputs, "_destinations", [])
    link = tmp_path / "link.png"
    link.symlink_to(mounted / "new" / "x.png")
    assert os_error(OSError(errno.ENOSPC, "No space left on device", str(link))) == (
        f"{link}: no space left on {mounted}", 1)
