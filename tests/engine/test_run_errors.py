"""Engine errors reach the user as one line naming the LIGGGHTS message and the deck
(or included file) line."""

import shutil

import h5py

from helpers import DECKS, vibrofeed
from vibrofeed.results.check import check_file


def deck_copy(tmp_path, edit=None, name="broken", meshes=True, include_edit=None):
    """single_part.liggghts, changed by ``edit``, in ``tmp_path`` with its
    include/ blocks (``include_edit``: ``(block name, edit)`` changes one) and,
    unless ``meshes`` is false, its meshes."""
    text = (DECKS / "single_part.liggghts").read_text()
    new = text if edit is None else edit(text)
    if edit is not None:
        assert new != text, "the edit did not apply"
    path = tmp_path / f"{name}.liggghts"
    path.write_text(new)
    shutil.copytree(DECKS / "include", tmp_path / "include")
    if include_edit is not None:
        block = tmp_path / "include" / include_edit[0]
        before = block.read_text()
        after = include_edit[1](before)
        assert after != before, "the edit of the include did not apply"
        block.write_text(after)
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
    # the LIGGGHTS log is kept for diagnosis, as an unfinished run's: r.log is a finished result's
    assert out.with_name("r.log.part").exists() and not out.with_suffix(".log").exists()


def test_error_in_an_included_block_names_that_file_and_line(tmp_path):
    deck = deck_copy(tmp_path, include_edit=(
        "contact.liggghts", lambda t: t.replace("property/global coefficientFriction",
                                                "property/globall coefficientFriction")))
    proc = vibrofeed("run", deck, "-o", tmp_path / "r.h5")
    assert proc.returncode == 1
    err = proc.stderr.strip()
    assert err.count("\n") == 0 and "Traceback" not in err
    assert 'Invalid fix style: "property/globall"' in err
    line = line_of(tmp_path / "include" / "contact.liggghts", "property/globall")
    assert f"include/contact.liggghts:{line}: fix m4 all property/globall coefficientFriction" in err


def test_missing_mesh_file(tmp_path):
    deck = deck_copy(tmp_path, name="nomesh", meshes=False)  # no meshes/ next to it
    proc = vibrofeed("run", deck, "-o", tmp_path / "r.h5")
    assert proc.returncode == 1
    assert "plate.stl" in proc.stderr
    assert f"nomesh.liggghts:{line_of(deck, 'fix             plate all mesh/surface')}:" in proc.stderr


def test_missing_include_is_refused_before_the_engine_starts(tmp_path):
    deck = tmp_path / "alone.liggghts"
    deck.write_text((DECKS / "single_part.liggghts").read_text())  # no include/ next to it
    proc = vibrofeed("run", deck, "-o", tmp_path / "r.h5")
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1
    # the first include command of the deck is the one refused
    assert f"alone.liggghts:{line_of(deck, 'include         ${deck_dir}/include/')}: included file" \
        in proc.stderr
    assert "not found" in proc.stderr and not (tmp_path / "r.log").exists()


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
