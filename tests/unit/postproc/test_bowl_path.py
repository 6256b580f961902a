"""Where a part is along a bowl's track (postproc.path): the helix's arc length of its centre
in the bowl's frame, the recorded rotation and lift undone; NaN off the track; and the
bowl's dilute limit, the single-part model under the drive the helix sees. And along a linear
track: x in the track's frame, up to the outlet edge of the outlet table or the deck."""

import math

import numpy as np
import pytest

from helpers import parts, write_bulk_result
from vibrofeed.bowl import THETA_END, bowl_from, track_drive
from vibrofeed.postproc.feedrate import dilute_limit
from vibrofeed.postproc.path import along, outlet_x, path_end
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import Recording, ResultWriter

BOWL = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "turns": 1.5,
        "wall_height": 1e-3, "cone_angle": 3.0, "cross_tilt": 3.0, "lip_height": 0.0,
        "chute_length": 8e-3, "freq": 100.0, "amp_t": 5e-5, "amp_n": 3e-5, "phase": -20.0,
        "mu": 0.5, "restitution": 0.3, "shape": 0, "part_size": 3e-4, "density": 2330.0}
LENGTH = 1e-9  # [m]
ENGINE = "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)"


def write_bowl(path, angles, lifts, points):
    """A rotating result: at frame k the parts are the bowl-frame ``points`` turned by
    angles[k] about z and lifted by lifts[k], as parts riding the bowl are."""
    variables = {k: (repr(v), "", k, repr(v)) for k, v in BOWL.items()}
    w = ResultWriter(path, deck_name="bowl_feeder", deck_path="bowl_feeder.liggghts", deck_text="#\n",
                     variables=variables, derived={"dt_used": 1e-6}, engine_version=ENGINE,
                     seed=1, run_id="x" * 64, recording=Recording(rotating=True))
    for k, (a, z) in enumerate(zip(angles, lifts)):
        c, s = math.cos(a), math.sin(a)
        lab = np.column_stack([c * points[:, 0] - s * points[:, 1], s * points[:, 0] + c * points[:, 1],
                               points[:, 2] + z])
        w.write_frame(k, k * 1e-3, parts(np.arange(1, len(points) + 1), lab, radius=1.5e-4),
                      [0, 0, z], [0, 0, 0], surface_rotation=([0, 0, a], [0, 0, 0]))
    w.finish("complete")


def test_a_part_is_where_the_helix_puts_it_whatever_the_bowl_turned(tmp_path):
    b = bowl_from(BOWL)
    thetas = np.array([b.theta_start + 0.3, -8.0, -2.0, THETA_END - 0.01])  # 1.5 turns to -pi/2
    on_helix = b.helix_point(thetas) + [0, 0, 1.5e-4]  # resting on the floor
    chute = np.array([[3e-3, -b.r_mid, b.end_z + 3e-3 * math.tan(math.radians(3)) + 1.5e-4]])
    pile = np.array([[0.0, 0.0, 1e-3], [5e-3, 0.0, 6e-4]])  # inside the track's inner edge
    points = np.vstack([on_helix, chute, pile])
    angles = [0.0, 4e-3, -4e-3]  # [rad]: well beyond a drive's angle, to see it undone
    lifts = [0.0, 3e-5, -3e-5]
    write_bowl(tmp_path / "b.h5", angles, lifts, points)
    want = np.r_[b.arc_length(thetas), b.length + 3e-3 / math.cos(math.radians(3)), np.nan, np.nan]
    with Result(tmp_path / "b.h5") as r:
        s, moved = along(r, np.arange(3))
        assert path_end(r) == pytest.approx(b.length + b.chute_length, rel=1e-12, abs=0)
    for k in range(3):
        assert np.allclose(s[k], want, rtol=0, atol=LENGTH, equal_nan=True)
    assert np.array_equal(moved, s, equal_nan=True)
    # not undoing the rotation would misplace them by r * angle: 38 um at 4 mrad
    assert b.r_mid * 4e-3 > 1e4 * LENGTH


def test_a_bowls_dilute_limit_is_the_model_under_the_drive_the_helix_sees():
    from vibrofeed.models.deck import transport

    got, note = dilute_limit(BOWL)
    d = track_drive(5e-5, 3e-5, -20.0, 100.0, 3.0, bowl_from(BOWL).r_mid)
    want = transport({**BOWL, "amp_t": d.amp_t, "amp_n": d.amp_n, "phase": d.phase,
                      "incline": d.incline}).velocity
    assert got == pytest.approx(want, rel=1e-12, abs=0) and note == ""
    flat = transport(BOWL).velocity  # the bowl's own numbers, read as a level linear track
    assert abs(got - flat) > 0.02 * abs(want)  # the projection and the climb matter


def test_a_bowls_path_ends_at_the_chutes_end():
    """The helix's centre line, 1.5 turns at 9.4 mm rising at 3 deg, then the 8 mm chute."""
    class Bowl:
        parameters = {**BOWL, "track_length": 0.05}  # (a linear track's length: not a bowl's end)
        outlet_plane = {"outlet_x": 0.03, "catch_z": -1e-3, "method": "synthetic"}

    want = 3 * math.pi * 9.4e-3 / math.cos(math.radians(3)) + 8e-3
    assert path_end(Bowl()) == pytest.approx(want, rel=1e-12, abs=0)


# ------------------------------------------------------------------ a linear track
LINEAR = {"freq": ("100", "Hz", "vibration frequency", "100"),
          "track_length": ("0.02", "m", "track length", "0.02")}
OUTLET = {"outlet_x": 0.018, "catch_z": -3e-4, "method": "synthetic"}


def linear_result(path, outlet, variables=LINEAR):
    """Three frames of two slots (the second empty in the middle one); the surface moved by
    (1e-5, 2e-6, 0), (-2e-5, 0, 0), (3e-5, -1e-6, 0)."""
    frames = [(0, 0.0, parts([1, 2], [[1e-3, 2e-4, 1.5e-4], [5e-3, -2e-4, 1.5e-4]])),
              (1, 0.01, parts([1], [[2e-3, 3e-4, 1.5e-4]])),
              (2, 0.02, parts([1, 2], [[3e-3, 4e-4, 1.5e-4], [7e-3, -1e-4, 1.5e-4]]))]
    surface = [((1e-5, 2e-6, 0.0), (0.0, 0.0, 0.0)), ((-2e-5, 0.0, 0.0), (0.0, 0.0, 0.0)),
               ((3e-5, -1e-6, 0.0), (0.0, 0.0, 0.0))]
    return write_bulk_result(path, frames, variables=variables, outlet=outlet, surface=surface)


def test_a_linear_tracks_coordinate_is_x_in_the_tracks_frame_and_its_speed_the_raw_x(tmp_path):
    with Result(linear_result(tmp_path / "l.h5", OUTLET)) as r:
        x, moved = along(r, np.arange(3))
        want = np.array([[1e-3 - 1e-5, 5e-3 - 1e-5], [2e-3 + 2e-5, np.nan], [3e-3 - 3e-5, 7e-3 - 3e-5]])
        assert np.allclose(x, want, rtol=0, atol=LENGTH, equal_nan=True)
        assert np.allclose(moved, [[1e-3, 5e-3], [2e-3, np.nan], [3e-3, 7e-3]], rtol=0, atol=LENGTH,
                           equal_nan=True)
        # across the track (axis 1), the same
        y, raw = along(r, [0, 2], axis=1)
        assert np.allclose(y, [[2e-4 - 2e-6, -2e-4 - 2e-6], [4e-4 + 1e-6, -1e-4 + 1e-6]], rtol=0, atol=LENGTH)
        assert np.allclose(raw, [[2e-4, -2e-4], [4e-4, -1e-4]], rtol=0, atol=LENGTH)


@pytest.mark.parametrize("outlet, want", [
    (OUTLET, 0.018),                                          # the outlet table's edge ...
    ({"catch_z": -3e-4, "method": "synthetic"}, 0.02),        # ... without one, the deck's length
    ({"outlet_x": math.nan, "catch_z": -3e-4, "method": ""}, 0.02),
    (None, 0.02),                                             # no outlet table at all
])
def test_a_linear_tracks_outlet_edge_is_the_outlet_tables_else_the_tracks_end(tmp_path, outlet, want):
    with Result(linear_result(tmp_path / "l.h5", outlet)) as r:
        assert outlet_x(r) == pytest.approx(want, rel=1e-15, abs=0)
        assert path_end(r) == pytest.approx(want, rel=1e-15, abs=0)


def test_without_an_outlet_edge_or_a_track_length_there_is_no_end(tmp_path):
    variables = {"freq": LINEAR["freq"]}
    with Result(linear_result(tmp_path / "l.h5", None, variables)) as r:
        assert math.isnan(outlet_x(r)) and math.isnan(path_end(r))


def test_the_recorded_lift_is_undone_before_the_turn_is_found(tmp_path):
    """Parts resting on the second turn and on the chute, the bowl lifted by half a millimetre
    down and by more than a pitch up (no drive does either: to see the lift undone). Left in,
    the first would put them a turn down, the second a turn up or off the track."""
    b = bowl_from(BOWL)
    a = math.radians(3.0)
    thetas = np.array([-6.0, -4.0, -2.0])  # on the second turn (the first ends at -7.85)
    on_helix = b.helix_point(thetas) + [0, 0, 1.5e-4]
    chute = np.array([[3e-3, -b.r_mid, b.end_z + 3e-3 * math.tan(a) + 1.5e-4]])
    points = np.vstack([on_helix, chute])
    write_bowl(tmp_path / "b.h5", [0.0, 0.0, 0.0], [0.0, -5e-4, 3.2e-3], points)
    r_mid = 9.4e-3
    start = -math.pi / 2 - 3 * math.pi
    want = np.r_[(thetas - start) * r_mid, 3 * math.pi * r_mid + 3e-3] / math.cos(a)
    with Result(tmp_path / "b.h5") as r:
        s, _ = along(r, np.arange(3))
    assert np.allclose(s, want, rtol=0, atol=LENGTH)


def test_a_bowls_track_clusters_leave_out_the_pile_and_its_edge_speed_is_along_the_chute(tmp_path,
                                                                                        monkeypatch):
    """Singulation in a bowl: the clusters on the track are those of the parts on the helix and
    the chute (path coordinate up to its end), not the pile on the bottom (off the track); the
    edge speed is the chute's parts' speed along the path near its end.

    By hand: three parts touching in the pile, a touching pair on the chute near its end and
    two parts alone on the helix; the chute's pair moves along +x at 20 mm/s, the rest stand.
    On the track: clusters of 1, 1 and 2, a singulated fraction of 2/4; the edge speed 20 mm/s
    along x.
    """
    from vibrofeed.postproc.feedrate import FeedRate
    from vibrofeed.postproc.singulation import Singulation

    b = bowl_from(BOWL)
    d = 3e-4  # [m] the spheres' diameter: touching parts are a diameter apart
    tan3 = math.tan(math.radians(3))
    helix = b.helix_point(np.array([b.theta_start + 1.0, b.theta_start + 3.0])) + [0, 0, d / 2]
    pile = np.array([[0.0, 0.0, 1e-3], [d, 0.0, 1e-3], [2 * d, 0.0, 1e-3]])
    speed, dt = 0.02, 2.5e-3  # [m/s], [s]: frames a quarter period apart at 100 Hz
    frames, n = [], 9
    for k in range(n):
        x0 = 6e-3 + speed * k * dt
        chute = np.array([[x, -b.r_mid, b.end_z + x * tan3 + d / 2] for x in (x0, x0 + d)])
        pos = np.vstack([helix, pile, chute])
        frames.append((k, k * dt, parts(np.arange(1, 8), pos, radius=d / 2)))
    events = {"time": np.array([0.001, 0.011, 0.019]), "id": np.array([101, 102, 103]),
              "position": np.tile([b.outlet_x + 1e-4, -b.r_mid, -1e-3], (3, 1)),
              "velocity": np.zeros((3, 3)), "orientation": np.tile([1.0, 0, 0, 0], (3, 1))}
    variables = {k: (repr(v), "", k, repr(v)) for k, v in BOWL.items()}
    path = write_bulk_result(tmp_path / "b.h5", frames, events=events, variables=variables,
                             outlet={"outlet_x": b.outlet_x, "catch_z": -5e-4, "method": "synthetic"})
    from vibrofeed.pictures import plots

    drawn = {}
    monkeypatch.setattr(plots, "save", lambda fig, p: drawn.setdefault(p.name, fig) and p)
    with Result(path) as r:
        s = Singulation(r, start=0.0, end=0.02, cluster_frames=3).run().results
        analysis = FeedRate(r, start=0.0, end=0.02, model=False).run()
        plots.feedrate_figures(analysis, tmp_path)
    fr = analysis.results
    # the feed rate's speed profile is one in height too: each bin's centre-line floor height,
    # and the figure's top axis [mm] maps the path's coordinate [mm] to it
    assert len(fr.profile_x) == 20
    assert np.allclose(fr.profile_height, b.height_at(fr.profile_x), rtol=0, atol=LENGTH)
    ax = drawn["feedrate_velocity_profile.png"].axes[0]
    (top,) = ax.child_axes
    assert top.get_xlabel() == "height of the track's centre line [mm]"
    assert ax.get_xlabel().startswith("position along the helix and the chute s [mm]")
    to_height = top._functions[0]  # (matplotlib keeps the forward map there)
    assert to_height(fr.profile_x[3] * 1e3) == pytest.approx(fr.profile_height[3] * 1e3, rel=1e-12, abs=0)
    for fig in drawn.values():
        plots.pyplot().close(fig)
    # (clusters per sampled frame: counts, exact)
    assert s.cluster_sizes == {1: 2.0, 2: 1.0}
    assert s.track_singulated_fraction == pytest.approx(0.5, rel=0, abs=1e-12)
    # (the chute rises at the helix angle: along it, the pair moves 1/cos(3 deg) faster than in x)
    assert s.edge_velocity == pytest.approx(speed / math.cos(math.radians(3)), rel=1e-9, abs=0)


def test_the_profile_in_height_is_the_centre_lines_floor_up_the_helix_and_the_chute():
    """Bowl.height_at(s): the helix's centre-line floor where its arc length is s, and past
    its end the chute's floor, rising at the helix angle from the end's height."""
    b = bowl_from(BOWL)
    thetas = np.linspace(b.theta_start, THETA_END, 7)
    assert np.allclose(b.height_at(b.arc_length(thetas)), b.helix_point(thetas)[:, 2], rtol=0, atol=LENGTH)
    along = np.array([0.0, 2e-3, b.chute_length])  # [m] along the chute
    want = b.end_z + along * math.sin(math.radians(b.helix_angle))
    assert np.allclose(b.height_at(b.length + along), want, rtol=0, atol=LENGTH)


@pytest.mark.parametrize("per_block", [None, 2, 3])  # None: one block; else frames read at once
def test_falls_are_parts_that_leave_the_track_for_the_bowl_counted_once_each_time(tmp_path, monkeypatch,
                                                                                  per_block):
    """By hand, five frames 5 ms apart: part 1 rides the helix, then lies inside its inner edge
    at frame 3 (a fall at 15 ms) and back on the helix at frame 4 (picked up: no fall); part 2
    lies in the pile, then on the helix (no fall); part 3 goes off the chute's end and beyond
    the wall (leaving, not falling); slot 4 holds part 4 on the helix, then part 5 in the pile
    (another part in the slot: no fall). FeedRate counts the fall in its window: 1 in 20 ms."""
    from vibrofeed.postproc.feedrate import FeedRate
    from vibrofeed.postproc.path import falls

    b = bowl_from(BOWL)
    on = b.helix_point(np.array([b.theta_start + 2.0]))[0] + [0, 0, 1.5e-4]
    pile = np.array([2e-3, 1e-3, 8e-4])
    chute = np.array([7e-3, -b.r_mid, b.end_z + 7e-3 * math.tan(math.radians(3)) + 1.5e-4])
    beyond = np.array([b.outlet_x + 1e-3, -b.r_mid, -3e-4])
    rows = {  # frame -> positions of ids 1, 2, 3 and the fourth slot's part
        0: [on, pile, chute, on + [0, 0, 1e-4]],
        1: [on, pile, chute, on + [0, 0, 1e-4]],
        2: [on, on + [0, 0, 2e-4], chute, pile],
        3: [pile, on + [0, 0, 2e-4], beyond, pile],
        4: [on, on + [0, 0, 2e-4], beyond, pile],
    }
    frames = [(k, 5e-3 * k, parts(np.array([1, 2, 3, 4 if k < 2 else 5]), np.array(rows[k]),
                                  radius=1.5e-4)) for k in range(5)]
    events = {"time": np.array([0.012]), "id": np.array([3]), "position": beyond[None, :],
              "velocity": np.zeros((1, 3)), "orientation": np.array([[1.0, 0, 0, 0]])}
    variables = {k: (repr(v), "", k, repr(v)) for k, v in BOWL.items()}
    path = write_bulk_result(tmp_path / "f.h5", frames, events=events, variables=variables,
                             outlet={"outlet_x": b.outlet_x, "catch_z": -5e-4, "method": "synthetic"})
    with Result(path) as r:
        if per_block is not None:  # blocks that overlap by a frame: the pair 2-3 across two
            import vibrofeed.postproc.path as pp

            monkeypatch.setattr(pp, "BLOCK_VALUES", 4 * r.n_slots * per_block)
        times, ids, where = falls(r, np.arange(5))
        analysis = FeedRate(r, start=0.0, end=0.02, model=False).run()
        later = FeedRate(r, start=0.005, end=0.02, model=False).run().results   # 15 ms
    fr, summary = analysis.results, analysis.summary()
    assert {k: summary[k] for k in ("fell", "fell_per_s")} == {"fell": 1, "fell_per_s": fr.fell_per_s}
    assert ids.tolist() == [1] and times == pytest.approx([0.015], rel=0, abs=1e-12)
    # where it left the helix: its coordinate at the frame before, on the track
    assert where == pytest.approx([float(b.arc_length(b.theta_start + 2.0))], rel=1e-12, abs=0)
    assert fr.fell == 1
    assert fr.fell_per_s == pytest.approx(1 / 0.02, rel=1e-12, abs=0)  # [1/s]
    assert fr.fell_per_s_err == pytest.approx(1 / 0.02, rel=1e-12, abs=0)  # sqrt(1) / 0.02 s
    # per second of the window, not of the time from 0
    assert later.fell == 1 and later.fell_per_s == pytest.approx(1 / 0.015, rel=1e-12, abs=0)
    assert later.fell_per_s_err == pytest.approx(1 / 0.015, rel=1e-12, abs=0)


def test_a_bowls_sections_are_its_helix_and_its_chute(tmp_path):
    """FeedRate splits a bowl's path where the helix ends: by hand, 41 frames a quarter period
    apart (0 to 0.1 s). Part 1 climbs the helix at 2 rad/s throughout; part 2 climbs it at
    2 rad/s and crosses onto the chute at 51.25 ms, then runs along it at 10 mm/s; part 3 runs
    along the chute at 10 mm/s throughout; part 4 climbs the helix at 2 rad/s and falls into
    the pile at 31.25 ms. The helix: speed 2 r_mid / cos(3 deg), hold-up (41 + 21 + 13) / 41,
    1 crossing and 1 fall in 0.1 s (10 /s each); the chute: speed 10 mm/s, hold-up
    (41 + 20) / 41; the models: the helix's dilute limit, the chute's lone part crossing it."""
    from vibrofeed.bowl import chute_speed
    from vibrofeed.cli.feedrate import table
    from vibrofeed.postproc.feedrate import BOWL_SECTIONS, FeedRate

    b = bowl_from(BOWL)
    d = 3e-4  # [m] the spheres' diameter
    a = math.radians(3.0)
    up = np.array([math.cos(a), 0.0, math.sin(a)])  # along the chute

    def chute(s):
        return b.helix_point(THETA_END) + s * up + [0, 0, d / 2]

    def helix(theta):
        return b.helix_point(theta) + [0, 0, d / 2]

    rate, v, cross, fall = 2.0, 0.01, 0.05125, 0.03125  # [rad/s], [m/s], [s], [s]
    pile = np.array([2e-3, 1e-3, 8e-4])
    frames = []
    for k in range(41):
        t = 2.5e-3 * k
        pos = np.array([helix(b.theta_start + 1.0 + rate * t),
                        helix(THETA_END - rate * (cross - t)) if t < cross else chute(v * (t - cross)),
                        chute(1e-3 + v * t),
                        helix(b.theta_start + 3.0 + rate * t) if t < fall else pile])
        frames.append((k, t, parts(np.arange(1, 5), pos, radius=d / 2)))
    events = {"time": np.array([0.001, 0.011, 0.019]), "id": np.array([101, 102, 103]),
              "position": np.tile([b.outlet_x + 1e-4, -b.r_mid, -1e-3], (3, 1)),
              "velocity": np.zeros((3, 3)), "orientation": np.tile([1.0, 0, 0, 0], (3, 1))}
    params = {**BOWL, "amp_n": 1.5e-5}  # (sliding: the chute's model has no flights)
    variables = {k: (repr(v_), "", k, repr(v_)) for k, v_ in params.items()}
    path = write_bulk_result(tmp_path / "s.h5", frames, events=events, variables=variables,
                             outlet={"outlet_x": b.outlet_x, "catch_z": -5e-4, "method": "synthetic"})
    with Result(path) as r:
        analysis = FeedRate(r, start=0.0, end=0.1, batches=5).run()
        found = FeedRate(r).run().summary()  # (the window searched: the bed's pass comes first)
    assert [sec["name"] for sec in found["sections"]] == ["helix", "chute"]
    s = analysis.summary()
    helix_s, chute_s = s["sections"]
    assert [sec["name"] for sec in s["sections"]] == list(BOWL_SECTIONS) == ["helix", "chute"]
    assert (helix_s["x_from"], chute_s["x_to"]) == (0.0, pytest.approx(b.length + b.chute_length, rel=1e-12))
    assert helix_s["x_to"] == chute_s["x_from"] == pytest.approx(b.length, rel=1e-12, abs=0)
    assert helix_s["along"] == chute_s["along"] == "path"  # along the helix, then the chute
    assert helix_s["speed"] == pytest.approx(rate * b.r_mid / math.cos(a), rel=1e-9, abs=0)
    assert chute_s["speed"] == pytest.approx(v, rel=1e-9, abs=0)
    assert helix_s["hold_up"] == pytest.approx((41 + 21 + 13) / 41, rel=1e-12, abs=0)
    assert chute_s["hold_up"] == pytest.approx((41 + 20) / 41, rel=1e-12, abs=0)
    assert helix_s["joint_flux"] == pytest.approx(1 / 0.1, rel=1e-12, abs=0)  # [1/s]
    assert helix_s["reject_rate"] == pytest.approx(1 / 0.1, rel=1e-12, abs=0)  # the fall
    assert chute_s["reject_rate"] == 0.0
    assert helix_s["model_speed"] == pytest.approx(dilute_limit(params)[0], rel=1e-12, abs=0)
    assert helix_s["speed_ratio"] == pytest.approx(helix_s["speed"] / helix_s["model_speed"], rel=1e-12)
    # the chute's model: a lone part's mean speed across it, L / integral dx / v(x) by trapezoids
    # on 9 points from the slot to a part short of the outlet
    xs = np.linspace(0.0, b.chute_length - 3e-4, 9)
    v_x = np.array([chute_speed(params, float(x)).velocity for x in xs])
    harmonic = (xs[-1] - xs[0]) / np.sum(np.diff(xs) * (1 / v_x[1:] + 1 / v_x[:-1]) / 2)
    assert chute_s["model_speed"] == pytest.approx(harmonic, rel=1e-12, abs=0)
    assert chute_s["model_note"] == "" and 0 < chute_s["model_speed"] < helix_s["model_speed"]
    # (a drive that throws the part: no model, and why)
    from vibrofeed.postproc.feedrate import chute_model

    assert chute_model(BOWL)[0] is None and "only slides" in chute_model(BOWL)[1]
    # the sweep's columns: the helix is section 1, the chute 2
    from vibrofeed.sweep.metrics import section_columns

    columns = section_columns(s["sections"], True)
    assert (columns["speed_1"], columns["speed_2"]) == (helix_s["speed"], chute_s["speed"])
    assert columns["joint_flux_1"] == helix_s["joint_flux"] and columns["reject_rate_2"] == 0.0
    text = table(s)
    assert "sections       path [mm]" in text and "fell back [/s]" in text
    assert f"helix: 0 .. {b.length * 1e3:.3g}" in text and "chute: " in text
    assert "helix: " + f"{helix_s['model_speed'] * 1e3:.3g}" in text
    assert "chute: " + f"{chute_s['model_speed'] * 1e3:.4g} mm/s (DEM / model" in text
    # the fall by tooling: this bowl has neither a side drop nor a wiper
    assert s["rejects_by_tooling"]["side_drop"] is None and s["rejects_by_tooling"]["wiper"] is None
    assert {k: s["rejects_by_tooling"]["other"][k] for k in ("in_window", "total")} == \
        {"in_window": 1, "total": 1}
    assert ("fell back by   side drop: none on the bowl; wiper: none on the bowl; other n/a (1 in the "
            "window, 1 in all)") in text  # (n/a: too few exits for a rate)


def test_a_bowls_falls_by_tooling_where_they_left_the_helix():
    """tooling of a bowl's falls: the side drop's stretch (its stations' arc lengths) widened
    by a part size either way; else from 3 part sizes upstream of the wiper's face to its bar's
    end; else other; by hand at each boundary, a nanometre either side."""
    from vibrofeed.feeders import Feeder
    from vibrofeed.postproc.line import TOOLING, tooling

    size = 3e-4
    tooled = {**BOWL, "drop_from": 0.5, "drop_to": 0.7, "drop_width": 4e-4,
              "wiper_height": 4.5e-4, "wiper_at": 0.2}
    b = bowl_from(tooled)
    d0, d1 = (float(b.arc_length(t)) for t in b.drop)
    w0, w1 = (float(b.arc_length(t)) for t in b.wiper)
    eps = 1e-9
    where = np.array([d0 - size - eps, d0 - size + eps, d1 + size - eps, d1 + size + eps,
                      w0 - 3 * size - eps, w0 - 3 * size + eps, w1 - eps, w1 + eps, 0.0])
    want = ["other", "side_drop", "side_drop", "other", "other", "wiper", "wiper", "other", "other"]
    assert [TOOLING[k] for k in tooling(where, 1, Feeder.from_values(tooled).stations, size)] == want
    plain = Feeder.from_values(BOWL)  # no tooling: every fall is other
    assert set(tooling(where, 1, plain.stations, size)) == {TOOLING.index("other")}


def test_no_falls_on_a_linear_track_nor_in_fewer_than_two_frames(tmp_path):
    """falls: three empty arrays (the ids integers) on a linear track, and in a bowl's result
    given a single frame (no pair of frames to fall between)."""
    from vibrofeed.postproc.path import falls

    with Result(linear_result(tmp_path / "l.h5", OUTLET)) as r:
        found = [falls(r, np.arange(3)), falls(r, [])]
    b = bowl_from(BOWL)
    points = np.array([b.helix_point(b.theta_start + 2.0) + [0, 0, 1.5e-4]])
    write_bowl(tmp_path / "b.h5", [0.0, 0.0], [0.0, 0.0], points)
    with Result(tmp_path / "b.h5") as r:
        found.append(falls(r, [1]))
    for times, ids, where in found:
        assert (times.shape, ids.shape, where.shape) == ((0,), (0,), (0,))
        assert ids.dtype == np.int64


def test_a_fall_is_into_the_bowl_within_its_wall_whichever_way_from_the_axis(tmp_path):
    """Four parts on the helix at frame 0; at frame 1 parts 1 and 2 lie in the pile near the
    wall, 8 mm from the axis along +y and +x (inside the 10 mm wall: falls), parts 3 and 4 have
    left over the chute's end, 12 mm from the axis and more (outside it: no falls), one 6 mm
    aside of the chute's line, one beyond its end on it: the distance from the axis is the
    hypotenuse of both coordinates, not either alone."""
    from vibrofeed.postproc.path import falls

    b = bowl_from(BOWL)
    on = b.helix_point(b.theta_start + np.array([1.0, 2.0, 3.0, 4.0])) + [0, 0, 1.5e-4]
    away = np.array([[0.0, 8e-3, 2e-4], [8e-3, 0.0, 2e-4],
                     [b.outlet_x + 4e-3, -6e-3, -3e-4], [b.outlet_x + 4e-3, -b.r_mid, -3e-4]])
    assert np.all(np.hypot(away[:2, 0], away[:2, 1]) < b.radius - b.track_width)  # the pile
    assert np.all(np.hypot(away[2:, 0], away[2:, 1]) > 1.2e-2)
    frames = [(k, 5e-3 * k, parts(np.arange(1, 5), pos, radius=1.5e-4)) for k, pos in enumerate((on, away))]
    variables = {k: (repr(v), "", k, repr(v)) for k, v in BOWL.items()}
    path = write_bulk_result(tmp_path / "f.h5", frames, variables=variables,
                             outlet={"outlet_x": b.outlet_x, "catch_z": -5e-4, "method": "synthetic"})
    with Result(path) as r:
        times, ids, where = falls(r, np.arange(2))
    assert ids.tolist() == [1, 2] and times == pytest.approx([5e-3, 5e-3], rel=0, abs=1e-12)
    assert where == pytest.approx(b.arc_length(b.theta_start + np.array([1.0, 2.0])), rel=1e-12, abs=0)
