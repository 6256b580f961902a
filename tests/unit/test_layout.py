"""The project's structure rules, checked on its source.

- The engine, results and postproc layers never import validation (the models
  and cross-checks sit on top of the core, never under it).
- The command line imports a command's module only when that command runs:
  listing decks loads neither the models, h5py, scipy nor the plotting
  libraries; pyvista and matplotlib load only when something is drawn.
- Every exception the package raises to its user belongs to one tree
  (vibrofeed.errors), and every command is documented in the README.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys

import pytest

from helpers import REPO

CORE_LAYERS = [REPO / "vibrofeed" / "engine", REPO / "vibrofeed" / "results", REPO / "postproc"]
PACKAGE_DIRS = [REPO / "vibrofeed", REPO / "postproc", REPO / "validation"]


def _imports(path) -> list[tuple[int, str]]:
    """(line, module) of every import in a file, relative ones as written (leading dots)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = "." * node.level + (node.module or "")
            out.append((node.lineno, base))
            sep = "." if node.module else ""
            out += [(node.lineno, base + sep + a.name) for a in node.names]  # a name may be a module
    return out


def _imports_validation(module: str) -> bool:
    parts = module.lstrip(".").split(".")
    return "validation" in parts


@pytest.mark.parametrize("layer", CORE_LAYERS, ids=lambda p: p.name)
def test_core_layers_never_import_validation(layer):
    offenders = [f"{path.relative_to(REPO)}:{line}: {module}"
                 for path in sorted(layer.rglob("*.py"))
                 for line, module in _imports(path) if _imports_validation(module)]
    assert not offenders, "core layer imports validation:\n" + "\n".join(offenders)


def test_the_import_check_sees_relative_and_absolute_imports(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("from ..validation.models import x\nimport vibrofeed.validation.cases\n"
                 "def g():\n    from vibrofeed import validation\n")
    lines = {line for line, m in _imports(f) if _imports_validation(m)}
    assert lines == {1, 2, 4}


def _modules_loaded_by(code: str) -> set[str]:
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys, json\n"
                          "print(json.dumps(sorted(sys.modules)))"],
                         capture_output=True, text=True, cwd=REPO, check=True)
    return set(json.loads(out.stdout.strip().splitlines()[-1]))


HEAVY = ("scipy", "h5py", "matplotlib", "pyvista", "vibrofeed.validation", "mpi4py")


@pytest.mark.parametrize("argv", [["decks"], ["params", "single_part"], ["--help"],
                                  ["run", "--help"]])
def test_light_commands_load_no_heavy_module(argv):
    code = ("from vibrofeed.cli import main\n"
            f"try:\n    main({argv!r})\nexcept SystemExit:\n    pass")
    loaded = _modules_loaded_by(code)
    heavy = sorted(m for m in loaded if m.split(".")[0] in HEAVY or m.startswith(HEAVY))
    assert not heavy, f"vibrofeed {' '.join(argv)} loaded {heavy}"


def test_results_and_analyses_load_no_plotting_library():
    loaded = _modules_loaded_by("import vibrofeed.results.reader, vibrofeed.results.check, "
                                "vibrofeed.postproc, vibrofeed.engine.runner, vibrofeed.summary")
    assert not {m.split(".")[0] for m in loaded} & {"matplotlib", "pyvista"}
    assert not any(m.startswith("vibrofeed.validation") for m in loaded)


def test_every_exception_class_belongs_to_the_error_tree():
    """No module defines its own exception class: all live in vibrofeed/errors.py."""
    offenders = []
    for folder in PACKAGE_DIRS:
        for path in sorted(folder.rglob("*.py")):
            if path.name == "errors.py" and path.parent.name == "vibrofeed":
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.ClassDef):
                    bases = [ast.unparse(b) for b in node.bases]
                    if any(b.endswith(("Error", "Exception")) for b in bases):
                        offenders.append(f"{path.relative_to(REPO)}:{node.lineno}: class {node.name}")
    assert not offenders, "exception classes outside vibrofeed/errors.py:\n" + "\n".join(offenders)


def test_error_tree_exit_codes():
    from vibrofeed import errors as E

    for cls in (E.UsageError, E.DeckError, E.ParameterError, E.CaseError, E.TrialFileError):
        assert issubclass(cls, E.InputError) and cls.exit_code == 2
    for cls in (E.EngineError, E.LibraryNotFound, E.OutputError, E.ResultError,
                E.IncompleteResult):
        assert issubclass(cls, E.RunError) and cls.exit_code == 1
    assert not issubclass(E.InputError, E.RunError) and not issubclass(E.RunError, E.InputError)
