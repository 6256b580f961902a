"""Engine errors reach the user as one line naming the LIGGGHTS message and the deck line."""

import shutil

import h5py
import pytest

from vibrofeed.results.check import check_file

from helpers import DECKS, vibrofeed


def deck_copy(tmp_path, edit, name="broken", meshes=True):
    text = (DECKS / "single_part.liggghts").read_text()
    new = edit(text)
    assert new != text, "the edit did not apply"
    path = tmp_path / f"{name}.liggghts"
    path.write_text(new)
    if meshes:
        shutil.copytree(DECKS / "meshes", tmp_path / "meshes")
    return path


def line_of(path, fragment):
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if fragment in line:
            return number
    raise AssertionError(fragment)


def test_error_in_a_deck_command_names_message_and_line(tmp_path):
    deck = deck_copy(tmp_path, lambda t: t.replace("all gravity ", "all gravityy "))
    out = tmp_path / "out" / "r.h5"
    proc = vibrofeed("run", deck, "-o", out)
    assert proc.returncode == 1
    err = proc.stderr.strip()
    assert err.count("\n") == 0 and "Traceback" not in err
    assert 'Invalid fix style: "gravityy"' in err
    assert f"broken.liggghts:{line_of(deck, 'gravityy')}: fix gravi all gravityy" in err
    assert not out.exists() and not out.with_name("r.h5.part").exists()
    assert out.with_suffix(".log").exists()  # the LIGGGHTS log is kept for diagnosis


def test_missing_mesh_file(tmp_path):
    deck = tmp_path / "nomesh.liggghts"
    deck.write_text((DECKS / "single_part.liggghts").read_text())  # no meshes/ next to it
    proc = vibrofeed("run", deck, "-o", tmp_path / "r.h5")
    assert proc.returncode == 1
    assert "plate.stl" in proc.stderr
    assert f"nomesh.liggghts:{line_of(deck, 'fix             plate all mesh/surface')}:" in proc.stderr


def test_error_during_the_run_keeps_the_frames_written_before(tmp_path):
    # A steady push drives the part off the plate and out of the box: LIGGGHTS
    # stops with "Lost atoms" part-way through the run.
    deck = deck_copy(tmp_path, lambda t: t.replace(
        "thermo_style ", "fix push all addforce 2e-4 0 0\nthermo_style ", 1), name="push")
    out = tmp_path / "r.h5"
    proc = vibrofeed("run", deck, "-o", out, "-p", "t_end=1")
    assert proc.returncode == 1
    assert "Lost atoms" in proc.stderr and "during the run" in proc.stderr
    part = tmp_path / "r.h5.part"
    assert not out.exists() and part.exists()
    with h5py.File(part, "r") as f:
        frames = len(f["particles/parts/position/step"])
        assert f["parameters/run"].attrs["status"] == "failed"
        assert "Lost atoms" in f["parameters/run"].attrs["message"]
    assert frames > 10 and f"{frames} frames" in proc.stderr
    assert not check_file(part).ok
    assert check_file(part, allow_incomplete=True).ok


def test_deck_without_the_driver_contract(tmp_path):
    deck = deck_copy(tmp_path, lambda t: t.replace("variable n_steps ", "variable n_steps_unused "),
                     name="nocontract")
    proc = vibrofeed("run", deck, "-o", tmp_path / "r.h5")
    assert proc.returncode == 1 and "n_steps" in proc.stderr and "does not define" in proc.stderr
    assert not (tmp_path / "r.h5").exists() and not (tmp_path / "r.h5.part").exists()
