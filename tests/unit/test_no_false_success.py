"""No false success from input or analysis (issue 19): what the commands refuse,
and what they say instead of a traceback or a result that is not one."""

from __future__ import annotations

import json

from helpers import REPO, vibrofeed

SWEEP = """deck = "single_part"
[fixed]
t_end = 0.01
[grid]
freq = [40, 50]
"""


def one_line_error(proc, code: int, *words: str) -> None:
    assert proc.returncode == code, proc.stderr
    assert proc.stderr.startswith("vibrofeed: error: ") and proc.stderr.count("\n") == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    for word in words:
        assert word in proc.stderr, proc.stderr


def test_a_corrupt_sweep_summary_is_named_in_one_line(tmp_path):
    from vibrofeed.sweep import folder as F
    from vibrofeed.sweep.execute import find_deck
    from vibrofeed.sweep.plan import plan
    from vibrofeed.sweep.spec import load

    spec_path = tmp_path / "s.toml"
    spec_path.write_text(SWEEP)
    spec = load(spec_path)
    deck = find_deck(spec)
    out = tmp_path / "out"
    out.mkdir()
    F.write_manifest(out, spec, plan(spec, deck), str(deck.path))
    summary = out / "summary.h5"
    summary.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 40)  # a truncated HDF5 file
    one_line_error(vibrofeed("sweep-report", out), 1, str(summary))
    one_line_error(vibrofeed("sweep", spec_path, "-o", out, "--dry-run"), 1, str(summary))


def test_json_listings_are_json():
    listed = json.loads(vibrofeed("validate", "--list", "--json", check=True).stdout)
    assert len(listed) == len(list((REPO / "validation" / "cases").glob("*.toml")))
