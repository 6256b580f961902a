"""No success without the file (issue 19): a command reports a file only when it is whole,
an OSError met while writing is one line with its exit status, never a traceback, and a
figure's name taken by a folder is refused or named in one line."""

from __future__ import annotations

import errno
import io
import os
import shutil
import subprocess

import numpy as np
import pytest

from helpers import vibrofeed
from vibrofeed.cli.outputs import incomplete, os_error, written
from vibrofeed.errors import OutputError


def one_line_error(proc, code: int, *words: str) -> None:
    assert proc.returncode == code, proc.stderr
    assert proc.stderr.startswith("vibrofeed: error: ") and proc.stderr.count("\n") == 1, proc.stderr
    for word in words:
        assert word in proc.stderr, proc.stderr


def fill(disk, leave: int) -> None:
    """Fill ``disk`` until ``leave`` bytes (rounded down to its blocks) are free."""
    st = os.statvfs(disk)
    free = st.f_bfree * st.f_frsize
    with open(disk / "filler", "ab") as f:
        f.write(b"\0" * max(0, free - leave))
    st = os.statvfs(disk)
    assert st.f_bfree * st.f_frsize <= leave


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    """A small result with moving parts, for pictures and plots."""
    from bulk_synthetic import feeder

    folder = tmp_path_factory.mktemp("r")
    return feeder(folder / "run.h5", np.arange(0, 0.2 + 1e-9, 0.01), 0.02 + 0.15 * np.arange(40) / 40,
                  freq=100.0)


# ----------------------------------------------------------------- whole files
def _png_bytes() -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    buf = io.BytesIO()
    plt.imsave(buf, np.random.default_rng(0).random((64, 64)), format="png")
    return buf.getvalue()


def _box(kind: bytes, payload: bytes) -> bytes:
    return (8 + len(payload)).to_bytes(4, "big") + kind + payload


def test_a_png_is_whole_only_up_to_its_end_chunk(tmp_path):
    png = _png_bytes()
    (tmp_path / "whole.png").write_bytes(png)
    assert incomplete(tmp_path / "whole.png") is None
    for cut in (len(png) - 1, len(png) - 12, len(png) // 2, 8, 20):
        (tmp_path / "cut.png").write_bytes(png[:cut])
        assert incomplete(tmp_path / "cut.png") is not None, cut
    (tmp_path / "text.png").write_bytes(b"not a picture at all")
    assert "does not start as a PNG" in incomplete(tmp_path / "text.png")


def test_an_mp4_is_whole_when_its_boxes_tile_the_file_and_it_has_its_index(tmp_path):
    movie = _box(b"ftyp", b"isom\0\0\2\0") + _box(b"mdat", b"\1" * 1000) + _box(b"moov", b"\0" * 40)
    (tmp_path / "m.mp4").write_bytes(movie)
    assert incomplete(tmp_path / "m.mp4") is None
    (tmp_path / "m.mp4").write_bytes(movie[:-10])  # cut inside the index
    assert "stops after" in incomplete(tmp_path / "m.mp4")
    (tmp_path / "m.mp4").write_bytes(movie[:-48])  # index missing: ffmpeg writes it last
    assert "no index" in incomplete(tmp_path / "m.mp4")


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="needs ffmpeg")
def test_a_movie_ffmpeg_finished_is_whole_and_one_it_did_not_is_not(tmp_path):
    out = tmp_path / "t.mp4"
    subprocess.run(["ffmpeg", "-y", "-loglevel", "error", "-f", "lavfi", "-i",
                    "testsrc=duration=0.5:size=64x64:rate=10", "-pix_fmt", "yuv420p", str(out)],
                   check=True, timeout=60)
    assert incomplete(out) is None
    data = out.read_bytes()
    out.write_bytes(data[: len(data) * 3 // 4])
    assert incomplete(out) is not None


def test_vtk_xml_and_hdf5_files_are_whole_to_their_end(tmp_path):
    import h5py

    pvd = tmp_path / "r.pvd"
    pvd.write_text('<?xml version="1.0"?>\n<VTKFile type="Collection">\n</VTKFile>\n')
    assert incomplete(pvd) is None
    pvd.write_text('<?xml version="1.0"?>\n<VTKFile type="Collection">\n<Coll')
    assert "</VTKFile>" in incomplete(pvd)
    h5 = tmp_path / "r.h5md"
    with h5py.File(h5, "w") as f:
        f["x"] = np.arange(100000.0)
    assert incomplete(h5) is None
    h5.write_bytes(h5.read_bytes()[:5000])
    assert "HDF5 cannot open it" in incomplete(h5)


def test_a_file_reported_is_whole(tmp_path):
    with pytest.raises(OutputError, match="was not written"):
        written(tmp_path / "none.png")
    (tmp_path / "empty.png").write_bytes(b"")
    with pytest.raises(OutputError, match="written empty"):
        written(tmp_path / "empty.png")
    (tmp_path / "cut.png").write_bytes(_png_bytes()[:100])
    with pytest.raises(OutputError, match=r"cut.png is incomplete: its image data stops after 100 bytes"):
        written(tmp_path / "cut.png")
    (tmp_path / "whole.png").write_bytes(_png_bytes())
    assert written(tmp_path / "whole.png") == tmp_path / "whole.png"
    (tmp_path / "notes.txt").write_text("x")  # a kind without a check: not empty is whole
    assert written(tmp_path / "notes.txt") == tmp_path / "notes.txt"


# ----------------------------------------------------------------- OSError as one line
def test_an_oserror_becomes_one_line_with_the_exit_status_of_its_cause(tmp_path):
    from vibrofeed.cli import outputs

    assert os_error(IsADirectoryError(errno.EISDIR, "Is a directory", "p/x.png")) == (
        "p/x.png: Is a directory", 2)
    assert os_error(PermissionError(errno.EACCES, "Permission denied", "/x.png"))[1] == 2
    assert os_error(OSError(errno.EIO, "Input/output error", "x.h5")) == ("x.h5: Input/output error", 1)
    full = os_error(OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "x.png")))
    assert full == (f"{tmp_path / 'x.png'}: no space left on {outputs.mount_point(tmp_path)}", 1)
    moved = os_error(IsADirectoryError(errno.EISDIR, "Is a directory", "a.part", None, "a"))
    assert moved == ("cannot move a.part to a: Is a directory", 2)
    # a plotting library's ENOSPC names no file: the destination the command checked is named
    outputs.folder_destination("--plot", tmp_path / "plots")
    assert os_error(OSError(errno.ENOSPC, "No space left on device")) == (
        f"writing into {tmp_path / 'plots'}: no space left on {outputs.mount_point(tmp_path)}", 1)


@pytest.mark.parametrize("exc, code, line", [
    (OSError(errno.EIO, "Input/output error", "x.png"), 1, "x.png: Input/output error"),
    (IsADirectoryError(errno.EISDIR, "Is a directory", "d/f.png"), 2, "d/f.png: Is a directory"),
])
def test_the_command_line_prints_an_oserror_as_one_line(monkeypatch, capsys, exc, code, line):
    import vibrofeed.cli.decks as decks
    from vibrofeed.cli import main

    def broken(args):
        raise exc

    monkeypatch.setattr(decks, "run", broken)
    monkeypatch.delenv("VIBROFEED_DEBUG", raising=False)
    assert main(["decks"]) == code
    assert capsys.readouterr().err == f"vibrofeed: error: {line}\n"


# ----------------------------------------------------------------- a full disk
def no_library_noise(proc) -> None:
    for noise in ("Traceback", "libpng", "HDF5", "Segmentation"):
        assert noise not in proc.stderr, proc.stderr


def test_render_on_a_full_disk_writes_no_picture_and_keeps_the_old_one(run_file, tmp_path, small_disk):
    sample = tmp_path / "sample.png"
    vibrofeed("render", run_file, "-o", sample, check=True)
    size = sample.stat().st_size
    assert size > 3 * 4096  # more than the one block of room left below
    # with room: written, and whole
    out = small_disk / "r.png"
    proc = vibrofeed("render", run_file, "-o", out, check=True)
    assert proc.stdout.startswith(f"wrote {out} ") and incomplete(out) is None
    before = out.read_bytes()
    # room for part of a picture: one line (no libpng "Write Error" before it), exit 1,
    # the name asked for, the full disk
    fill(small_disk, 4096)
    proc = vibrofeed("render", run_file, "-o", out)
    one_line_error(proc, 1, f"writing into {out}: no space left on {small_disk}")
    no_library_noise(proc)
    assert "wrote" not in proc.stdout
    assert out.read_bytes() == before                     # the older picture is kept whole
    assert sorted(p.name for p in small_disk.iterdir()) == ["filler", "r.png"]  # nothing else
    proc = vibrofeed("render", run_file, "-o", small_disk / "new.png")
    one_line_error(proc, 1, "new.png", f"no space left on {small_disk}")
    no_library_noise(proc)
    assert not (small_disk / "new.png").exists()
    # no room at all: refused before drawing, one line
    fill(small_disk, 0)
    proc = vibrofeed("render", run_file, "-o", small_disk / "new.png")
    one_line_error(proc, 1, f"-o {small_disk / 'new.png'}: no space left on {small_disk}")


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="needs ffmpeg")
def test_a_movie_cut_by_a_full_disk_is_not_reported(run_file, small_disk):
    fill(small_disk, 8192)
    proc = vibrofeed("render", run_file, "-o", small_disk / "m.mp4", "--every", "4")
    one_line_error(proc, 1, "m.mp4", f"no space left on {small_disk}")  # (ffmpeg's stderr is read)
    assert "wrote" not in proc.stdout and not (small_disk / "m.mp4").exists()


def test_plots_on_a_full_disk_are_one_line_naming_the_folder(run_file, small_disk):
    fill(small_disk, 8192)  # room for the folder, not for the figures
    plots = small_disk / "plots"
    proc = vibrofeed("feedrate", run_file, "--plot", plots)
    one_line_error(proc, 1, f"writing into {plots}: no space left on {small_disk}")
    assert proc.stdout == ""


@pytest.mark.parametrize("leave", [64 * 1024, 1024 * 1024])
def test_a_paraview_export_on_a_full_disk_is_one_line_and_leaves_nothing(run_file, small_disk, leave):
    # 64 kB: room for one frame's file; 1 MB: for more than half of the series (1.6 MB)
    fill(small_disk, leave)
    out = small_disk / "pv"
    proc = vibrofeed("export", run_file, "-o", out)
    one_line_error(proc, 1, f"writing into {out}: no space left on {small_disk}")
    no_library_noise(proc)
    assert proc.stdout == ""
    # no .pvd, no series without its .pvd: the files and folders the export made are gone
    assert sorted(p.name for p in small_disk.iterdir()) == ["filler"]


def test_a_paraview_export_that_fits_is_written_whole(run_file, small_disk):
    proc = vibrofeed("export", run_file, "-o", small_disk / "pv", check=True)
    assert proc.stdout.startswith(f"wrote {small_disk / 'pv' / 'run.pvd'} ")
    for path in (small_disk / "pv").rglob("*.*"):
        assert incomplete(path) is None, path
    assert not [p for p in (small_disk / "pv").rglob(".*")]  # no temporary file left


@pytest.fixture(scope="module")
def md_size(run_file, tmp_path_factory):
    """Bytes of run_file's h5md-md export."""
    folder = tmp_path_factory.mktemp("md")
    vibrofeed("export", run_file, "--format", "h5md-md", "-o", folder, check=True)
    return (folder / "run.h5md").stat().st_size


@pytest.mark.parametrize("room", [0.05, 0.85])
def test_an_h5md_md_export_on_a_full_disk_is_one_line_and_leaves_nothing(run_file, small_disk, md_size,
                                                                          room):
    # 5 %: less than the parts' data, refused before writing; 85 %: more, HDF5 is writing when
    # the disk fills (HDF5's own writing: error stacks on stderr, then a segfault)
    fill(small_disk, int(room * md_size))
    out = small_disk / "md"
    proc = vibrofeed("export", run_file, "--format", "h5md-md", "-o", out)
    one_line_error(proc, 1, f"cannot write {out / 'run.h5md'}: no space left on {small_disk}")
    no_library_noise(proc)
    assert ("needs at least" in proc.stderr) == (room < 0.5)
    assert proc.stdout == "" and not out.exists()  # neither run.h5md nor its .part, nor the folder it made
    # with room again, the same command writes it whole
    (small_disk / "filler").unlink()
    proc = vibrofeed("export", run_file, "--format", "h5md-md", "-o", out, check=True)
    assert incomplete(out / "run.h5md") is None and [p.name for p in out.iterdir()] == ["run.h5md"]


# ----------------------------------------------------------------- names taken by folders
@pytest.mark.parametrize("command, figure", [("feedrate", "feedrate_cumulative.png"),
                                             ("singulation", "singulation_interarrival.png")])
def test_a_figure_named_like_a_folder_in_the_plot_folder_is_one_line(run_file, tmp_path, command, figure):
    (tmp_path / "plots" / figure).mkdir(parents=True)
    proc = vibrofeed(command, run_file, "--plot", tmp_path / "plots")
    one_line_error(proc, 2, f"{tmp_path / 'plots' / figure}: Is a directory")
    assert proc.stdout == ""


@pytest.mark.parametrize("fmt, taken, what", [
    ("paraview", "run.pvd", "is a folder"), ("paraview", "run_outlet.vtp", "is a folder"),
    ("paraview", "run", "is a file"), ("h5md-md", "run.h5md", "is a folder"),
])
def test_export_refuses_a_name_it_writes_that_is_taken_before_any_work(run_file, tmp_path, fmt, taken,
                                                                       what):
    out = tmp_path / "out"
    out.mkdir()
    if what == "is a file":
        (out / taken).write_text("x")
    else:
        (out / taken).mkdir()
    proc = vibrofeed("export", run_file, "-o", out, "--format", fmt)
    one_line_error(proc, 2, f"{out / taken} {what}")
    assert sorted(p.name for p in out.iterdir()) == [taken] and proc.stdout == ""


def test_prepare_names_a_file_it_cannot_write_in_one_line(tmp_path):
    (tmp_path / "p" / "track.stl").mkdir(parents=True)
    # named before anything is written (prepare learns its files' names first)
    one_line_error(vibrofeed("prepare", "bulk_feeder", "-o", tmp_path / "p"), 2,
                   f"{tmp_path / 'p' / 'track.stl'} is a folder; the command writes a file there")
    assert [p.name for p in (tmp_path / "p").iterdir()] == ["track.stl"]


def test_sweep_report_names_a_map_it_cannot_write_in_one_line(tmp_path):
    from vibrofeed.sweep import summary as S

    rows = [{"job": k, "status": S.DONE, "a": a, "b": b, "parts_per_s": 10.0 * a + b,
             "parts_per_s_err": 1.0, "n_events": 50}
            for k, (a, b) in enumerate((a, b) for a in (1.0, 2.0) for b in (3.0, 4.0))]
    S.write(tmp_path, rows, ["a", "b"], {"varied": '["a", "b"]', "n_jobs": 4, "deck": "bulk_feeder"})
    (tmp_path / "maps" / "sweep_map.png").mkdir(parents=True)
    proc = vibrofeed("sweep-report", tmp_path, "--plot", tmp_path / "maps")
    one_line_error(proc, 2, f"{tmp_path / 'maps' / 'sweep_map.png'}: Is a directory")


def test_validate_names_a_case_whose_figures_cannot_be_written_and_goes_on(monkeypatch, capsys, tmp_path):
    from vibrofeed.cli import main
    from vibrofeed.validation.crosscheck import CrossCheck

    tried = []

    def run(self):
        tried.append(self.case.name)
        raise IsADirectoryError(errno.EISDIR, "Is a directory", f"{tmp_path}/{self.case.name}/speed.png")

    monkeypatch.setattr(CrossCheck, "run", run)
    assert main(["validate", "hop_flights", "jkr_pulloff", "-o", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert tried == ["hop_flights", "jkr_pulloff"]         # the second case still ran
    assert f"vibrofeed: error: case hop_flights: {tmp_path}/hop_flights/speed.png: Is a directory" in err
    assert "Traceback" not in err
