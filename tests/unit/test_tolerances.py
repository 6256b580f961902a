"""Every approximate comparison in the tests states its tolerance at the scale of what it compares.

The quantities here are micro-scale: a part's mass is ~1e-9 kg, a force ~1e-8 N, a gap
~1e-7 m, a speed ~1e-2 m/s. The default tolerances of the comparison helpers are absolute
numbers chosen for quantities of order one, and at this scale they compare nothing:

- numpy's ``isclose`` / ``allclose`` pass when ``|a - b| <= atol + rtol * |b|`` with a default
  ``atol=1e-8``: ``np.allclose(mass, 1e-9, rtol=0)`` holds for a mass nine times too large, and
  any force below 1e-8 N equals zero; the default ``rtol=1e-5`` is 0.2 um at 2 cm.
- ``pytest.approx(x)`` defaults to ``rel=1e-6`` *or* ``abs=1e-12``: the absolute 1e-12 is a
  tenth of a percent of a 1e-9 kg mass and 1e-4 of a 1e-8 N force, and it is the whole
  tolerance of ``approx(0)`` or of any expected value below 1e-6.

The rule, checked on the source (ast) of every ``tests/**/*.py`` file, this one included, and
reported as ``file:line``:

1. Every use of ``allclose`` or ``isclose`` (``np.isclose``, ``numpy.allclose``,
   ``np.ma.allclose``, a name imported from numpy, any callee of that name) is a call that passes
   ``atol=`` by keyword: the absolute tolerance in the quantity's unit (``atol=0`` with an
   ``rtol`` is a statement too). A use whose tolerance cannot be read is a failure as well: the
   function passed as a value (``map(np.isclose, ...)``, ``partial(np.isclose, ...)``), ``atol``
   passed by position or hidden in ``**kwargs``. Only the standard library's ``math.isclose`` /
   ``cmath.isclose`` are allowed as they are: their default ``abs_tol`` is 0, so a default can
   only be too strict, never blind.
2. Every ``pytest.approx(expected, ...)`` (or ``approx`` imported from pytest, or any callee
   named ``approx``) passes ``rel`` or ``abs`` (by keyword, not ``None``, or by position),
   unless ``expected`` is a literal of nonzero ints and bools (``approx(3)``,
   ``approx([1, 2])``, a dict of them): there the literal itself states the scale and the
   default ``rel=1e-6`` is relative to it. Zero is not exempt: ``approx(0)`` is ``abs=1e-12``
   alone, a unit-less number. A bare reference to ``approx`` that is not a call fails too.

   What the source cannot show is left to the writer: ``rel=`` alone keeps ``abs=1e-12`` as a
   floor (the tolerance is the larger of the two), so below ``1e-12 / rel`` in its unit (a mass,
   a pull-off force, a Stefan constant, a gap of nanometres) a comparison also states ``abs=``:
   ``abs=0`` for a purely relative one. ``numpy.testing.assert_allclose`` is not checked: its
   default ``atol`` is 0, so its default can only be too strict (its ``rtol=1e-7`` is relative).

An exception is written where it is made, not here: a comment ``# tolerance: default <reason>``
on any line of the call (from its first line to its last) lets that one call keep the default,
and the reason must be given (e.g. ``# tolerance: default - dimensionless ratios of order 1``).
A marker on a line where nothing would fail is itself reported (a stale exception hides the
next call written there). Nothing else is skipped: no file, no folder, no name.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

import pytest

from helpers import REPO

TESTS = REPO / "tests"
CLOSE_NAMES = {"allclose", "isclose"}
STDLIB_CLOSE_MODULES = {"math", "cmath"}  # isclose with abs_tol=0 by default: allowed as is
MARKER = re.compile(r"#\s*tolerance:\s*default\b(?P<reason>.*)$")


def _dotted(node: ast.AST) -> list[str] | None:
    """``a.b.c`` -> ["a", "b", "c"]; None when the chain does not start at a name."""
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    parts.append(node.id)
    return parts[::-1]


def _imports(tree: ast.AST) -> tuple[dict[str, str], dict[str, str]]:
    """(module alias -> module, imported name -> "module.name") over the whole file."""
    modules, names = {}, {}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.asname:
                    modules[a.asname] = a.name
                else:
                    root = a.name.split(".")[0]
                    modules[root] = root
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            for a in node.names:
                names[a.asname or a.name] = f"{node.module}.{a.name}"
    return modules, names


def _qualified(node: ast.AST, modules: dict[str, str], names: dict[str, str]) -> str | None:
    """The dotted name ``node`` refers to, its first part resolved through the imports."""
    parts = _dotted(node)
    if parts is None:
        return None
    head, rest = parts[0], parts[1:]
    if head in names:
        head = names[head]
    elif head in modules:
        head = modules[head]
    return ".".join([head, *rest])


def _is_close_function(qualified: str) -> bool:
    """An allclose/isclose whose default tolerance must be replaced (not the stdlib's)."""
    *module, last = qualified.split(".")
    if last not in CLOSE_NAMES:
        return False
    return not (module and module[0] in STDLIB_CLOSE_MODULES and len(module) == 1)


def _is_approx(qualified: str) -> bool:
    return qualified.split(".")[-1] == "approx"


def _scale_free_literal(node: ast.AST) -> bool:
    """A literal of nonzero ints and bools (or a container of only them)."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        node = node.operand
        return isinstance(node, ast.Constant) and type(node.value) is int and node.value != 0
    if isinstance(node, ast.Constant):
        return type(node.value) is bool or (type(node.value) is int and node.value != 0)
    if isinstance(node, (ast.List, ast.Tuple, ast.Set)):
        return all(_scale_free_literal(e) for e in node.elts)
    if isinstance(node, ast.Dict):
        return all(_scale_free_literal(v) for v in node.values)
    return False


def _stated(call: ast.Call, name: str) -> bool:
    """``call`` passes keyword ``name`` with a value other than None."""
    return any(k.arg == name and not (isinstance(k.value, ast.Constant) and k.value.value is None)
               for k in call.keywords)


def _markers(source: str) -> dict[int, str]:
    """Line -> the reason of a ``# tolerance: default <reason>`` comment on that line."""
    out = {}
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT and (m := MARKER.search(tok.string)):
            out[tok.start[0]] = m["reason"].strip(" -—:,()")
    return out


def violations(source: str, filename: str = "<test>") -> list[str]:
    """The rule's failures in one file's source, each as ``filename:line: why``."""
    tree = ast.parse(source, filename=filename)
    modules, names = _imports(tree)
    markers = _markers(source)
    found = []  # (first line, last line, message)

    called = set()  # the callee nodes of calls (a callee used elsewhere is a bare reference)
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        qualified = _qualified(node.func, modules, names)
        if qualified is None:
            continue
        span = (node.lineno, node.end_lineno or node.lineno)
        if _is_close_function(qualified):
            called.add(id(node.func))
            if not _stated(node, "atol"):
                if len(node.args) >= 4:
                    how = "atol passed by position: pass it as atol="
                elif any(k.arg is None for k in node.keywords):
                    how = "atol hidden in **kwargs: pass it as atol="
                else:
                    how = ("no atol=: numpy's default atol=1e-8 exceeds a micro-part's mass (1e-9 kg) "
                           "and force (1e-8 N); state it in the quantity's unit")
                found.append((*span, f"{qualified}(...) {how}"))
        elif _is_approx(qualified):
            called.add(id(node.func))
            if len(node.args) >= 2 or _stated(node, "rel") or _stated(node, "abs"):
                continue
            if node.args and _scale_free_literal(node.args[0]):
                continue
            found.append((*span, f"{qualified}(...) with neither rel= nor abs=: its default abs=1e-12 "
                                 "is 1e-3 of a part's mass (1e-9 kg); state the tolerance"))
    for node in ast.walk(tree):
        if isinstance(node, (ast.Name, ast.Attribute)) and id(node) not in called:
            if isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                continue
            parts = _dotted(node)
            if parts is None or parts[-1] not in CLOSE_NAMES | {"approx"}:
                continue
            # only the outermost node of a chain (np.isclose, not np as a part of it)
            qualified = _qualified(node, modules, names)
            if qualified and (_is_close_function(qualified) or _is_approx(qualified)):
                if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                    continue
                line = node.lineno
                found.append((line, node.end_lineno or line,
                              f"{qualified} used as a value: its tolerance cannot be read; call it with "
                              "atol= (isclose/allclose) or rel=/abs= (approx)"))

    out, used = [], set()
    for first, last, message in sorted(found):
        marked = [n for n in range(first, last + 1) if n in markers]
        if marked:
            used.update(marked)
            if not any(markers[n] for n in marked):
                out.append(f"{filename}:{first}: '# tolerance: default' without a reason")
            continue
        out.append(f"{filename}:{first}: {message}")
    for line in sorted(set(markers) - used):
        out.append(f"{filename}:{line}: '# tolerance: default' marker where no default tolerance is used "
                   "(stale: remove it)")
    return out


def _test_files() -> list[Path]:
    return sorted(TESTS.rglob("*.py"))


@pytest.mark.parametrize("path", _test_files(), ids=lambda p: str(p.relative_to(TESTS)))
def test_tolerances_are_stated(path):
    """A file's approximate comparisons state their tolerances (the rule: this module's docstring)."""
    found = violations(path.read_text(), str(path.relative_to(REPO)))
    assert not found, "tolerance left at a default meant for order-one numbers:\n" + "\n".join(found)


def test_the_test_files_are_found():
    """The parametrisation above covers the test folders (an empty glob would pass everything)."""
    files = {p.relative_to(TESTS).parts[0] for p in _test_files()}
    assert {"unit", "engine"} <= files
    assert Path(__file__).resolve() in {p.resolve() for p in _test_files()}


# ------------------------------------------------------------------ the rule on examples
@pytest.mark.parametrize("code", [
    "import numpy as np\nnp.isclose(m, 1e-9)",
    "import numpy as np\nnp.allclose(m, 1e-9, rtol=0)",
    "import numpy\nnumpy.allclose(f, 0)",
    "import numpy as np\nnp.ma.allclose(f, 0)",
    "from numpy import isclose\nisclose(m, 1e-9)",
    "from numpy import allclose as close\nclose(m, 1e-9, rtol=1e-9)",
    "import numpy as np\nnp.isclose(m, 1e-9, 1e-9, 1e-15)",  # atol by position
    "import numpy as np\nnp.isclose(m, 1e-9, **tol)",
    "import numpy as np\nnp.isclose(m, 1e-9, atol=None)",
    "import numpy as np\nlist(map(np.isclose, a, b))",
    "import numpy as np\nf = np.allclose",
    "import pytest\nassert m == pytest.approx(1e-9)",
    "import pytest\nassert f == pytest.approx(0)",
    "import pytest\nassert f == pytest.approx(0.0)",
    "import pytest\nassert f == pytest.approx([0, 1])",
    "import pytest\nassert f == pytest.approx(-x)",
    "import pytest\nassert f == pytest.approx(x, rel=None)",
    "from pytest import approx\nassert f == approx(m)",
    "import pytest as pt\nassert f == pt.approx(m)",
    "import pytest\nassert f == pytest.approx(m)  # tolerance: default",  # no reason
    "import numpy as np\nnp.isclose(m, 1e-9, atol=1e-15)  # tolerance: default - stale",
])
def test_the_rule_fails(code):
    assert violations(code), code


@pytest.mark.parametrize("code", [
    "import numpy as np\nnp.isclose(m, 1e-9, atol=1e-15)",
    "import numpy as np\nnp.allclose(m, 1e-9, rtol=1e-12, atol=0)",
    "from numpy import isclose\nisclose(m, 1e-9, atol=1e-15)",
    "import numpy as np\nnp.testing.assert_allclose(m, 1e-9, rtol=1e-12)",  # default atol=0
    "import math\nmath.isclose(m, 1e-9)",
    "from math import isclose\nisclose(m, 1e-9)",
    "import pytest\nassert n == pytest.approx(3)",
    "import pytest\nassert n == pytest.approx([1, -2, True])",
    "import pytest\nassert n == pytest.approx({'a': 1})",
    "import pytest\nassert f == pytest.approx(0, abs=1e-20)",
    "import pytest\nassert m == pytest.approx(1e-9, rel=1e-12)",
    "import pytest\nassert m == pytest.approx(1e-9, 1e-12)",
    "from pytest import approx\nassert m == approx(1e-9, abs=1e-18)",
    "import numpy as np\nnp.isclose(\n    r, 1.0,\n)  # tolerance: default - a ratio of order one",
    "import numpy as np\nclass A:\n    isclose = 1\n",  # a name stored, not numpy's
])
def test_the_rule_passes(code):
    assert not violations(code), violations(code)
