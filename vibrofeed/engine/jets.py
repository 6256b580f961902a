"""A feeder line's orienting stations: a camera senses each part and an air jet blows off those
in a wrong state (vibrofeed.feeders.records.Jet).

The deck holds each jet's block and force (``fix addforce`` on the spheres in the block,
``region s<k>_jet``), switched by the variable ``s<k>_jet_on``, 0 as the deck leaves it (the
elements' ``jet_commands``, vibrofeed.feeders.linear and .mesh_element): a run by hand never
fires. Here the driver senses and fires, at every frame, on rank 0, which has the bodies'
positions and orientations:

* a part is **sensed** when its centre crossed the sensing point between the last frame and
  this one (along x on a straight section, along the path on a mesh element; each part once,
  a part first seen past it not); the crossing's time is interpolated linearly between the
  two frames, its state classified
  (vibrofeed.orientation.turned_states: the body frame of the run's clump template, as the
  analyses read it; tangent the path's direction there, up the floor's normal) at the
  frame nearer the crossing;
* a part sensed **not** in the state the jet keeps gets a **firing window** [t + delay,
  t + delay + duration] (t its crossing); so does one in that state sensed less than the
  jet's ``headway`` after the last part it let pass (a jet that spaces the stream: the
  parts crossing between two frames are taken in the order they crossed). The frame
  interval limits when a crossing is seen: a window that would start before the frame that
  sensed it starts at that frame instead, lasts ``duration`` and is counted **late**;
* the jet's ``fix addforce`` is in place only while a window is pending: the driver removes
  it (``unfix``) at the first frame and whenever every window is over, and gives the deck's
  own line again with the next window. Its variables are evaluated at every step while it
  is there, for every atom in ideal mode: idle, it would cost the run as much as the rest of
  it (BENCHMARKS.md, "The orientation demo");
* when there are new windows, the driver redefines ``s<k>_jet_on`` before the next run
  segment (the same commands on every rank: collective), pruning the windows already over:
  ``region`` mode, an equal-style sum of the windows merged where they overlap,
  ``(time>=t1)*(time<t2)+...``, so that the jet blows whatever is in its block then;
  ``ideal`` mode, an atom-style one whose term for each sensed body holds only its atoms
  (a body's atom ids are consecutive: ``(id>=a)*(id<=b)*(windows)``), so that only the
  sensed part is blown, when it is in the block. The ideal jet's fix acts on the group
  ``s<k>_jet_parts`` of those bodies' atoms, redefined with the variable (the fix removed
  first: LIGGGHTS deletes no group a fix uses): LIGGGHTS evaluates an atom-style force at
  every step for each atom of the fix's group, and over every atom that was a third of the
  orientation demo's run.

LIGGGHTS 3.8 re-creates a redefined variable at the end of its list (Variable::set removes
the old one, shifting those after it), and ``fix addforce`` finds its variables by index at
init: the segment after a redefinition runs with setup (``run N`` without ``pre no``), as the
worker does for any commands. Forces added to a clump's spheres reach the body: fix
multisphere sums its spheres' forces and torques after post_force (calc_force in
final_integrate), across ranks (the forces are sent to the body's ghost spheres first).

Each firing is recorded (FORMAT.md, ``vibrofeed/jet``): the time sensed, the body, the
section, its state (index into vibrofeed.orientation.STATES), its window and whether it was
late.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..feeders.linear import jet_fix_group
from ..orientation import axes_quaternion, turned_states


def crossings(x_sense: float, t0: float, ids0, x0, t1: float, ids1, x1):
    """The parts present at both frames whose coordinate (``x0``, ``x1``: x, or along the path;
    NaN: off it) went from below ``x_sense`` (at ``t0``) to at or beyond it (at ``t1``):
    (indices into the second frame's, crossing times interpolated linearly, whether the first
    frame is the nearer one)."""
    ids0, ids1 = np.asarray(ids0, dtype=np.int64), np.asarray(ids1, dtype=np.int64)
    x0, x1 = np.asarray(x0, dtype=float), np.asarray(x1, dtype=float)
    empty = np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0, dtype=bool)
    if not len(ids0) or not len(ids1):
        return empty
    order = np.argsort(ids0)
    k = np.minimum(np.searchsorted(ids0[order], ids1), len(ids0) - 1)
    known = ids0[order][k] == ids1
    before = np.where(known, x0[order][k], np.nan)
    hit = np.nonzero(known & (before < x_sense) & (x1 >= x_sense))[0]
    if not len(hit):
        return empty
    frac = (x_sense - before[hit]) / (x1[hit] - before[hit])
    return hit, t0 + frac * (t1 - t0), frac < 0.5


def merged(windows) -> list[tuple[float, float]]:
    """Time windows (start, end) as their union: sorted, overlapping or touching ones merged."""
    out: list[list[float]] = []
    for a, b in sorted((float(a), float(b)) for a, b in windows if b > a):
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return [(a, b) for a, b in out]


def window_expression(windows) -> str:
    """LIGGGHTS' formula, 1 within the union of ``windows`` and 0 outside: a sum of
    ``(time>=a)*(time<b)`` over the merged windows (disjoint: the sum is 0 or 1); "0" for none."""
    terms = [f"(time>={a:.12g})*(time<{b:.12g})" for a, b in merged(windows)]  # (to 1e-11 s)
    return "+".join(terms) if terms else "0"


def atom_expression(targets) -> str:
    """An atom-style formula, 1 on the atoms of each target body within its windows: targets
    are (first atom id, last atom id, windows); "0" for none."""
    terms = []
    for lo, hi, windows in targets:
        w = window_expression(windows)
        if w != "0":
            terms.append(f"(id>={int(lo)})*(id<={int(hi)})*({w})")
    return "+".join(terms) if terms else "0"


@dataclass
class Station:
    """One jet (of element ``section``: its deck names ``s<k>_jet_*``): where it senses
    (``x_sense``: along the coordinate ``along`` gives a point of the deck's frame, its x if
    None; an element's vibrofeed.feeders.records.Camera), what it keeps, its delay, duration
    and mode, the floor's ``up`` and the path's ``tangent``, and the part's lowest centre over
    the section (``z_floor``: below it a part is falling)."""

    section: int
    x_sense: float
    keep: object
    delay: float
    duration: float
    mode: str
    up: tuple = (0.0, 0.0, 1.0)
    tangent: tuple = (1.0, 0.0, 0.0)
    z_floor: float = -math.inf
    axes_q: tuple = (1.0, 0.0, 0.0, 0.0)  # the template's axes (vibrofeed.orientation.axes_quaternion)
    windows: list = field(default_factory=list)  # (start, end, body id, first atom, last atom)
    sensed: set = field(default_factory=set)
    along: object = None  # (n, 3) points -> (n,) coordinates [m]; None: x
    fix: str = ""  # the deck's ``fix s<k>_jet ... addforce`` line ("": left as the deck has it)
    placed: bool = True  # whether the fix is in place (the deck places it)
    headway: float = 0.0  # [s] a part sensed sooner after the last one passed is fired at too
    path_section: int = 0  # the path section (1-based) it is on, as recorded (0: ``section``)
    passed: float = -math.inf  # when the last part passed was sensed [s]

    def coordinate(self, points) -> np.ndarray:
        """Where ``points`` (n, 3) of the deck's frame are along what the camera senses [m]."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        return p[:, 0] if self.along is None else np.asarray(self.along(p), dtype=float)

    def sense(self, t0: float, prev: dict | None, t1: float, parts: dict, atoms=None) -> list[tuple]:
        """The firings of the parts that crossed between the frames ``prev`` (at ``t0``) and
        ``parts`` (at ``t1``): (time sensed, id, section, state, start, end, late); their
        windows are kept. ``atoms``: {body id: (first atom id, last atom id)} (ideal mode)."""
        if prev is None or not len(parts["id"]):
            return []
        x1 = np.asarray(parts["position"], dtype=float).reshape(-1, 3)
        hit, when, nearer_first = crossings(self.x_sense, t0, prev["id"], self.coordinate(prev["position"]),
                                            t1, parts["id"], self.coordinate(x1))
        ids = np.asarray(parts["id"], dtype=np.int64)
        q1 = np.asarray(parts["orientation"], dtype=float).reshape(-1, 4)
        firings = []
        order = np.argsort(when, kind="stable")  # in the order they crossed: the headway's
        for i, t, first in zip(hit[order], when[order], nearer_first[order]):
            pid = int(ids[i])
            if pid in self.sensed or x1[i, 2] < self.z_floor:
                continue
            self.sensed.add(pid)
            q = q1[i]
            if first:  # the orientation at the frame nearer the crossing
                j = np.nonzero(prev["id"] == pid)[0]
                q = prev["orientation"][j[0]] if len(j) else q
            states = turned_states(q[None, :], self.axes_q, self.tangent, self.up)
            if self.keep.of(states)[0] and t - self.passed >= self.headway:
                self.passed = float(t)
                continue
            start, late = t + self.delay, False
            if start < t1:
                start, late = t1, True
            end = start + self.duration
            lo, hi = (atoms or {}).get(pid, (-1, -1))
            self.windows.append((start, end, pid, lo, hi))
            firings.append((float(t), pid, self.path_section or self.section, int(states.state[0]),
                            start, end, late))
        return firings

    def commands(self, now: float) -> list[str]:
        """The redefinition of ``s<k>_jet_on`` for the windows not over at ``now`` (pruned), and
        the jet's fix placed again if it was removed; with no window left, the fix removed."""
        self.windows = [w for w in self.windows if w[1] > now]
        if not self.windows and self.fix:
            return self.idle()
        name = f"s{self.section}_jet_on"
        if self.mode == "ideal":
            bodies: dict[int, list] = {}
            for start, end, _, lo, hi in self.windows:
                bodies.setdefault((lo, hi), []).append((start, end))
            out = [f"variable {name} atom {atom_expression((lo, hi, w) for (lo, hi), w in bodies.items())}"]
            if self.fix:  # the fix's group: the atoms of the bodies with a window pending
                group = jet_fix_group(self.section, self.mode)
                ranges = " ".join(f"{lo}:{hi}" for lo, hi in bodies)
                out = [*self.idle(force=True), f"group {group} delete", f"group {group} id {ranges}", *out]
        else:
            out = [f"variable {name} equal {window_expression((s, e) for s, e, *_ in self.windows)}"]
        if self.fix and not self.placed:
            out.append(self.fix)
            self.placed = True
        return out

    def idle(self, force: bool = False) -> list[str]:
        """The jet's fix removed if it is in place and no window is pending (none otherwise;
        ``force``: with windows pending too, for its group to be redefined)."""
        if not self.fix or not self.placed or (self.windows and not force):
            return []
        self.placed = False
        return [f"unfix s{self.section}_jet"]

    def over(self, now: float) -> bool:
        """Whether the fix is in place with every window over at ``now``."""
        return self.placed and all(w[1] <= now for w in self.windows)


FIRING_COLUMNS = ("time", "id", "section", "state", "start", "end", "late")


def firing_table(firings: list[tuple]) -> dict | None:
    """Firings as the result's table (vibrofeed.results.layout.JET_ELEMENTS), None for none."""
    if not firings:
        return None
    cols = list(zip(*firings))
    return {name: np.asarray(col) for name, col in zip(FIRING_COLUMNS, cols)}


def atom_ranges(atoms: dict) -> dict[int, tuple[int, int]]:
    """{body id: (first atom id, last atom id)} of gathered multisphere atoms (``molecule``,
    ``id``); a body's atoms are numbered consecutively (vibrofeed.engine.bodies)."""
    mol = np.asarray(atoms["molecule"], dtype=np.int64)
    aid = np.asarray(atoms["id"], dtype=np.int64)
    keep = mol >= 0
    mol, aid = mol[keep], aid[keep]
    if not len(mol):
        return {}
    order = np.lexsort((aid, mol))
    mol, aid = mol[order], aid[order]
    starts = np.r_[0, np.nonzero(np.diff(mol))[0] + 1]
    ends = np.r_[starts[1:], len(mol)] - 1
    return {int(m): (int(a), int(b)) for m, a, b in zip(mol[starts], aid[starts], aid[ends])}


class Jets:
    """A line's jets (one :class:`Station` per section with one), on every rank: ``step`` at
    each frame returns the commands to give before the next segment (the same on every rank)
    and, on rank 0, the new firings' table."""

    def __init__(self, feeder, template=None):
        self.stations = []
        # the path section each element's jet is on (after a bowl's helix and chute, not its
        # element's number): what the rejects are recorded by
        on = {st.element: st.section for st in feeder.stations if st.kind == "jet"}
        for e in feeder.elements:
            j = getattr(e, "jet", None)
            if j is None:
                continue
            cam = e.camera(feeder.part, feeder.origin_of(e))
            self.stations.append(Station(
                section=e.number, x_sense=cam.at, keep=j.keep, delay=j.delay, duration=j.duration,
                mode=j.mode, up=cam.up, tangent=cam.tangent, z_floor=cam.z_floor, along=cam.along,
                fix=e.jet_fix(), headway=j.headway, path_section=on[e.number]))
        self.ideal = any(s.mode == "ideal" for s in self.stations)
        self.use_template(template)
        self._prev = None  # (time, {"id", "position", "orientation"}) of the last frame, rank 0

    def use_template(self, template) -> None:
        """Classify with the body frame of the clump ``template`` (n, 4) (None: the recorded
        quaternion's own frame, a template laid out along the body axes)."""
        q = (1.0, 0.0, 0.0, 0.0) if template is None else tuple(axes_quaternion(template))
        for s in self.stations:
            s.axes_q = q

    def step(self, comm, t: float, parts: dict | None, atoms: dict | None = None):
        """(commands for every rank, firing table or None on rank 0)."""
        commands, table = [], None
        if parts is not None:  # rank 0
            firings = []
            prev = self._prev
            for s in self.stations:
                new = s.sense(prev[0], prev[1], t, parts, atoms) if prev is not None else []
                firings += new
                if new or s.over(t):  # (new windows; or every window over: the fix removed)
                    commands += s.commands(t)
            ids = np.asarray(parts["id"], dtype=np.int64)
            x = np.asarray(parts["position"], dtype=float).reshape(-1, 3)
            q = np.asarray(parts["orientation"], dtype=float).reshape(-1, 4)
            self._prev = (t, {"id": ids, "position": x, "orientation": q})
            table = firing_table(firings)
        if comm is not None and comm.size > 1:
            commands = comm.bcast(commands, root=0)
        return commands, table
