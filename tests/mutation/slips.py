"""Mutation operators for the slips people make in numerical code (cosmic-ray provider ``slips``).

cosmic-ray's own operators swap one operator token or move a number by one. They already
cover some slips: ``axis=0`` becomes ``axis=1`` or ``axis=-1`` (NumberReplacer), ``axis=-1``
becomes ``axis=1`` (ReplaceUnaryOperator_Delete_USub), and ``n + 1`` becomes ``n + 0``, which
is the ``+ 1`` dropped (NumberReplacer). These four add the ones they miss:

``slips/MeanMedian``
    ``np.mean`` <-> ``np.median`` (``nanmean`` <-> ``nanmedian``, ``statistics.mean`` <->
    ``statistics.median``), and the method ``a.mean(...)`` -> ``np.median(a, ...)``.
``slips/AxisNone``
    ``axis=K`` -> ``axis=None``: the axis forgotten, the reduction over every element. Not
    where a function's own default axis is not None (``np.concatenate``, ``np.diff``,
    ``np.sort``, ``ufunc.reduceat`` ...): forgetting it there gives that default, which is
    either K (no change) or another number (NumberReplacer's mutants).
``slips/OffByOne``
    A bound of a slice or of ``range(...)`` (start, stop) that is neither a number nor
    ``E +/- 1`` (those are NumberReplacer's) gets ``+ 1`` and ``- 1``: the ``+ 1`` that was
    needed and forgotten, or added and not needed; a slice bound ``-1`` is dropped
    (``a[:-1]`` -> ``a[:]``, the last element not left out).
``slips/LoosenTolerance``
    A tolerance ten times looser: the value of a keyword argument, parameter default or
    assignment whose name is tolerance-like (``rtol``, ``atol``, ``xtol``, ``rel_tol``,
    ``tol``, ``*_tol``, ``*_TOLERANCE`` ...) and holds a non-zero number is multiplied by 10.

The operators work on cosmic-ray's parso trees; a mutated piece is replaced by one leaf holding
its new source text, so the lines around it do not move. ``check()`` runs every operator's
examples (tests/mutation/run.py does before it starts a session).

cosmic-ray finds providers through the entry-point group ``cosmic_ray.operator_providers``.
run.py registers this module without installing anything: it copies it next to a small
``*.dist-info`` folder (``entry_points.txt``: ``slips = vibrofeed_mutation_slips:Provider``)
in the session folder and puts that folder on PYTHONPATH, where ``importlib.metadata`` (and so
stevedore) sees it as an installed distribution.
"""

from __future__ import annotations

import ast
import re

import parso
from cosmic_ray.operators.operator import Example, Operator
from parso.python.tree import Name

# -- helpers ---------------------------------------------------------------------------------
# Expressions that take `+ 1`, `* 10` ... on their right without parentheses (left-associative
# arithmetic or tighter).
_BARE_ADD = {"name", "number", "atom", "atom_expr", "power", "factor", "term", "arith_expr"}
_BARE_MUL = {"name", "number", "atom", "atom_expr", "power", "factor", "term"}


def _code(node) -> str:
    return node.get_code(include_prefix=False)


def _prefix(node) -> str:
    return node.get_first_leaf().prefix


def _leaf(node, text: str):
    """A leaf standing for ``node`` with the new source ``text`` (same prefix, same place)."""
    return Name(text, node.start_pos, prefix=_prefix(node))


def _joined(nodes) -> str:
    """The source of consecutive sibling nodes (the first one's prefix left out)."""
    nodes = list(nodes)
    if not nodes:
        return ""
    return _code(nodes[0]) + "".join(n.get_code(include_prefix=True) for n in nodes[1:])


def _is(node, type_: str, value: str | None = None) -> bool:
    return node is not None and node.type == type_ and (value is None or node.value == value)


def _numbers(node):
    if node.type == "number":
        yield node
    for c in getattr(node, "children", ()):
        yield from _numbers(c)


def _numpy_name(node) -> str:
    """How the module of ``node`` names numpy (``np`` after ``import numpy as np``)."""
    src = node.get_root_node().get_code()
    m = re.search(r"^\s*import numpy as (\w+)\s*$", src, re.M)
    if m:
        return m.group(1)
    return "numpy" if re.search(r"^\s*import numpy\s*$", src, re.M) else '__import__("numpy")'


# -- mean <-> median -------------------------------------------------------------------------
_SWAP = {"mean": "median", "median": "mean", "nanmean": "nanmedian", "nanmedian": "nanmean"}
_MODULES = {"np", "numpy", "statistics"}


def _mean_sites(node):
    """(index of the attribute trailer, kind) for each mean/median call in an atom_expr."""
    if node.type not in ("atom_expr", "power"):
        return
    ch = node.children
    for i in range(1, len(ch) - 1):
        t, call = ch[i], ch[i + 1]
        if not (t.type == "trailer" and t.children[0].value == "." and call.type == "trailer"
                and call.children[0].value == "("):
            continue
        attr = t.children[1].value
        if (i == 1 and _is(ch[0], "name") and attr in _SWAP
                and ch[0].value in _MODULES | {_numpy_name(node)}):
            if not (ch[0].value == "statistics" and attr.startswith("nan")):
                yield i, "function"
        elif attr == "mean":
            yield i, "method"


class MeanMedian(Operator):
    """``np.mean`` <-> ``np.median`` (and nan-, statistics.); ``a.mean(...)`` -> ``np.median(a, ...)``."""

    def mutation_positions(self, node):
        for i, _kind in _mean_sites(node):
            attr = node.children[i].children[1]
            yield attr.start_pos, attr.end_pos

    def mutate(self, node, index):
        i, kind = list(_mean_sites(node))[index]
        ch = node.children
        attr = ch[i].children[1].value
        if kind == "function":
            text = _joined(ch[:i]) + "." + _SWAP[attr] + "".join(c.get_code() for c in ch[i + 1:])
        else:
            args = _joined(ch[i + 1].children[1:-1]).strip()
            base = _joined(ch[:i])
            rest = "".join(c.get_code() for c in ch[i + 2:])
            text = f"{_numpy_name(node)}.median({base}{', ' + args if args else ''}){rest}"
        return _leaf(node, text)

    @classmethod
    def examples(cls):
        return (
            Example("import numpy as np\nm = np.mean(x, axis=0)\n",
                    "import numpy as np\nm = np.median(x, axis=0)\n"),
            Example("import numpy as np\nm = np.nanmedian(x)\n", "import numpy as np\nm = np.nanmean(x)\n"),
            Example("import numpy as np\nm = x[:3].mean(axis=1).item()\n",
                    "import numpy as np\nm = np.median(x[:3], axis=1).item()\n"),
            Example("m = float(y.mean())\n", 'm = float(__import__("numpy").median(y))\n'),
            Example("m = statistics.mean(v)\n", "m = statistics.median(v)\n"),
        )


# -- axis=K -> axis=None ---------------------------------------------------------------------
# Functions whose own default axis is not None (or that need one).
_AXIS_DEFAULT_NOT_NONE = {
    "concatenate", "stack", "split", "array_split", "diff", "sort", "argsort", "cross", "reduce",
    "reduceat", "accumulate", "take_along_axis", "put_along_axis", "apply_along_axis",
    "expand_dims", "moveaxis", "swapaxes", "rollaxis", "trapz", "trapezoid", "linspace",
    "logspace", "geomspace", "gradient", "fft", "ifft", "rfft", "irfft", "partition",
    "argpartition", "lexsort", "unwrap", "interp",
    "CubicSpline", "PchipInterpolator", "Akima1DInterpolator", "interp1d", "make_interp_spline",
}


def _callee(argument) -> str | None:
    """The name of the function a keyword argument is passed to (``np.linalg.norm`` -> norm)."""
    trailer = argument.parent if argument.parent.type == "trailer" else argument.parent.parent
    if trailer is None or trailer.type != "trailer" or trailer.parent is None:
        return None
    ch = trailer.parent.children
    k = ch.index(trailer)
    if k == 0:
        return None
    before = ch[k - 1]
    if before.type == "trailer" and before.children[0].value == ".":
        return before.children[1].value
    return before.value if before.type == "name" else None


class AxisNone(Operator):
    """``axis=K`` -> ``axis=None``: the axis forgotten (numpy reductions then take every element)."""

    def mutation_positions(self, node):
        if (node.type == "argument" and len(node.children) == 3 and _is(node.children[0], "name", "axis")
                and node.children[1].value == "=" and not _is(node.children[2], "keyword", "None")
                and _callee(node) not in _AXIS_DEFAULT_NOT_NONE):
            yield node.children[2].start_pos, node.children[2].end_pos

    def mutate(self, node, index):
        value = node.children[2]
        node.children[2] = _leaf(value, "None")
        return node

    @classmethod
    def examples(cls):
        return (
            Example("s = x.sum(axis=1)\n", "s = x.sum(axis=None)\n"),
            Example("n = np.linalg.norm(d, axis=-1, keepdims=True)\n",
                    "n = np.linalg.norm(d, axis=None, keepdims=True)\n"),
            Example("c = np.concatenate(parts, axis=0)\n", None),
            Example("s = CubicSpline(t, y, axis=0)\n", None),
        )


# -- off by one in slices and ranges ---------------------------------------------------------
def _bound_role(node) -> str | None:
    """"slice" or "range" when ``node`` is a slice's start/stop or range()'s start/stop."""
    parent = node.parent
    if parent is None or node.type in ("operator", "sliceop", "arglist", "subscript", "subscriptlist"):
        return None
    if parent.type == "subscript":
        return "slice"
    if parent.type == "arglist":
        args = [c for c in parent.children if not _is(c, "operator", ",")]
        if any(a.type == "argument" for a in args) or len(args) > 3 or args.index(node) > 1:
            return None
        parent = parent.parent
    if parent.type == "trailer" and parent.children[0].value == "(" and parent.parent is not None:
        ch = parent.parent.children
        if ch.index(parent) == 1 and _is(ch[0], "name", "range") and node.type != "argument":
            return "range"
    return None


def _zipped(bound) -> bool:
    """Whether the sliced expression is an argument of zip(): ``zip(x[:-1], x[1:])`` stops at
    the shorter anyway, so dropping the ``-1`` changes nothing."""
    arg = bound.parent.parent  # subscript -> trailer
    while arg is not None and arg.type in ("trailer", "subscriptlist"):
        arg = arg.parent
    holder = arg.parent if arg is not None else None
    if holder is not None and holder.type == "arglist":
        holder = holder.parent
    if holder is None or holder.type != "trailer" or holder.parent is None:
        return False
    ch = holder.parent.children
    return ch.index(holder) == 1 and _is(ch[0], "name", "zip")


def _off_by_one_kind(node) -> str | None:
    role = _bound_role(node)
    if role is None or node.type in ("number", "string", "keyword", "star_expr"):
        return None  # numbers: NumberReplacer's
    ch = getattr(node, "children", ())
    if node.type == "factor" and ch[0].value == "-" and _is(ch[1], "number", "1"):
        return "drop" if role == "slice" and not _zipped(node) else None
    if node.type == "factor" and ch[1].type == "number":
        return None  # -2 ...: NumberReplacer's
    if node.type == "arith_expr" and ch[-2].value in ("+", "-") and _is(ch[-1], "number", "1"):
        return None  # E + 1 -> E + 0 is NumberReplacer's
    return "shift"


class OffByOne(Operator):
    """A slice or range() bound ``E`` -> ``E + 1``, ``E - 1``; a slice bound ``-1`` dropped."""

    def mutation_positions(self, node):
        kind = _off_by_one_kind(node)
        if kind is not None:
            for _ in range(1 if kind == "drop" else 2):
                yield node.start_pos, node.end_pos

    def mutate(self, node, index):
        if _off_by_one_kind(node) == "drop":
            return None
        text = _code(node) if node.type in _BARE_ADD else f"({_code(node)})"
        return _leaf(node, text + (" + 1", " - 1")[index])

    @classmethod
    def examples(cls):
        return (
            Example("y = x[:third]\n", "y = x[:third + 1]\n"),
            Example("y = x[:third]\n", "y = x[:third - 1]\n", occurrence=1),
            Example("y = x[a:a + len(b)]\n", "y = x[a + 1:a + len(b)]\n"),
            Example("y = x[a:a + len(b)]\n", "y = x[a:a + len(b) + 1]\n", occurrence=2),
            Example("y = x[:-1]\n", "y = x[:]\n"),
            Example("for a, b in zip(x[:-1], x[1:]):\n    pass\n", None),
            Example("y = x[1:n + 1]\n", None),
            Example("for i in range(n):\n    pass\n", "for i in range(n + 1):\n    pass\n"),
            Example("for i in range(1, len(v) - k):\n    pass\n",
                    "for i in range(1, len(v) - k - 1):\n    pass\n", occurrence=1),
            Example("for i in range(a, b, step):\n    pass\n", "for i in range(a - 1, b, step):\n    pass\n",
                    occurrence=1),
            Example("y = x[i]\n", None),
        )


# -- a tolerance ten times looser ------------------------------------------------------------
_TOL_NAME = re.compile(r"(?i)(^|_)(r|a|x|f|g|rel_|abs_)?tol(erance)?s?(_|$)")
_VALUE_TYPES = {"number", "term", "power", "arith_expr", "atom_expr", "atom", "factor", "test"}


def _tolerance_value(node) -> bool:
    """Whether ``node`` is the value given to a tolerance-like name, holding a non-zero number."""
    parent = node.parent
    if parent is None:
        return False
    name = None
    if parent.type == "argument" and len(parent.children) == 3 and parent.children[2] is node:
        name = parent.children[0]
    elif parent.type == "param" and parent.default is node:
        name = parent.name
    elif (parent.type == "expr_stmt" and len(parent.children) == 3 and parent.children[2] is node
          and parent.children[1].value == "="):
        name = parent.children[0]
    elif (parent.type == "annassign" and len(parent.children) == 4 and parent.children[3] is node
          and parent.parent is not None):
        name = parent.parent.children[0]
    if not (_is(name, "name") and _TOL_NAME.search(name.value)):
        return False
    if node.type not in _VALUE_TYPES or (node.type == "atom" and (
            node.children[0].value != "(" or len(node.children) != 3
            or node.children[1].type in ("testlist_comp", "yield_expr"))):
        return False
    numbers = list(_numbers(node))
    return bool(numbers) and not (node.type == "number" and ast.literal_eval(node.value) == 0)


class LoosenTolerance(Operator):
    """The value of a tolerance-like name multiplied by 10 (``rtol=1e-6`` -> ``rtol=1e-6 * 10``)."""

    def mutation_positions(self, node):
        if _tolerance_value(node):
            yield node.start_pos, node.end_pos

    def mutate(self, node, index):
        text = _code(node) if node.type in _BARE_MUL else f"({_code(node)})"
        return _leaf(node, text + " * 10")

    @classmethod
    def examples(cls):
        return (
            Example("ok = np.allclose(a, b, rtol=1e-6, atol=0.0)\n",
                    "ok = np.allclose(a, b, rtol=1e-6 * 10, atol=0.0)\n"),
            Example("def f(x, tol: float = 1e-9):\n    pass\n",
                    "def f(x, tol: float = 1e-9 * 10):\n    pass\n"),
            Example("_PERIOD_TOLERANCE = 1e-4\n", "_PERIOD_TOLERANCE = 1e-4 * 10\n"),
            Example("DRIVE_RTOL: float = 1e-3\n", "DRIVE_RTOL: float = 1e-3 * 10\n"),
            Example("default_tol = 0.01 * d if ok else 0.0\n",
                    "default_tol = (0.01 * d if ok else 0.0) * 10\n"),
            Example("tol += 1e-3\n", None),
            Example("r = f(x, atol=0.0)\n", None),
            Example("default_tol = 0.01 * d\n", "default_tol = 0.01 * d * 10\n"),
            Example("eps = a + 1e-3\n", None),
            Example("tol = a + 1e-3\n", "tol = (a + 1e-3) * 10\n"),
            Example("v = x.tolist()\n", None),
            Example("r = root(f, xtol=xtol)\n", None),
        )


# -- the provider ----------------------------------------------------------------------------
OPERATORS = {op.__name__: op for op in (MeanMedian, AxisNone, OffByOne, LoosenTolerance)}
PROVIDER = "slips"


class Provider:
    """cosmic-ray operator provider (entry point group ``cosmic_ray.operator_providers``)."""

    def __iter__(self):
        return iter(OPERATORS)

    def __getitem__(self, name):
        return OPERATORS[name]


def check() -> None:
    """Run every operator's examples; AssertionError on the first that does not hold.

    An example whose result is None must have no mutation site; otherwise occurrence k must
    give exactly the code shown, and the mutated code must still parse.
    """
    from cosmic_ray.mutating import mutate_code

    for name, op in OPERATORS.items():
        for ex in op.examples():
            got = mutate_code(ex.pre_mutation_code, op(), ex.occurrence)
            assert got == ex.post_mutation_code, (
                f"{PROVIDER}/{name} on {ex.pre_mutation_code!r} (occurrence {ex.occurrence}): "
                f"{got!r}, expected {ex.post_mutation_code!r}")
            if got is not None:
                assert not list(parso.load_grammar().iter_errors(parso.parse(got))), got


if __name__ == "__main__":
    check()
    print(f"{PROVIDER}: {len(OPERATORS)} operators, every example holds")
