"""Singulation on synthetic bulk-feeder results whose answers are known by construction
(tests/bulk_synthetic.py): arrival patterns, planted doubles, clusters of known sizes, chips."""

import numpy as np
import pytest

from bulk_synthetic import OUTLET_X, RADIUS, enclosing_radius, feeder, poisson_times
from vibrofeed.errors import InputError
from vibrofeed.postproc import Singulation
from vibrofeed.postproc.feedrate import period_velocities
from vibrofeed.postproc.singulation import face_orientation, thin_axis
from vibrofeed.results.reader import Result

FREQ = 100.0
FRAMES = np.arange(0, 1.0 + 1e-9, 0.01)
D = 2 * RADIUS


def open_feeder(tmp_path, exit_times, name="feed.h5", frames=FRAMES, **kw):
    return Result(feeder(tmp_path / name, frames, exit_times, freq=FREQ, **kw))


# -- inter-arrival times -------------------------------------------------------------
def test_random_arrivals_have_cv_one_and_periodic_ones_cv_zero(tmp_path):
    rng = np.random.default_rng(4)
    exits = poisson_times(400.0, 0.0, 1.0, rng)
    lanes = np.arange(len(exits)) % 7 * 1e-3   # spread out: few touch
    with open_feeder(tmp_path, exits, name="poisson.h5", speed=0.05, lanes=lanes) as r:
        sg = Singulation(r, start=0.0, end=1.0).run().results
    assert sg.n_arrivals == len(exits)
    assert sg.interarrival == pytest.approx(np.diff(exits), abs=1e-15)  # s: differences of times ~1 s
    assert sg.cv_interarrival == pytest.approx(1.0, abs=0.1)   # ~400 intervals: +-0.05
    assert sg.mean_interarrival == pytest.approx(np.diff(exits).mean(), rel=1e-12)
    periodic = 0.05 + np.arange(300) / 300.0
    with open_feeder(tmp_path, periodic, name="periodic.h5", speed=0.5) as r:
        sg = Singulation(r).run().results
    assert sg.cv_interarrival < 1e-9
    assert sg.n_doubles == 0 and sg.singulated_fraction == 1.0 and sg.doubles_rate == 0.0


# -- doubles and gaps ----------------------------------------------------------------
def planted(period=0.02, n=45, at=(5, 12, 30), lag=1e-3, lane=1e-3, t0=0.05):
    """Periodic arrivals with a second part ``lag`` seconds after arrivals ``at``, in ``lane``."""
    exits = list(t0 + period * np.arange(n))
    lanes = [0.0] * n
    for k in at:
        exits.append(exits[k] + lag)
        lanes.append(lane)
    order = np.argsort(exits)
    return np.asarray(exits)[order], np.asarray(lanes)[order]


def test_doubles_planted_at_known_times_are_found_by_time_and_by_distance(tmp_path):
    v = 0.05  # regular spacing 1 mm, clear gap 0.7 mm; planted partners 50 um behind, 1 mm aside
    exits, lanes = planted()
    with open_feeder(tmp_path, exits, speed=v, lanes=lanes) as r:
        by_time = Singulation(r, gap=2e-3, start=0.0, end=1.0).run().results
        by_distance = Singulation(r, start=0.0, end=1.0).run().results   # no clear track between
        roomy = Singulation(r, gap_distance=0.71e-3, start=0.0, end=1.0).run().results
        loose = Singulation(r, gap=0.9e-3, start=0.0, end=1.0).run().results
    pairs = len(exits) - 1
    for sg in (by_time, by_distance):
        assert sg.n_doubles == 3 and not sg.touching.any()
        assert sg.doubles_rate == pytest.approx(3 / pairs, rel=1e-12)
        assert sg.singulated_fraction == pytest.approx((len(exits) - 6) / len(exits), rel=1e-12)
        assert sg.doubles_per_s == pytest.approx(3 / 1.0, rel=1e-12)
        first = np.nonzero(sg.doubles)[0]
        assert sg.arrival_times[first] == pytest.approx(exits[[5, 13, 32]], rel=1e-12)
    assert by_distance.gap_distance == 0.0 and by_distance.gap is None
    # asking for more than the regular 0.7 mm of clear track makes every pair a double
    assert roomy.n_doubles == pairs and roomy.singulated_fraction == 0.0
    assert loose.n_doubles == 0 and loose.gap_distance is None  # 1 ms apart is not < 0.9 ms
    # gaps: clear distance along the track from the edge speed (exact here)
    assert by_time.edge_velocity == pytest.approx(v, rel=1e-9)
    assert by_time.gaps == pytest.approx(np.diff(exits) * v - D, rel=1e-9, abs=1e-12)
    assert by_time.mean_gap == pytest.approx((np.diff(exits) * v - D).mean(), rel=1e-9)


def test_touching_parts_are_doubles_whatever_the_gap(tmp_path):
    v = 0.05
    tol = 0.01 * D
    # same lane: a partner exactly one diameter behind touches, one diameter plus
    # two tolerances behind does not
    exits_t, lanes_t = planted(at=(4, 20), lag=D / v, lane=0.0)
    exits_n, lanes_n = planted(at=(4, 20), lag=(D + 2 * tol) / v, lane=0.0)
    with open_feeder(tmp_path, exits_t, name="t.h5", speed=v, lanes=lanes_t) as r:
        touching = Singulation(r, gap=1e-6, start=0.0, end=1.0).run().results
    with open_feeder(tmp_path, exits_n, name="n.h5", speed=v, lanes=lanes_n) as r:
        near = Singulation(r, gap=1e-6, start=0.0, end=1.0).run().results
        wide = Singulation(r, gap=1e-6, tolerance=3 * tol, start=0.0, end=1.0).run().results
    assert touching.tolerance == pytest.approx(tol, rel=1e-12, abs=0)
    assert touching.n_doubles == 2 and touching.touching.sum() == 2
    assert near.n_doubles == 0
    assert wide.n_doubles == 2


# -- clusters on the track -------------------------------------------------------------
def test_cluster_sizes_of_chains_on_the_track(tmp_path):
    v = 0.005
    # chains of 1..5 parts touching along the track, 2 mm apart, all on the track for
    # the whole run (the first reaches the edge after it, the last is past the inlet)
    exits, lanes, start = [], [], 1.2
    for size in range(1, 6):
        for j in range(size):
            exits.append(start + j * D / v)
            lanes.append(0.0)
        start += (size - 1) * D / v + 2e-3 / v
    with open_feeder(tmp_path, np.array(exits), speed=v, lanes=np.array(lanes), amp=3e-5) as r:
        sg = Singulation(r, cluster_frames=7).run().results
    assert sg.cluster_frames == 7
    assert sg.cluster_sizes == {1: 1.0, 2: 1.0, 3: 1.0, 4: 1.0, 5: 1.0}
    assert sg.track_singulated_fraction == pytest.approx(1 / 15, rel=1e-12)
    assert sg.n_arrivals == 0


def test_parts_falling_off_are_not_on_the_track(tmp_path):
    # every part leaves within the run; the falling ones are beyond the edge
    exits = 0.055 + np.arange(90) / 100.0
    with open_feeder(tmp_path, exits, speed=0.3) as r:
        sg = Singulation(r, cluster_frames=101, start=0.0, end=1.0).run().results
        on_track = r.mass_balance["on_track"]
    # parts 3 mm apart: all alone; the count per frame is the mass balance's on_track
    assert set(sg.cluster_sizes) == {1}
    assert sg.cluster_sizes[1] == pytest.approx(on_track.mean(), rel=1e-12)


# -- chips --------------------------------------------------------------------------------
R_S = 75e-6
CHIP = np.array([[x, y, 0.0, R_S] for x in (-1e-4, 0, 1e-4) for y in (-1e-4, 0, 1e-4)])


def q_axis(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.r_[np.cos(angle / 2), np.sin(angle / 2) * axis]


def q_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def test_chip_faces_and_alignment_at_the_outlet(tmp_path):
    deg = np.pi / 180
    yaw = [0, 30, 100, -50, 5, 185, 92]                 # face up, turned about z
    quats = [q_axis([0, 0, 1], a * deg) for a in yaw]
    quats += [q_mul(q_axis([0, 0, 1], 20 * deg), q_axis([1, 0, 0], np.pi))] * 2   # face down
    quats += [q_axis([1, 0, 0], np.pi / 2)]              # on edge
    quats = np.array(quats)
    exits = 0.1 + 0.08 * np.arange(len(quats))
    lanes = np.arange(len(quats)) * 1e-3
    with open_feeder(tmp_path, exits, speed=0.05, orientations=quats, body_template=CHIP,
                     lanes=lanes) as r:
        sg = Singulation(r, start=0.0, end=1.0).run().results
    assert sg.face_up_fraction == pytest.approx(0.7, rel=1e-12)
    assert sg.face_down_fraction == pytest.approx(0.2, rel=1e-12)
    assert sg.on_edge_fraction == pytest.approx(0.1, rel=1e-12)
    assert sg.cos_tilt == pytest.approx([1] * 7 + [-1, -1, 0], abs=1e-12)
    # yaw folded by the square's quarter-turn symmetry into (-45, 45]
    assert sg.yaw_deg[:7] == pytest.approx([0, 30, 10, 40, 5, 5, 2], abs=1e-9)
    assert sg.aligned_fraction == pytest.approx(6 / 10, rel=1e-12)  # 0, 10, 5, 5, 2 face up; 20 face down
    # face up and aligned, part by part: the five face-up ones within 10 degrees (the one on
    # edge is aligned, not face up) -- not the product of the fractions, 0.7 x 0.6 = 0.42
    assert sg.orientation_yield == pytest.approx(5 / 10, abs=1e-12)


def test_chip_faces_are_taken_as_the_track_delivers_them(tmp_path):
    # flat on the track, tipped 80 degrees about y as they fall past the edge (the events'
    # and the falling frames' orientation): the faces are read before the tip
    n = 6
    flat = np.array([q_axis([0, 0, 1], a * np.pi / 180) for a in (0, 3, 60, 90, 7, 2)])
    tip = np.array([q_mul(q_axis([0, 1, 0], 80 * np.pi / 180), q) for q in flat])
    exits = 0.1 + 0.08 * np.arange(n)
    with open_feeder(tmp_path, exits, speed=0.05, orientations=flat, tipped=tip, body_template=CHIP,
                     lanes=np.arange(n) * 1e-3) as r:
        sg = Singulation(r, start=0.0, end=1.0).run().results
    assert sg.face_up_fraction == pytest.approx(1.0, abs=1e-12)
    assert sg.on_edge_fraction == pytest.approx(0.0, abs=1e-12)
    assert sg.cos_tilt == pytest.approx([1.0] * n, abs=1e-12)
    assert sg.yaw_deg == pytest.approx([0, 3, -30, 0, 7, 2], abs=1e-9)
    assert sg.aligned_fraction == pytest.approx(5 / 6, rel=1e-12)
    # the tipped orientation alone would read every chip on edge (cos 80 deg)
    cos_tipped, _ = face_orientation(tip, CHIP)
    assert cos_tipped == pytest.approx([np.cos(80 * np.pi / 180)] * n, abs=1e-12)


def test_the_orientation_yield_counts_the_parts_both_face_up_and_aligned(tmp_path):
    # two face up and aligned, one face up at 30 degrees, two face down along the track:
    # 2 of 5 (the fractions, 3/5 face up and 4/5 aligned, would make 0.48)
    flip = q_axis([1, 0, 0], np.pi)
    quats = np.array([yaw_quat(0), yaw_quat(5), yaw_quat(30), flip, q_mul(yaw_quat(3), flip)])
    exits = 0.1 + 0.08 * np.arange(5)
    with open_feeder(tmp_path, exits, speed=0.05, orientations=quats, body_template=CHIP,
                     lanes=np.arange(5) * 1e-3) as r:
        sg = Singulation(r, start=0.0, end=1.0).run().results
    assert sg.face_up_fraction == pytest.approx(3 / 5, abs=1e-12)
    assert sg.aligned_fraction == pytest.approx(4 / 5, abs=1e-12)
    assert sg.orientation_yield == pytest.approx(2 / 5, abs=1e-12)
    assert abs(sg.yaw_deg[4]) == pytest.approx(3.0, abs=1e-9)   # face down, along the track


@pytest.mark.parametrize("yaw", [0.0, 45.0, 90.0, 30.0])
def test_a_chips_gap_is_its_clear_track_as_it_lies_not_its_circumscribed_sphere(tmp_path, yaw):
    """Chips in one lane, each centre a + g behind the one before with a its reach along the
    track as it lies (yaw about z; by hand: the square of sphere centres at +-1e-4 m, spheres
    of R_S, reaches 1e-4 + R_S square on, (1e-4 cos + 1e-4 sin) + R_S turned), a clear gap
    of g = 20 um: every gap reads g, and none is a double. Square on, the circumscribed sphere
    (2 x 2.16e-4 m) read them all as overlapping: doubles."""
    deg = np.pi / 180
    c, s = abs(np.cos(yaw * deg)), abs(np.sin(yaw * deg))
    reach = 1e-4 * (c + s) + R_S  # [m] either way along the track
    g, v = 2e-5, 0.05
    n = 12
    exits = 0.1 + (2 * reach + g) / v * np.arange(n)
    quats = np.tile(q_axis([0, 0, 1], yaw * deg), (n, 1))
    with open_feeder(tmp_path, exits, speed=v, orientations=quats, body_template=CHIP, clumps=True) as r:
        sg = Singulation(r, start=0.0, end=1.0).run().results
    assert sg.edge_velocity == pytest.approx(v, rel=1e-9, abs=0)
    assert sg.gaps == pytest.approx(np.full(n - 1, g), rel=1e-6, abs=0)
    assert sg.n_doubles == 0 and sg.singulated_fraction == 1.0
    if yaw in (0.0, 90.0):  # square on: the circumscribed sphere read these as doubles
        assert 2 * enclosing_radius(CHIP) > 2 * reach + g


def test_along_extents_of_a_turned_clump_by_hand():
    """The reach of a clump along a direction and against it: an offset template (its centre
    is its spheres' mean) turned by 90 degrees about z, along x: the spheres at y = +-1e-4
    land on x = -+1e-4."""
    from vibrofeed.postproc.clusters import along_extents

    template = np.array([[0.0, 0.0, 0.0, 1e-5], [0.0, 2e-4, 0.0, 3e-5]])  # centre at y = 1e-4
    q = np.array([q_axis([0, 0, 1], np.pi / 2), [1.0, 0, 0, 0]])
    front, back = along_extents(q, template, [1.0, 0.0, 0.0])
    # turned: the sphere of 3e-5 at x = -1e-4, the one of 1e-5 at x = +1e-4
    assert front == pytest.approx([1e-4 + 1e-5, 3e-5], rel=1e-12, abs=0)
    assert back == pytest.approx([1e-4 + 3e-5, 3e-5], rel=1e-12, abs=0)


def test_thin_axis_and_orientation_of_a_template():
    assert thin_axis(CHIP) == pytest.approx([0, 0, 1], abs=1e-12)
    tilted = CHIP[:, [2, 0, 1, 3]]           # the same chip lying in the yz plane
    assert thin_axis(tilted) == pytest.approx([1, 0, 0], abs=1e-12)
    cos_tilt, yaw = face_orientation([q_axis([0, 1, 0], np.pi / 2)], tilted)
    assert cos_tilt == pytest.approx([-1.0], abs=1e-12)  # x turned onto -z: face down
    # standing on edge unturned: the in-plane reference is its y axis (x is the normal), 90 deg,
    # folded to 0 by the square's symmetry
    cos_tilt, yaw = face_orientation([[1.0, 0, 0, 0]], tilted)
    assert cos_tilt == pytest.approx([0.0], abs=1e-12) and yaw == pytest.approx([0.0], abs=1e-9)


def test_spheres_have_no_face(tmp_path):
    with open_feeder(tmp_path, 0.1 + np.arange(50) / 60) as r:
        sg = Singulation(r).run().results
    assert sg.face_up_fraction is None and sg.yaw_deg is None
    assert sg.orientation_yield is None


def test_settings_are_checked(tmp_path):
    with open_feeder(tmp_path, [0.5]) as r:
        for bad in ({"gap": 0.0}, {"gap_distance": -1e-4}, {"cluster_frames": 0}, {"edge_length": 0}):
            with pytest.raises(InputError):
                Singulation(r, **bad)
        assert Singulation(r, gap_distance=0.0).gap_distance == 0.0   # abreast only: allowed
    assert OUTLET_X > 0


# -- the pieces at their edges ------------------------------------------------------
def yaw_quat(deg):
    return q_axis([0, 0, 1], deg * np.pi / 180)


def tipping_chips(path, n):
    """Chips on a track displaced by 0.5 mm along x (the outlet edge at x = 0.0205 in the
    simulation frame). Chip 1 turns from 0 to 5 degrees and tips 60 degrees as its centre
    passes the edge at the frame before it crosses the catch plane; chip 2 (n = 2) lies flat
    at 20 degrees until it leaves."""
    from helpers import parts, write_bulk_result

    shift = 5e-4
    tipped = q_mul(q_axis([0, 1, 0], np.pi / 3), yaw_quat(5))
    chip1 = [(0.0190, yaw_quat(0)), (0.0196, yaw_quat(5)), (0.0203, tipped), None, None]
    chip2 = [(0.0150, yaw_quat(20)), (0.0165, yaw_quat(20)), (0.0180, yaw_quat(20)),
             (0.0195, yaw_quat(20)), None]
    frames = []
    for k in range(5):
        rows = [(1, chip1[k])] + ([(2, chip2[k])] if n == 2 else [])
        rows = [(i, s) for i, s in rows if s is not None]
        p = parts([i for i, _ in rows], [[s[0] + shift, 0.0, RADIUS] for _, s in rows], radius=RADIUS)
        p["orientation"] = np.array([s[1] for _, s in rows]).reshape(-1, 4)
        frames.append((k, 0.01 * k, p))
    times, ids = [0.025, 0.035][:n], [1, 2][:n]
    events = {"time": np.array(times), "id": np.array(ids), "position": np.zeros((n, 3)),
              "velocity": np.zeros((n, 3)), "orientation": np.tile(tipped, (n, 1))}
    surface = [([shift, 0, 0], [0, 0, 0])] * 5
    return Result(write_bulk_result(path, frames, events=events, body_template=CHIP, surface=surface,
                                    outlet={"outlet_x": 0.02, "catch_z": -3e-4, "method": "synthetic"}))


def test_a_chip_past_the_edge_at_the_frame_before_its_exit_is_read_a_frame_earlier(tmp_path):
    with tipping_chips(tmp_path / "tip.h5", 2) as r:
        sg = Singulation(r, start=0.0, end=0.04).run().results
    # chip 1: the frame before its crossing sees it tipped past the edge (of the displaced
    # track): read at the frame before that, flat at 5 degrees (not 0, two frames back)
    assert sg.cos_tilt == pytest.approx([1.0, 1.0], abs=1e-12)
    assert sg.yaw_deg == pytest.approx([5.0, 20.0], abs=1e-9)
    assert sg.face_up_fraction == 1.0 and sg.aligned_fraction == 0.5
    assert sg.orientation_yield == 0.5                   # chip 1 (5 degrees), not chip 2 (20)


def test_a_chip_never_over_the_track_before_its_exit_keeps_the_events_orientation(tmp_path):
    # chip 1 is seen only past the edge (tipped) before it crosses at 25 ms, and over the track
    # again, flat, at the last frame (the same id, later): only frames up to its crossing are
    # searched, down to the first; the event's orientation (tipped 60 degrees) stands
    from helpers import parts, write_bulk_result

    shift = 5e-4
    tipped = q_mul(q_axis([0, 1, 0], np.pi / 3), yaw_quat(5))
    chip1 = [None, None, (0.0203, tipped), None, (0.0100, yaw_quat(30))]
    frames = []
    for k, s in enumerate(chip1):
        rows = [] if s is None else [s]
        p = parts([1] * len(rows), np.array([[x + shift, 0.0, RADIUS] for x, _ in rows]).reshape(-1, 3),
                  radius=RADIUS)
        p["orientation"] = np.array([q for _, q in rows]).reshape(-1, 4)
        frames.append((k, 0.01 * k, p))
    events = {"time": np.array([0.025]), "id": np.array([1]), "position": np.zeros((1, 3)),
              "velocity": np.zeros((1, 3)), "orientation": tipped[None, :]}
    path = write_bulk_result(tmp_path / "never.h5", frames, events=events, body_template=CHIP,
                             surface=[([shift, 0, 0], [0, 0, 0])] * 5,
                             outlet={"outlet_x": 0.02, "catch_z": -3e-4, "method": "synthetic"})
    with Result(path) as r:
        sg = Singulation(r, start=0.0, end=0.04).run().results
    assert sg.cos_tilt == pytest.approx([0.5], abs=1e-12)     # cos 60 degrees
    assert sg.face_up_fraction == 0.0 and sg.on_edge_fraction == 1.0


def test_one_chip_arriving_has_a_face(tmp_path):
    with tipping_chips(tmp_path / "one.h5", 1) as r:
        sg = Singulation(r, start=0.0, end=0.04).run().results
    assert sg.n_arrivals == 1 and sg.face_up_fraction == 1.0 and sg.yaw_deg == pytest.approx([5.0], abs=1e-9)


def test_a_chip_is_face_up_within_forty_five_degrees(tmp_path):
    # two chips over the track, tilted 44.5 and 45.5 degrees about y, cross the catch plane
    # after frame 1: one face up, one on edge
    from helpers import parts, write_bulk_result

    tilts = [q_axis([0, 1, 0], np.radians(a)) for a in (44.5, 45.5)]
    frames = []
    for k in range(3):
        p = parts([1, 2], [[0.015, 0.0, RADIUS], [0.010, 2e-3, RADIUS]], radius=RADIUS)
        p["orientation"] = np.array(tilts)
        frames.append((k, 0.01 * k, p))
    events = {"time": np.array([0.015, 0.016]), "id": np.array([1, 2]), "position": np.zeros((2, 3)),
              "velocity": np.zeros((2, 3)), "orientation": np.tile([1.0, 0, 0, 0], (2, 1))}
    path = write_bulk_result(tmp_path / "face.h5", frames, events=events, body_template=CHIP,
                             outlet={"outlet_x": 0.02, "catch_z": -3e-4, "method": "synthetic"})
    with Result(path) as r:
        sg = Singulation(r, start=0.0, end=0.02).run().results
    assert sg.cos_tilt == pytest.approx(np.cos(np.radians([44.5, 45.5])), abs=1e-12)
    assert sg.face_up_fraction == 0.5 and sg.on_edge_fraction == 0.5 and sg.face_down_fraction == 0.0


def test_aligned_means_within_ten_degrees():
    cos_tilt, yaw = face_orientation([yaw_quat(a) for a in (9.9, 10.5, -10.5, 44)], CHIP)
    assert yaw == pytest.approx([9.9, 10.5, -10.5, 44], abs=1e-9)
    from vibrofeed.postproc.singulation import ALIGNED_ANGLE

    assert ALIGNED_ANGLE == 10.0  # the README's and the summary's "aligned"


def test_a_template_thin_along_x_measures_its_yaw_in_its_yz_face():
    tilted = CHIP[:, [2, 0, 1, 3]]           # thin along x: its face is the yz plane
    flat = q_axis([0, 1, 0], -np.pi / 2)     # turns x onto +z: the chip lies face up
    q = q_mul(yaw_quat(30), flat)
    cos_tilt, yaw = face_orientation([q], tilted)
    assert cos_tilt == pytest.approx([1.0], abs=1e-12) and yaw == pytest.approx([30.0], abs=1e-9)


def test_the_thin_axis_does_not_depend_on_where_the_template_sits():
    assert thin_axis(CHIP + [1e-3, -2e-3, 5e-4, 0]) == pytest.approx([0, 0, 1], abs=1e-12)


def test_the_thin_axis_is_the_least_spread_about_the_spheres_mean():
    # four spheres at (+-a, +-a, 0) and a bump 2.1 a above their centre: about the mean (z = 0.42 a)
    # the spread along z is 0.8 (2.1 a)^2 = 3.5 a^2 < 4 a^2 along x or y: thin along z (about
    # the median, z = 0, it would be 4.4 a^2)
    a = 1e-4
    bump = np.array([[a, a, 0, R_S], [-a, a, 0, R_S], [a, -a, 0, R_S], [-a, -a, 0, R_S],
                     [0, 0, 2.1 * a, R_S]])
    assert thin_axis(bump) == pytest.approx([0, 0, 1], abs=1e-12)


def test_the_cv_of_a_few_intervals_uses_the_sample_deviation(tmp_path):
    # arrivals 1, 2 and 3 ms apart: mean 2 ms, sample deviation 1 ms: CV 0.5
    exits = 0.1 + np.cumsum([0.0, 0.001, 0.002, 0.003])
    with open_feeder(tmp_path, exits, speed=0.05, lanes=np.arange(4) * 1e-3) as r:
        sg = Singulation(r, start=0.0, end=1.0).run().results
    assert sg.cv_interarrival == pytest.approx(0.5, rel=1e-9)


def test_the_edge_speed_is_that_of_the_parts_within_five_diameters(tmp_path):
    # a lane of fast parts (0.06 m/s) arriving through the window, and slow ones (0.5 mm/s) that stay
    # 5.2-5.8 diameters behind the edge all through it (5.5 at its middle, 0.5 s): only the fast ones
    # are within five diameters of the edge; six would take the slow ones in
    n, slow_speed = 40, 5e-4
    fast = 0.3 + np.arange(n) * 0.01
    slow = 0.5 + 5.5 * D / slow_speed + np.arange(5) * 1e-3
    exits = np.r_[fast, slow]
    speeds = np.r_[np.full(n, 0.06), np.full(5, slow_speed)]
    lanes = np.r_[np.zeros(n), 2e-3 + np.arange(5) * 1e-3]
    with open_feeder(tmp_path, exits, speed=speeds, lanes=lanes) as r:
        sg = Singulation(r, start=0.3, end=0.7).run().results
        x_mid, v, _, _ = period_velocities(r, np.arange(30, 71), 0, OUTLET_X)
    behind = (OUTLET_X - x_mid[v < 0.01]) / D
    assert len(behind) and behind.min() > 5.1 and behind.max() < 5.9   # the slow ones are there
    assert sg.edge_velocity == pytest.approx(0.06, rel=1e-9)


def test_cluster_frames_include_the_window_end(tmp_path):
    exits = 0.05 + np.arange(80) * 0.01
    with open_feeder(tmp_path, exits, speed=0.05, lanes=np.arange(80) % 4 * 1e-3) as r:
        sg = Singulation(r, start=0.2, end=0.5, cluster_frames=1000).run().results
    assert sg.cluster_frames == 31   # 0.20, 0.21, ..., 0.50
