"""`vibrofeed check` fails a file that breaks any one of its rules (FORMAT.md, "What
`vibrofeed check` checks"), so that a damaged or incomplete result is never taken as good.

Each test starts from a file that passes (written through the writer), breaks one rule (in the
writer's inputs, or by editing the file with h5py) and expects that rule's error at the path it
concerns; where the file breaks nothing else, that error alone. The physical limits are
computed here from FORMAT.md's formulas, not taken from the checker.
"""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest

from helpers import parts, write_bulk_result, write_result
from vibrofeed.results import check as check_module
from vibrofeed.results import layout as L
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import Recording, ResultWriter

G = 9.81  # m/s^2, FORMAT.md's g
FREQ_ONLY = {"freq": ("50", "Hz", "vibration frequency", "50")}  # no amplitude: no surface speed
DRIVE = {"freq": ("100", "Hz", "", "100"), "amp_t": ("3e-5", "m", "", "0"), "amp_n": ("4e-5", "m", "", "0")}
DRIVE_PEAK = 2 * math.pi * 100 * math.hypot(3e-5, 4e-5)  # m/s: 2 pi freq sqrt(amp_t^2 + amp_n^2)
FLOOR = (np.array([[0, -1e-3, 0], [0.02, -1e-3, 0], [0.02, 1e-3, 0], [0, 1e-3, 0.0]]),
         np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32))  # a flat 20 x 2 mm track at z = 0


def problems(path, **kw):
    return [f"{p.level}: /{p.where}: {p.message}" for p in check_file(path, **kw).problems]


def errors(path, **kw):
    return [p for p in problems(path, **kw) if p.startswith("error")]


def has(found, where, text):
    return any(f"/{where}: " in p and text in p for p in found)


def copy(src, dst):
    dst.write_bytes(src.read_bytes())
    return dst


def sequence(path, frames, variables=FREQ_ONLY, track=None, surface=None):
    """A complete result from ``frames`` of (time, ids, positions, velocities or None), the k-th
    at step k; parts of radius 0.5 mm and 1 mg."""
    return write_bulk_result(path, [(k, t, parts(ids, x, velocity=v))
                                    for k, (t, ids, x, v) in enumerate(frames)],
                             variables=variables, track=track, surface=surface)


# -- the base files: each passes, without a single problem -------------------------------------
Q = np.array([math.cos(0.4), 0, math.sin(0.4), 0])  # a unit quaternion
IDENTITY = [1.0, 0, 0, 0]
TEMPLATE = np.array([[-1e-4, 0, 0, 7.5e-5], [1e-4, 0, 0, 7.5e-5]])


def write_bulk(path, track_sections=None):
    """Part 2 leaves the track at 7 ms (outlet event), falls through frame 1 and is gone at
    frame 2; part 1 rides on. Orientation, outlet, mass balance, track mesh, clump template."""
    def with_q(p, qs):
        p["orientation"] = np.array(qs, float)
        return p

    frames = [(0, 0.0, with_q(parts([1, 2], [[0, 0, 1e-4], [19e-3, 0, 1e-4]]), [IDENTITY, Q])),
              (1, 0.01, with_q(parts([1, 2], [[1e-3, 0, 1e-4], [20.5e-3, 0, -4e-4]]), [IDENTITY, Q])),
              (2, 0.02, with_q(parts([1], [[2e-3, 0, 1e-4]]), [IDENTITY]))]
    counts = [dict(inserted=2, on_track=2, exited=0, lost=0), dict(inserted=2, on_track=1, exited=1, lost=0),
              dict(inserted=2, on_track=1, exited=1, lost=0)]
    events = {"time": [0.007], "id": [2], "position": [[20.2e-3, 0, -3e-4]],
              "velocity": [[0.04, 0, -0.05]], "orientation": [Q]}
    if track_sections is None:
        return write_bulk_result(path, frames, events=events, counts=counts, track=FLOOR,
                                 body_template=TEMPLATE)
    w = ResultWriter(path, deck_name="d", deck_path="d", deck_text="d", variables=FREQ_ONLY,
                     derived={"dt_used": 1e-6}, engine_version="LIGGGHTS (synthetic)", seed=1,
                     run_id="a" * 64, track=FLOOR, track_sections=track_sections)
    for step, t, p in frames:
        del p["orientation"]
        w.write_frame(step, t, p, np.zeros(3), np.zeros(3))
    w.finish()
    return path


@pytest.fixture(scope="module")
def bulk(tmp_path_factory):
    path = write_bulk(tmp_path_factory.mktemp("base") / "bulk.h5")
    assert problems(path) == []
    return path


def test_the_base_files_pass_without_a_problem(bulk, tmp_path):
    report = check_file(bulk)
    assert report.ok and report.problems == []
    assert (report.frames, report.parts, report.status) == (3, 2, "complete")
    assert problems(write_bulk(tmp_path / "split.h5", track_sections=[1, 1, 1, 1])) == []


# -- layout: one corruption each ---------------------------------------------------------------
def _replace(group, name, data, **kw):
    """Replace dataset ``name`` of ``group`` by ``data``, keeping its attributes."""
    attrs = dict(group[name].attrs)
    del group[name]
    ds = group.create_dataset(name, data=data, **kw)
    for k, v in attrs.items():
        ds.attrs[k] = v


def _set(path, index, value):
    def edit(f):
        data = f[path][()]
        data[index] = value
        f[path][...] = data
    return edit


def _shift_step(element):
    def edit(f):
        g = f[element]
        step = g["step"][()]
        del g["step"]
        g["step"] = step + 1   # the same length, strictly increasing: other values
    return edit


def _float_values(path):
    def edit(f):
        group, name = path.rsplit("/", 1)
        _replace(f[group], name, f[path][()].astype(float))
    return edit


def _resize(path, n, axis):
    return lambda f: f[path].resize(n, axis=axis)


def _del(path):
    def edit(f):
        del f[path]
    return edit


def _attr(path, name, value=None):
    def edit(f):
        if value is None:
            del f[path].attrs[name]
        else:
            f[path].attrs[name] = value
    return edit


def _fill_value(f):
    g = f[f"{L.PARTS}/id"]
    _replace(g, "value", g["value"][()], fillvalue=0)


def _quaternion_norm(norm):
    return _set(f"{L.PARTS}/orientation/value", (1, 1), norm * Q)


def _text_dataset(path, text):
    def edit(f):
        group, name = path.rsplit("/", 1)
        _replace(f[group], name, text, dtype=h5py.string_dtype())
    return edit


def _no_variables(f):
    for name in list(f[L.VARIABLES]):
        del f[f"{L.VARIABLES}/{name}"]


def _h5md_dataset(f):
    del f["h5md"]
    f["h5md"] = 1


def _values(path, make):
    """Replace a series' value by ``make(value)``, its unit kept."""
    def edit(f):
        group = path.rsplit("/", 1)[0]
        _replace(f[group], "value", make(f[path][()]))
    return edit


P, OUT, MB, T, S, R = L.PARTS, L.OUTLET, L.MASS_BALANCE, L.TRACK, L.SURFACE, L.RUN
EARLY = "target error 0.03 reached: 0.028 at t = 0.02 s"
TARGET = "attribute 'target_error' must be a number in (0, 1)"
CORRUPTIONS = {
    # h5md
    "h5md a dataset": (_h5md_dataset, "h5md", "must be a group"),
    "no author": (_del("h5md/author"), "h5md/author", "missing"),
    "author without name": (_attr("h5md/author", "name"), "h5md/author", "attribute 'name' missing"),
    "empty creator version": (_attr("h5md/creator", "version", np.bytes_(b"")), "h5md/creator",
                              "attribute 'version' is empty"),
    # any time series
    "no value": (_del(f"{P}/mass/value"), f"{P}/mass/value", "missing"),
    "no time": (_del(f"{S}/velocity/time"), f"{S}/velocity/time", "missing"),
    "rank": (_values(f"{P}/species/value", lambda v: v[..., None]), f"{P}/species/value",
             "rank 3, expected 2"),
    "last dimension": (_values(f"{P}/velocity/value", lambda v: v[..., :2]), f"{P}/velocity/value",
                       "last dimension 2, expected 3"),
    # particles
    "no box": (_del(f"{P}/box"), f"{P}/box", "missing"),
    "box dimension": (_attr(f"{P}/box", "dimension", 2), f"{P}/box", "attribute 'dimension' must be 3"),
    "two boundaries": (_attr(f"{P}/box", "boundary", np.array([b"none", b"none"])), f"{P}/box",
                       "attribute 'boundary' must be 3 of none/periodic"),
    "unknown boundary": (_attr(f"{P}/box", "boundary", np.array([b"none", b"wall", b"none"])), f"{P}/box",
                         "attribute 'boundary' must be 3 of none/periodic"),
    "other steps": (_shift_step(f"{P}/velocity"), f"{P}/velocity/step", "differs from position/step"),
    "id fill value": (_fill_value, f"{P}/id/value", "fill value must be -1, got 0"),
    "negative id": (_set(f"{P}/id/value", (2, 0), -5), f"{P}/id/value",
                    "frame 2: negative id other than the fill value"),
    "non-finite position": (_set(f"{P}/position/value", (1, 0, 0), np.nan), f"{P}/position/value",
                            "an existing particle has a non-finite position"),
    "float step": (_float_values(f"{P}/position/step"), f"{P}/position/step", "must be of integer type"),
    "time without unit": (_attr(f"{P}/position/time", "unit"), f"{P}/position/time",
                          "unit attribute must be 's'"),
    "time backwards": (_set(f"{P}/position/time", 2, 0.005), f"{P}/position/time",
                       "not monotonically increasing"),
    "step repeated": (_set(f"{P}/position/step", 2, 1), f"{P}/position/step", "not strictly increasing"),
    "short value": (_resize(f"{P}/position/value", 2, 0), f"{P}/position",
                    "step (3), time (3) and value (2) frame counts differ"),
    "fewer slots": (_resize(f"{P}/radius/value", 1, 1), P, "elements disagree on (frames, slots)"),
    # orientation
    "quaternion 2e-6 long": (_quaternion_norm(1 + 2e-6), f"{P}/orientation/value",
                             "an existing part's orientation is not a unit quaternion"),
    "half quaternion": (_quaternion_norm(0.5), f"{P}/orientation/value",
                        "an existing part's orientation is not a unit quaternion"),
    "NaN quaternion": (_quaternion_norm(np.nan), f"{P}/orientation/value",
                       "an existing part's orientation is not a unit quaternion"),
    "quaternion in an empty slot": (_set(f"{P}/orientation/value", (2, 1), IDENTITY),
                                    f"{P}/orientation/value", "empty slots (id -1) must hold NaN"),
    "orientation steps": (_shift_step(f"{P}/orientation"), f"{P}/orientation/step",
                          "differs from position/step"),
    "orientation slots": (_resize(f"{P}/orientation/value", 3, 1), f"{P}/orientation/value",
                          "(frames, slots) (3, 3), id has (3, 2)"),
    # reported, not a crash of the unit-length test (one value per part: rank 2)
    "orientation of rank 2": (_values(f"{P}/orientation/value", lambda v: v[..., 0]),
                              f"{P}/orientation/value", "rank 2, expected 3"),
    # the surface's motion (none at all: its elements are missing, the drive checks skip it)
    "no surface": (_del(S), f"{S}/position", "missing"),
    "surface at other frames": (_shift_step(f"{S}/velocity"), f"{S}/velocity/step",
                                "not sampled at the particle frames"),
    "non-finite surface": (_set(f"{S}/position/value", (1, 2), np.nan), f"{S}/position/value",
                           "non-finite values"),
    # the outlet's event table
    "no method": (_attr(OUT, "method"), OUT, "attribute 'method' missing"),
    "event unit": (_attr(f"{OUT}/position", "unit", "mm"), f"{OUT}/position", "unit attribute must be 'm'"),
    "no event orientation": (_del(f"{OUT}/orientation"), f"{OUT}/orientation", "missing"),
    "events of two lengths": (_resize(f"{OUT}/id", 0, 0), OUT, "the event datasets differ in length"),
    "non-finite event": (_set(f"{OUT}/velocity", (0, 2), np.inf), f"{OUT}/velocity", "non-finite values"),
    "misshapen event": (lambda f: _replace(f[OUT], "time", f[f"{OUT}/time"][()][:, None]), f"{OUT}/time",
                        "shape (1, 1), expected (E)"),
    # the mass balance's series
    "count missing": (_del(f"{MB}/exited"), f"{MB}/exited", "missing"),
    "count not an integer": (_float_values(f"{MB}/lost/value"), f"{MB}/lost/value",
                             "must be of integer type"),
    "count at other frames": (_shift_step(f"{MB}/lost"), f"{MB}/lost/step",
                              "not sampled at the particle frames"),
    # the track mesh and the clump template
    "no triangles": (_del(f"{T}/triangles"), f"{T}/triangles", "missing"),
    "no vertices": (_del(f"{T}/vertices"), f"{T}/vertices", "missing"),
    "triangle index -1": (_set(f"{T}/triangles", (1, 2), -1), f"{T}/triangles",
                          "index a vertex that does not exist"),
    "triangle index V": (_set(f"{T}/triangles", (1, 2), 4), f"{T}/triangles",
                         "index a vertex that does not exist"),
    "non-finite vertex": (_set(f"{T}/vertices", (2, 1), np.nan), f"{T}/vertices", "must be (V, 3) finite"),
    "float triangles": (_float_values(f"{T}/triangles"), f"{T}/triangles", "must be (T, 3) integers"),
    "vertices without unit": (_attr(f"{T}/vertices", "unit"), f"{T}/vertices", "unit attribute must be 'm'"),
    "sphere of radius 0": (_set(L.BODY_TEMPLATE, (1, 3), 0.0), L.BODY_TEMPLATE,
                           "non-finite values or radii <= 0"),
    "negative radius": (_set(L.BODY_TEMPLATE, (0, 3), -7.5e-5), L.BODY_TEMPLATE,
                        "non-finite values or radii <= 0"),
    "non-finite template": (_set(L.BODY_TEMPLATE, (0, 1), np.nan), L.BODY_TEMPLATE,
                            "non-finite values or radii <= 0"),
    "template of x, y, z": (lambda f: _replace(f[L.PARAMETERS], "body_template", TEMPLATE[:, :3]),
                            L.BODY_TEMPLATE, "must be an (n, 4) dataset: x, y, z, r"),
    # the parameters and the run
    "no parameters": (_del(L.PARAMETERS), L.PARAMETERS, "missing"),
    "no engine version": (_del(f"{L.PARAMETERS}/liggghts_version"), f"{L.PARAMETERS}/liggghts_version",
                          "missing"),
    "blank deck": (_text_dataset(f"{L.PARAMETERS}/deck", " \n"), f"{L.PARAMETERS}/deck",
                   "deck text is empty"),
    "another engine": (_text_dataset(f"{L.PARAMETERS}/liggghts_version", "LAMMPS (2 Aug 2023)"),
                       f"{L.PARAMETERS}/liggghts_version", "does not name a LIGGGHTS version"),
    "no variables": (_no_variables, L.VARIABLES, "no deck variables recorded"),
    "variable without unit": (_attr(f"{L.VARIABLES}/freq", "unit"), f"{L.VARIABLES}/freq",
                              "attribute 'unit' missing"),
    "no derived values": (_del(L.DERIVED), L.DERIVED, "missing"),
    "no run": (_del(R), R, "missing"),
    "failed": (_attr(R, "status", "failed"), R, "run status is 'failed'"),
    "interrupted with a message": (lambda f: f[R].attrs.update(status="interrupted", message="Ctrl-C"),
                                   R, "run status is 'interrupted': Ctrl-C"),
    "target error 1": (_attr(R, "target_error", 1.0), R, TARGET),
    "target error 0": (_attr(R, "target_error", 0.0), R, TARGET),
    "target error text": (_attr(R, "target_error", "0.03"), R, TARGET),
    "target errors": (_attr(R, "target_error", [0.03, 0.05]), R, TARGET),
    "unknown stop reason": (_attr(R, "stop_reason", "killed"), R, "attribute 'stop_reason' must start "
                            "with 't_end' or 'target error', got 'killed'"),
    "early stop without target": (_attr(R, "stop_reason", EARLY), R, "attribute 'stop_reason' says the "
                                  "target error was reached, but the run records no 'target_error'"),
}


@pytest.mark.parametrize("name", CORRUPTIONS)
def test_check_fails_each_corruption_where_it_is(bulk, tmp_path, name):
    corrupt, where, message = CORRUPTIONS[name]
    path = copy(bulk, tmp_path / "bad.h5")
    with h5py.File(path, "r+") as f:
        corrupt(f)
    found = errors(path)
    assert has(found, where, message), found


@pytest.mark.parametrize("attrs", [
    {"stop_reason": "t_end"}, {"stop_reason": EARLY, "target_error": 0.03}, {"target_error": 0.5},
    {"stop_reason": "t_end (target error 0.03 not reached: 0.05)", "target_error": 0.03}])
def test_a_recorded_stop_and_target_error_pass(bulk, tmp_path, attrs):
    path = copy(bulk, tmp_path / "stop.h5")
    with h5py.File(path, "r+") as f:
        f[L.RUN].attrs.update(attrs)
    assert problems(path) == []


def test_a_malformed_run_id_is_a_warning(bulk, tmp_path):
    """--reuse cannot recognise the run; its results stay valid."""
    for rid in ("a" * 63, "A" * 64, "g" * 64):
        path = copy(bulk, tmp_path / "id.h5")
        with h5py.File(path, "r+") as f:
            f[L.RUN].attrs["id"] = rid
        found = problems(path)
        assert len(found) == 1 and found[0].startswith(f"warning: /{L.RUN}: attribute 'id'"), (rid, found)


def test_a_fixed_step_beyond_the_contact_fails(tmp_path):
    """A 0.5 mm silicon sphere (E = 50 MPa): its Rayleigh time is ~20 us; dt = 1e-4 s is far beyond
    20 % of it, dt = 1e-6 s well within."""
    single = {"radius": ("5e-4", "m", "", "5e-4"), "density": ("2330", "kg/m^3", "", "2330"),
              "youngs": ("5e7", "Pa", "", "5e7"), "poisson": ("0.3", "-", "", "0.3"), **FREQ_ONLY}
    frames = [(k, k * 1e-3, parts([1], [[0, 0, 5e-4]])) for k in range(2)]

    def run(name, **extra):
        return errors(write_result(tmp_path / name, frames, variables={**single, **extra}))

    assert run("fine.h5", dt=("1e-6", "s", "", "0")) == []
    found = run("long.h5", dt=("1e-4", "s", "", "0"))
    assert len(found) == 1 and found[0].startswith(f"error: /{L.VARIABLES}/dt: dt=0.0001 s is ") and \
        "of the Rayleigh time (limit 20%)" in found[0] and \
        found[0].endswith(": the contacts were not resolved"), found
    found = run("insisted.h5", dt=("1e-4", "s", "", "0"), dt_unchecked=("1", "-", "", "0"))
    assert len(found) == 1 and "(run with dt_unchecked=1): the contacts were not resolved" in found[0]


@pytest.mark.parametrize("norm", [1 - 5e-7, 1 + 5e-7])
def test_a_quaternion_within_a_millionth_of_unit_length_passes(bulk, tmp_path, norm):
    path = copy(bulk, tmp_path / "q.h5")
    with h5py.File(path, "r+") as f:
        _quaternion_norm(norm)(f)
    assert problems(path) == []


def test_time_may_repeat_where_step_may_not(tmp_path):
    """FORMAT.md asks a strictly increasing step (a repeat fails, "step repeated" above); the
    time must only never go back: two frames at one time pass (the part at rest)."""
    path = sequence(tmp_path / "t.h5", frames_of([[1]] * 3, still(3)))
    with h5py.File(path, "r+") as f:
        _set(f"{L.PARTS}/position/time", 2, 1e-3)(f)
        assert f[f"{L.PARTS}/position/time"][()].tolist() == [0.0, 1e-3, 1e-3]
    assert problems(path) == []


@pytest.mark.parametrize("version", [None, "1.4", np.array([b"one", b"four"])])
def test_a_format_unrecorded_or_unreadable_is_the_first(bulk, tmp_path, version):
    """As Result.format_version: the first files recorded none, they are format 1.0."""
    path = copy(bulk, tmp_path / "v.h5")
    with h5py.File(path, "r+") as f:
        if version is None:
            del f[L.PARAMETERS].attrs["format_version"]
        else:
            f[L.PARAMETERS].attrs["format_version"] = version
        assert check_module.format_version(f) == (1, 0)


def test_a_missing_surface_element_does_not_stop_the_checks_of_the_others(bulk, tmp_path):
    """position is checked first: missing; velocity's non-finite value must still be reported."""
    path = copy(bulk, tmp_path / "surface.h5")
    with h5py.File(path, "r+") as f:
        del f[f"{L.SURFACE}/position"]
        _set(f"{L.SURFACE}/velocity/value", (1, 0), np.nan)(f)
    found = errors(path)
    assert has(found, f"{L.SURFACE}/position", "missing"), found
    assert has(found, f"{L.SURFACE}/velocity/value", "non-finite values"), found


def test_a_missing_section_does_not_stop_the_checks_of_the_next(tmp_path):
    """A line of 3 sections without section 2's motion: section 3's is checked all the same
    (its velocity in the wrong unit). Made from a 2-section line whose section 2 becomes 3."""
    path = balance(tmp_path / "l.h5", LINE_PRESENT, LINE_COUNTS, events=[2], line=True, rejects=[3])
    assert problems(path) == []
    s2, s3 = L.surface_path(2), L.surface_path(3)
    with h5py.File(path, "r+") as f:
        _text_dataset(f"{L.VARIABLES}/sections", "3")(f)
        for name in L.SECTION_DRIVE:
            f.copy(f"{L.VARIABLES}/s2_{name}", f"{L.VARIABLES}/s3_{name}")
        f.move(s2, s3)
        f[f"{s3}/velocity/value"].attrs["unit"] = "mm s-1"
    found = errors(path)
    assert found == [f"error: /{s2}: missing: section 2's motion (the line has 3 sections; its sine "
                     "drive must be recorded)",
                     f"error: /{s3}/velocity/value: unit attribute must be 'm s-1'"], found


def test_elements_that_disagree_on_the_slots_count_no_parts(bulk, tmp_path):
    path = copy(bulk, tmp_path / "slots.h5")
    with h5py.File(path, "r+") as f:
        f[f"{L.PARTS}/radius/value"].resize(1, axis=1)
    report = check_file(path)
    assert not report.ok and report.parts == 0


def test_a_misshapen_event_element_does_not_stop_the_checks_of_the_others(bulk, tmp_path):
    path = copy(bulk, tmp_path / "events.h5")
    with h5py.File(path, "r+") as f:
        CORRUPTIONS["misshapen event"][0](f)
        _set(f"{L.OUTLET}/position", (0, 0), np.nan)(f)   # after time in the table
    found = errors(path)
    assert has(found, f"{L.OUTLET}/time", "shape (1, 1)"), found
    assert has(found, f"{L.OUTLET}/position", "non-finite values"), found


@pytest.mark.parametrize("first", ["missing", "short"])
def test_a_broken_count_does_not_stop_the_checks_of_the_others(bulk, tmp_path, first):
    """inserted is checked first: missing, or with fewer frames than the parts; lost (checked
    last) of the wrong type must still be reported."""
    path = copy(bulk, tmp_path / "counts.h5")
    with h5py.File(path, "r+") as f:
        g = f[f"{L.MASS_BALANCE}/inserted"]
        if first == "missing":
            del f[f"{L.MASS_BALANCE}/inserted"]
        else:
            for name in ("step", "time", "value"):
                _replace(g, name, g[name][:2])
        _float_values(f"{L.MASS_BALANCE}/lost/value")(f)
    found = errors(path)
    expected = "missing" if first == "missing" else "2 frames, particles have 3"
    assert has(found, f"{L.MASS_BALANCE}/inserted", expected), found
    assert has(found, f"{L.MASS_BALANCE}/lost/value", "must be of integer type"), found


def test_a_track_without_triangles_passes(tmp_path):
    """A mesh of vertices only (T = 0) indexes no vertex: nothing to fail."""
    path = write_bulk_result(tmp_path / "t.h5", [(0, 0.0, parts([1], [[1e-3, 0, 1e-4]]))],
                             track=(FLOOR[0], np.zeros((0, 3), np.int32)))
    assert problems(path) == []


@pytest.mark.parametrize("sections, message", [
    ([0, 1, 1, 1], "sections must lie in 1..1"), ([1, 1, 2, 1], "sections must lie in 1..1"),
    ([1, 1, 1], "must be (4,) integers: one section per vertex"),
    ([1.0, 1, 1, 1], "must be (4,) integers: one section per vertex")])
def test_each_track_vertex_belongs_to_a_section_of_the_run(tmp_path, sections, message):
    path = write_bulk(tmp_path / "split.h5", track_sections=[1, 1, 1, 1])
    with h5py.File(path, "r+") as f:
        _replace(f[L.TRACK], "section", np.array(sections))
    found = errors(path)
    assert found == [f"error: /{L.TRACK_SECTION}: {message}"], found


# -- what the report says --------------------------------------------------------------------
def test_a_file_that_is_not_hdf5_has_no_frames_and_no_parts(tmp_path):
    (tmp_path / "x.h5").write_text("not hdf5")
    report = check_file(tmp_path / "x.h5")
    assert not report.ok and (report.frames, report.parts, report.status) == (0, 0, "")
    assert "cannot open as HDF5" in report.problems[0].message
    assert "feeder description" not in report.problems[0].message


def test_a_feeder_description_or_a_deck_given_for_a_result_is_named_as_such(tmp_path):
    from vibrofeed.errors import ResultError
    from vibrofeed.results.reader import Result

    for name, what in (("line.toml", "a feeder description"), ("mine.liggghts", "a deck")):
        (tmp_path / name).write_text("[feeder]\n")
        message = check_file(tmp_path / name).problems[0].message
        assert message.startswith("cannot open as HDF5 (") and message.endswith(
            f": {what}, not a result (vibrofeed run makes one of it)")
        with pytest.raises(ResultError, match=f"{name}: cannot open as HDF5 .*: {what}, not a result"):
            Result(tmp_path / name)


def test_a_file_without_particles_has_no_frames_and_no_parts(bulk, tmp_path):
    path = copy(bulk, tmp_path / "np.h5")
    with h5py.File(path, "r+") as f:
        del f["particles"]
    report = check_file(path)
    assert not report.ok and (report.frames, report.parts) == (0, 0)
    assert any(p.where == L.PARTS and p.message == "missing" for p in report.problems)


def test_a_sections_parameter_that_is_not_a_number_means_a_single_track(tmp_path):
    variables = {**FREQ_ONLY, "sections": ("nan", "", "sections", "1")}
    path = write_result(tmp_path / "s.h5", [(0, 0.0, parts([1], [[0, 0, 1e-4]]))], variables=variables)
    assert problems(path) == []
    with Result(path) as r:
        assert math.isnan(r.parameters["sections"]) and r.n_sections == 1


def test_a_part_file_that_says_complete_fails(bulk, tmp_path):
    """A .part file is renamed when its run completes: both at once is a writer that died."""
    path = copy(bulk, tmp_path / "run.h5.part")
    assert errors(path) == [f"error: /{L.RUN}: a .part file says 'complete': never renamed"]
    assert problems(path, allow_incomplete=True) == [
        f"warning: /{L.RUN}: a .part file says 'complete': never renamed"]


# -- the mass balance: the counts must add up ------------------------------------------------
def balance(path, present, counts, events=(), line=False, returns=False, rejects=()):
    """A run whose frame k holds the parts ``present[k]`` (ids) and the ``counts[k]`` (tuples in
    the order of L.MASS_BALANCE_COUNTS, L.LINE_COUNTS or L.RETURN_COUNTS); ``events``: ids of
    the outlet's events, ``rejects``: of a line's reject events. A line of two sections,
    section 2 at rest (its drive of amplitude 0)."""
    names = L.RETURN_COUNTS if returns else L.LINE_COUNTS if line else L.MASS_BALANCE_COUNTS
    variables = dict(FREQ_ONLY)
    if line:
        variables.update({"sections": ("2", "", "", "1"), "s2_freq": ("100", "Hz", "", "100"),
                          **{k: ("0", "", "", "0") for k in ("s2_amp_t", "s2_amp_n", "s2_phase")}})
    w = ResultWriter(path, deck_name="d", deck_path="d", deck_text="d", variables=variables,
                     derived={"dt_used": 1e-6}, engine_version="LIGGGHTS (synthetic)", seed=1,
                     run_id="b" * 64, outlet={"outlet_x": 0.02, "catch_z": -5e-4, "method": "m"},
                     recording=Recording(sections=2 if line else 1, rejects=line, returns=returns))

    def table(ids, **extra):
        n = len(ids)
        return {"time": np.full(n, 0.005), "id": list(ids), "position": np.zeros((n, 3)),
                "velocity": np.zeros((n, 3)), **extra}

    for k, (ids, c) in enumerate(zip(present, counts)):
        if k == len(present) - 1:
            if events:
                w.write_events(table(events))
            if rejects:
                w.write_events(table(rejects, section=[1] * len(rejects)), L.REJECTS)
        x = [[1e-3 * i, 0, 1e-4] for i in ids]
        w.write_frame(k, 0.01 * k, parts(ids, np.reshape(x, (len(ids), 3))), np.zeros(3), np.zeros(3),
                      counts=dict(zip(names, c)),
                      section_surfaces=[(np.zeros(3), np.zeros(3))] if line else ())
    w.finish()
    return path


def test_a_balance_that_closes_passes(tmp_path):
    # part 2 exits at frame 1 and falls (present, not on the track), gone at frame 2
    path = balance(tmp_path / "b.h5", [[1, 2], [1, 2], [1]], [(2, 2, 0, 0), (2, 1, 1, 0), (2, 1, 1, 0)],
                   events=[2])
    assert problems(path) == []


@pytest.mark.parametrize("present, counts, events, where, message", [
    # exited falls back by one (2 climbed back onto the track), ends right
    ([[1, 2], [1, 2], [1, 2], [1]], [(2, 2, 0, 0), (2, 1, 1, 0), (2, 2, 0, 0), (2, 1, 1, 0)], [2],
     f"{L.MASS_BALANCE}/exited", "decreases"),
    # inserted falls back by one, together with the parts on the track
    ([[1, 2], [1]], [(2, 2, 0, 0), (1, 1, 0, 0)], [], f"{L.MASS_BALANCE}/inserted", "decreases"),
    # one part more on the track than present
    ([[1], [1]], [(2, 2, 0, 0), (2, 2, 0, 0)], [], L.MASS_BALANCE,
     "on_track does not match the parts present"),
    # a part present, neither on the track nor exited
    ([[1, 2], [1, 2]], [(1, 1, 0, 0), (1, 1, 0, 0)], [], L.MASS_BALANCE,
     "on_track does not match the parts present"),
    # the balance does not close
    ([[1, 2], [1, 2]], [(2, 2, 0, 0), (3, 2, 0, 0)], [], L.MASS_BALANCE,
     "inserted differs from on_track + exited + lost"),
    # one exit more counted than the outlet's events
    ([[1, 2], [1]], [(2, 2, 0, 0), (2, 1, 1, 0)], [], f"{L.MASS_BALANCE}/exited",
     "1 exited at the last frame, 0 outlet events"),
])
def test_a_balance_that_breaks_one_rule_fails_it_alone(tmp_path, present, counts, events, where, message):
    found = errors(balance(tmp_path / "b.h5", present, counts, events=events))
    assert len(found) == 1 and found[0].startswith(f"error: /{where}: {message}"), found


# a line: part 3 falls off a side at frame 1 (a reject), part 2 exits at frame 2 and falls
LINE_PRESENT = [[1, 2, 3], [1, 2], [1, 2]]
LINE_COUNTS = [(3, 3, 0, 0, 0), (3, 2, 0, 0, 1), (3, 1, 1, 0, 1)]   # inserted .. lost, rejected


def test_a_lines_balance_counts_its_rejects(tmp_path):
    path = balance(tmp_path / "l.h5", LINE_PRESENT, LINE_COUNTS, events=[2], line=True, rejects=[3])
    assert problems(path) == []
    with Result(path) as r:
        assert r.mass_balance["rejected"].tolist() == [0, 1, 1] and r.rejects["id"].tolist() == [3]


def test_a_lines_last_rejected_count_must_match_its_reject_events(tmp_path):
    # a fourth part is inserted and rejected by frame 2, its reject event missing
    counts = LINE_COUNTS[:2] + [(4, 1, 1, 0, 2)]
    found = errors(balance(tmp_path / "l.h5", LINE_PRESENT, counts, events=[2], line=True, rejects=[3]))
    assert found == [f"error: /{L.MASS_BALANCE}/rejected: 2 rejected at the last frame, "
                     "1 reject events"], found


def test_a_lines_rejected_count_never_decreases(tmp_path):
    counts = LINE_COUNTS[:2] + [(3, 2, 1, 0, 0)]   # the reject forgotten at frame 2
    found = errors(balance(tmp_path / "l.h5", LINE_PRESENT, counts, events=[2], line=True, rejects=[3]))
    assert f"error: /{L.MASS_BALANCE}/rejected: decreases" in found, found


# recirculating: part 3's reject comes back as part 4 at frame 2 (counted in inserted)
RETURN_PRESENT = [[1, 2, 3], [1, 2], [1, 2, 4]]
RETURN_COUNTS = [(3, 3, 0, 0, 0, 0), (3, 2, 0, 0, 1, 0), (4, 2, 1, 0, 1, 1)]


def test_a_recirculating_lines_balance_counts_its_returns(tmp_path):
    path = balance(tmp_path / "r.h5", RETURN_PRESENT, RETURN_COUNTS, events=[2], line=True,
                   returns=True, rejects=[3])
    assert problems(path) == []


@pytest.mark.parametrize("present, counts, message", [
    # two parts returned (parts 4 and 5, new), one rejected
    (RETURN_PRESENT[:2] + [[1, 2, 4, 5]], RETURN_COUNTS[:2] + [(5, 3, 1, 0, 1, 2)],
     "more parts returned to the inlet than rejected"),
    # part 3's reject returned at frame 1 (part 4), the count taken back at frame 2
    ([[1, 2, 3], [1, 2, 4], [1, 2, 4]], [RETURN_COUNTS[0], (4, 3, 0, 0, 1, 1), (4, 2, 1, 0, 1, 0)],
     "decreases"),
])
def test_returned_never_decreases_nor_exceeds_rejected(tmp_path, present, counts, message):
    found = errors(balance(tmp_path / "r.h5", present, counts, events=[2], line=True, returns=True,
                          rejects=[3]))
    assert found == [f"error: /{L.MASS_BALANCE}/returned: {message}"], found


# -- physics: speed, mass, jumps, region -----------------------------------------------------
def moving(path, speed, z0=0.0, variables=FREQ_ONLY, track=None):
    """Part 1 rests at height z0; part 2, at rest on the floor at x = 1 mm, is recorded moving
    at ``speed`` along x at frame 1 (its position unchanged: no jump)."""
    frames = [(k * 1e-3, [1, 2], [[0, 0, z0], [1e-3, 0, 0]], [[0, 0, 0], [speed if k == 1 else 0.0, 0, 0]])
              for k in range(3)]
    return sequence(path, frames, variables=variables, track=track)


TALL = (np.array([[0, -1e-3, 0], [0.02, -1e-3, 0], [0.02, 1e-3, 0.2], [0, 1e-3, 0.2]]),
        FLOOR[1])   # the floor tilted up to z = 0.2 m at y = 1 mm
LIMITS = {  # name -> (file arguments, the speed limit by FORMAT.md's formula)
    "floor of 1 m/s": (dict(), 1.0),
    "100 x the drive's peak speed": (dict(variables=DRIVE), 100 * DRIVE_PEAK),
    # a drive without a frequency (amplitudes of 1 cm) moves nothing: the floor again
    "no frequency, no surface speed": (dict(variables={"amp_t": ("6e-3", "m", "", "0"),
                                                       "amp_n": ("8e-3", "m", "", "0")}), 1.0),
    "free fall from the first frame's parts": (dict(z0=0.2), math.sqrt(2 * G * 0.2)),
    "free fall from the track's top": (dict(track=TALL), math.sqrt(2 * G * 0.2)),
}


@pytest.mark.parametrize("case", LIMITS)
def test_the_speed_limit_is_the_largest_of_its_terms(tmp_path, case):
    kw, limit = LIMITS[case]
    assert not errors(moving(tmp_path / "slow.h5", 0.995 * limit, **kw))
    found = errors(moving(tmp_path / "fast.h5", 1.005 * limit, **kw))
    assert any(f"part 2 moves at {1.005 * limit:.3g} m/s at frame 1 (t = 0.001 s), beyond the "
               f"{limit:.3g} m/s" in e for e in found), found


@pytest.mark.parametrize("v_factor", [1.40, 1.42, 3.0])
def test_a_speed_beyond_the_limit_is_one_error_whatever_the_energy(tmp_path, v_factor):
    """Two parts of equal mass, one at rest: their energy per kg, v^2 / 4, passes limit^2 / 2
    from v = sqrt(2) limit on; the speed rule reports the part, and nothing else does."""
    limit = 100 * DRIVE_PEAK
    found = errors(moving(tmp_path / "e.h5", v_factor * limit, variables=DRIVE))
    assert len(found) == 1 and "part 2 moves at" in found[0], found


@pytest.mark.parametrize("vx, fails", [(0.9, False), (1.1, True)])
def test_a_velocity_component_not_recorded_is_no_speed(tmp_path, vx, fails):
    """FORMAT.md's Values rule fails a non-finite position only: a part's NaN velocity
    components count as 0, its speed is that of the others (limit 1 m/s here)."""
    frames = [(k * 1e-3, [1, 2], [[0, 0, 0], [1e-3, 0, 0]],
               [[0, 0, 0], [vx, np.nan, np.nan] if k == 1 else [0, 0, 0]]) for k in range(3)]
    found = errors(sequence(tmp_path / "nan.h5", frames))
    if fails:
        assert len(found) == 1 and "part 2 moves at 1.1 m/s at frame 1" in found[0], found
    else:
        assert found == []


@pytest.mark.parametrize("bad", [-1e-6, 0.0, np.nan, np.inf])
def test_a_part_whose_mass_is_not_finite_and_positive_fails(tmp_path, bad):
    """Part 2's mass is bad from frame 1 on; part 1 moves within the limit (1 m/s) at 0.9 m/s.
    (A negative mass once passed as an energy from nothing: (2 mg x 0.81 / 2) / (2 - 1) mg.)"""
    frames = [(k, k * 1e-3, parts([1, 2], [[0, 0, 0], [1e-3, 0, 0]],
                                  velocity=[[0.9 if k == 1 else 0.0, 0, 0], [0, 0, 0]])) for k in range(3)]
    for k, _, p in frames:
        p["mass"] = np.array([2e-6, bad if k else 1e-6])
    found = errors(write_result(tmp_path / "m.h5", frames))
    assert found == [f"error: /{L.PARTS}/mass/value: part 2 has a mass of {bad:.3g} kg at frame 1 "
                     "(t = 0.001 s): a part's mass is finite and positive"], found


def test_an_empty_slots_mass_is_not_judged(tmp_path):
    """Part 2 leaves after frame 0: its slot's fill value is not a part's mass."""
    frames = [(0, 0.0, parts([1, 2], [[0, 0, 0], [1e-3, 0, 0]])),
              (1, 1e-3, parts([1], [[0, 0, 0]])), (2, 2e-3, parts([1], [[0, 0, 0]]))]
    assert errors(write_result(tmp_path / "e.h5", frames)) == []


def still(n, x=0.0):
    """n frames 1 ms apart of part 1 at rest at (x, 0, 0): positions (n, 1, 3)."""
    return np.tile([[x, 0.0, 0.0]], (n, 1, 1))


def frames_of(ids, x, dt=1e-3):
    return [(k * dt, ids[k], x[k], None) for k in range(len(ids))]


def test_a_jump_names_the_part_and_its_two_frames(tmp_path):
    """Part 2 appears at frame 1 (its slot empty at frame 0) and moves 1 cm in 1 ms between
    frames 2 and 3: 10 m/s, beyond 1.5 x the 1 m/s limit."""
    ids = [[1], [1, 2], [1, 2], [1, 2]]
    x = [[[0, 0, 0]], [[0, 0, 0], [5e-3, 0, 0]], [[0, 0, 0], [5e-3, 0, 0]], [[0, 0, 0], [15e-3, 0, 0]]]
    found = errors(sequence(tmp_path / "j.h5", frames_of(ids, x)))
    assert found == [f"error: /{L.PARTS}/position/value: part 2 moves 0.01 m between frames 2 and 3, "
                     "faster than the 1 m/s any part can reach"], found


def test_a_slot_taken_over_by_another_part_is_no_jump(tmp_path):
    """Part 2 leaves at frame 1 and part 3 takes its slot at once, 0.5 m away."""
    ids = [[1, 2], [1, 3], [1, 3]]
    x = [[[0, 0, 0], [0.2, 0, 0]], [[0, 0, 0], [-0.3, 0, 0]], [[0, 0, 0], [-0.3, 0, 0]]]
    path = sequence(tmp_path / "s.h5", frames_of(ids, x))
    with Result(path) as r:
        assert r.ids[:, 1].tolist() == [2, 3, 3]   # the same slot
    assert problems(path) == []


def test_a_step_of_1_5_limits_times_dt_passes_and_one_beyond_fails(tmp_path):
    """The limit is 1 m/s here; the check allows 1 nm for rounding on top of 1.5 limit dt."""
    threshold = 1.5 * 1.0 * 1e-3 + 1e-9
    for x1, fails in ((threshold, False), (np.nextafter(threshold, 1.0), True)):
        path = sequence(tmp_path / f"{fails}.h5", frames_of([[1], [1]], [[[0, 0, 0]], [[x1, 0, 0]]]))
        assert bool(errors(path)) == fails, (x1, errors(path))


@pytest.mark.parametrize("jump_at", [None, 2, 4])
def test_jumps_are_found_across_the_blocks_frames_are_read_in(tmp_path, monkeypatch, jump_at):
    """Blocks of 2 frames (one slot): frames 0-1, 2-3, 4; a jump between frames 1 and 2, or
    3 and 4, spans two blocks; without a jump the file passes."""
    monkeypatch.setattr(check_module, "_BLOCK_VALUES", 6)
    x = still(5)
    if jump_at is not None:
        x[jump_at:, 0, 0] = 0.01   # 1 cm in 1 ms
    found = errors(sequence(tmp_path / "b.h5", frames_of([[1]] * 5, x)))
    if jump_at is None:
        assert found == []
    else:
        assert len(found) == 1 and f"between frames {jump_at - 1} and {jump_at}," in found[0], found


def test_jumps_are_not_checked_with_periodic_boundaries(tmp_path):
    x = still(3)
    x[2:, 0, 0] = 0.01
    path = sequence(tmp_path / "p.h5", frames_of([[1]] * 3, x))
    assert any("moves 0.01 m between frames 1 and 2" in e for e in errors(path))
    with h5py.File(path, "r+") as f:
        f[f"{L.PARTS}/box"].attrs["boundary"] = np.array([b"periodic", b"none", b"none"])
    assert errors(path) == [f"error: /{L.PARTS}/box/pbc: disagrees with the box's boundary "
                            "(x periodic, y none, z none)"]
    with h5py.File(path, "r+") as f:
        f[f"{L.PARTS}/box/pbc/value"][:, 0] = True
    assert problems(path) == []


def test_box_pbc_says_what_the_boundary_says_and_may_be_absent(tmp_path):
    path = sequence(tmp_path / "p.h5", frames_of([[1]] * 3, still(3)))
    with h5py.File(path, "r") as f:
        pbc = f[f"{L.PARTS}/box/pbc"]
        assert pbc["value"].dtype == bool and not pbc["value"][()].any() and pbc["value"].shape == (3, 3)
        assert pbc["step"] == f[f"{L.PARTS}/position/step"] and pbc["time"] == f[f"{L.PARTS}/position/time"]
    with h5py.File(path, "r+") as f:
        f[f"{L.PARTS}/box/pbc/value"][1, 2] = True
    assert errors(path) == [f"error: /{L.PARTS}/box/pbc: disagrees with the box's boundary "
                            "(x none, y none, z none)"]
    with h5py.File(path, "r+") as f:
        del f[f"{L.PARTS}/box/pbc/step"]
    assert errors(path) == [f"error: /{L.PARTS}/box/pbc: must be sampled with the positions (their step)"]
    with h5py.File(path, "r+") as f:
        del f[f"{L.PARTS}/box/pbc"]
        f[f"{L.PARTS}/box/pbc"] = np.zeros(3, dtype=bool)
    assert errors(path) == [f"error: /{L.PARTS}/box/pbc: must be a time series of 3 booleans per frame"]
    with h5py.File(path, "r+") as f:
        del f[f"{L.PARTS}/box/pbc"]  # files written before it: valid
    assert problems(path) == []


@pytest.mark.parametrize("offset, axis, fails", [
    (0.0205, 0, False), (0.0215, 0, True), (-0.0205, 1, False), (-0.0215, 1, True),
    (0.0205, 2, False), (-0.0215, 2, True)])
def test_parts_must_stay_within_a_tracks_size_and_the_surfaces_travel_of_the_track(tmp_path, offset,
                                                                                  axis, fails):
    """The floor spans x 0..20 mm, y -1..1 mm, z 0: its largest size is 20 mm, and the surface
    moves up to 1 mm (along z, frame 1): a part 20.5 mm beyond the box passes, 21.5 mm fails."""
    edge = (FLOOR[0].max(axis=0) if offset > 0 else FLOOR[0].min(axis=0))[axis]
    where = np.array([0.01, 0, 0])
    where[axis] = edge + offset
    x = np.tile(where, (3, 1, 1))
    surface = [(np.zeros(3), np.zeros(3)), (np.array([0, 0, 1e-3]), np.zeros(3)), (np.zeros(3), np.zeros(3))]
    found = errors(sequence(tmp_path / "r.h5", frames_of([[1]] * 3, x), track=FLOOR, surface=surface))
    assert bool(found) == fails, found
    if fails:
        assert found[0].startswith(f"error: /{L.PARTS}/position/value: part 1 is at ") and \
            "at frame 0 (t = 0 s), far outside the track" in found[0], found


@pytest.mark.parametrize("offset, fails", [(0.0795, False), (0.0805, True)])
def test_a_part_an_air_jet_blew_off_may_fly_four_track_sizes(tmp_path, offset, fails):
    """With jet firings recorded (vibrofeed/jet), the floor's 20 mm size counts four times: a
    part 79.5 mm beside it passes (it flies to the catch plane), 80.5 mm fails. Without them
    the same part fails (the test above: a track's size)."""
    x = np.tile(np.array([0.01, FLOOR[0][:, 1].max() + offset, 0.0]), (3, 1, 1))
    path = sequence(tmp_path / "jet.h5", frames_of([[1]] * 3, x), track=FLOOR)
    assert errors(path)  # no firing: far outside
    with h5py.File(path, "r+") as f:
        f[f"{L.JET}/time"] = np.array([0.001])
    assert bool(errors(path)) == fails


def test_a_run_whose_frames_hold_no_part_passes(tmp_path):
    path = write_result(tmp_path / "none.h5", [(k, k * 1e-3, parts([], np.zeros((0, 3)))) for k in range(3)])
    with h5py.File(path, "r") as f:
        assert f[f"{L.PARTS}/id/value"].shape == (3, 0)
    report = check_file(path)
    assert report.problems == [] and (report.frames, report.parts) == (3, 0)


def test_a_part_far_outside_is_named_with_its_frame_in_a_later_block(tmp_path, monkeypatch):
    """Blocks of 2 frames (two slots): part 2 appears 50 mm along x at frame 3, the second
    frame of the second block, beyond the floor's 20 mm and a margin of its 20 mm size;
    part 1 stays on the floor. The error names part 2, frame 3 and its time."""
    monkeypatch.setattr(check_module, "_BLOCK_VALUES", 12)
    ids = [[1], [1], [1], [1, 2]]
    x = [[[0.01, 0, 0]]] * 3 + [[[0.01, 0, 0], [0.05, 0, 0]]]
    found = errors(sequence(tmp_path / "far.h5", frames_of(ids, x), track=FLOOR))
    assert len(found) == 1, found
    assert found[0].startswith(f"error: /{L.PARTS}/position/value: part 2 is at ") and \
        "at frame 3 (t = 0.003 s), far outside the track" in found[0], found


def test_the_part_named_is_one_beyond_the_speed_limit_not_one_at_it(tmp_path):
    """Frame 1: part 1 moves at exactly the 1 m/s limit (allowed), part 2 at 1.5 m/s."""
    frames = [(k * 1e-3, [1, 2], [[0, 0, 0], [1e-3, 0, 0]],
               [[1.0, 0, 0], [1.5, 0, 0]] if k == 1 else [[0, 0, 0], [0, 0, 0]]) for k in range(3)]
    found = errors(sequence(tmp_path / "at.h5", frames))
    assert len(found) == 1 and "part 2 moves at 1.5 m/s at frame 1" in found[0], found


@pytest.mark.parametrize("value", [1.0, np.float64(2.5), np.int64(3)])
def test_a_value_read_from_the_file_is_shown_as_its_number(bulk, tmp_path, value):
    """h5py reads a number as a numpy scalar: check said 'got np.float64(1.0)'."""
    path = copy(bulk, tmp_path / "bad.h5")
    with h5py.File(path, "r+") as f:
        f[R].attrs["target_error"] = value
    assert has(errors(path), R, f"{TARGET}, got {value.item() if hasattr(value, 'item') else value}")
