"""Synthetic bulk-feeder results whose answers are known by construction.

A straight track from x = 0 (the inlet) to ``outlet_x`` vibrates along x as
``amp sin(2 pi freq t)``; every part rides it (its x in the simulation frame
is its track coordinate plus the track's displacement) and moves along the
track at its own constant speed. Part k is given the time it crosses the
outlet; it enters at the inlet (x = 0) when its schedule puts it there after
the first frame (else it is on the track from the start), leaves over the edge
at its exit time (one outlet event, exact), is seen falling beyond the edge at
the first frame at or after that (flying on at twice its speed), and is gone
from the next one. Parts whose exit
time is after the last frame stay on the track.

Real runs are less tidy, and :func:`feeder` can write each of their untidy features
(all off by default): the frames of a run whose ``t_end`` is not a whole number of
``output_dt`` (:func:`run_frames`: a shorter last interval), or that alias the vibration
(any ``frame_times``, e.g. every period); parts put on the track downstream of the inlet
between frames (``insert_x``) and parts removed between frames without being seen falling
(``seen_falling=False``); multisphere bodies written as the engine writes them
(``clumps=True`` with a ``body_template``, e.g. :func:`chip_template`).
"""

from __future__ import annotations

import numpy as np

from helpers import write_bulk_result

OUTLET_X = 0.02
CATCH_Z = -3e-4
RADIUS = 1.5e-4
G = 9.81


def feeder(path, frame_times, exit_times, speed=0.02, amp=0.0, freq=100.0, radius=RADIUS,
           mass=1e-7, lanes=None, orientations=None, body_template=None, variables=None,
           outlet_x=OUTLET_X, seed=0, tipped=None, track=None, insert_x=0.0, seen_falling=True,
           clumps=False, turn=None):
    """Write the result file (module docstring); returns ``path``.

    ``speed``, ``mass``, ``radius``: scalars or one value per part; ``lanes``:
    each part's y [m] (default 0); ``orientations``: (parts, 4) quaternions
    (written only when given); ``tipped``: (parts, 4) orientations once past the
    edge, in the event and the falling frame (default: ``orientations``);
    ``track``: the track mesh (vertices, triangles), if any. The parts are
    shuffled at every frame.

    Real runs' features (module docstring), off by default: ``insert_x`` (scalar or per
    part, m): where along the track each part is put on it (0: the inlet), at the time
    its schedule puts it there, so between frames; ``seen_falling=False``: a part is
    deleted between its exit and the next frame (its outlet event stands, no frame sees
    it past the edge); ``clumps=True`` (with ``body_template``): each row is a body as the
    engine writes it (FORMAT.md, "Parts are bodies"): ``radius`` the sphere about the
    centre that encloses the clump, its centre where its lowest sphere rests on the track
    (z = 0), force NaN (not recorded). ``turn`` = (x, quaternions (parts, 4)): on the track
    at or past track x [m], a part lies in its second orientation (a station that turns
    parts), and so it leaves (unless ``tipped``).
    """
    rng = np.random.default_rng(seed)
    frame_times = np.asarray(frame_times, dtype=float)
    exit_times = np.asarray(exit_times, dtype=float)
    n = len(exit_times)
    speed, mass, radius = (np.broadcast_to(np.asarray(v, dtype=float), (n,)) for v in (speed, mass, radius))
    lanes = np.zeros(n) if lanes is None else np.asarray(lanes, dtype=float)
    insert_x = np.broadcast_to(np.asarray(insert_x, dtype=float), (n,))
    height = radius
    if clumps:
        if body_template is None:
            raise ValueError("clumps=True needs a body_template")
        q = np.tile([1.0, 0, 0, 0], (n, 1)) if orientations is None else np.asarray(orientations, float)
        radius = np.full(n, enclosing_radius(body_template))
        height = lowest_depth(body_template, q)
    w = 2 * np.pi * freq
    t_last = frame_times[-1]
    # The frame that reports each exit: the first at or after it.
    report = np.searchsorted(frame_times, exit_times, side="left")
    frames, counts = [], []
    for j, t in enumerate(frame_times):
        track_x = outlet_x - speed * (exit_times - t)
        on_track = (track_x >= insert_x) & (exit_times > t)
        inserted = (track_x >= insert_x) | (exit_times <= t)
        falling = (report == j) & seen_falling
        present = np.nonzero(on_track | falling)[0]
        present = rng.permutation(present)
        dt_fall = np.where(falling[present], t - exit_times[present], 0.0)
        # Falling parts fly off twice as fast as they were conveyed (a speed no
        # conveying-velocity measurement may pick up), without the track's motion.
        x = np.where(falling[present], outlet_x + 2 * speed[present] * dt_fall,
                     track_x[present] + amp * np.sin(w * t))
        z = np.where(falling[present], CATCH_Z - G / 2 * dt_fall ** 2 - 1e-6, height[present])
        vx = np.where(falling[present], 2 * speed[present], speed[present] + amp * w * np.cos(w * t))
        vz = np.where(falling[present], -G * dt_fall, 0.0)
        m = len(present)
        parts = {"id": present + 1, "species": np.ones(m, int), "radius": radius[present],
                 "mass": mass[present], "position": np.column_stack([x, lanes[present], z]),
                 "velocity": np.column_stack([vx, np.zeros(m), vz]),
                 "angular_velocity": np.zeros((m, 3)),
                 "force": np.full((m, 3), np.nan) if clumps else np.zeros((m, 3))}
        if orientations is not None:
            q = np.asarray(orientations, dtype=float)[present]
            if turn is not None:
                past = (track_x[present] >= turn[0]) | falling[present]
                q = np.where(past[:, None], np.asarray(turn[1], dtype=float)[present], q)
            if tipped is not None:
                q = np.where(falling[present][:, None], np.asarray(tipped, dtype=float)[present], q)
            parts["orientation"] = q
        frames.append((j, float(t), parts))
        exited = int((exit_times <= t).sum())
        counts.append({"inserted": int(inserted.sum()), "on_track": int(on_track.sum()),
                       "exited": exited, "lost": 0})
    out = np.nonzero(exit_times <= t_last)[0]
    events = {"time": exit_times[out], "id": out + 1,
              "position": np.column_stack([np.full(len(out), outlet_x), lanes[out],
                                           np.full(len(out), CATCH_Z)]),
              "velocity": np.column_stack([speed[out], np.zeros(len(out)), np.full(len(out), -0.05)]),
              "orientation": (np.tile([1.0, 0, 0, 0], (len(out), 1)) if orientations is None
                              else np.asarray(tipped if tipped is not None else orientations if turn is None
                                              else turn[1], dtype=float)[out])}
    surface = [([amp * np.sin(w * t), 0, 0], [amp * w * np.cos(w * t), 0, 0]) for t in frame_times]
    base = {"freq": (repr(float(freq)), "Hz", "vibration frequency", "100"),
            "track_length": (repr(outlet_x), "m", "track length", "0.02"),
            "part_size": (repr(2 * float(radius.mean())), "m", "part diameter", "3e-4")}
    base.update(variables or {})
    return write_bulk_result(path, frames, events=events, counts=counts, variables=base,
                             body_template=body_template, surface=surface, track=track,
                             outlet={"outlet_x": outlet_x, "catch_z": CATCH_Z, "method": "synthetic"})


def run_frames(t_end, output_dt, t0=0.0):
    """The frame times of a run as the engine writes them: the state after setup at ``t0``,
    then one frame every ``output_dt`` and one at ``t_end`` (a shorter last interval when
    ``t_end - t0`` is not a whole number of ``output_dt``; the last segment runs the steps
    that are left). Frame k is k whole intervals after ``t0``, as steps k * output_every."""
    whole = int(np.floor((t_end - t0) / output_dt * (1 + 1e-12)))
    times = t0 + output_dt * np.arange(whole + 1)
    if t_end - times[-1] > 1e-9 * output_dt:
        times = np.r_[times, t_end]
    return times


def chip_template(per_side=2, r_s=7.5e-5, pitch=1e-4):
    """A square chip of ``per_side`` x ``per_side`` spheres of radius ``r_s`` [m], ``pitch``
    apart in the body's xy plane (z its thin axis): (n, 4) x, y, z, r as
    ``parameters/body_template`` holds it (listed row by row, as LIGGGHTS numbers them)."""
    c = (np.arange(per_side) - (per_side - 1) / 2) * pitch
    return np.array([[x, y, 0.0, r_s] for y in c for x in c])


def enclosing_radius(template):
    """The radius of the sphere about a clump's centre (its spheres' mean) that encloses it [m]."""
    t = np.asarray(template, dtype=float)
    return float((np.linalg.norm(t[:, :3] - t[:, :3].mean(axis=0), axis=1) + t[:, 3]).max())


def lowest_depth(template, quaternions):
    """(N,) how far below its centre each body's lowest point lies [m], turned by its
    quaternion (w, x, y, z): the centre's height when it rests on the plane z = 0."""
    from vibrofeed.rotations import quaternion_matrices

    t = np.asarray(template, dtype=float)
    offsets = t[:, :3] - t[:, :3].mean(axis=0)
    z = np.einsum("nj,kj->nk", quaternion_matrices(np.asarray(quaternions, float))[:, 2, :], offsets)
    return (t[:, 3][None, :] - z).max(axis=1)


def poisson_times(rate, t0, t1, rng):
    """Arrival times of a Poisson process of ``rate`` on (t0, t1]."""
    n = rng.poisson(rate * (t1 - t0) * 1.5 + 20)
    times = t0 + np.cumsum(rng.exponential(1 / rate, n))
    return times[times <= t1]


# -- beds whose parts follow given paths: feeder lines, drifting beds ----------------------
JOINT = 0.006       # a line's section 1: 6 mm
S2_LENGTH = 0.005   # its section 2: 5 mm, outlet edge at 11 mm


def bed(path, frame_times, x_at, enter, leave, rejected=None, reject_seen=True, amp=0.0, freq=100.0,
        outlet_x=OUTLET_X, lanes=None, radius=RADIUS, variables=None, line=False, joint=None):
    """Write a result whose parts follow given paths along the track; returns ``path``.

    ``x_at(t)``: (parts,) track x of every part at time t (a closed form); part k is on
    the track from ``enter[k]`` (-inf: pre-filled) to ``leave[k]`` (inf: stays), when it
    exits over the edge (an outlet event) or, where ``rejected[k]``, falls off a side
    there (a reject event at x_at(leave), section 1 before ``joint``, else 2). At the first
    frame at or after leaving an exited part is seen falling beyond the edge; a rejected
    one falling where it fell, as far along x as its path goes on (its x-speed kept),
    unless ``reject_seen[k]`` is False: then it is gone (removed between frames). Gone at
    the next frame either way. The track vibrates along x as ``amp sin(2 pi freq t)``,
    every part riding it. ``line``: a feeder line's result (reject table, ``rejected``
    count); ``variables`` add to the deck's (freq, track_length, part_size). Parts are
    shuffled at every frame.
    """
    import hashlib

    from vibrofeed.results import layout as L
    from vibrofeed.results.writer import Recording, ResultWriter

    rng = np.random.default_rng(0)
    frame_times = np.asarray(frame_times, dtype=float)
    enter, leave = np.asarray(enter, dtype=float), np.asarray(leave, dtype=float)
    n = len(enter)
    rejected = np.zeros(n, bool) if rejected is None else np.asarray(rejected, bool)
    seen = np.broadcast_to(np.asarray(reject_seen, bool), (n,))
    lanes = np.zeros(n) if lanes is None else np.asarray(lanes, dtype=float)
    joint = outlet_x if joint is None else joint
    w = 2 * np.pi * freq
    report = np.searchsorted(frame_times, leave, side="left")
    t_last = frame_times[-1]
    base = {"freq": (repr(float(freq)), "Hz", "vibration frequency", "100"),
            "track_length": (repr(joint if line else outlet_x), "m", "track length", "0.02"),
            "part_size": (repr(2 * radius), "m", "part diameter", "3e-4")}
    if line:
        base.update({"sections": ("2", "-", "sections", "1"),
                     "s2_length": (repr(outlet_x - joint), "m", "section 2 length", "0.01")})
    base.update(variables or {})
    outlet = {"outlet_x": outlet_x, "catch_z": CATCH_Z, "method": "synthetic"}
    w_ = ResultWriter(path, deck_name="synthetic_bulk", deck_path="synthetic_bulk.liggghts",
                      deck_text="# synthetic bulk feeder\n", variables=base, derived={"dt_used": 1e-6},
                      engine_version="LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)", seed=1,
                      run_id=hashlib.sha256(str(path).encode()).hexdigest(), outlet=outlet,
                      recording=Recording(rejects=line))
    leave_x = np.array([x_at(t)[k] if np.isfinite(t) else np.nan for k, t in enumerate(leave)])
    for j, t in enumerate(frame_times):
        x = x_at(t)
        on = (enter <= t) & (leave > t)
        falling = (report == j) & (~rejected | seen)
        present = rng.permutation(np.nonzero(on | falling)[0])
        fall = falling[present]
        dt_fall = np.where(fall, t - leave[present], 0.0)
        px = np.where(fall & ~rejected[present], outlet_x + 1e-3 + dt_fall, x[present] + amp * np.sin(w * t))
        pz = np.where(fall, CATCH_Z - G / 2 * dt_fall ** 2 - 1e-6, radius)
        m = len(present)
        parts = {"id": present + 1, "species": np.ones(m, int), "radius": np.full(m, radius),
                 "mass": np.full(m, 1e-7), "position": np.column_stack([px, lanes[present], pz]),
                 "velocity": np.zeros((m, 3)), "angular_velocity": np.zeros((m, 3)),
                 "force": np.zeros((m, 3))}
        gone = leave <= t
        counts = {"inserted": int((enter <= t).sum()), "exited": int((gone & ~rejected).sum()),
                  "lost": 0}
        counts["on_track"] = counts["inserted"] - counts["exited"] - int((gone & rejected).sum())
        if line:
            counts["rejected"] = int((gone & rejected).sum())
        if j == len(frame_times) - 1:
            for table, which in ((L.OUTLET, ~rejected), (L.REJECTS, rejected)):
                k = np.nonzero(which & (leave <= t_last))[0]
                if table == L.REJECTS and not line:
                    continue
                xs = outlet_x if table == L.OUTLET else leave_x[k]
                ev = {"time": leave[k], "id": k + 1,
                      "position": np.column_stack([np.broadcast_to(xs, (len(k),)), lanes[k],
                                                   np.full(len(k), CATCH_Z)]),
                      "velocity": np.zeros((len(k), 3)), "orientation": np.tile([1.0, 0, 0, 0], (len(k), 1))}
                if table == L.REJECTS:
                    ev["section"] = np.where(leave_x[k] < joint, 1, 2)
                w_.write_events(ev, table)
        w_.write_frame(j, float(t), parts, [amp * np.sin(w * t), 0, 0], [amp * w * np.cos(w * t), 0, 0],
                       counts=counts)
    w_.finish("complete")
    return path


def line_feeder(path, frame_times, joint_times, v1=0.02, v2=0.04, reject_at=None, **kw):
    """A feeder line (sections 1 and 2: :data:`JOINT`, :data:`S2_LENGTH`) whose part k
    crosses the joint at ``joint_times[k]``, conveyed at ``v1`` on section 1 and ``v2`` on
    section 2 (m/s); it entered at x = 0 at joint_time - JOINT / v1 and leaves over the
    outlet edge JOINT + S2_LENGTH at joint_time + S2_LENGTH / v2, or falls off at
    ``reject_at[k]`` (x [m], NaN: not rejected). Other keywords: :func:`bed`."""
    tj = np.asarray(joint_times, dtype=float)
    reject_at = np.full(len(tj), np.nan) if reject_at is None else np.asarray(reject_at, dtype=float)
    rejected = np.isfinite(reject_at)

    def x_at(t):
        return np.where(t < tj, JOINT - v1 * (tj - t), JOINT + v2 * (t - tj))

    # the time each part reaches its reject point (before or after the joint)
    reach = np.where(reject_at < JOINT, tj - (JOINT - reject_at) / v1, tj + (reject_at - JOINT) / v2)
    leave = np.where(rejected, reach, tj + S2_LENGTH / v2)
    enter = tj - JOINT / v1
    return bed(path, frame_times, x_at, enter, leave, rejected=rejected, outlet_x=JOINT + S2_LENGTH,
               line=True, joint=JOINT, **kw)
