"""A slot trap in a linear section's floor: its mesh (the hole's edges, the floor's area, one
connected manifold surface around it), its keys and deck names, its checks, and the rejects'
attribution to it."""

import math
import warnings
from collections import Counter

import numpy as np
import pytest

from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.linear import SlotWarning, deck_name
from vibrofeed.line import Section, section_mesh
from vibrofeed.postproc.line import TOOLING, tooling

TOL = 1e-12
# boxes 0.4 x 0.3 x 0.1 mm on a section 0.6 mm wide, a slot 0.13 mm wide (T < it < W/2)
BOX = {"shape": 3, "part_size": 4e-4, "part_width": 3e-4, "part_thickness": 1e-4}
LINE = {**BOX, "sections": 2, "track_length": 3e-3, "track_width": 1e-3, "gate_width": 6e-4,
        "gate_at": 0.6, "wall_height": 1e-3, "s2_length": 1.4e-3,
        "s2_width": 6e-4, "s2_wall_height": 1e-3, "s2_step": 4e-5, "s2_cross_tilt": 3.0,
        "s2_slot_from": 0.3, "s2_slot_to": 0.75, "s2_slot_width": 1.3e-4}


def section(**kw) -> Section:
    base = dict(x0=0.01, length=4e-3, width=6e-4, wall_height=6e-4, step=5e-5, cross_tilt=10.0,
                slot_from=0.25, slot_to=0.6, slot_width=1.3e-4, slot_offset=2e-4)
    return Section(**{**base, **kw})


def edge_counts(t):
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    return Counter(map(tuple, np.sort(e, axis=1)))


def floor_triangles(s, v, t):
    """The triangles lying on the floor's plane."""
    c = v[t]
    return t[np.all(np.isclose(c[..., 2], s.floor_z(c[..., 1]), rtol=0, atol=TOL), axis=1)]


def area(v, t):
    c = v[t]
    return 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum()


@pytest.mark.parametrize("offset", [2e-4, 6.5e-5])  # past a ledge; along the wall (the default)
def test_the_hole_has_exactly_the_slots_edges(offset):
    s = section(slot_offset=offset)
    v, t = section_mesh(s)
    (x0, x1), (y0, y1) = s.slot_x, s.slot_y
    assert math.isclose(y1 - y0, s.slot_width) and math.isclose((y0 + y1) / 2, -s.width / 2 + offset)
    opened = [v[list(e)] for e, n in edge_counts(t).items() if n == 1]
    # the open edges on the floor inside the slot's rectangle are its outline, and all of it
    inside = [e for e in opened if np.all((e[:, 0] >= x0 - TOL) & (e[:, 0] <= x1 + TOL)
                                          & (e[:, 1] >= y0 - TOL) & (e[:, 1] <= y1 + TOL)
                                          & np.isclose(e[:, 2], s.floor_z(e[:, 1]), rtol=0, atol=TOL))]
    along = sum(abs(e[1, 0] - e[0, 0]) for e in inside if np.isclose(e[0, 1], e[1, 1], rtol=0, atol=TOL))
    across = sum(abs(e[1, 1] - e[0, 1]) for e in inside if np.isclose(e[0, 0], e[1, 0], rtol=0, atol=TOL))
    assert math.isclose(along, 2 * (x1 - x0), rel_tol=1e-9)
    assert math.isclose(across, 2 * (y1 - y0), rel_tol=1e-9)


def test_the_floor_is_the_full_floor_less_the_slot():
    s = section()
    v, t = section_mesh(s)
    tilt = math.cos(math.radians(s.cross_tilt))
    full = s.length * s.width / tilt
    hole = (s.slot_x[1] - s.slot_x[0]) * s.slot_width / tilt
    assert math.isclose(area(v, floor_triangles(s, v, t)), full - hole, rel_tol=1e-9)
    v0, t0 = section_mesh(section(slot_to=0.0))  # no slot: the whole floor
    assert math.isclose(area(v0, floor_triangles(s, v0, t0)), full, rel_tol=1e-9)


@pytest.mark.parametrize("kw", [{}, {"slot_offset": 6.5e-5}, {"drop_from": 0.7, "drop_to": 0.9,
                                                            "drop_width": 4e-4}])
def test_one_connected_manifold_surface_around_the_hole(kw):
    v, t = section_mesh(section(**kw))
    counts = edge_counts(t)
    assert max(counts.values()) <= 2  # no edge shared by three faces
    # no T-junction: no vertex lies inside another triangle's edge
    for (a, b) in counts:
        p, q = v[a], v[b]
        d = q - p
        u = (v - p) @ d / (d @ d)
        off = np.linalg.norm(v - p - np.outer(u, d), axis=1)
        assert not np.any((u > 1e-9) & (u < 1 - 1e-9) & (off < 1e-12))
    # connected through shared edges
    parent = list(range(len(t)))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    by_edge = {}
    for k, tri in enumerate(t):
        for e in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            key = tuple(sorted(e))
            if key in by_edge:
                parent[root(k)] = root(by_edge[key])
            by_edge[key] = k
    assert len({root(k) for k in range(len(t))}) == 1


def test_the_keys_deck_names_and_default_place():
    assert [deck_name(3, ("slot", k)) for k in ("from", "to", "width", "offset")] == [
        "s3_slot_from", "s3_slot_to", "s3_slot_width", "s3_slot_offset"]
    assert deck_name(1, ("slot", "width")) is None  # not on the first section
    f = Feeder.from_values(LINE)
    slot = f.elements[1].slot
    assert (slot.start, slot.end, slot.width) == (0.3, 0.75, 1.3e-4)
    assert slot.offset == 1.3e-4 / 2  # along the wall
    ((station),) = [st for st in f.stations if st.kind == "slot"]  # (section 1's gate too)
    assert station.kind == "slot" and station.section == 2
    assert math.isclose(station.start, 3e-3 + 0.3 * 1.4e-3)
    assert math.isclose(station.end, 3e-3 + 0.75 * 1.4e-3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        f.check()  # T < width < W/2, along the wall: no word
    assert Feeder.from_values({**LINE, "s2_slot_to": 0.3}).elements[1].slot is None  # to <= from: none


def test_rejects_in_the_slots_stretch_are_the_slots():
    f = Feeder.from_values(LINE)
    (slot,) = [st for st in f.stations if st.kind == "slot"]
    a, b = slot.start, slot.end
    size = BOX["part_size"]
    where = np.array([a, (a + b) / 2, b + size, b + 1.5 * size, 3.01e-3])
    assert [TOOLING[k] for k in tooling(where, 2, f.stations, size)] == [
        "slot", "slot", "slot", "other", "other"]


@pytest.mark.parametrize("given, words", [
    ({"s2_slot_to": 1.2}, "s2_slot_to=1.2: the slot lies outside section 2"),
    ({"s2_slot_width": 6e-4}, "s2_slot_width=0.0006 m must be > 0 and narrower than the floor"),
    ({"s2_slot_offset": 5.8e-4}, "s2_slot_offset=0.00058 m: the slot (0.00013 m across) runs under a wall"),
    ({"s2_drop_from": 0.5, "s2_drop_to": 0.9, "s2_drop_width": 4.5e-4},
     "the slot overlaps the side drop (s2_drop_from)"),
    ({"s2_wiper_height": 3e-4, "s2_wiper_at": 0.6}, "the slot overlaps the wiper (s2_wiper_at)"),
])
def test_slots_that_cannot_be_built_are_refused_in_one_line(given, words):
    with pytest.raises(ParameterError) as e:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            Feeder.from_values({**LINE, **given}).check()
    assert words in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize("given, words", [
    ({"s2_slot_width": 8e-5}, "s2_slot_width=8e-05 m is no wider than a part's thinnest dimension"),
    ({"s2_slot_width": 4.5e-4, "s2_width": 1e-3}, "the slot rejects everything"),
    ({"s2_slot_width": 1.6e-4}, "no narrower than half a part's width (0.00015 m)"),
    ({"s2_slot_offset": 1.5e-4}, "leaves a ledge 8.5e-05 m wide"),
    ({"shape": 0, "part_size": 1e-4, "s2_slot_width": 1.3e-4}, "spheres bridge the slot or fall"),
])
def test_slots_that_cannot_sort_are_a_warning_naming_the_key(given, words):
    with pytest.warns(SlotWarning) as caught:
        Feeder.from_values({**LINE, **given}).check()
    assert any(words in str(w.message) for w in caught)
    assert all("\n" not in str(w.message) for w in caught)
