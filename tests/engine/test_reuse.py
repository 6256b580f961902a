"""Runs are identified by a hash of deck text, includes, parameters and version;
`--reuse` keeps a complete result with the same id and reruns anything else."""

import shutil

import h5py

from helpers import DECKS, vibrofeed

SHORT = ["-p", "t_end=0.01", "-p", "output_dt=1e-3", "-q"]


def _id(path):
    with h5py.File(path, "r") as f:
        return str(f["parameters/run"].attrs["id"])


def test_reuse_keeps_the_same_run_and_reruns_a_changed_one(tmp_path):
    out = tmp_path / "r.h5"
    vibrofeed("run", "single_part", "-o", out, *SHORT, check=True)
    first = _id(out)
    assert len(first) == 64 and int(first, 16) >= 0
    stamp = out.stat().st_mtime_ns

    proc = vibrofeed("run", "single_part", "-o", out, *SHORT, "--reuse", check=True)
    assert "kept" in proc.stderr and out.stat().st_mtime_ns == stamp
    # Nothing ran: the summary says where the result is and its id, not a speed.
    assert f"reused {out} (run id {first[:12]}..." in proc.stdout and "steps/s" not in proc.stdout

    # A changed parameter is another run: rerun, new id.
    vibrofeed("run", "single_part", "-o", out, *SHORT, "-p", "mu=0.4", "--reuse", check=True)
    assert out.stat().st_mtime_ns != stamp and _id(out) != first

    # Without --reuse the same run is computed again (same id).
    vibrofeed("run", "single_part", "-o", out, *SHORT, check=True)
    assert _id(out) == first


def test_an_edited_deck_is_another_run(tmp_path):
    decks = tmp_path / "decks"
    shutil.copytree(DECKS, decks)
    deck = decks / "single_part.liggghts"
    out = tmp_path / "r.h5"
    vibrofeed("run", deck, "-o", out, *SHORT, check=True)
    first = _id(out)
    deck.write_text(deck.read_text() + "\n# an edit that changes nothing physical\n")
    proc = vibrofeed("run", deck, "-o", out, *SHORT, "--reuse", check=True)
    assert "kept" not in proc.stderr and _id(out) != first


def test_the_result_holds_the_deck_and_its_includes(tmp_path):
    from vibrofeed.decks import Deck
    from vibrofeed.results.reader import Result

    out = tmp_path / "r.h5"
    vibrofeed("run", "single_part", "-o", out, *SHORT, check=True)
    deck = Deck.find("single_part")
    with Result(out) as r:
        assert r.deck_text == deck.text
        stored = r.deck_includes
    expected = {k: v for k, v in deck.sources.items() if k != deck.path.name}
    assert expected and stored == expected
