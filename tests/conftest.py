"""Test suite configuration.

Tests under tests/unit need neither LIGGGHTS nor MPI; tests under
tests/engine start LIGGGHTS through vibrofeed and take seconds each.
Shared helpers live in tests/helpers.py.
"""

import os
import subprocess

import pytest
from hypothesis import settings

# Property-based tests draw the same examples on every run (a red CI run is
# reproducible, a green one is not luck) and keep no example database in the tree.
settings.register_profile("vibrofeed", derandomize=True, database=None, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "vibrofeed"))


@pytest.fixture(scope="session")
def measured_trials_dir():
    """The folder of the measured vertical-transport trials.

    Where it is absent the test is skipped, except on CI (``CI=true``), which
    has the data: there an absent folder is a failure, not a silent pass.
    """
    from vibrofeed.validation.replay.trials import trials_dir

    folder = trials_dir()
    if folder is None:
        message = ("measured trials not found: put them in ../shared/data/vertical-transport "
                   "or set VIBROFEED_TRIALS_DIR")
        if os.environ.get("CI", "").lower() in ("1", "true", "yes"):
            pytest.fail(message + " (CI must have them)")
        pytest.skip(message)
    return folder


@pytest.fixture
def result_reads(monkeypatch):
    """The (element, frames) of every ``Result.read`` call the test makes: to
    check that an analysis reads windows, not whole datasets."""
    from vibrofeed.results.reader import Result

    reads = []
    original = Result.read

    def spy(self, name, frames=None, slots=None):
        reads.append((name, frames))
        return original(self, name, frames, slots)

    monkeypatch.setattr(Result, "read", spy)
    return reads


@pytest.fixture
def small_disk(tmp_path):
    """A 2 MB tmpfs: a disk that fills up (skipped where mounting is not allowed)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    mount = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(disk)],
                           capture_output=True, text=True)
    if mount.returncode != 0:
        pytest.skip(f"cannot mount a 2 MB tmpfs here: {mount.stderr.strip()}")
    yield disk
    subprocess.run(["umount", "-l", str(disk)], check=False)
