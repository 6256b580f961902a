"""An air jet on a bowl's helix (vibrofeed.feeders.bowl.BowlElement, vibrofeed.engine.jets),
against geometry by hand: its camera senses by the helix's path coordinate, its block is six
planes turned with the helix where it stands, it blows towards the axis (the track's open inner
edge: a part blown off falls back into the bowl); its slips are one line naming the bowl's key.

The bowl: 20 mm across, a 1.2 mm track (centre line radius 9.4 mm) climbing 3 degrees for half a
turn, counter-clockwise from the polar angle -270 to -90 degrees (the chute's start), 29.6 mm of
helix. A jet at 0.6 of it senses at -162 degrees; its block, 1 mm long and 0.5 mm past the camera,
is centred 0.5 mm further round (3.05 degrees at 9.4 mm, the helix's 3 degrees counted along it)."""

import math

import numpy as np
import pytest

from vibrofeed.bowl import path_coordinate
from vibrofeed.engine.jets import Jets
from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.deck import line_files

R, W, HELIX = 0.01, 1.2e-3, 3.0
R_MID = R - W / 2
COS = math.cos(math.radians(HELIX))
HELIX_LENGTH = math.pi * R_MID / COS
THETA_CAM = math.radians(-270 + 0.6 * 180)  # the helix climbs from -270 to -90 degrees
# chips face down on the helix lie turned half a turn about x (quaternions w, x, y, z)
UP, DOWN = (1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0)
TOL = 1e-12


def values(**more):
    return {"bowl_diameter": 2 * R, "track_width": W, "helix_angle": HELIX, "turns": 0.5,
            "wall_height": 1e-3, "cross_tilt": 3.0, "chute_length": 6e-3, "shape": 1,
            "part_size": 5e-4, "part_thickness": 2.5e-4, "freq": 75, "amp_t": 2e-4, "amp_n": 4e-5,
            "phase": -60, "jet_force": 4e-6, "jet_at": 0.6, "jet_keep": "up,any-direction",
            "jet_mode": "ideal", **more}


def test_the_bowls_jet_is_read_under_its_decks_own_names_and_is_a_station_of_the_helix():
    f = Feeder.from_values(values(jet_offset=5e-4, jet_length=1e-3, jet_headway=0.01))
    f.check()
    bowl = f.elements[0]
    assert f.has_jets and bowl.jet.force == 4e-6 and bowl.jet.mode == "ideal"
    assert bowl.jet.headway == 0.01 and str(bowl.jet.keep).startswith("up")
    assert bowl.sensing == pytest.approx(0.6 * HELIX_LENGTH, rel=0, abs=1e-15)
    (st,) = [s for s in f.stations if s.kind == "jet"]
    centre = 0.6 * HELIX_LENGTH + 5e-4
    assert (st.section, st.element) == (1, 1)
    assert (st.start, st.end) == (pytest.approx(centre - 5e-4, rel=0, abs=1e-15),
                                  pytest.approx(centre + 5e-4, rel=0, abs=1e-15))
    plain = {k: v for k, v in values().items() if not k.startswith("jet_")}
    assert Feeder.from_values(plain).has_jets is False


def test_its_block_is_turned_with_the_helix_and_blows_towards_the_axis():
    f = Feeder.from_values(values(jet_offset=5e-4, jet_length=1e-3))
    bowl, part = f.elements[0], f.part
    theta = THETA_CAM + 5e-4 * COS / R_MID
    c, t, n = bowl.jet_frame(part.size)
    assert np.abs(c[:2] - R_MID * np.array([math.cos(theta), math.sin(theta)])).max() <= TOL
    assert c[2] == pytest.approx(float(bowl.bowl.floor_z(theta, R_MID)), rel=0, abs=TOL)
    assert np.abs(t - [-math.sin(theta), math.cos(theta), 0.0]).max() <= TOL
    assert np.abs(n - [-math.cos(theta), -math.sin(theta), 0.0]).max() <= TOL  # the axis's way
    planes = bowl.jet_planes(part)

    def within(p):
        return all(np.dot(p - q, m) >= 0 for q, m in planes)

    lift = np.array([0.0, 0.0, 1e-4])
    half_w = W / 2 + 2 * part.widest
    for face in (c - 0.5e-3 * t, c + 0.5e-3 * t, c - half_w * n, c + half_w * n):
        way = (face - c) / np.linalg.norm(face - c)
        assert within(face - 1e-6 * way + lift) and not within(face + 1e-6 * way + lift)
    # from below the floor at the block's far edge (its tilt across, the lift and a part) to
    # 9/10 of a pitch above it: the turn above (none here) would lie a pitch up
    pitch = 2 * math.pi * R_MID * math.tan(math.radians(HELIX))
    top = c[2] + 0.9 * pitch
    bottom = c[2] - half_w * math.tan(math.radians(3.0)) - 4e-5 - part.widest
    assert within(np.array([*c[:2], top - 1e-7])) and not within(np.array([*c[:2], top + 1e-7]))
    assert within(np.array([*c[:2], bottom + 1e-7])) and not within(np.array([*c[:2], bottom - 1e-7]))


def test_its_commands_go_into_the_line_files_of_a_bowl_alone_with_the_force_towards_the_axis():
    f = Feeder.from_values(values(jet_offset=5e-4, jet_length=1e-3))
    motion = line_files(f)["line_motion.in"].splitlines()
    assert sum(" plane " in line for line in motion) == 6
    assert "region s1_jet intersect 6 s1_jet_1 s1_jet_2 s1_jet_3 s1_jet_4 s1_jet_5 s1_jet_6" in motion
    assert "variable s1_jet_on atom 0" in motion
    assert "fix s1_jet s1_jet_parts addforce v_s1_jet_fx v_s1_jet_fy v_s1_jet_fz region s1_jet" in motion
    theta = THETA_CAM + 5e-4 * COS / R_MID
    for axis, want in (("fx", -math.cos(theta)), ("fy", -math.sin(theta))):
        line = next(x for x in motion if x.startswith(f"variable s1_jet_{axis}"))
        assert "v_jet_force/v_body_spheres*cos((v_jet_angle+v_cross_tilt)*PI/180)" in line
        assert float(line.rsplit("*", 1)[1].rstrip(")")) == pytest.approx(want, rel=0, abs=1e-15)
    # without a jet a bowl alone's line files hold its wall contact only, as before
    plain = Feeder.from_values({k: v for k, v in values().items() if not k.startswith("jet_")})
    assert line_files(plain)["line_motion.in"].count("\n") == 1


def test_the_driver_senses_a_chip_crossing_the_camera_along_the_helix():
    f = Feeder.from_values(values())
    b = f.elements[0].bowl
    jets = Jets(f)
    (s,) = jets.stations
    assert (s.section, s.path_section) == (1, 1)
    assert s.x_sense == pytest.approx(0.6 * HELIX_LENGTH, rel=0, abs=1e-15)
    assert np.allclose(s.tangent, (-math.sin(THETA_CAM), math.cos(THETA_CAM), 0.0), rtol=0, atol=TOL)

    def frame(ids, arcs, q):  # chips on the centre line, 0.1 mm above its floor, ``arcs`` [m] up it
        theta = b.theta_start + np.asarray(arcs) * COS / R_MID
        p = b.helix_point(theta) + [0.0, 0.0, 1e-4]
        q = np.asarray(q, dtype=float).reshape(-1, 4)
        return {"id": np.asarray(ids), "position": p, "orientation": q}

    cam = 0.6 * HELIX_LENGTH
    assert path_coordinate(b, frame([1], [cam], [UP])["position"])[0] == pytest.approx(cam, abs=1e-12)
    jets.step(None, 0.0, frame([1, 2], [cam - 1e-4, cam - 2e-4], [DOWN, UP]))
    commands, table = jets.step(None, 0.01, frame([1, 2], [cam + 1e-4, cam + 2e-4], [DOWN, UP]))
    # both crossed; the face-down one is fired at, halfway between the frames
    assert table["id"].tolist() == [1] and table["section"].tolist() == [1]
    assert table["time"] == pytest.approx([0.005], rel=0, abs=1e-12)
    assert commands[0] == "group s1_jet_parts delete" and commands[1].startswith("group s1_jet_parts id ")
    assert commands[2].startswith("variable s1_jet_on atom")
    assert commands[3].startswith("fix s1_jet s1_jet_parts ")
    # a chip in the pile below the camera's polar angle is not on the helix: never sensed
    pile = {"id": np.array([3]), "position": np.array([[0.5 * R * math.cos(THETA_CAM),
                                                       0.5 * R * math.sin(THETA_CAM), 1e-4]]),
            "orientation": np.array([DOWN])}
    assert np.isnan(path_coordinate(b, pile["position"])[0])


@pytest.mark.parametrize("change, words", [
    ({"jet_at": 1.2}, "jet_at=1.2: the sensing point lies outside"),
    ({"jet_keep": "up|down|side|end,any-direction"}, "jet_keep="),
    ({"jet_mode": "gentle"}, "jet_mode=gentle must be region or ideal"),
    ({"jet_delay": -1}, "jet_delay=-1 must be >= 0"),
    ({"jet_headway": -1}, "jet_headway=-1 must be >= 0"),
    ({"shape": 0}, "jet_force=4e-06 N: a jet sorts parts by their orientation"),
])
def test_a_bowls_bad_jet_is_one_line_naming_its_key(change, words):
    with pytest.raises(ParameterError) as info:
        Feeder.from_values(values(**change)).check()
    assert words in str(info.value) and "\n" not in str(info.value)
    assert "s1_" not in str(info.value) and "s2_" not in str(info.value)
