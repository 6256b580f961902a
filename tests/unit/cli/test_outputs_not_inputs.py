"""An output that is one of the command's inputs, or that takes a name the run gives its own
files, is refused before any work, for every command that writes (issue 36): `vibrofeed run
my.liggghts -o my.liggghts` replaced the deck with HDF5 and exited 0, `-o sp.h5.part` left a
complete result under an unfinished one's name."""

from __future__ import annotations

import re
import shutil

import pytest

from helpers import DECKS, REPO, vibrofeed
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import check_output, deck_inputs
from vibrofeed.errors import UsageError


@pytest.fixture
def decks(tmp_path):
    """A copy of the project's decks, which a test may try to overwrite."""
    folder = tmp_path / "decks"
    shutil.copytree(DECKS, folder, ignore=shutil.ignore_patterns("*.h5", "*.log"))
    return folder


def untouched(folder, before):
    return {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()} == before


@pytest.mark.parametrize("output, words", [
    ("single_part.liggghts", "the result would replace single_part.liggghts, which the run reads"),
    ("include/contact.liggghts", "the result would replace contact.liggghts"),
    ("meshes/plate.stl", "the result would replace plate.stl"),
    ("include/surface_motion.h5", None),  # its log, surface_motion.log: no input; allowed
])
def test_a_run_into_its_own_deck_include_or_mesh_is_refused(decks, output, words):
    deck = Deck(decks / "single_part.liggghts")
    if words is None:
        check_output(deck, decks / output)
        return
    with pytest.raises(UsageError, match=words):
        check_output(deck, decks / output)


def test_the_command_line_refuses_it_in_one_line_and_leaves_the_deck(decks):
    before = {p: p.read_bytes() for p in decks.rglob("*") if p.is_file()}
    deck = decks / "single_part.liggghts"
    proc = vibrofeed("run", deck, "-o", deck)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1
    assert proc.stderr == (f"vibrofeed: error: -o {deck}: the result would replace single_part.liggghts, "
                           "which the run reads (deck single_part); give another output name\n")
    assert untouched(decks, before)


def test_a_log_that_would_replace_the_deck_is_refused(decks):
    deck = decks / "hop.log"
    shutil.copy(decks / "single_part.liggghts", deck)
    with pytest.raises(UsageError, match="its log would replace hop.log, which the run reads"):
        check_output(Deck(deck), decks / "hop.h5")


@pytest.mark.parametrize("output, words", [
    ("sp.h5.part", "-o {out}: a name ending in .part is a run's unfinished result (the run writes "
                   "sp.h5.part.part until it completes); give the result's own name, such as sp.h5"),
    ("sp.log", "-o {out}: the run writes its LIGGGHTS log as OUT.log, so the result and its log would "
               "be one file; give the result another suffix (.h5)"),
])
def test_an_output_named_as_the_runs_own_files_is_refused(tmp_path, output, words):
    out = tmp_path / output
    proc = vibrofeed("run", "single_part", "-o", out)
    assert proc.returncode == 2 and proc.stderr == f"vibrofeed: error: {words.format(out=out)}\n"
    assert list(tmp_path.iterdir()) == []


def test_the_inputs_of_a_deck_are_every_file_it_reads():
    deck = Deck.find("single_part")
    names = {p.name for p in deck_inputs(deck)}
    assert {"single_part.liggghts", "contact.liggghts", "surface_motion.liggghts", "plate.stl"} <= names


def test_a_feeder_description_is_an_input_of_its_run(tmp_path):
    description = tmp_path / "line.toml"
    shutil.copy(DECKS.parent / "feeders" / "three_section_line.toml", description)
    deck = Deck.find(description)
    with pytest.raises(UsageError, match="the result would replace line.toml"):
        check_output(deck, description, "-o")


def test_export_into_the_result_it_reads_is_refused(tmp_path):
    result = tmp_path / "run.h5md"
    result.write_bytes(b"not touched")
    proc = vibrofeed("export", result, "--format", "h5md-md", "-o", tmp_path)
    assert proc.returncode == 2 and proc.stderr == (
        f"vibrofeed: error: -o {tmp_path}: writing {tmp_path / 'run.h5md'} would replace {result}, which "
        "the command reads; give another output\n")
    assert result.read_bytes() == b"not touched"


def test_render_over_the_result_it_reads_is_refused_by_default_or_by_name(tmp_path):
    result = tmp_path / "r.png"
    result.write_bytes(b"not touched")
    proc = vibrofeed("render", "r.png", cwd=tmp_path)
    assert proc.returncode == 2 and "the output r.png (the default: name it with -o): writing r.png would " \
                                   "replace r.png, which the command reads" in proc.stderr
    proc = vibrofeed("render", "r.png", "-o", tmp_path / "r.png", cwd=tmp_path)
    assert proc.returncode == 2 and proc.stderr.startswith(f"vibrofeed: error: -o {tmp_path / 'r.png'}: ")
    assert result.read_bytes() == b"not touched"


def test_prepare_into_the_decks_it_reads_is_refused_and_leaves_them(decks, tmp_path, monkeypatch):
    """A description named as the project deck it is made from, prepared into the decks'
    folder, would have replaced bulk_feeder.liggghts with the generated deck; an STL a mesh
    element reads, in the output folder under a name prepare writes, likewise."""
    monkeypatch.setenv("VIBROFEED_DECKS", str(decks))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    before = {p: p.read_bytes() for p in decks.rglob("*") if p.is_file()}
    text = (REPO / "feeders" / "demo_line.toml").read_text()
    named = tmp_path / "bulk.toml"
    named.write_text(re.sub(r'(?m)^name = ".*"$', 'name = "bulk_feeder"', text))
    proc = vibrofeed("prepare", named, "-o", decks)
    assert proc.returncode == 2 and len(proc.stderr.splitlines()) == 1, proc.stderr
    assert f"would replace {decks / 'bulk_feeder.liggghts'}, which the command reads" in proc.stderr
    assert untouched(decks, before)
    proc = vibrofeed("prepare", named, "-o", tmp_path / "elsewhere")  # the same, elsewhere: fine
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "elsewhere" / "bulk_feeder.liggghts").is_file()
