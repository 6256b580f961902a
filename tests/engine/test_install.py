"""A non-editable install works: a wheel built from the checkout, installed into a
fresh virtual environment, runs from any folder with its own decks and abort shim.

The venv reuses the test interpreter's dependencies through a .pth file (as
`pip install .` into an environment that has them would), so only vibrofeed
itself is built and installed: about half a minute.
"""

import filecmp
import os
import subprocess
import sys
import venv
from pathlib import Path

import pytest

from helpers import DECKS, REPO
from vibrofeed.results.check import check_file

# The small demo of test_demo: the line fed twice as fast, 0.6 s.
SMALL = ["-p", "inlet_rate=60", "-p", "t_end=0.6", "-q", "--no-pictures"]


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(venv folder, its site-packages) with vibrofeed installed from a wheel."""
    root = tmp_path_factory.mktemp("install")
    wheels, env = root / "wheels", root / "venv"
    run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", str(wheels), str(REPO)], cwd=root)
    venv.create(env, with_pip=False)
    site = next((env / "lib").glob("python3*/site-packages"))
    deps = [p for p in sys.path if p.endswith("site-packages")]  # appended after the venv's own
    (site / "zz-test-deps.pth").write_text("\n".join(deps) + "\n")
    (wheel,) = wheels.glob("vibrofeed-*.whl")
    run([env / "bin/python", "-m", "pip", "install", "--no-deps", "--no-index", "-q", wheel], cwd=root)
    return env, site


def run(cmd, cwd, check=True):
    """``cmd`` in ``cwd`` (outside the checkout), without the overrides CTest sets."""
    environment = {k: v for k, v in os.environ.items()
                   if k not in ("VIBROFEED_ABORT_SHIM", "VIBROFEED_DECKS", "PYTHONPATH")}
    proc = subprocess.run([str(c) for c in cmd], cwd=cwd, env=environment, capture_output=True,
                          text=True, timeout=600)
    if check and proc.returncode != 0:
        raise AssertionError(f"{cmd} failed:\n{proc.stdout}\n{proc.stderr}")
    return proc


def test_the_package_holds_the_decks_and_the_shim(installed, tmp_path):
    env, site = installed
    where = run([env / "bin/python", "-c",
                 "import vibrofeed, vibrofeed.decks as d, vibrofeed.engine.runner as r;"
                 "print(vibrofeed.__file__, d.decks_dir(), r.abort_shim(), sep='\\n')"], cwd=tmp_path)
    module, decks, shim = (Path(line) for line in where.stdout.splitlines())
    package = site / "vibrofeed"
    assert module.parent == package  # the installed copy, not the checkout
    assert decks == package / "_decks" and shim == package / "engine/libvibrofeed_abortflush.so"
    # every file of decks/ (decks, include/ blocks, meshes), byte for byte: same deck text, same run id
    shipped = [p.relative_to(DECKS) for p in DECKS.rglob("*") if p.is_file() and "__pycache__" not in p.parts]
    assert shipped and all(filecmp.cmp(DECKS / p, decks / p, shallow=False) for p in shipped)


def test_the_installed_command_runs_the_demo_from_another_folder(installed, tmp_path):
    env, _ = installed
    proc = run([env / "bin/vibrofeed", "demo", "-o", "results", *SMALL], cwd=tmp_path)
    assert "Feed rate" in proc.stdout and "Singulation" in proc.stdout
    assert check_file(tmp_path / "results/feeder_line.h5").ok


def test_the_installed_shim_flushes_an_engine_error(installed, tmp_path):
    # A mesh file that cannot be opened is an error->one: its message survives MPI_Abort only
    # through the shim (without it the user sees a bare "worker exited with status 1").
    env, site = installed
    deck = tmp_path / "nomesh.liggghts"
    deck.write_text((site / "vibrofeed/_decks/single_part.liggghts").read_text())
    (tmp_path / "include").symlink_to(site / "vibrofeed/_decks/include")
    proc = run([env / "bin/vibrofeed", "run", deck, "-o", "r.h5", "-q"], cwd=tmp_path, check=False)
    assert proc.returncode == 1
    assert "Cannot open mesh file" in proc.stderr and "plate.stl" in proc.stderr
