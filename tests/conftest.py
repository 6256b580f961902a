"""Test suite configuration.

Tests under tests/unit need neither LIGGGHTS nor MPI; tests under
tests/engine start LIGGGHTS through vibrofeed and take seconds each.
Shared helpers live in tests/helpers.py.
"""

import os

import pytest


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
