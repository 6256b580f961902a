"""The study file: the deck, its fixed parameters, the design variables, the constraints,
the objective, the budget and the robustness check of ``vibrofeed optimize``.

::

    deck = "bulk_feeder"           # a deck name, or a deck file (relative to this file)
    ranks_per_run = 1              # MPI ranks of each DEM run
    seed = 5489                    # the sampler's seed, and the DEM runs' (each its own)
    target_error = 0.05            # optional: a run stops once its feed rate is this precise
    description = "..."

    [fixed]                        # deck parameters of every run
    sections = 2

    [variables]                    # the design: bounds (float; type = "int"; log = true) or choices
    s2_amp_t = { low = 6e-5, high = 2.4e-4 }
    freq = { low = 50, high = 200, log = true }
    shape = { choices = [0, 1] }

    [constraints]                  # all optional; checked on the models before any DEM run
    max_acceleration = 6.0         # [g] peak acceleration of every section's drive
    max_displacement = 3e-4        # [m] peak displacement (half the stroke) of every section
    frequency = [50, 200]          # [Hz] every section's frequency
    min_model_speed = 2e-3         # [m/s] the single-part model must convey this fast, every section
    no_hopping = [2]               # sections whose drive must not throw a part off the floor
    require = ["s2_amp_t >= 2 * amp_t"]   # inequalities between parameters

    [objective]
    maximize = "singulated_rate"   # a metric, or two of them (a Pareto front)
    at_least = { parts_per_s = 25 }  # targets a DEM run must reach to count (optional)

    [budget]
    runs = 20                      # DEM runs of the search
    seeds = 6                      # of which placed by the model screen, space-filling
    screen = 256                   # settings the models screen
    confirm = 3                    # best settings re-run with fresh seeds ...
    replicates = 3                 # ... this many times each

    [robustness]                   # the confirmed best re-run at each of these values
    mu = [0.4, 0.6]
    rolling_friction = [0.0, 0.05]

Everything is checked before anything runs, a problem named with its line (the sweep
file's reader: :func:`vibrofeed.sweep.spec.key_lines`); the fingerprint (SHA-256 of the
parsed content) ties an output folder to one study.
"""

from __future__ import annotations

import ast
import dataclasses
import math
import operator
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import said
from ..sweep.spec import KeyReader, fingerprint, flat, parse_toml, read_file, scalar, target_error

TOP_KEYS = ("deck", "ranks_per_run", "seed", "description", "target_error", "fixed", "variables",
            "constraints", "objective", "budget", "robustness")
CONSTRAINT_KEYS = ("max_acceleration", "max_displacement", "frequency", "min_model_speed",
                   "no_hopping", "require")
BUDGET = {"runs": 20, "seeds": 6, "screen": 256, "confirm": 3, "replicates": 3}
# The most settings the model screen takes: each is checked as vibrofeed run checks it and
# screened on the models, about 90 ms with the single-part model
# (studies/line_singulated_rate.toml on a 2-core Xeon, 2026-12-03): 10 000 take 15 minutes
# before the first DEM run (screen = 1000000000 ended in a memory traceback).
MAX_SCREEN = 10_000
# Metrics an objective may name: the sweep's metrics of a bulk result, and a product.
METRICS = ("parts_per_s", "mass_per_s", "mean_velocity", "singulated_fraction", "orientation_yield",
           "singulated_rate", "oriented_rate", "correct_fraction", "cv_interarrival", "doubles_rate")
# Of them, the ones only parts with an orientation measure (not spheres).
ORIENTED = ("orientation_yield", "oriented_rate", "correct_fraction")
# Lower is better for these (the others are maximised).
MINIMISED = ("cv_interarrival", "doubles_rate")
# Names an inequality may use besides the parameters: arithmetic only.
_FUNCTIONS = {"abs": abs, "min": min, "max": max, "sqrt": math.sqrt}
_OPERATORS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
              ast.Div: operator.truediv, ast.Pow: operator.pow}
_NODES = (ast.Expression, ast.Compare, ast.BinOp, ast.UnaryOp, ast.Name, ast.Load, ast.Constant,
          ast.Call, ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd, ast.Lt,
          ast.LtE, ast.Gt, ast.GtE)


@dataclass
class Variable:
    """A design variable: ``kind`` float, int or choice."""

    name: str
    kind: str
    low: float | None = None
    high: float | None = None
    log: bool = False
    choices: list = field(default_factory=list)


@dataclass
class Inequality:
    """``left OP right`` between parameters (``s2_amp_t >= 2 * amp_t``); ``margin()`` is
    the amount it is broken by (<= 0: holds), as Optuna's constraints take it."""

    text: str
    tree: ast.Expression
    names: list[str]

    def margin(self, values: dict) -> float:
        node = self.tree.body
        left = _evaluate(node.left, values)
        right = _evaluate(node.comparators[0], values)
        op = node.ops[0]
        return right - left if isinstance(op, ast.Gt | ast.GtE) else left - right

    def holds(self, values: dict) -> bool:
        m = self.margin(values)
        return m < 0 or (m == 0 and isinstance(self.tree.body.ops[0], ast.LtE | ast.GtE))


@dataclass
class StudySpec:
    source: Path
    text: str
    data: dict
    deck: str
    ranks_per_run: int
    seed: int
    description: str
    fixed: dict
    variables: list[Variable]
    constraints: dict
    inequalities: list[Inequality]
    maximize: list[str]
    at_least: dict
    budget: dict
    robustness: dict
    lines: dict
    target_error: float | None = None
    # a parameter's name as the file wrote it -> the deck's own (a feeder description's dotted
    # names, read as the deck's; StudySpec.renamed)
    renames: dict = field(default_factory=dict)

    @property
    def fingerprint(self) -> str:
        return fingerprint(self.data)

    @property
    def names(self) -> list[str]:
        return [v.name for v in self.variables]

    @property
    def parameters(self) -> list[str]:
        """Every parameter the file names: fixed, then the variables."""
        return list(self.fixed) + [n for n in self.names if n not in self.fixed]

    @property
    def multi(self) -> bool:
        return len(self.maximize) > 1

    def where(self, *path) -> str:
        return KeyReader(self.source, self.lines).where(*path)

    def renamed(self, names: dict[str, str]) -> StudySpec:
        """The study with each parameter called as ``names`` says (a feeder description's
        dotted name -> the deck's own, vibrofeed.optimize.search.own_names), each line kept."""
        if not names:
            return self
        reader = KeyReader(self.source, self.lines)
        lines = dict(self.lines)
        keyed = ([("fixed", n) for n in self.fixed] + [("variables", v.name) for v in self.variables]
                 + [("robustness", n) for n in self.robustness])
        for table, old in keyed:
            if old in names and (line := reader.line(table, old)) is not None:
                lines.setdefault((table, names[old]), line)
        return dataclasses.replace(
            self, fixed={names.get(n, n): v for n, v in self.fixed.items()},
            variables=[dataclasses.replace(v, name=names.get(v.name, v.name)) for v in self.variables],
            robustness={names.get(n, n): v for n, v in self.robustness.items()}, lines=lines,
            renames={**self.renames, **names})


def _evaluate(node, values: dict) -> float:
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.Name):
        return float(values[node.id])
    if isinstance(node, ast.UnaryOp):
        x = _evaluate(node.operand, values)
        return -x if isinstance(node.op, ast.USub) else x
    if isinstance(node, ast.Call):
        return float(_FUNCTIONS[node.func.id](*[_evaluate(a, values) for a in node.args]))
    return _OPERATORS[type(node.op)](_evaluate(node.left, values), _evaluate(node.right, values))


def load(path) -> StudySpec:
    return parse(read_file(path, "study file"), Path(path))


def parse(text: str, source: Path | str = "study.toml") -> StudySpec:
    source = Path(source)
    data, r = parse_toml(text, source)
    r.ONCE = "a parameter is fixed or a design variable, not both"
    for key in data:
        if key not in TOP_KEYS:
            r.fail((key,), f"unknown key {key}; a study file has {', '.join(TOP_KEYS)}")
    for key in ("fixed", "variables", "constraints", "objective", "budget", "robustness"):
        if key in data and not isinstance(data[key], dict):
            r.fail((key,), f"{key} must be a table [{key}]")
    if not isinstance(data.get("deck"), str) or not data["deck"].strip():
        r.fail(("deck",), "deck must be a deck name or file (a string), e.g. deck = \"bulk_feeder\"")
    ranks, seed = data.get("ranks_per_run", 1), data.get("seed", 5489)
    for key, value, low in (("ranks_per_run", ranks, 1), ("seed", seed, 0)):
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            r.fail((key,), f"{key} must be a whole number >= {low}, got {said(value)}")
    fixed = {}
    for name, path, value in flat(data.get("fixed", {})):
        if not scalar(value):
            r.fail(("fixed", *path), f"[fixed] {name} must be one number or string, got {said(value)}")
        r.claim(name, ("fixed", *path))
        fixed[name] = value
    variables = [_variable(name, spec, r, path)
                 for name, path, spec in flat(data.get("variables", {}), leaf=_VARIABLE_KEYS)]
    if not variables:
        r.fail(("variables",), "no design variables: add [variables] with name = { low = .., high = .. }")
    constraints, inequalities = _constraints(data.get("constraints", {}), r)
    maximize, at_least = _objective(data.get("objective", {}), r)
    budget = _budget(data.get("budget", {}), r)
    robustness = _robustness(data.get("robustness", {}), r, {v.name for v in variables})
    target = target_error(data, r)
    return StudySpec(source=source, text=text, data=data, deck=data["deck"].strip(),
                     ranks_per_run=ranks, seed=seed, description=str(data.get("description", "")),
                     fixed=fixed, variables=variables, constraints=constraints,
                     inequalities=inequalities, maximize=maximize, at_least=at_least, budget=budget,
                     robustness=robustness, lines=r.lines, target_error=target)


def _number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


_VARIABLE_KEYS = {"low", "high", "log", "type", "choices"}


def _variable(name: str, spec, r: KeyReader, path: tuple = ()) -> Variable:
    key = ("variables", *(path or (name,)))
    r.claim(name, key)
    if not isinstance(spec, dict):
        r.fail(key, f"variable {name} must be a table: {{ low = .., high = .. }} or {{ choices = [..] }}")
    unknown = set(spec) - _VARIABLE_KEYS
    if unknown:
        r.fail(key, f"variable {name}: unknown key(s) {', '.join(sorted(unknown))} "
                    "(low, high, log, type, choices)")
    if "choices" in spec:
        choices = spec["choices"]
        if set(spec) != {"choices"}:
            r.fail(key, f"variable {name}: choices or low/high, not both")
        if not isinstance(choices, list) or len(choices) < 2 or not all(scalar(c) for c in choices):
            r.fail(key, f"variable {name}: choices must list two or more numbers or strings")
        if len({repr(c) for c in choices}) != len(choices):
            r.fail(key, f"variable {name}: a choice is listed twice")
        return Variable(name, "choice", choices=list(choices))
    kind = spec.get("type", "float")
    if kind not in ("float", "int"):
        r.fail(key, f"variable {name}: type must be \"float\" or \"int\", got {said(kind)}")
    low, high = spec.get("low"), spec.get("high")
    if not (_number(low) and _number(high)) or not low < high:
        r.fail(key, f"variable {name}: needs numbers low < high, got low={said(low)}, high={said(high)}")
    if kind == "int" and not (float(low).is_integer() and float(high).is_integer()):
        r.fail(key, f"variable {name}: an int variable needs whole bounds")
    log = spec.get("log", False)
    if not isinstance(log, bool):
        r.fail(key, f"variable {name}: log must be true or false")
    if log and low <= 0:
        r.fail(key, f"variable {name}: a log scale needs low > 0, got {said(low)}")
    return Variable(name, kind, float(low), float(high), log)


def _constraints(table: dict, r: KeyReader) -> tuple[dict, list[Inequality]]:
    out = {}
    for key, value in table.items():
        where = ("constraints", key)
        if key not in CONSTRAINT_KEYS:
            r.fail(where, f"unknown constraint {key}; known: {', '.join(CONSTRAINT_KEYS)}")
        if key in ("max_acceleration", "max_displacement", "min_model_speed"):
            if not _number(value) or value <= 0:
                r.fail(where, f"{key} must be a number > 0, got {said(value)}")
        elif key == "frequency":
            if not (isinstance(value, list) and len(value) == 2 and all(_number(v) for v in value)
                    and 0 < value[0] < value[1]):
                r.fail(where, f"frequency must be [low, high] in Hz with 0 < low < high, got {said(value)}")
        elif key == "no_hopping":
            if not (isinstance(value, list) and all(isinstance(v, int) and not isinstance(v, bool)
                                                    and v >= 1 for v in value)):
                r.fail(where, f"no_hopping must list section numbers (1, 2), got {said(value)}")
        elif key == "require" and not (isinstance(value, list) and all(isinstance(v, str) for v in value)):
            r.fail(where, f"require must list inequalities as strings, got {said(value)}")
        out[key] = value
    inequalities = [_inequality(text, r) for text in out.get("require", [])]
    return out, inequalities


def _inequality(text: str, r: KeyReader) -> Inequality:
    where = ("constraints", "require")
    try:
        tree = ast.parse(text, mode="eval")
    except SyntaxError:
        r.fail(where, f"require: {said([text])[1:-1]} is not an inequality such as \"s2_amp_t >= 2 * amp_t\"")
    body = tree.body
    if not (isinstance(body, ast.Compare) and len(body.ops) == 1
            and isinstance(body.ops[0], ast.Lt | ast.LtE | ast.Gt | ast.GtE)):
        r.fail(where, f"require: {said([text])[1:-1]} must be one comparison (<, <=, >, >=)")
    names = []
    for node in ast.walk(tree):
        if not isinstance(node, _NODES):
            r.fail(where, f"require: {said([text])[1:-1]} may use numbers, parameters, + - * / ** and "
                          f"{', '.join(_FUNCTIONS)} only")
        called = isinstance(node, ast.Call)
        if called and not (isinstance(node.func, ast.Name) and node.func.id in _FUNCTIONS):
            r.fail(where, f"require: {said([text])[1:-1]} calls something other than {', '.join(_FUNCTIONS)}")
        if isinstance(node, ast.Name) and node.id not in _FUNCTIONS:
            names.append(node.id)
    # the names are checked against the deck's parameters once the deck is known (search.optimize)
    return Inequality(text, tree, names)


def _objective(table: dict, r: KeyReader) -> tuple[list[str], dict]:
    unknown = set(table) - {"maximize", "at_least"}
    if unknown:
        r.fail(("objective",), f"unknown key(s) in [objective]: {', '.join(sorted(unknown))} "
                               "(maximize, at_least)")
    goal = table.get("maximize")
    goals = [goal] if isinstance(goal, str) else goal
    if not (isinstance(goals, list) and 1 <= len(goals) <= 2 and all(isinstance(g, str) for g in goals)):
        r.fail(("objective", "maximize"), "maximize must name a metric, or two (a Pareto front), "
                                          f"e.g. maximize = \"singulated_rate\"; known: {', '.join(METRICS)}")
    for g in goals:
        if g not in METRICS:
            r.fail(("objective", "maximize"), f"unknown metric {g}; known: {', '.join(METRICS)}")
    if len(set(goals)) != len(goals):
        r.fail(("objective", "maximize"), "the two objectives are the same metric")
    at_least = table.get("at_least", {})
    if not isinstance(at_least, dict):
        r.fail(("objective", "at_least"), "at_least must be a table: { parts_per_s = 25 }")
    for name, value in at_least.items():
        if name not in METRICS or not _number(value):
            r.fail(("objective", "at_least"), f"at_least: {name} = {said(value)} must be a known metric "
                                              "and a number")
    return goals, dict(at_least)


def _budget(table: dict, r: KeyReader) -> dict:
    out = dict(BUDGET)
    for key, value in table.items():
        if key not in BUDGET:
            r.fail(("budget", key), f"unknown key {key} in [budget]; known: {', '.join(BUDGET)}")
        low = 0 if key in ("seeds", "confirm") else 1
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            r.fail(("budget", key), f"{key} must be a whole number >= {low}, got {said(value)}")
        out[key] = value
    for key in ("confirm", "replicates"):  # confirmation runs are jobs 10000 + 100 x rank + replicate
        if out[key] > 100:
            r.fail(("budget", key), f"{key} must be at most 100 (confirmation runs are numbered "
                                    f"10000 + 100 x rank + replicate), got {out[key]}")
    if out["screen"] > MAX_SCREEN:
        r.fail(("budget", "screen"), f"screen = {out['screen']} is more settings than the models screen "
                                     f"in reasonable time: at most {MAX_SCREEN} (about 90 ms a setting "
                                     "with the single-part model: 15 minutes before the first run)")
    if out["seeds"] > out["runs"]:
        r.fail(("budget", "seeds"), f"seeds ({out['seeds']}) exceeds runs ({out['runs']}): the "
                                    "screen's settings are part of the search's runs")
    if out["screen"] < out["seeds"]:
        r.fail(("budget", "screen"), f"screen ({out['screen']}) must be at least seeds ({out['seeds']})")
    return out


def _robustness(table: dict, r: KeyReader, variables: set[str]) -> dict:
    out = {}
    for name, path, values in flat(table):
        where = ("robustness", *path)
        if name in variables:
            r.fail(where, f"{name} is a design variable; robustness varies what the design does not fix")
        if not (isinstance(values, list) and values and all(scalar(v) for v in values)):
            r.fail(where, f"robustness {name} must list the values to try, got {said(values)}")
        out[name] = list(values)
    return out
