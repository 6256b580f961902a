"""Every analysis of postproc/ on results as untidy as real runs, whose answers are known.

Real results differ from evenly spaced synthetic frames in four ways (tests/bulk_synthetic.py
writes each on request):

* a shorter last frame interval: ``t_end`` not a whole number of ``output_dt`` (the engine's
  last segment runs the steps left), or a run stopped between two outputs;
* parts put on the track and removed between frames: ids appear and disappear, freed slots
  are taken by other parts (FORMAT.md, "Particles that come and go");
* frames that alias the vibration: ``output_dt`` a period (the bulk deck's default: 10 ms at
  100 Hz), a few periods, or close to one;
* multisphere bodies (chips): one row per body, ``radius`` the sphere enclosing the clump,
  force not recorded (NaN), ``parameters/body_template`` its spheres (FORMAT.md, "Parts are
  bodies").

Each test states the answer by hand or from a closed form and compares at the quantity's scale.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from bulk_synthetic import (
    JOINT,
    OUTLET_X,
    RADIUS,
    S2_LENGTH,
    bed,
    chip_template,
    enclosing_radius,
    feeder,
    line_feeder,
    lowest_depth,
    run_frames,
)
from helpers import parts, write_bulk_result, write_conveyor, write_result
from vibrofeed.errors import InputError
from vibrofeed.postproc import FeedRate, Flights, Singulation, Transport, cluster_labels, cluster_sizes
from vibrofeed.postproc.clusters import clump_labels
from vibrofeed.postproc.line import bed_pass
from vibrofeed.results.reader import Result

FREQ = 100.0
T = 1 / FREQ          # the period: 10 ms
AMP = 5e-5            # the track's swing along x [m], as a real drive's amp_t
V = 0.02              # conveying speed [m/s]
G = 9.81
W = 2 * np.pi * FREQ
R_S, PITCH = 7.5e-5, 1e-4   # a chip of 2 x 2 spheres: 75 um spheres 100 um apart (350 x 350 x 150 um)
CHIP4 = chip_template(2, R_S, PITCH)


def swing(t):
    """The track's displacement along x [m] at t."""
    return AMP * np.sin(W * np.asarray(t, dtype=float))


# =========================================================================== the writer
def test_the_synthetic_run_frames_end_with_the_shorter_interval_the_engine_writes():
    # t_end 0.994 s, output_dt 10 ms: 99 whole intervals, then 4 ms (0.4 of one)
    frames = run_frames(0.994, T)
    assert len(frames) == 101
    assert np.diff(frames)[:-1] == pytest.approx(np.full(99, T), rel=1e-9)
    assert frames[-1] - frames[-2] == pytest.approx(0.4 * T, rel=1e-9)
    assert len(run_frames(1.0, T)) == 101 and run_frames(1.0, T)[-1] == pytest.approx(1.0, rel=1e-12)


def test_the_synthetic_chip_is_a_body_as_the_engine_writes_it(tmp_path):
    # 2 x 2 spheres: enclosing radius = half the diagonal pitch + a sphere's radius
    assert enclosing_radius(CHIP4) == pytest.approx(PITCH / math.sqrt(2) + R_S, rel=1e-12, abs=0)
    flat, tilted = [1.0, 0, 0, 0], [math.cos(math.pi / 12), math.sin(math.pi / 12), 0, 0]  # 30 deg about x
    # lying flat its lowest point is a sphere's radius below the centre; tilted 30 degrees
    # about x, the lower row of spheres sits PITCH / 2 sin 30 deg lower
    assert lowest_depth(CHIP4, [flat, tilted]) == pytest.approx([R_S, R_S + PITCH / 4], rel=1e-12, abs=0)
    exits = 0.1 + np.arange(20) * 0.02
    with Result(feeder(tmp_path / "c.h5", run_frames(0.5, T), exits, body_template=CHIP4,
                       clumps=True, mass=3e-8)) as r:
        f = r.frame(10, fields=("position", "radius", "force", "mass"))
        assert len(f) > 0 and np.isnan(f["force"]).all()
        assert f["radius"] == pytest.approx(np.full(len(f), enclosing_radius(CHIP4)), rel=1e-12, abs=0)
        on = f["position"][:, 2] > 0
        assert f["position"][on, 2] == pytest.approx(np.full(on.sum(), R_S), rel=1e-12, abs=0)  # m: flat
        assert f["mass"] == pytest.approx(np.full(len(f), 3e-8), rel=1e-12, abs=0)     # kg: the body's
        assert r.body_template.shape == (4, 4)


# =========================================================================== feed rate
def test_the_feed_rate_over_a_shorter_last_interval_is_the_exit_rate(tmp_path):
    # 250 parts/s leave from 0.1 s; the run stops at 0.994 s, 0.4 of an interval after the
    # frame at 0.99 s. The rate is timed from the events, so the short interval neither
    # loses nor adds exits: the window's bins are whole periods from the first frame and the
    # short interval (no whole period) is in none of them.
    rate = 250.0
    exits = 0.1 + np.arange(240) / rate
    frames = run_frames(0.994, T)
    with Result(feeder(tmp_path / "f.h5", frames, exits, speed=V, amp=AMP, freq=FREQ)) as r:
        fr = FeedRate(r, model=False).run().results
        given = FeedRate(r, model=False, start=0.2, end=0.994).run().results
    assert fr.n_events == int((exits <= 0.994).sum())     # the exits after 0.99 s are there
    w = fr.bin_width
    assert fr.steady_to <= 0.99 + 1e-12 and (fr.steady_to / w) == pytest.approx(round(fr.steady_to / w),
                                                                                 abs=1e-9)
    span = fr.steady_to - fr.steady_from
    n_in = int(((exits >= fr.steady_from) & (exits < fr.steady_to)).sum())
    assert fr.parts_per_s == pytest.approx(n_in / span, rel=1e-12)
    assert abs(fr.parts_per_s - rate) <= 1 / span + 1e-9  # parts/s: one part's worth at most
    # a window given up to the last frame counts the short interval's exits over its length
    n_given = int(((exits >= 0.2) & (exits < 0.994)).sum())
    assert given.parts_per_s == pytest.approx(n_given / 0.794, rel=1e-12)
    assert abs(given.parts_per_s - rate) <= 1 / 0.794 + 1e-9
    # the speed: whole-period intervals only (the last one, 0.4 of a period, would alias the
    # track's swing into it)
    assert fr.velocity_lag == 1 and fr.mean_velocity == pytest.approx(V, rel=1e-9)
    over_last = V + (swing(0.994) - swing(0.99)) / 0.004
    assert abs(over_last - V) > 0.1 * V


@pytest.mark.parametrize("output_dt, lag", [(T, 1), (2 * T, 1), (1.05 * T, 20), (0.7 * T, 10)])
def test_frames_that_alias_the_period_give_the_conveying_speed(tmp_path, output_dt, lag):
    # output_dt a period (the bulk deck's default), two, 1.05 of one (20 frames = 21 periods)
    # or 0.7 of one (10 frames = 7 periods), the run ending 0.4 of an interval after a frame
    frames = run_frames(1.0 + 0.4 * output_dt, output_dt)
    exits = 0.05 + np.arange(300) / 300.0
    with Result(feeder(tmp_path / "a.h5", frames, exits, speed=V, amp=AMP, freq=FREQ)) as r:
        fr = FeedRate(r, model=False).run().results
    assert fr.velocity_lag == lag and fr.velocity_alias == 0.0
    assert fr.mean_velocity == pytest.approx(V, rel=1e-9)   # m/s: the 50 um swing cancels
    assert fr.mean_velocity_err < 1e-9 * V
    span = fr.steady_to - fr.steady_from
    assert abs(fr.parts_per_s - 300.0) <= 1 / span + 1e-9


def test_parts_put_on_the_track_mid_way_are_not_conveyed_from_the_inlet(tmp_path):
    # Every part is put on the track at x = 10 mm (an insertion region half-way along), between
    # frames, and deleted between its exit and the next frame (never seen falling). Nothing is
    # conveyed over the first 10 mm: the profile's first ten 1 mm bins are empty, the others
    # hold the conveying speed; the masses of the parts gone by the frame after their exit are
    # read at the frame before.
    exits = 0.55 + np.arange(200) / 250.0
    masses = np.where(np.arange(200) % 2, 3e-8, 1e-8)            # kg, alternating
    frames = run_frames(1.0, T)
    with Result(feeder(tmp_path / "m.h5", frames, exits, speed=V, amp=AMP, freq=FREQ, mass=masses,
                       insert_x=0.01, seen_falling=False)) as r:
        fr = FeedRate(r, model=False, start=0.6, end=1.0).run().results
        first = r.frame(0, fields=("position",))
        balance = r.mass_balance
    put_on = exits - (OUTLET_X - 0.01) / V                        # when each is put on the track
    assert len(first) == int(((put_on <= 0) & (exits > 0)).sum())
    assert (first["position"][:, 0] - swing(0.0) >= 0.01 - 1e-12).all()
    assert fr.profile_count[:10].tolist() == [0] * 10 and np.isnan(fr.profile_velocity[:10]).all()
    assert (fr.profile_count[10:] > 0).all()
    assert fr.profile_velocity[10:] == pytest.approx(np.full(10, V), rel=1e-9)
    assert fr.mean_velocity == pytest.approx(V, rel=1e-9)
    inside = (exits >= 0.6) & (exits < 1.0)
    assert fr.event_mass == pytest.approx(masses[exits <= 1.0], rel=1e-12, abs=0)   # kg
    assert fr.mass_per_s == pytest.approx(masses[inside].sum() / 0.4, rel=1e-12, abs=0)
    assert fr.parts_per_s == pytest.approx(inside.sum() / 0.4, rel=1e-12)
    # the mass balance counts a part inserted from the frame after it was put on
    assert balance["inserted"][-1] == int(((put_on <= 1.0) | (exits <= 1.0)).sum())
    assert fr.lost == 0 and fr.exited == int((exits <= 1.0).sum())


def test_the_feed_rate_of_chips_counts_bodies_and_weighs_them_whole(tmp_path):
    # chips of 4 spheres, one row each, each row the body's mass (LIGGGHTS gives every sphere
    # of a clump the whole body's mass): 250 bodies/s of 3e-8 kg is 7.5e-6 kg/s, not 4 times it
    m_body = 3e-8
    exits = 0.1 + np.arange(225) / 250.0
    with Result(feeder(tmp_path / "c.h5", run_frames(0.995, T), exits, speed=V, amp=AMP, freq=FREQ,
                       body_template=CHIP4, clumps=True, mass=m_body,
                       lanes=np.arange(225) % 3 * 1e-3)) as r:
        fr = FeedRate(r, model=False, start=0.2, end=0.9).run().results
    n = int(((exits >= 0.2) & (exits < 0.9)).sum())
    assert fr.parts_per_s == pytest.approx(n / 0.7, rel=1e-12)
    assert fr.mass_per_s == pytest.approx(n * m_body / 0.7, rel=1e-12, abs=0)   # kg/s, ~1e-5
    assert fr.mean_velocity == pytest.approx(V, rel=1e-9)


# =========================================================================== transport
def conveyor_file(tmp_path, times, speeds, name="c.h5"):
    """write_conveyor: part k + 1 at k mm + v_k t + AMP sin(w t), present at every frame."""
    lifetimes = [(0, len(times) - 1)] * len(speeds)
    return write_conveyor(tmp_path / name, times, lifetimes, speeds, amp=AMP, freq=FREQ)


@pytest.mark.parametrize("output_dt", [T, T / 10])
def test_a_shorter_last_interval_does_not_alias_into_the_transport_speed(tmp_path, output_dt):
    # A run stopped 0.4 of an interval after a frame: no frame lies whole periods before the
    # last one, so the window ends at the frame before it (the old window, last frame to the
    # frame nearest whole periods before it, was 0.4 of an interval off: the track's 50 um
    # swing added up to 0.3 % of the speed over half a second, in proportion more over less)
    rng = np.random.default_rng(3)
    speeds = rng.uniform(0.005, 0.03, 12)
    times = run_frames(1.0 + 0.4 * output_dt, output_dt)
    with Result(conveyor_file(tmp_path, times, speeds)) as r:
        tr = Transport(r, start=0.5).run().results
    t0, t1 = tr.window
    assert t1 == pytest.approx(times[-2], rel=1e-12, abs=0) and t0 == pytest.approx(0.5, rel=1e-12, abs=0)
    assert tr.alias == 0.0
    assert tr.velocities == pytest.approx(speeds, rel=1e-9, abs=1e-12)   # m/s
    # what the last frame would have added: (swing(1.0 + 0.4 dt) - swing(nearest)) / window
    t_old = times[np.argmin(np.abs(times - (times[-1] - np.floor((times[-1] - 0.5) * FREQ) * T)))]
    added = (swing(times[-1]) - swing(t_old)) / (times[-1] - t_old)
    assert abs(added) > 1e-3 * speeds.min()


def test_frames_every_period_give_the_transport_speed_exactly(tmp_path):
    # output_dt = the period: every frame at one phase of the swing; any two frames are whole
    # periods apart, and the window is the longest after start
    speeds = np.array([0.01, 0.02, 0.03])
    times = np.arange(101) * T
    with Result(conveyor_file(tmp_path, times, speeds)) as r:
        tr = Transport(r, start=0.3).run().results
    assert tr.window == pytest.approx((0.3, 1.0), rel=1e-12, abs=0) and tr.alias == 0.0
    assert tr.velocities == pytest.approx(speeds, rel=1e-9)


def test_frames_close_to_the_period_find_the_frames_whole_periods_apart(tmp_path):
    # output_dt = 1.05 periods: the frame nearest 49 periods before the end of 96 frames is
    # 0.5 period off whole ones (47 frames = 49.35 periods), which aliased the track's swing
    # into the speed by up to 2 AMP / window (~1 %); 40 frames span 42 periods exactly
    speeds = np.array([0.01, 0.02, 0.03])
    times = np.arange(96) * 1.05 * T
    with Result(conveyor_file(tmp_path, times, speeds)) as r:
        tr = Transport(r, start=0.48).run().results
    t0, t1 = tr.window
    assert tr.alias == 0.0 and (t1 - t0) * FREQ == pytest.approx(42.0, rel=1e-9)
    assert t0 >= 0.48
    assert tr.velocities == pytest.approx(speeds, rel=1e-9)
    old = times[np.argmin(np.abs(times - (t1 - math.floor((t1 - 0.48) * FREQ) * T)))]
    off = (t1 - old) * FREQ - round((t1 - old) * FREQ)
    assert abs(off) > 0.3                                # periods: the old window was that far off


def test_parts_inserted_in_the_window_are_not_counted_as_conveyed_from_zero(tmp_path):
    # parts put on the track at 5 mm all through the run, deleted between their exit and the
    # next frame (freed slots go to newcomers): only the parts on the track at both ends of
    # the window count, each at the conveying speed; a part put on during the window, counted
    # from x = 0 (or from its slot's previous holder), would add a speed far off V
    exits = 0.3 + np.arange(150) / 150.0
    frames = run_frames(1.0, T)
    with Result(feeder(tmp_path / "i.h5", frames, exits, speed=V, amp=AMP, freq=FREQ, insert_x=0.005,
                       seen_falling=False)) as r:
        tr = Transport(r, start=0.5).run().results
        slots_reused = r.n_slots < len(np.unique(r.read("id")[r.read("id") >= 0]))
    put_on = exits - (OUTLET_X - 0.005) / V
    t0, t1 = tr.window
    assert (t0, t1) == pytest.approx((0.5, 1.0), rel=1e-12, abs=0)
    both = np.nonzero((put_on <= t0) & (exits > t1))[0]
    assert tr.ids.tolist() == (both + 1).tolist() and len(both) > 0
    assert tr.velocities == pytest.approx(np.full(len(both), V), rel=1e-9)
    assert tr.mean_velocity == pytest.approx(V, rel=1e-9)
    assert slots_reused


# =========================================================================== singulation
@pytest.mark.parametrize("output_dt", [T, 1.05 * T])
def test_singulation_over_frames_that_alias_and_a_shorter_last_interval(tmp_path, output_dt):
    # periodic arrivals 300 /s of spheres 300 um across at 20 mm/s: 66.7 um apart in time x speed,
    # so every pair overlaps along the track (lanes 1 mm apart keep them from touching)
    rate = 300.0
    exits = 0.05 + np.arange(290) / rate
    lanes = np.arange(290) % 5 * 1e-3
    frames = run_frames(1.0 + 0.4 * output_dt, output_dt)
    with Result(feeder(tmp_path / "s.h5", frames, exits, speed=V, amp=AMP, freq=FREQ, lanes=lanes)) as r:
        sg = Singulation(r, start=0.2, end=0.9).run().results
    inside = exits[(exits >= 0.2) & (exits < 0.9)]
    assert sg.n_arrivals == len(inside)
    assert sg.mean_interarrival == pytest.approx(1 / rate, rel=1e-9)
    assert sg.cv_interarrival < 1e-6
    assert sg.edge_velocity == pytest.approx(V, rel=1e-9)   # whole periods: the swing cancels
    assert sg.gaps == pytest.approx(np.full(len(inside) - 1, V / rate - 2 * RADIUS), rel=1e-9, abs=1e-12)
    assert not sg.touching.any() and sg.n_doubles == len(inside) - 1   # no clear track between


def chips_in_a_row(gaps, x_last):
    """Track x of chips in one lane, the last at ``x_last``, centre distances ``gaps`` [m] back."""
    return x_last - np.r_[0.0, np.cumsum(gaps)][::-1]


def test_singulation_of_chips_of_four_spheres_counts_bodies(tmp_path):
    # Chips 2 x 2 spheres lying flat, aligned, in one lane: a row of three touching face to
    # face (centres 250 um apart: a sphere diameter past the pitch), a pair 270 um apart (20 um
    # of clear track between their spheres, yet their enclosing spheres, 291 um across, overlap)
    # and two alone. Arrivals, doubles and clusters count chips: 7 arrivals, 2 touching pairs,
    # clusters {1: 4, 3: 1}; the enclosing spheres would have joined the pair as well.
    touch, near = PITCH + 2 * R_S, PITCH + 2 * R_S + 2e-5
    x = chips_in_a_row([touch, touch, 2e-3, near, 2e-3, 2e-3], 0.012)   # on the track at t = 0
    exits = 0.2 + (OUTLET_X - x) / V      # leave in turn from 0.6 s on
    with Result(feeder(tmp_path / "c.h5", run_frames(1.0, T), exits, speed=V, amp=AMP, freq=FREQ,
                       body_template=CHIP4, clumps=True, mass=3e-8)) as r:
        sg = Singulation(r, gap=1e-6, start=0.0, end=1.0, cluster_frames=1).run().results
        tracked = Singulation(r, gap=1e-6, start=0.0, end=0.5, cluster_frames=1).run().results
        first = r.frame(0, fields=("position", "radius"))
    assert sg.n_arrivals == 7
    assert sg.touching.tolist() == [True, True, False, False, False, False]
    assert sg.n_doubles == 2 and sg.singulated_fraction == pytest.approx(4 / 7, rel=1e-12, abs=0)
    assert sg.face_up_fraction == 1.0 and sg.aligned_fraction == 1.0
    assert sg.tolerance == pytest.approx(0.02 * enclosing_radius(CHIP4), rel=1e-12, abs=0)   # m
    # on the track at the window's start (t = 0: all seven, still)
    assert tracked.cluster_sizes == {1: 4.0, 3: 1.0}
    assert tracked.track_singulated_fraction == pytest.approx(4 / 7, rel=1e-12, abs=0)
    # the spheres enclosing the chips join the pair too: sizes 1, 2, 3 (what a sphere's view says)
    spheres = cluster_sizes(cluster_labels(first["position"], first["radius"], sg.tolerance))
    assert spheres == {1: 2, 2: 1, 3: 1}


# =========================================================================== clusters
def chips_at(x, yaw_deg=0.0):
    """Centres (N, 3) on the x axis and orientations (N, 4) of flat chips turned by ``yaw_deg``."""
    x = np.asarray(x, dtype=float)
    a = math.radians(yaw_deg) / 2
    q = np.tile([math.cos(a), 0.0, 0.0, math.sin(a)], (len(x), 1))
    return np.column_stack([x, np.zeros(len(x)), np.full(len(x), R_S)]), q


def test_chips_of_four_spheres_touch_by_their_spheres_at_known_spacings():
    tol = 1e-6
    d = PITCH + 2 * R_S          # aligned chips face to face: the near spheres just touch
    # row: touch (d), touch within the tolerance (d + 0.9 tol), apart (d + 1.1 tol), touch
    x = np.cumsum([0.0, d, d + 0.9 * tol, d + 1.1 * tol, d])
    centres, q = chips_at(x)
    labels = clump_labels(centres, q, CHIP4, tol)
    assert labels.tolist() == [0, 0, 0, 1, 1]
    assert cluster_sizes(labels) == {2: 1, 3: 1}
    # turned 45 degrees about z the chips meet corner to corner: their spheres reach
    # PITCH / sqrt(2) + R_S along x, the enclosing radius, so 2 x that apart they touch
    reach = 2 * (PITCH / math.sqrt(2) + R_S)
    centres, q = chips_at([0.0, reach, 2 * reach + 1.1 * tol], yaw_deg=45.0)
    assert clump_labels(centres, q, CHIP4, tol).tolist() == [0, 0, 1]
    # aligned, that far apart there is clear track between them; their enclosing spheres
    # (radius PITCH / sqrt(2) + R_S) touch all the same
    centres, q = chips_at([0.0, reach])
    assert clump_labels(centres, q, CHIP4, tol).tolist() == [0, 1]
    assert cluster_labels(centres, np.full(2, enclosing_radius(CHIP4)), tol).tolist() == [0, 0]


# =========================================================================== flights
def inelastic_hops(gamma, t_end):
    """(lift-off, landing) times [s] of a perfectly inelastic part on a plate vibrating normal
    to itself as z_s = A sin(w t), A = gamma g / w^2, resting on it at t = 0: it lifts off
    where the plate's acceleration falls to -g (sin(w t) = 1 / gamma) and lands at the first
    root of its free flight minus z_s (found to 1e-15 s), where it stays until the next lift-off."""
    amp = gamma * G / W ** 2
    phi = math.asin(1 / gamma)
    out, t_l = [], phi / W
    while t_l < t_end:
        z0, v0 = amp * math.sin(W * t_l), amp * W * math.cos(W * t_l)

        def gap(t, t_l=t_l, z0=z0, v0=v0):
            return z0 + v0 * (t - t_l) - G / 2 * (t - t_l) ** 2 - amp * np.sin(W * t)

        grid = t_l + np.linspace(1e-6, 2 * T, 20001)
        k = int(np.nonzero(gap(grid) < 0)[0][0])
        t_land = brentq(gap, grid[k - 1], grid[k], xtol=1e-15)
        assert math.sin(W * t_land) < 1 / gamma          # it stays down when it lands
        out.append((t_l, t_land))
        t_l = (phi + 2 * math.pi * math.ceil((W * t_land - phi) / (2 * math.pi))) / W
    return amp, out


def hopping_record(path, times, gamma=2.0, depth=RADIUS, chip=None, mass=1e-7):
    """A result of one part hopping as :func:`inelastic_hops` says, its lowest point ``depth``
    below its centre: a sphere of that radius with its force (contact force m (g + a_s) on the
    plate, none in flight), or a ``chip`` (its orientation) of CHIP4 as a body: force NaN."""
    amp, hops = inelastic_hops(gamma, times[-1])
    frames, surface = [], []
    for k, t in enumerate(times):
        zs, vs, a_s = amp * math.sin(W * t), amp * W * math.cos(W * t), -amp * W ** 2 * math.sin(W * t)
        up = [(a, b) for a, b in hops if a <= t < b]
        if up:
            t_l = up[0][0]
            z0, v0 = amp * math.sin(W * t_l), amp * W * math.cos(W * t_l)
            z, vz, fc = z0 + v0 * (t - t_l) - G / 2 * (t - t_l) ** 2, v0 - G * (t - t_l), 0.0
        else:
            z, vz, fc = zs, vs, mass * (G + a_s)
        p = parts([1], [[0.0, 0.0, z + depth]], radius=depth, mass=mass, velocity=[[0, 0, vz]],
                  force=[[0, 0, fc - mass * G]])
        if chip is not None:
            p["radius"] = np.array([enclosing_radius(CHIP4)])
            p["force"] = np.full((1, 3), np.nan)
            p["orientation"] = np.array([chip], dtype=float)
        frames.append((k, float(t), p))
        surface.append(([0.0, 0.0, zs], [0.0, 0.0, vs]))
    variables = {"freq": (repr(FREQ), "Hz", "vibration frequency", "100"),
                 "incline": ("0", "deg", "incline", "0")}
    if chip is None:
        write_result(path, frames, surface=surface, variables=variables)
    else:
        write_bulk_result(path, frames, variables=variables, body_template=CHIP4, surface=surface)
    return Result(path), hops


def test_hops_on_a_sine_plate_with_a_shorter_last_interval(tmp_path):
    # Gamma = 2: lift-off at 0.833 ms of each period, landing at 8.248 ms; 100 frames per
    # period, the run ending at 28.26 ms, 0.6 of an interval after the frame at 28.2 ms: the
    # third landing (28.248 ms) is inside that last, short interval
    dt = T / 100
    times = run_frames(0.02826, dt)
    assert times[-1] - times[-2] == pytest.approx(0.6 * dt, rel=1e-6) and times[-2] < 0.028248 < times[-1]
    r, hops = hopping_record(tmp_path / "s.h5", times)
    with r:
        fl = Flights(r).run().results
    t_l, t_land = np.array(hops).T
    assert fl.landings == pytest.approx(t_land[t_land <= times[-1]], abs=1e-9)   # s
    # lift-off: the contact force m g (1 - gamma sin w t) extrapolated linearly from the last two
    # frames in contact to zero: off by at most w tan(phi) dt^2 (its curvature over 2 dt)
    assert fl.takeoff_kinds == ["lift-off"] * 3
    bound = W * math.tan(math.asin(0.5)) * dt ** 2
    assert np.abs(fl.takeoffs - t_l[:3]).max() <= bound
    assert fl.n_hops == 3 and fl.realised_restitution == 0.0
    assert fl.in_flight_at_end is None   # the third landing ends the record in contact
    assert fl.airborne_fraction == pytest.approx((t_land - t_l)[:3].sum() / times[-1],
                                                 abs=3 * bound / times[-1])


@pytest.mark.parametrize("tilt_deg", [0.0, 30.0])
def test_a_chip_of_four_spheres_hops_from_its_lowest_sphere(tmp_path, tilt_deg):
    # The same hops by a chip lying flat or tilted 30 degrees about x: its lowest point lies
    # R_S + PITCH / 2 sin(tilt) (75 or 100 um) below its centre, not its enclosing radius
    # (146 um): from that sphere the chip would overlap the plate by 71 or 46 um when it lies
    # on it, and its hops (63 um high) would not show, or only their tops. Its force is not
    # recorded, so contact is a gap below 0.2 % of its spheres' radius and a lift-off is where
    # the flight seen after it, traced back over the frames of the contact, meets the plate.
    a = math.radians(tilt_deg) / 2
    tilt = [math.cos(a), math.sin(a), 0.0, 0.0]
    depth = R_S + PITCH / 2 * math.sin(2 * a)
    assert lowest_depth(CHIP4, [tilt]) == pytest.approx([depth], rel=1e-12, abs=0)
    dt = T / 100
    times = run_frames(0.0365, dt)
    r, hops = hopping_record(tmp_path / "c.h5", times, depth=depth, chip=tilt)
    with r:
        assert r.body_template is not None and not r.recorded("force")
        fl = Flights(r).run().results
    t_l, t_land = np.array(hops).T
    assert fl.contact_force is None
    assert fl.landings == pytest.approx(t_land[t_land <= times[-1]], abs=1e-9)   # s
    assert fl.n_hops == 3 and len(fl.takeoffs) == 4      # the fourth flight is under way at the end
    # a tangential lift-off: the gap grows as (t - t_l)^3, and the plate is known between frames
    # to its cubic's error (~2e-12 m here), so the root is known to about a tenth of a frame
    assert np.abs(fl.takeoffs - t_l[:4]).max() <= 0.1 * dt
    # the highest gap seen at a frame: its lowest point's flight over the plate there (~63 um)
    amp = 2.0 * G / W ** 2

    def gap(t):
        for a, b in hops:
            if a <= t < b:
                z0, v0 = amp * math.sin(W * a), amp * W * math.cos(W * a)
                return z0 + v0 * (t - a) - G / 2 * (t - a) ** 2 - amp * math.sin(W * t)
        return 0.0

    assert fl.max_gap == pytest.approx(max(gap(t) for t in times), rel=1e-9, abs=0)   # m
    # the three flights, and the fourth from its launch to the end of the record
    assert not fl.airborne_at_start and fl.in_flight_at_end == pytest.approx(t_l[3], abs=0.1 * dt)
    assert fl.airborne_fraction == pytest.approx(
        ((t_land - t_l)[:3].sum() + times[-1] - t_l[3]) / times[-1], abs=0.4 * dt / times[-1])


@pytest.mark.parametrize("output_dt", [T, 2 * T, 1.05 * T, T / 4])
def test_flights_refuse_frames_too_far_apart_to_follow_the_plate(tmp_path, output_dt):
    # Frames a period apart see the plate at one phase, standing still: the events between
    # frames cannot be told. Refused, saying why and what output_dt would do.
    r, _ = hopping_record(tmp_path / "p.h5", run_frames(0.1, output_dt))
    with r, pytest.raises(InputError, match=r"cannot follow a surface vibrating at 100 Hz.*"
                                           r"output_dt <= 0\.00125 s"):
        Flights(r).run()


def test_flights_follow_the_plate_at_eight_frames_a_period(tmp_path):
    # at the limit (1.25 ms): the plate's cubic between frames is off by A (w h)^4 / 384, 1e-3 of
    # A, and the landings are found to about that over the relative speed of the landing
    times = run_frames(0.0365, T / 8)
    r, hops = hopping_record(tmp_path / "e.h5", times)
    with r:
        fl = Flights(r).run().results
    t_land = np.array(hops)[:, 1]
    assert fl.landings == pytest.approx(t_land[t_land <= times[-1]], abs=2e-6)   # s
    assert fl.n_hops == 3


# =========================================================================== feeder lines
V1, V2 = 0.02, 0.04


def test_a_lines_joint_flux_over_frames_every_period_with_a_shorter_last_interval(tmp_path):
    # a part crosses the joint every 4 ms; frames every period (10 ms), the run stopping
    # 4 ms after the frame at 0.49 s: the window's ends are frames, and an interpolated crossing
    # stays between the frames of the true one, so the counts are exact
    tj = -0.199 + 0.004 * np.arange(175)
    frames = run_frames(0.494, T)
    with Result(line_feeder(tmp_path / "l.h5", frames, tj, v1=V1, v2=V2, amp=3e-5)) as r:
        fr = FeedRate(r, start=0.1, end=0.494, model=False).run().results
    s1, s2 = fr.sections
    exits = tj + S2_LENGTH / V2
    count = lambda t: int(((t >= 0.1) & (t < 0.494)).sum())   # noqa: E731
    assert s1["joint_flux"] == pytest.approx(count(tj) / 0.394, rel=1e-12)
    assert s2["joint_flux"] == pytest.approx(count(exits) / 0.394, rel=1e-12)
    # whole periods over each section (the last, short interval left out): each its own speed
    assert s1["speed"] == pytest.approx(V1, rel=1e-9) and s2["speed"] == pytest.approx(V2, rel=1e-9)


def test_parts_put_on_a_line_between_frames_cross_the_joint_only_from_below_it(tmp_path):
    # Parts on a line, each at its own constant speed along it (no track swing in the track's
    # frame, so a crossing interpolated between frames is exact):
    #   1: on the track from the start at 5.9 mm: crosses the joint (6 mm) at 5 ms;
    #   2: put on at 1 mm at 0.1034 s (between frames): crosses at 0.1034 + 5 mm / V1;
    #   3: put on section 2 at 7 mm at 0.1517 s: never below the joint, crosses nothing;
    #   4: put on at 2 mm at 0.2008 s, falls off at 4 mm between frames (never seen falling);
    #   5: put on at 5.95 mm at 0.3003 s, first seen beyond the joint at 0.31 s (crossed it
    #      between being put on and the first frame that saw it): crosses nothing we can see.
    mm = 1e-3
    x0 = np.array([5.9, 1.0, 7.0, 2.0, 5.95]) * mm
    enter = np.array([-np.inf, 0.1034, 0.1517, 0.2008, 0.3003])
    t_ref = np.where(np.isfinite(enter), enter, 0.0)
    edge = JOINT + S2_LENGTH

    def x_at(t):
        return x0 + V1 * (t - t_ref)

    leave = t_ref + (edge - x0) / V1
    leave[3] = enter[3] + (4.0 - 2.0) * mm / V1
    rejected = np.array([False, False, False, True, False])
    frames = run_frames(0.5037, T)
    path = bed(tmp_path / "b.h5", frames, x_at, enter, leave, rejected=rejected, reject_seen=False,
               outlet_x=edge, line=True, joint=JOINT)
    with Result(path) as r:
        out, rj = r.outlet, r.rejects
        crossings, counts = bed_pass(r, np.arange(r.n_frames), [JOINT], edge, np.r_[out["id"], rj["id"]],
                                     np.r_[out["time"], rj["time"]])
        fr = FeedRate(r, start=0.0, end=0.5, model=False).run().results
    times, ids = crossings[0]
    assert ids.tolist() == [1, 2]
    assert times == pytest.approx([0.1 * mm / V1, 0.1034 + 5 * mm / V1], abs=1e-12)   # s
    assert fr.sections[0]["joint_flux"] == pytest.approx(2 / 0.5, rel=1e-12)
    # parts over each section at each frame: from the frame after they were put on, until they
    # leave (over the edge, or off the side)
    for j, t in enumerate(frames):
        on = (enter <= t) & (leave > t)
        x = x_at(t)
        assert counts[j].tolist() == [int((on & (x < JOINT)).sum()), int((on & (x >= JOINT)).sum())], t
