"""Helpers shared by the tests (import as ``from helpers import ...``)."""

from __future__ import annotations

import hashlib
import math
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
DECKS = REPO / "decks"


def run_in_flight(record: list, wait: float = 10.0) -> threading.Thread:
    """A run going on in another (daemon) thread, registered with vibrofeed.interrupt once this
    returns: stopped, it appends why to ``record``, takes a moment to record its end, appends
    "recorded its end" and only then unregisters, as runner.run_deck does."""
    from vibrofeed import interrupt

    registered = threading.Event()

    def in_flight():
        stopped = threading.Event()
        key = interrupt.register(lambda why: (record.append(why), stopped.set()))
        registered.set()
        stopped.wait(wait)
        time.sleep(0.05)  # recording the end takes a while: a stopper that does not wait misses it
        record.append("recorded its end")
        interrupt.unregister(key)

    thread = threading.Thread(target=in_flight, daemon=True)  # a failure must not hold the suite
    thread.start()
    assert registered.wait(wait), "the run did not register"
    return thread


class FakeClock:
    """A stand-in for the ``time`` module's ``monotonic``, moved by hand (``now``): no
    sleeping, no race with a thread that reads the clock."""

    def __init__(self):
        self.now = 0.0

    def monotonic(self):
        return self.now


def vibrofeed(*args, cwd=None, check=False, timeout=600):
    """Run the CLI in a child process (as a user would); returns CompletedProcess."""
    env = dict(os.environ)
    env.pop("VIBROFEED_DEBUG", None)
    proc = subprocess.run([sys.executable, "-m", "vibrofeed.cli", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, env=env, timeout=timeout)
    if check and proc.returncode != 0:
        raise AssertionError(f"vibrofeed {' '.join(map(str, args))} failed:\n{proc.stderr}")
    return proc


def frames_now(path: Path) -> int:
    """Frames in a result file another process is writing (no HDF5 file lock)."""
    import h5py

    try:
        with h5py.File(path, "r", locking=False) as f:
            return len(f["particles/parts/position/step"])
    except (OSError, KeyError):
        return 0


def stamp(path: Path) -> tuple:
    """Which file this is: a run made again would replace it by another (inode, mtime, start)."""
    import h5py

    st = path.stat()
    with h5py.File(path, "r") as f:
        return st.st_ino, st.st_mtime_ns, str(f["parameters/run"].attrs["started"])


def liggghts_text(deck_text, folder, variables, dump, extra=(), timeout=600):
    """Run a deck's text by hand, `liggghts -in` in ``folder`` with ``-var deck_dir`` and
    ``variables`` (name -> value); returns (stdout, the text of the dump file ``dump`` the deck
    writes in folder, "" if none)."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "deck.liggghts"
    path.write_text(deck_text)
    args = ["liggghts", "-in", str(path), "-log", "none", "-nocite", "-var", "deck_dir", str(DECKS),
            *map(str, extra)]
    for name, value in variables.items():
        args += ["-var", name, str(value)]
    proc = subprocess.run(args, cwd=folder, capture_output=True, text=True, timeout=timeout)
    out = folder / dump
    return proc.stdout, out.read_text() if out.exists() else ""


def lying_flat(shape, size, thickness, density, hamaker, roughness, viscosity):
    """The models' view of a bulk chip (shape 1 or "chip": a square face of side ``size``) or
    disc (2 or "disc": a round face of diameter ``size``) of ``thickness`` lying on its face:
    (mass [kg], its Adhesion, its Film at the roughness' clearance)."""
    from vibrofeed.models import adhesion as ad
    from vibrofeed.models import squeeze_film as sf

    h_c = sf.clearance(roughness)
    if shape in (1, "chip"):
        return (size ** 2 * thickness * density, ad.Adhesion(hamaker, roughness, face_side=size),
                sf.Film(viscosity, 0.0, h_c, side=size))
    if shape in (2, "disc"):
        return (math.pi * (size / 2) ** 2 * thickness * density,
                ad.Adhesion(hamaker, roughness, face_radius=size / 2), sf.Film(viscosity, size / 2, h_c))
    raise ValueError(f"not a flat part: shape {shape!r}")


def write_result(path, frames, surface=None, variables=None, status="complete"):
    """A result file from synthetic frames: a list of (step, time, parts dict)."""
    from vibrofeed.results.writer import ResultWriter

    variables = variables or {"freq": ("50", "Hz", "vibration frequency", "50")}
    w = ResultWriter(path, deck_name="synthetic", deck_path="synthetic.liggghts",
                     deck_text="# synthetic\n", variables=variables, derived={"dt_used": 1e-6},
                     engine_version="LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)",
                     seed=1, run_id=hashlib.sha256(str(path).encode()).hexdigest())
    for k, (step, t, parts) in enumerate(frames):
        sp = np.zeros(3) if surface is None else surface[k][0]
        sv = np.zeros(3) if surface is None else surface[k][1]
        w.write_frame(step, t, parts, sp, sv)
    if status is None:
        w.close()
    else:
        w.finish(status)
    return path


def parts(ids, positions, radius=5e-4, velocity=None, force=None, mass=1e-6):
    ids = np.asarray(ids)
    n = len(ids)
    positions = np.asarray(positions, dtype=float).reshape(n, 3)
    velocity = np.zeros((n, 3)) if velocity is None else np.asarray(velocity, float).reshape(n, 3)
    force = np.zeros((n, 3)) if force is None else np.asarray(force, float).reshape(n, 3)
    return {"id": ids, "species": np.ones(n, int), "radius": np.full(n, radius),
            "mass": np.full(n, mass), "position": positions, "velocity": velocity,
            "angular_velocity": np.zeros((n, 3)), "force": force}



def write_bulk_result(path, frames, events=None, counts=None, track=None, variables=None,
                      body_template=None, outlet=None, surface=None, status="complete"):
    """A bulk-feeder result file from synthetic data (FORMAT.md, "Bulk feeders").

    ``frames``: a list of (step, time, parts dict) as for :func:`write_result`;
    a parts dict may hold ``orientation`` (N, 4). ``events``: one table for
    ``ResultWriter.write_events`` (``time``, ``id``, ``position``,
    ``velocity``, ``orientation``), written with the last frame. ``counts``:
    one ``{"inserted", "on_track", "exited", "lost"}`` dict per frame, or None.
    ``track``: (vertices, triangles); ``outlet``: the table's attributes
    (default: outlet_x 0.02 m, catch_z -3e-4 m, method "synthetic"), the table
    exists whenever ``events`` or ``outlet`` is given.
    """
    from vibrofeed.results.writer import ResultWriter

    variables = variables or {"freq": ("100", "Hz", "vibration frequency", "100")}
    if outlet is None and events is not None:
        outlet = {"outlet_x": 0.02, "catch_z": -3e-4, "method": "synthetic"}
    w = ResultWriter(path, deck_name="synthetic_bulk", deck_path="synthetic_bulk.liggghts",
                     deck_text="# synthetic bulk feeder\n", variables=variables,
                     derived={"dt_used": 1e-6},
                     engine_version="LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)",
                     seed=1, run_id=hashlib.sha256(str(path).encode()).hexdigest(),
                     track=track, body_template=body_template, outlet=outlet)
    for k, (step, t, parts) in enumerate(frames):
        sp = np.zeros(3) if surface is None else surface[k][0]
        sv = np.zeros(3) if surface is None else surface[k][1]
        if events is not None and k == len(frames) - 1:
            w.write_events(events)
        w.write_frame(step, t, parts, sp, sv, counts=None if counts is None else counts[k])
    if status is None:
        w.close()
    else:
        w.finish(status)
    return path


def write_line_frames(path, frames, inserted, written, returns=False):
    """A two-section line result (outlet at 18 mm, joint at 10 mm, catch plane at -0.5 mm;
    section 2 standing still: its recorded motion is zeros) from ``frames`` of (ids,
    positions), each through the real LineOutlet with ``inserted[k]`` parts inserted; the
    frame's counts are written with ``written[k]`` over them (the test's own counts)."""
    from vibrofeed.engine.outlet import LineOutlet, gravity_vector
    from vibrofeed.results.layout import REJECTS
    from vibrofeed.results.writer import Recording, ResultWriter

    w = ResultWriter(path, deck_name="synthetic_line", deck_path="synthetic_line.liggghts",
                     deck_text="# synthetic line\n",
                     variables={"sections": ("2", "-", "sections", "1"), "s2_freq": ("100", "Hz", "", "100"),
                                **{k: ("0", "", "", "0") for k in ("s2_amp_t", "s2_amp_n", "s2_phase")}},
                     derived={"dt_used": 1e-6}, engine_version="LIGGGHTS (synthetic)", seed=1,
                     run_id=hashlib.sha256(str(path).encode()).hexdigest(),
                     outlet={"outlet_x": 0.018, "catch_z": -5e-4, "method": "synthetic"},
                     recording=Recording(sections=2, rejects=True, returns=returns))
    o = LineOutlet(0.018, -5e-4, gravity_vector(9.81, 0.0), (0.0, 0.01))
    for k, (ids, x) in enumerate(frames):
        p = parts(ids, x, radius=1.5e-4)
        events, rejects, counts = o.step(0.01 * k, p, inserted[k])
        if rejects is not None:
            w.write_events(rejects, REJECTS)
        w.write_frame(k, 0.01 * k, p, np.zeros(3), np.zeros(3), counts={**counts, **written[k]},
                      section_surfaces=[(np.zeros(3), np.zeros(3))])
    w.finish("complete")
    return path


def write_conveyor(path, times, lifetimes, speeds, amp=0.0, freq=50.0, seed=0, radius=5e-4):
    """A many-part result whose answers are known by construction.

    Part ``k + 1`` exists from frame ``lifetimes[k][0]`` to frame
    ``lifetimes[k][1]`` (inclusive) and moves along x as ``k * 1e-3 +
    speeds[k] * t + amp * sin(2 pi freq t)``; y = k * 1e-3, z = radius. The
    parts are listed in a shuffled order at each frame, as LIGGGHTS hands them
    over, and freed slots are reused by later parts.
    """
    rng = np.random.default_rng(seed)
    lifetimes, speeds = np.asarray(lifetimes), np.asarray(speeds, dtype=float)
    w = 2 * np.pi * freq
    frames = []
    for j, t in enumerate(times):
        alive = np.nonzero((lifetimes[:, 0] <= j) & (j <= lifetimes[:, 1]))[0]
        alive = rng.permutation(alive)
        pos = np.column_stack([alive * 1e-3 + speeds[alive] * t + amp * np.sin(w * t),
                               alive * 1e-3, np.full(len(alive), radius)])
        vel = np.column_stack([speeds[alive] + amp * w * np.cos(w * t),
                               np.zeros(len(alive)), np.zeros(len(alive))])
        frames.append((j, float(t), parts(alive + 1, pos, radius=radius, velocity=vel)))
    variables = {"freq": (repr(float(freq)), "Hz", "vibration frequency", "50")}
    return write_result(path, frames, variables=variables)

# -- measured-trial files (vertical transport) ---------------------------------------
DT = 1 / 960.0
PLACEHOLDER = "\ufffd"  # what the published files hold where a value is missing


def platform_truth(t, nu=0):
    """Smooth, well-resolved platform motion [m] (25 and 70 Hz), derivative nu."""
    out = 0.0
    for amp, f, ph in ((0.3e-3, 25.0, 0.0), (0.1e-3, 70.0, 1.0)):
        w = 2 * np.pi * f
        out = out + amp * w ** nu * np.sin(w * t + ph + nu * np.pi / 2)
    return out


def write_trial(path, n=300, sigma=5e-6, seed=0, placeholder=PLACEHOLDER, mutate=None):
    """A file laid out like the published ones: mm units, CRLF, placeholders at the ends."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT
    cols = {"t": t}
    for m, shift in (("p", 0.0), ("o", 2e-3), ("s", -3e-3)):
        z = platform_truth(t) + shift + sigma * rng.standard_normal(n)
        x = 1.5e-3 + sigma * rng.standard_normal(n)
        cols["x" + m], cols["z" + m] = x * 1e3, z * 1e3
        for q in ("x", "z"):
            v = np.gradient(cols[q + m], DT)
            a = np.gradient(v, DT)
            v[[0, -1]] = np.nan
            a[[0, 1, -2, -1]] = np.nan
            cols["v" + q + m], cols["a" + q + m] = v, a
    if mutate:
        mutate(cols)
    header = list(cols)
    lines = [",".join(header)]
    for k in range(len(cols["t"])):
        row = []
        for h in header:
            value = cols[h][k]
            row.append(placeholder if (isinstance(value, float) and math.isnan(value))
                       else f"{value:.8f}")
        lines.append(",".join(row))
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode("utf-8"))
    return path


# A detour from CAD, in millimetres: its floor's centre line with legs of 4, 5, 4, 5 and 4 mm, 22
# mm of path for 20 along x, ending where it started across, heading +x.
# A description's parts for a run by construction of one chip component: the 1.0 x 0.5 x 0.35 mm
# box of 36 spheres, at the stiffness floor, restitution 0.3 (tests/engine/test_mesh_jet_run.py,
# test_bowl_jet_run.py).
BOX_PARTS = """[parts]
shape = "box"
size = 1e-3
width = 5e-4
thickness = 3.5e-4
clump_spacing = 1.0
youngs = 2e7
restitution = 0.3
"""
DETOUR = np.array([(0, 0, 0), (4, 0, 0), (8, 3, 0), (12, 3, 0), (16, 0, 0), (20, 0, 0)], dtype=float)


def detour_stl(folder) -> Path:
    """The :data:`DETOUR` channel, 1.2 mm wide with walls 1 mm high, as folder/detour.stl."""
    from vibrofeed.mesh import write_stl

    path = Path(folder) / "detour.stl"
    write_stl(*channel(DETOUR, 1.2, 1.0), path, "detour")
    return path


def channel(points, width, wall, holes=(), flipped=()):
    """An open channel along a polyline in plan (points (N, 3), any unit): its floor, two strips
    either side of the path, and two walls ``wall`` high, mitred at the corners, open at both
    ends and along the walls' tops, every face wound towards the inside (its floor's normals up):
    a track as a CAD export gives it. ``holes``: (segment, side) floor strips left out (side
    +1 left of the path, -1 right); ``flipped``: indices of triangles wound the other way.
    Returns (vertices, triangles)."""
    from vibrofeed.mesh import MeshBuilder

    p = np.asarray(points, dtype=float)
    d = np.diff(p[:, :2], axis=0)
    d /= np.linalg.norm(d, axis=1)[:, None]
    n = np.column_stack([-d[:, 1], d[:, 0]])  # left of the path
    m = np.vstack([n[:1], n[:-1] + n[1:], n[-1:]])
    m /= np.linalg.norm(m, axis=1)[:, None]
    m /= np.concatenate([[1.0], np.einsum("ij,ij->i", m[1:-1], n[1:]), [1.0]])[:, None]  # (mitre)
    left = np.column_stack([p[:, :2] + width / 2 * m, p[:, 2]])
    right = np.column_stack([p[:, :2] - width / 2 * m, p[:, 2]])
    up = np.array([0.0, 0.0, wall])
    b = MeshBuilder()
    for i in range(len(p) - 1):
        if (i, -1) not in holes:
            b.quad(right[i], right[i + 1], p[i + 1], p[i])
        if (i, 1) not in holes:
            b.quad(p[i], p[i + 1], left[i + 1], left[i])
        b.quad(left[i], left[i + 1], left[i + 1] + up, left[i] + up)
        b.quad(right[i + 1], right[i], right[i] + up, right[i + 1] + up)
    v, t = b.mesh()
    t = t.copy()
    for k in flipped:
        t[k] = t[k][::-1]
    return v, t


def deck_values(params) -> dict[str, str]:
    """A test's deck parameters as the texts a deck takes: floats by repr (every digit kept)."""
    return {k: repr(v) if isinstance(v, float) else str(v) for k, v in params.items()}


def one_body_balanced(mb) -> None:
    """The mass balance of a run of :func:`place_one_body`: the one part inserted from the
    first step on (frame 0 is before it), none lost, and exact at every frame."""
    assert (mb["inserted"][1:] == 1).all() and (mb["lost"] == 0).all()
    assert (mb["inserted"] == mb["on_track"] + mb["exited"] + mb["rejected"]).all()


def place_one_body(at, quaternion, seed: int, half: float = 1e-7) -> list[str]:
    """LIGGGHTS commands (after a bulk feeder's deck) that remove its pre-fill and insert one part
    of the deck's own template with its centre of mass at ``at`` (3,) [m], turned by
    ``quaternion`` (w, x, y, z), in a block ``half`` either way around it; the mass balance
    counts it as the one part inserted."""
    lo, hi = (np.asarray(at) - half).tolist(), (np.asarray(at) + half).tolist()
    return [
        "delete_atoms region fill mol yes",
        f"region vf_here block {lo[0]!r} {hi[0]!r} {lo[1]!r} {hi[1]!r} {lo[2]!r} {hi[2]!r} units box "
        "volume_limit 1e-30",
        f"fix vf_put all insert/pack seed {seed} distributiontemplate pdd insert_every once "
        "overlapcheck yes all_in no vel constant 0 0 0 "
        f"orientation constant {' '.join(repr(float(v)) for v in quaternion)} region vf_here "
        "particles_in_region 1 ntry_mc 10000",
        "variable n_inserted delete", "variable n_inserted equal f_vf_put[1]"]
