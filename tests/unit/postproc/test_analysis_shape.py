"""Post-processing on small hand-computed trajectories: the analysis shape, transport, flights."""

import json
import pickle

import numpy as np
import pytest
from scipy.optimize import brentq

from helpers import parts, write_conveyor, write_result
from vibrofeed.errors import InputError
from vibrofeed.postproc import AnalysisBase, Flights, Results, Transport
from vibrofeed.results.reader import Result

G = 9.81
R = 5e-4
M = 1e-6


def run_file(tmp_path, times, z, vz, fz, x=None, surface_z=None, surface_vz=None, freq="50"):
    """A one-part result; force fz is the TOTAL force (gravity included), as LIGGGHTS records it."""
    n = len(times)
    x = np.zeros(n) if x is None else x
    sz = np.zeros(n) if surface_z is None else surface_z
    svz = np.zeros(n) if surface_vz is None else surface_vz
    frames = [(k, t, parts([1], [[x[k], 0.0, z[k]]], radius=R, mass=M,
                           velocity=[[0, 0, vz[k]]], force=[[0, 0, fz[k]]]))
              for k, t in enumerate(times)]
    surface = [([0, 0, sz[k]], [0, 0, svz[k]]) for k in range(n)]
    variables = {"freq": (freq, "Hz", "f", freq), "incline": ("0", "deg", "i", "0")}
    return Result(write_result(tmp_path / "one.h5", frames, surface, variables))


def test_lift_off_and_landing_on_a_sine_plate(tmp_path):
    # Rigid model, e = 0: on the plate until its downward acceleration reaches g,
    # free flight, then back on the plate (Khan & Sarma, §2.3.2, with the README's corrections).
    gamma, f, dt = 1.5, 50.0, 1e-4
    w = 2 * np.pi * f
    A = gamma * G / w ** 2
    t_l = np.arcsin(1 / gamma) / w
    zl, vl = A * np.sin(w * t_l), A * w * np.cos(w * t_l)
    fly = lambda t: zl + vl * (t - t_l) - G / 2 * (t - t_l) ** 2   # noqa: E731
    t_land = brentq(lambda t: fly(t) - A * np.sin(w * t), t_l + 1e-4, t_l + 0.02)
    times = np.arange(0, t_l + 1 / f, dt)  # up to the next lift-off
    zs, vs, acc = A * np.sin(w * times), A * w * np.cos(w * times), -A * w ** 2 * np.sin(w * times)
    air = (times > t_l) & (times < t_land)
    z = np.where(air, fly(times), zs) + R
    vz = np.where(air, vl - G * (times - t_l), vs)
    fz = np.where(air, -M * G, M * acc)  # in contact the part moves with the plate
    with run_file(tmp_path, times, z, vz, fz, surface_z=zs, surface_vz=vs) as r:
        fl = Flights(r).run().results
    assert fl.kinds == ["lift-off"] and fl.n_hops == 1
    # Linear extrapolation of the contact force m (g + a_s) over one frame:
    # error <= 2 w tan(theta_l) dt^2 (its curvature over its slope).
    theta = np.arcsin(1 / gamma)
    assert fl.takeoffs[0] == pytest.approx(t_l, abs=2 * w * np.tan(theta) * dt ** 2)
    # The landing is the root of the free flight: exact up to the surface's
    # Hermite interpolation (A w^4 dt^4 / 384 in height).
    assert fl.landings[0] == pytest.approx(t_land, abs=1e-9)
    assert fl.durations[0] == pytest.approx(t_land - t_l, abs=2 * w * np.tan(theta) * dt ** 2)
    assert fl.impacts[0, 2] == 0.0           # e = 0: no rebound
    assert fl.max_gap == pytest.approx(np.max(z - R - zs), abs=1e-18)  # m: rounding of z - R - z_s ~ 1e-4


def test_impacts_between_frames_are_found(tmp_path):
    # A ball bouncing on a still floor with e = 0.5; every impact falls between frames.
    e, v0, dt = 0.5, 0.2, 1e-4
    bounces, t, v = [], 0.00003, v0   # launched upwards at t = 3e-5 s
    while len(bounces) < 4:
        t += 2 * v / G
        bounces.append((t, v))
        v *= e
    times = np.arange(0, bounces[-1][0] - 1e-4, dt)
    z, vz = np.empty_like(times), np.empty_like(times)
    starts = [(0.00003, v0)] + [(tb, vb * e) for tb, vb in bounces]
    for k, s in enumerate(times):
        t0, v = max((st for st in starts if st[0] <= s), default=(0.00003, v0))
        z[k], vz[k] = v * (s - t0) - G / 2 * (s - t0) ** 2, v - G * (s - t0)
    z[times < 0.00003], vz[times < 0.00003] = 0.0, 0.0
    fz = np.where(times < 0.00003, 0.0, -M * G)
    with run_file(tmp_path, times, z + R, vz, fz) as r:
        fl = Flights(r).run().results
    expected = [tb for tb, _ in bounces if tb < times[-1]]
    assert len(fl.landings) == len(expected)
    assert np.allclose(fl.landings, expected, rtol=0, atol=1e-9)  # s
    assert fl.kinds[1:] == ["rebound"] * (len(fl.kinds) - 1)
    for k in range(len(expected)):
        assert fl.impacts[k, 2] == pytest.approx(e, rel=1e-6)


def test_no_hops_when_resting_on_a_moving_surface(tmp_path):
    times = np.arange(0, 0.04, 1e-4)
    w = 2 * np.pi * 50
    a = 0.8 * G / w ** 2  # Gamma = 0.8: the plate always pushes
    sz, sv = a * np.sin(w * times), a * w * np.cos(w * times)
    fz = M * (-a * w ** 2 * np.sin(w * times))
    with run_file(tmp_path, times, R + sz - 1e-8, sv, fz, surface_z=sz, surface_vz=sv) as r:
        fl = Flights(r).run().results
    assert fl.n_hops == 0 and fl.airborne_fraction == 0.0 and len(fl.landings) == 0
    assert fl.max_gap == pytest.approx(-1e-8, abs=1e-18)  # m: rounding of z ~ 1e-4 m


def test_transport_over_whole_periods_removes_the_oscillation(tmp_path):
    v, a, w = 0.01, 1e-3, 2 * np.pi * 50
    times = np.arange(0, 0.1 + 1e-12, 1e-4)
    x = v * times + a * np.sin(w * times)
    n = len(times)
    with run_file(tmp_path, times, np.full(n, R), np.zeros(n), np.zeros(n), x=x) as r:
        tr = Transport(r, start=0.013).run().results
        # a window of whole periods: the sine term cancels exactly
        assert (tr.window[1] - tr.window[0]) * 50 == pytest.approx(round((tr.window[1] - tr.window[0]) * 50),
                                                            abs=1e-12)  # periods: rounding
        assert tr.mean_velocity == pytest.approx(v, rel=1e-9)
        # a naive window of 0.013..0.1 s would be off by a sin term
        naive = (x[-1] - x[130]) / (times[-1] - times[130])
        assert abs(naive - v) > 1e-3


def test_transport_needs_a_window(tmp_path):
    times = np.arange(0, 0.01, 1e-4)
    n = len(times)
    with run_file(tmp_path, times, np.full(n, R), np.zeros(n), np.zeros(n)) as r:
        with pytest.raises(ValueError, match="no time window"):
            Transport(r, start=1.0).run()


# -- the analysis shape --------------------------------------------------------------
class PartCount(AnalysisBase):
    """A per-frame analysis: parts present and their mean x, frame by frame."""

    def __init__(self, result, offset=0.0):
        super().__init__(result)
        self.offset = offset

    def _prepare(self):
        self.results.count = []
        self.results.mean_x = []

    def _single_frame(self):
        self.results.count.append(len(self._frame))
        self.results.mean_x.append(self._frame["position"][:, 0].mean() + self.offset)

    def _conclude(self):
        self.results.count = np.array(self.results.count)
        self.results.total = int(self.results.count.sum())


def conveyor(tmp_path, n_parts=40, n_frames=1001, dt=1e-4, amp=1e-3, seed=3):
    """Parts at known speeds, entering and leaving at known frames (see helpers.write_conveyor)."""
    rng = np.random.default_rng(seed)
    times = np.arange(n_frames) * dt
    first = rng.integers(0, n_frames // 2, n_parts)
    last = np.minimum(first + rng.integers(n_frames // 4, n_frames, n_parts), n_frames - 1)
    first[:5], last[:5] = 0, n_frames - 1  # a few parts present throughout
    lifetimes = np.column_stack([first, last])
    speeds = rng.uniform(0.005, 0.03, n_parts)
    path = write_conveyor(tmp_path / "conveyor.h5", times, lifetimes, speeds, amp=amp)
    return Result(path), times, lifetimes, speeds


def test_run_selects_frames_like_a_slice_and_answers_in_results(tmp_path):
    r, times, lifetimes, _ = conveyor(tmp_path, n_frames=21)
    with r:
        alive = [((lifetimes[:, 0] <= j) & (j <= lifetimes[:, 1])).sum() for j in range(21)]
        pc = PartCount(r, offset=1.0)
        assert pc.run() is pc                                # run returns the analysis
        assert pc.frames.tolist() == list(range(21)) and pc.n_frames == 21
        assert pc.results.count.tolist() == alive and pc.results.total == sum(alive)
        assert pc.results["total"] == pc.results.total
        assert pc.offset == 1.0 and "offset" not in pc.results  # settings stay apart
        pc.run(start=2, stop=15, step=4)
        assert pc.frames.tolist() == [2, 6, 10, 14]
        assert np.allclose(pc.times, times[[2, 6, 10, 14]], rtol=0, atol=1e-15)  # s: copied
        assert pc.results.count.tolist() == [alive[j] for j in (2, 6, 10, 14)]  # answers renewed
        assert pc.run(start=-3).frames.tolist() == [18, 19, 20]
        assert pc.run(frames=[0, -1]).frames.tolist() == [0, 20]
        assert pc.run(start=30).n_frames == 0
        with pytest.raises(InputError):
            pc.run(step=0)
        with pytest.raises(InputError):
            pc.run(start=1, frames=[2])

        class Nothing(AnalysisBase):
            pass

        with pytest.raises(NotImplementedError):
            Nothing(r).run()


def test_results_are_a_dict_with_attributes():
    res = Results(a=1)
    res.b = np.array([1.0, np.nan])
    assert res == {"a": 1, "b": res["b"]} and res.a == 1 and "b" in dir(res)
    with pytest.raises(AttributeError, match="no result 'c'"):
        res.c  # noqa: B018
    with pytest.raises(KeyError):
        res["items"] = 3  # would hide the dict method
    del res.a
    assert list(res) == ["b"]
    with pytest.raises(AttributeError):   # as for an object: not the dict's KeyError
        del res.a
    back = pickle.loads(pickle.dumps(res))
    assert isinstance(back, Results) and np.array_equal(back.b, res.b, equal_nan=True)


@pytest.mark.parametrize("key", ["mean velocity", "2nd", "", 3, ("a", "b")])
def test_a_result_is_named_by_an_identifier(key):
    """A result is read as an attribute: a key that is not an identifier (a string with a
    space, a leading digit, empty, or no string at all) is refused as a dict method is."""
    res = Results()
    with pytest.raises(KeyError, match="cannot name a result"):
        res[key] = 1.0
    with pytest.raises(KeyError, match="cannot name a result"):
        Results({key: 1.0})
    assert res == {}

def test_as_dict_is_json_ready(tmp_path):
    r, *_ = conveyor(tmp_path, n_frames=21)
    with r:
        tr = Transport(r, start=0.0).run()
        view = tr.as_dict()
        assert json.loads(json.dumps(view, allow_nan=False)) == view
        assert view["ids"] == tr.results.ids.tolist()
        assert view["window"] == list(tr.results.window)
        assert set(tr.as_dict(["mean_velocity"])) == {"mean_velocity"}
    assert AnalysisBase.as_dict(type("A", (), {"results": Results(x=np.float64("nan"))})()) == {"x": None}


# -- transport of many parts ---------------------------------------------------------
def test_transport_counts_the_parts_present_at_both_ends_of_the_window(tmp_path, result_reads):
    r, times, lifetimes, speeds = conveyor(tmp_path)
    reads = result_reads
    with r:
        tr = Transport(r, start=0.013).run().results
        # 0.1 s - 0.013 s holds 4 whole periods at 50 Hz: the window is 0.02 .. 0.1 s
        assert tr.window_frames == (200, 1000) and tr.window == pytest.approx((0.02, 0.1), rel=1e-12)
        counted = np.nonzero((lifetimes[:, 0] <= 200) & (lifetimes[:, 1] >= 1000))[0]
        assert 5 <= len(counted) < len(speeds)  # some parts enter or leave during the window
        assert tr.ids.tolist() == (counted + 1).tolist()
        assert np.allclose(tr.velocities, speeds[counted], rtol=1e-9, atol=0)
        assert tr.mean_velocity == pytest.approx(speeds[counted].mean(), rel=1e-9)
        # Two frames read, no whole array.
        assert reads and all(list(f) == [200, 1000] for name, f in reads if name in ("id", "position"))
        assert not {"ids", "position"} & set(vars(r))


def test_transport_over_a_frame_selection_ends_at_its_last_frame(tmp_path):
    r, times, lifetimes, speeds = conveyor(tmp_path)
    with r:
        tr = Transport(r, start=0.0).run(stop=801, step=2).results
        assert tr.window_frames == (0, 800)  # 0.08 s: 4 whole periods ending at frame 800
        counted = np.nonzero((lifetimes[:, 0] <= 0) & (lifetimes[:, 1] >= 800))[0]
        assert tr.ids.tolist() == (counted + 1).tolist()
        assert np.allclose(tr.velocities, speeds[counted], rtol=1e-9, atol=0)
        # Default start: the middle frame analysed (frame 400); 0.04 s = 2 periods.
        assert Transport(r).run(stop=801, step=2).results.window_frames == (400, 800)


# -- flights from ballistic trajectories with known landings -------------------------
def bounces_on_a_sine_plate(e=0.5, amp=1e-4, freq=50.0, v0=0.15, t0=3e-5, n=4):
    """Exact impacts of a ball launched from a plate z_s = amp sin(w t): (t, v_in, v_out) each."""
    w = 2 * np.pi * freq
    plate = lambda t: amp * np.sin(w * t)  # noqa: E731
    plate_v = lambda t: amp * w * np.cos(w * t)  # noqa: E731
    starts, impacts = [(t0, plate(t0), v0)], []
    for _ in range(n):
        ts, zs, vs = starts[-1]
        gap = lambda t: zs + vs * (t - ts) - G / 2 * (t - ts) ** 2 - plate(t)  # noqa: E731,B023
        grid = np.linspace(ts + 1e-6, ts + 2 * vs / G + 0.01, 200001)
        k = np.argmax(gap(grid) < 0)
        t_hit = brentq(gap, grid[k - 1], grid[k], xtol=1e-15)
        v_in = vs - G * (t_hit - ts)
        v_out = plate_v(t_hit) - e * (v_in - plate_v(t_hit))
        impacts.append((t_hit, v_in, v_out))
        starts.append((t_hit, plate(t_hit), v_out))
    return starts, impacts, plate, plate_v


def test_landings_on_a_moving_plate_are_the_roots_of_free_flight(tmp_path):
    starts, impacts, plate, plate_v = bounces_on_a_sine_plate(n=5)
    dt = 1e-4
    times = np.arange(0, impacts[-1][0] - dt, dt)  # the record stops before the 5th impact
    impacts = impacts[:-1]
    z, vz = np.empty_like(times), np.empty_like(times)
    for k, s in enumerate(times):
        ts, zs, vs = max((st for st in starts if st[0] <= s), default=starts[0])
        z[k], vz[k] = zs + vs * (s - ts) - G / 2 * (s - ts) ** 2, vs - G * (s - ts)
    before = times < starts[0][0]
    z[before], vz[before] = plate(times[before]), plate_v(times[before])
    fz = np.where(before, 0.0, -M * G)  # before launch the plate carries the part
    sz, sv = plate(times), plate_v(times)
    with run_file(tmp_path, times, z + R, vz, fz, surface_z=sz, surface_vz=sv) as r:
        fl = Flights(r).run().results
        late = Flights(r, part_id=1).run(start=int(impacts[1][0] / dt) + 1).results
    t_hits = np.array([t for t, _, _ in impacts])
    # exact up to the surface's Hermite interpolation: amp w^4 dt^4 / 384 in height
    assert fl.landings == pytest.approx(t_hits, abs=1e-10)
    assert fl.kinds[1:] == ["rebound"] * (len(impacts) - 1)
    assert fl.flights[1:, 0] == pytest.approx(t_hits[:-1], abs=1e-10)
    w_in = np.array([v - plate_v(t) for t, v, _ in impacts])
    assert fl.impacts[:, 1] == pytest.approx(w_in, rel=1e-6)
    assert fl.impacts[:, 2] == pytest.approx(0.5, rel=1e-4)
    assert fl.realised_restitution == pytest.approx(0.5, rel=1e-4)
    # A run from a later frame sees only the later impacts.
    assert late.landings == pytest.approx(t_hits[2:], abs=1e-10)
    assert late.time[0] > t_hits[1]
