"""The element kinds a feeder is built from: each one's name in a description, its code in
the deck (``s<k>_kind``), the keys it takes, the ones it must state, whether it may start a
feeder (and on which project deck) or follow another, and how it is built from the deck's
parameters. The description (:mod:`.description`) and the feeder (:mod:`.feeder`) ask here,
never a kind by name: a new kind is its module and one entry in :data:`KINDS`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

from . import bowl, chute, linear, mesh_element


@dataclass(frozen=True)
class Kind:
    """One element kind (module docstring). ``keys(k)``: (every key the kind knows, the keys
    element ``k`` of that kind takes -> their deck names); ``tunables``: the kind's own
    declarations for a generated deck, (suffix, unit, meaning) per key, or None where its
    numbers are section 2's, numbered (a linear section); ``build(values, k, x0, level, part)``:
    element ``k >= 2`` from the deck's parameters (None: the kind is the first element only);
    ``template``: the project deck a feeder starting with it runs on (None: never first)."""

    name: str
    code: int | None
    keys: Callable[[int], tuple[dict, dict]]
    needed: tuple[str, ...]
    build: Callable | None
    template: str | None = None
    tunables: Mapping | None = None

    @property
    def later(self) -> bool:
        """Whether the kind may follow another element."""
        return self.build is not None


def _linear_keys(k: int) -> tuple[dict, dict]:
    return linear.KEYS, linear.deck_names(k)


def _bowl_keys(k: int) -> tuple[dict, dict]:
    return bowl.KEYS, (dict(bowl.KEYS) if k == 1 else {})


def _chute_keys(k: int) -> tuple[dict, dict]:
    known = {(key,): None for key in chute.KEYS}
    return known, ({} if k == 1 else {(key,): chute.deck_name(k, key) for key in chute.KEYS})


def _linear(values, k, x0, level, part):
    return linear.LinearSection.from_values(values, k, x0, level, part)


def _chute(values, k, x0, level, part):
    return chute.Chute.from_values(values, k, x0, level)


def _mesh(values, k, x0, level, part):
    return mesh_element.MeshElement.from_values(values, k, x0, level, part)


def _mesh_keys(k: int) -> tuple[dict, dict]:
    return mesh_element.KEYS, ({} if k == 1 else {key: mesh_element.deck_name(k, key)
                                                  for key in mesh_element.KEYS})


# In the order a user reads them in messages; the linear section is code 0 (an absent s<k>_kind).
KINDS: dict[str, Kind] = {
    "bowl": Kind("bowl", None, _bowl_keys, bowl.NEEDED, None, template="bowl_feeder"),
    "linear": Kind("linear", 0, _linear_keys, ("length", "width"),
                   _linear, template="bulk_feeder"),
    "chute": Kind("chute", chute.KIND_CODE, _chute_keys, ("length", "width", "slope"), _chute,
                  tunables=chute.KEYS),
    "mesh": Kind("mesh", mesh_element.KIND_CODE, _mesh_keys, mesh_element.NEEDED, _mesh,
                 tunables=mesh_element.KEYS),
}
BY_CODE: dict[int, Kind] = {kind.code: kind for kind in KINDS.values() if kind.code is not None}


def later_kinds_text() -> str:
    """The codes a later element may have, for messages: "0 (a linear section), ... or 2 (a mesh)"."""
    what = {"linear": "a linear section"}
    each = [f"{kind.code} ({what.get(kind.name, 'a ' + kind.name)})" for kind in BY_CODE.values()]
    return ", ".join(each[:-1]) + " or " + each[-1]
