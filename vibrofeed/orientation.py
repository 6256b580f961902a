"""A part's orientation state: which face is up, which end leads, and its long axis to the path.

A part's body frame (FORMAT.md, "Parts are bodies") is its template's: for a rectangular
part (``shape = box``) x along its length L, y across its width W, z through its thickness T,
and **+z is its marked face** (the face with the feature, or the marking a camera reads).
A square die and a disc have the same frame with x and y alike.

Three things make a part's state, each from its rotation R (body to simulation frame, the
quaternion a result records) and two directions where it is: ``up`` (the floor's normal)
and ``tangent`` (the path's direction of travel, along the floor):

* **which face is up**: the body face whose outward normal is closest to ``up``, one of
  :data:`FACES`; the faces are grouped into the named states of :data:`GROUPS` (``up``:
  marked face up, ``down``: marked face down, ``side``: on a long side, ``end``: standing on
  an end). A face turns up once its normal is nearer ``up`` than any other face's: the
  boundaries between states are at 45° of tilt about one axis (a part balanced on an edge is
  counted by the face it leans to);
* **which end leads**: +1 when the body's +x end points along ``tangent``, -1 when -x does;
* **the long axis's angle to the path**: the angle between the body x axis and ``tangent``,
  both projected on the floor (in [0°, 90°]: a part is as lengthwise leading with either end);
  NaN when the long axis stands within :data:`UPRIGHT` of ``up`` (a part on its end has no
  direction on the floor). A part is **lengthwise** within ``lengthwise`` degrees
  (default :data:`LENGTHWISE`) and **crosswise** otherwise.

What a designer calls correct is a :class:`Correct`: a state (or several) and optionally
``lengthwise`` and a leading end, named in one string (``"up, lengthwise"``,
``"up, lengthwise, lead +x"``, ``"up|down"``): :func:`parse_correct`. A feeder says it once,
for its part: the parameter ``correct`` (a deck tunable, ``[parts] correct`` of a description,
default :data:`CORRECT`), which a result records; the analyses, the sweeps' metrics, the
optimiser's objective and every air jet without a ``keep`` of its own take it from there
(:func:`run_correct`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import ParameterError
from .rotations import matrix_quaternion, quaternion_matrices, quaternion_product

# The body faces by their outward normals; index k: axis k // 2, sign + for even k.
FACES = ("+x", "-x", "+y", "-y", "+z", "-z")
# The named states: the faces that, turned up, put a part in each.
GROUPS: dict[str, tuple[str, ...]] = {
    "up": ("+z",),  # the marked face up, lying flat
    "down": ("-z",),  # the marked face down, lying flat
    "side": ("+y", "-y"),  # on a long side (an L x T face down)
    "end": ("+x", "-x"),  # standing on an end (a W x T face down)
}
STATES = tuple(GROUPS)
# Lengthwise: the long axis within this angle of the path [deg].
LENGTHWISE = 20.0
# A long axis within this angle of ``up`` has no direction on the floor [deg].
UPRIGHT = 5.0
# The parameter ``correct``'s default, as the decks hold it (a word: no blank); a result
# recorded before ``correct`` existed was analysed with it.
CORRECT = "up,lengthwise"


def _unit(v, name: str) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    if not np.all(np.isfinite(n)) or np.any(n == 0):
        raise ValueError(f"{name} must be non-zero, finite vectors")
    return v / n


def face_up(rotations, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Index into :data:`FACES` of the face turned up, per part: (N,) int.

    ``rotations``: (N, 3, 3) body-to-frame matrices; ``up``: (3,) or (N, 3)."""
    r = np.asarray(rotations, dtype=float)
    u = np.broadcast_to(_unit(up, "up"), (len(r), 3))
    c = np.einsum("nij,ni->nj", r, u)  # cosine of each body axis with up
    k = np.argmax(np.abs(c), axis=1)
    sign = np.take_along_axis(c, k[:, None], axis=1)[:, 0]
    return 2 * k + (sign < 0)


def leading_end(rotations, tangent=(1.0, 0.0, 0.0)) -> np.ndarray:
    """+1 where the body's +x end points along ``tangent``, -1 where -x does: (N,) int."""
    r = np.asarray(rotations, dtype=float)
    t = np.broadcast_to(_unit(tangent, "tangent"), (len(r), 3))
    return np.where(np.einsum("ni,ni->n", r[:, :, 0], t) >= 0, 1, -1)


def axis_angle(rotations, tangent=(1.0, 0.0, 0.0), up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """The angle [deg] in [0, 90] between the long (body x) axis and ``tangent``, both
    projected on the plane normal to ``up``; NaN for an upright long axis (module docstring)."""
    r = np.asarray(rotations, dtype=float)
    u = np.broadcast_to(_unit(up, "up"), (len(r), 3))
    t = np.broadcast_to(_unit(tangent, "tangent"), (len(r), 3))
    a = r[:, :, 0]
    a = a - u * np.einsum("ni,ni->n", a, u)[:, None]
    t = t - u * np.einsum("ni,ni->n", t, u)[:, None]
    na, nt = np.linalg.norm(a, axis=1), np.linalg.norm(t, axis=1)
    cos = np.abs(np.einsum("ni,ni->n", a, t)) / np.where(na * nt > 0, na * nt, 1.0)
    angle = np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))
    return np.where(na > np.sin(np.radians(UPRIGHT)), angle, np.nan)


@dataclass(frozen=True)
class States:
    """The orientation of N parts (module docstring): ``face`` (index into :data:`FACES`),
    ``state`` (index into :data:`STATES`), ``lead`` (+1 / -1) and ``angle`` [deg]."""

    face: np.ndarray
    state: np.ndarray
    lead: np.ndarray
    angle: np.ndarray

    def lengthwise(self, within: float = LENGTHWISE) -> np.ndarray:
        """Parts whose long axis lies within ``within`` degrees of the path."""
        return np.nan_to_num(self.angle, nan=90.0) <= within

    def names(self) -> list[str]:
        """Each part's state by name."""
        return [STATES[k] for k in self.state]


_STATE_OF_FACE = np.array([STATES.index(next(s for s, f in GROUPS.items() if face in f)) for face in FACES])


def classify(quaternions, tangent=(1.0, 0.0, 0.0), up=(0.0, 0.0, 1.0)) -> States:
    """The :class:`States` of parts with ``quaternions`` (N, 4) (w, x, y, z), body to frame;
    ``tangent`` and ``up`` (3,) or (N, 3), one per part where the path turns (a bowl)."""
    r = quaternion_matrices(np.asarray(quaternions, dtype=float).reshape(-1, 4))
    face = face_up(r, up)
    return States(face=face, state=_STATE_OF_FACE[face], lead=leading_end(r, tangent),
                  angle=axis_angle(r, tangent, up))


@dataclass(frozen=True)
class Correct:
    """What counts as correctly oriented: any of ``states``, and lengthwise (within
    ``within`` degrees) when ``lengthwise``, and leading with the body's ``lead`` end (+1: +x,
    -1: -x) when it is not 0."""

    states: tuple[str, ...] = ("up",)
    lengthwise: bool = True
    lead: int = 0
    within: float = LENGTHWISE

    def of(self, s: States) -> np.ndarray:
        """Which of the parts described by ``s`` are correct: (N,) bool."""
        ok = np.isin(s.state, [STATES.index(name) for name in self.states])
        if self.lengthwise:
            ok &= s.lengthwise(self.within)
        if self.lead:
            ok &= s.lead == self.lead
        return ok

    def __str__(self) -> str:
        words = ["|".join(self.states)]
        if self.lengthwise:
            words.append("lengthwise")
        elif "end" not in self.states:  # (said: parse_correct reads it back lengthwise otherwise)
            words.append("any-direction")
        if self.lead:
            words.append(f"lead {'+x' if self.lead > 0 else '-x'}")
        return ", ".join(words)


def parse_correct(text: str, name: str = "correct", within: float = LENGTHWISE) -> Correct:
    """A :class:`Correct` from its words, comma-separated: state names joined by ``|``
    (``up``, ``down``, ``side``, ``end``), ``lengthwise`` or ``any-direction``, ``lead +x`` or
    ``lead -x``. ``name`` is the option or parameter it came from, for the error."""
    words = [w.strip().lower() for w in str(text).split(",") if w.strip()]
    if not words:
        raise ParameterError(f"{name} is empty: give a state ({', '.join(STATES)}), e.g. 'up, lengthwise'")
    states = tuple(s.strip() for s in words[0].split("|"))
    unknown = [s for s in states if s not in GROUPS]
    if unknown:
        raise ParameterError(f"{name}: no state named {unknown[0]!r}; the states are {', '.join(STATES)}")
    lengthwise, lead = None, 0
    for w in words[1:]:
        if w == "lengthwise":
            if "end" in states:
                raise ParameterError(f"{name}: a part on its end has no direction on the floor: "
                                     "drop 'lengthwise' or the state 'end'")
            lengthwise = True
        elif w in ("any-direction", "any direction"):
            lengthwise = False
        elif w.replace(" ", "") in ("lead+x", "lead-x"):
            lead = 1 if w.endswith("+x") else -1
        else:
            raise ParameterError(f"{name}: {w!r} is not a state condition; use 'lengthwise', "
                                 "'any-direction', 'lead +x' or 'lead -x' after the states")
    if lengthwise is None:  # lengthwise unless said otherwise, or standing on its end
        lengthwise = "end" not in states
    return Correct(states=states, lengthwise=lengthwise, lead=lead, within=within)


def correct_word(text: str, name: str = "correct") -> str:
    """``text`` (:func:`parse_correct`'s words, checked: a ParameterError naming ``name``) as a
    deck holds it, without blanks: "up, lengthwise" -> "up,lengthwise"."""
    return str(parse_correct(text, name)).replace(", ", ",").replace(" ", "")


def run_correct(parameters, within: float = LENGTHWISE) -> Correct:
    """What a run counts as correct: its parameter ``correct`` (``parameters``: a result's or a
    deck's, words or numbers), :data:`CORRECT` where it records none (a result older than it)."""
    return parse_correct(str(parameters.get("correct", CORRECT)), "correct", within)


# -- a clump template's body frame ------------------------------------------------------
# Off-diagonal second moments below this fraction of their trace: the template lies along
# the body axes, which are then its principal axes as they are (no eigenvector's sign to pick).
_ALIGNED = 1e-9


def body_axes(template) -> np.ndarray:
    """(3, 3) rotation whose columns are a clump template's principal axes in its body frame,
    longest spread first, thinnest last (the frame of :mod:`vibrofeed.orientation`: x the
    length, y the width, z the thickness). A template laid out along the body axes keeps them
    (a permutation; equal spreads keep their order: a square chip stays as it is); another's
    axes are its spread's eigenvectors, each with its largest component positive; the middle
    one is turned so that the frame is right-handed."""
    xyz = np.asarray(template, dtype=float)[:, :3]
    xyz = xyz - xyz.mean(axis=0)
    m = xyz.T @ xyz
    off = m - np.diag(np.diag(m))
    if np.abs(off).max() <= _ALIGNED * max(np.trace(m), 1e-300):
        order = np.argsort(-np.diag(m), kind="stable")
        axes = np.eye(3)[:, order]
    else:
        values, vectors = np.linalg.eigh(m)
        axes = vectors[:, np.argsort(-values, kind="stable")]
        axes = axes * np.sign(axes[np.argmax(np.abs(axes), axis=0), np.arange(3)])
    if np.linalg.det(axes) < 0:
        axes[:, 1] *= -1
    return axes


def axes_quaternion(template) -> np.ndarray:
    """The quaternion (w, x, y, z) that turns the body frame of :func:`body_axes` into the
    frame a clump ``template`` is laid out in (identity for a template along the body axes)."""
    return matrix_quaternion(body_axes(template))


def turned_states(quaternions, axes_q, tangent=(1.0, 0.0, 0.0), up=(0.0, 0.0, 1.0)) -> States:
    """The :class:`States` of parts whose recorded ``quaternions`` (N, 4) turn a template whose
    axes are turned by ``axes_q`` (:func:`axes_quaternion`) from the body frame."""
    return classify(quaternion_product(quaternions, axes_q), tangent, up)


def part_states(quaternions, template, tangent=(1.0, 0.0, 0.0), up=(0.0, 0.0, 1.0)):
    """The :class:`~vibrofeed.orientation.States` of parts whose recorded ``quaternions`` (N, 4)
    turn the body ``template`` (its axes as :func:`body_axes` finds them), along ``tangent`` and
    ``up`` ((3,) or (N, 3)): what the analysis classifies, for pictures and other readers."""
    return turned_states(quaternions, axes_quaternion(template), tangent, up)
