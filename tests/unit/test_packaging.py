"""What pyproject.toml ships: every package folder and every file of decks/.

An installed package holds only what is listed; these catch a new subpackage or
deck file left out before the (engine) install test builds a wheel."""

import tomllib

from helpers import DECKS, REPO

SETUPTOOLS = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]


def test_every_package_folder_is_listed():
    listed = set(SETUPTOOLS["packages"])
    found = set()
    for package, folder in SETUPTOOLS["package-dir"].items():
        for init in (REPO / folder).rglob("__init__.py"):
            relative = init.parent.relative_to(REPO / folder)
            found.add(".".join((package, *relative.parts)))
    assert found, "no package folder found"
    assert found <= listed, f"not in [tool.setuptools] packages: {sorted(found - listed)}"


def test_every_data_folder_is_listed_as_a_package():
    """A folder inside a package is a package to Python (a namespace one) even without
    __init__.py: setuptools ships its package-data only with a warning ("Package would
    be ignored", to become an error) unless it is listed."""
    listed = set(SETUPTOOLS["packages"])
    folders = set()
    for package, folder in SETUPTOOLS["package-dir"].items():
        root = REPO / folder
        for sub in root.rglob("*"):
            if sub.is_dir() and "__pycache__" not in sub.parts and any(p.is_file() for p in sub.iterdir()):
                folders.add(".".join((package, *sub.relative_to(root).parts)))
    assert {"vibrofeed._decks.include", "vibrofeed._decks.meshes"} <= folders
    assert folders <= listed, f"not in [tool.setuptools] packages: {sorted(folders - listed)}"


def test_every_file_of_the_decks_folder_is_package_data():
    assert SETUPTOOLS["package-dir"]["vibrofeed._decks"] == "decks"
    patterns = SETUPTOOLS["package-data"]["vibrofeed._decks"]
    files = {p for p in DECKS.rglob("*") if p.is_file() and "__pycache__" not in p.parts}
    shipped = {p for pattern in patterns for p in DECKS.glob(pattern)}  # globbed as setuptools does
    assert len(files) > 5
    missed = sorted(p.relative_to(DECKS).as_posix() for p in files - shipped)
    assert not missed, f"decks/ files the package would not ship: {missed}"
