"""The project's structure rules, checked on its source.

- The import graph of the package (every module of every folder the package
  maps, imports at module level and inside functions alike, relative ones
  resolved, followed transitively) keeps the layers: the library never
  imports the command line; the results know no engine; nothing imports
  ``validation`` but the ``validate`` and ``replay`` commands (and
  validation itself); the models import nothing of the package but
  themselves. And it has no cycle.
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
import tomllib
from pathlib import Path

import pytest

from helpers import REPO

PACKAGE_DIRS = [REPO / "vibrofeed", REPO / "postproc", REPO / "validation"]


# ------------------------------------------------------------------ the import graph
def package_roots(repo: Path) -> dict[str, Path]:
    """Package name -> its folder: ``vibrofeed`` and the folders pyproject.toml maps into it."""
    setuptools = tomllib.loads((repo / "pyproject.toml").read_text()).get("tool", {}).get("setuptools", {})
    roots = {"vibrofeed": repo / "vibrofeed"}
    roots.update({name: repo / folder for name, folder in (setuptools.get("package-dir") or {}).items()
                  if name})
    return roots


def module_files(roots: dict[str, Path]) -> dict[str, Path]:
    """Dotted module name -> file, for every module under the roots (a package is its __init__.py)."""
    out = {}
    for name, root in roots.items():
        for path in sorted(root.rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            parts = parts[:-1] if parts[-1] == "__init__" else parts
            out[".".join((name, *parts))] = path
    return out


def imported_names(module: str, path: Path) -> set[str]:
    """Absolute names of everything ``module`` imports, anywhere in the file (relative imports
    resolved): ``import X`` gives X, ``from X import a`` gives X.a (a may be a module or a name
    defined in X: :func:`import_graph` tells them apart)."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1] + ([base] if base else []))
            out.update(f"{base}.{a.name}" for a in node.names)
    return out


def import_graph(repo: Path) -> dict[str, set[str]]:
    """Module -> the package's modules it imports, each name resolved to the deepest module it
    names (``from .models import deck`` and ``from .models.deck import part`` are both
    models.deck). The parent packages Python also runs on the way are not edges: a package's
    ``__init__`` importing its own modules is not a cycle."""
    files = module_files(package_roots(repo))
    graph = {}
    for module, path in files.items():
        edges = set()
        for name in imported_names(module, path):
            while name not in files and "." in name:
                name = name.rpartition(".")[0]
            if name in files and name != module:
                edges.add(name)
        graph[module] = edges
    return graph


def reachable(graph: dict[str, set[str]], start: str) -> dict[str, str]:
    """Every module ``start`` imports directly or indirectly -> the module that imports it
    (to print the chain)."""
    seen, todo = {}, [start]
    while todo:
        module = todo.pop()
        for target in sorted(graph.get(module, ())):
            if target not in seen and target != start:
                seen[target] = module
                todo.append(target)
    return seen


def chain(graph: dict[str, set[str]], start: str, target: str) -> str:
    """``start -> ... -> target``, the import path :func:`reachable` found."""
    via = reachable(graph, start)
    path = [target]
    while path[-1] != start:
        path.append(via[path[-1]])
    return " -> ".join(reversed(path))


def _under(module: str, *packages: str) -> bool:
    return any(module == p or module.startswith(p + ".") for p in packages)


#: The layering rules: (who, what it must never reach, who is exempt), by package prefix.
CLI = "vibrofeed.cli"
VALIDATION = "vibrofeed.validation"
MODELS = "vibrofeed.models"
#: What the command modules of ``vibrofeed validate`` and ``vibrofeed replay`` may import.
VALIDATION_COMMANDS = ("vibrofeed.cli.validate", "vibrofeed.cli.replay")
#: Small shared leaf modules the models may import besides their own package (none today).
MODEL_LEAVES: tuple[str, ...] = ()


def layer_violations(graph: dict[str, set[str]]) -> list[str]:
    """Every import chain that breaks a layering rule (module docstring), one line each."""
    out = []
    for module in sorted(graph):
        for target in sorted(reachable(graph, module)):
            why = None
            if not _under(module, CLI) and _under(target, CLI):
                why = "the library imports the command line"
            elif _under(module, "vibrofeed.results") and _under(target, "vibrofeed.engine"):
                why = "the results import the engine"
            elif (_under(target, VALIDATION) and not _under(module, VALIDATION, *VALIDATION_COMMANDS)):
                why = "only the validate and replay commands import validation"
            elif _under(module, MODELS) and not _under(target, MODELS, *MODEL_LEAVES):
                why = "the models import the package beyond themselves"
            if why:
                out.append(f"{why}: {chain(graph, module, target)}")
    return out


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle (``[a, b, ..., a]``), or None: depth-first search, a back edge closes it."""
    state: dict[str, int] = {}  # 1: on the current path, 2: finished
    path: list[str] = []

    def visit(module: str) -> list[str] | None:
        state[module] = 1
        path.append(module)
        for target in sorted(graph.get(module, ())):
            if state.get(target) == 1:
                return path[path.index(target):] + [target]
            if target not in state and (found := visit(target)):
                return found
        state[module] = 2
        path.pop()
        return None

    for module in sorted(graph):
        if module not in state and (found := visit(module)):
            return found
    return None


def test_the_graph_covers_every_package_and_module():
    graph = import_graph(REPO)
    for package in ("vibrofeed.cli", "vibrofeed.engine", "vibrofeed.results", "vibrofeed.sweep",
                    "vibrofeed.pictures", "vibrofeed.postproc", "vibrofeed.models", "vibrofeed.validation",
                    "vibrofeed.validation.replay", "vibrofeed.validation.studies"):
        assert package in graph, package
    # + the decks' helper scripts and the example feeders' (vibrofeed._decks, vibrofeed._feeders)
    folders = [*PACKAGE_DIRS, REPO / "decks", REPO / "feeders"]
    n_files = sum(len(list(folder.rglob("*.py"))) for folder in folders)
    assert len(graph) == n_files
    assert "vibrofeed.postproc.base" in graph["vibrofeed.postproc.feedrate"]  # a relative import
    assert "vibrofeed.models.deck" in graph["vibrofeed.postproc.feedrate"]  # one inside a function


def test_the_layers_hold_through_indirect_imports():
    violations = layer_violations(import_graph(REPO))
    assert not violations, "layering broken:\n" + "\n".join(violations)


def test_the_import_graph_has_no_cycle():
    cycle = find_cycle(import_graph(REPO))
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def _tree(root: Path, files: dict[str, str]) -> Path:
    for name, text in {"pyproject.toml": '[tool.setuptools]\npackage-dir = {"vibrofeed" = "vibrofeed", '
                                         '"vibrofeed.validation" = "validation"}\n', **files}.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)
    return root


def test_the_checker_finds_planted_violations_and_cycles(tmp_path):
    repo = _tree(tmp_path, {
        "vibrofeed/__init__.py": "",
        "vibrofeed/cli/__init__.py": "",
        "vibrofeed/cli/feedrate.py": "import json\n",
        "vibrofeed/cli/validate.py": "from ..validation import cases\n",
        "vibrofeed/sweep/__init__.py": "",
        # indirect, inside a function: sweep -> postproc.helper -> cli
        "vibrofeed/sweep/metrics.py": "def f():\n    from ..postproc import helper\n",
        "vibrofeed/postproc/__init__.py": "",
        "vibrofeed/postproc/helper.py": "import vibrofeed.cli.feedrate\n",
        "vibrofeed/results/__init__.py": "",
        "vibrofeed/results/reader.py": "from ..engine.runner import run\n",
        "vibrofeed/engine/__init__.py": "",
        "vibrofeed/engine/runner.py": "run = 1\n",
        "vibrofeed/models/__init__.py": "",
        "vibrofeed/models/deck.py": "from . import surface\nfrom ..sweep import metrics\n",
        "vibrofeed/models/surface.py": "from .deck import x\n",
        "validation/__init__.py": "",
        "validation/cases.py": "from ..models import surface\n",
    })
    graph = import_graph(repo)
    assert graph["vibrofeed.sweep.metrics"] == {"vibrofeed.postproc.helper"}
    assert graph["vibrofeed.validation.cases"] == {"vibrofeed.models.surface"}
    found = "\n".join(layer_violations(graph))
    assert ("the library imports the command line: vibrofeed.sweep.metrics -> vibrofeed.postproc.helper "
            "-> vibrofeed.cli.feedrate") in found
    assert "the results import the engine: vibrofeed.results.reader -> vibrofeed.engine.runner" in found
    assert ("the models import the package beyond themselves: vibrofeed.models.deck -> "
            "vibrofeed.sweep") in found
    assert "vibrofeed.cli.validate" not in found  # the validate command may import validation
    cycle = find_cycle(graph)
    assert cycle[0] == cycle[-1]
    assert sorted(cycle[1:]) == ["vibrofeed.models.deck", "vibrofeed.models.surface"]
    del graph["vibrofeed.models.surface"]
    assert find_cycle(graph) is None
    graph["vibrofeed.results.reader"].add("vibrofeed.validation.cases")
    assert ("only the validate and replay commands import validation: vibrofeed.results.reader -> "
            "vibrofeed.validation.cases") in "\n".join(layer_violations(graph))


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
                                "vibrofeed.postproc, vibrofeed.engine.runner, vibrofeed.run_summary")
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
