"""Transport over random synthetic conveyors whose answers are known by construction.

Each part ``k + 1`` moves as ``x = k mm + v_k t + amp sin(2 pi f t)`` between the
frames where it enters and leaves (``helpers.write_conveyor``). What Transport
promises (its docstring):

* the window ends at the last frame analysed and starts at the frame at or
  after ``start`` whose distance from whole periods T = 1/f, per period spanned,
  is the least (the earliest of equals: the longest window); a frame less than
  a period before the end (or none after start) leaves the frame nearest
  ``start``;
* ``start`` defaults to the time of the middle frame analysed;
* only parts present at both ends of the window count, each with its
  displacement over the window divided by the window's length.

With frames that divide the period the oscillation cancels and every counted
part's speed is its v_k exactly; with frames that alias the period it cancels
wherever some number of frames spans whole periods, and the window is never
farther from whole periods (per period) than the frame nearest ``end - P T``
(P the most whole periods after ``start``) would make it.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from helpers import write_conveyor
from vibrofeed.errors import InputError
from vibrofeed.postproc import Transport
from vibrofeed.results.reader import Result

AMP = 1e-3


@st.composite
def conveyors(draw, aliasing: bool):
    freq = draw(st.sampled_from([20.0, 50.0, 60.0, 137.0]))
    period = 1 / freq
    if aliasing:  # any spacing, down to a few frames per period and up to 1.7 periods
        dt = period * draw(st.floats(0.07, 1.7))
    else:
        dt = period / draw(st.integers(3, 25))
    n_frames = draw(st.integers(8, 160))
    n_parts = draw(st.integers(1, 30))
    first = draw(st.lists(st.integers(0, n_frames - 1), min_size=n_parts, max_size=n_parts))
    spans = draw(st.lists(st.integers(0, n_frames), min_size=n_parts, max_size=n_parts))
    lifetimes = np.array([(a, min(a + s, n_frames - 1)) for a, s in zip(first, spans)])
    speeds = np.array(draw(st.lists(st.floats(-0.05, 0.05), min_size=n_parts, max_size=n_parts)))
    step = draw(st.integers(1, 3)) if aliasing else 1  # a step of 2 frames of T/5 aliases too
    times = np.arange(n_frames) * dt
    analysed = np.arange(n_frames)[::step]
    start = draw(st.none() | st.floats(0.0, float(times[analysed[-1]])))
    return dict(freq=freq, dt=dt, times=times, lifetimes=lifetimes, speeds=speeds, step=step,
                analysed=analysed, start=start, seed=draw(st.integers(0, 1000)))


def position(c, k, t):
    return k * 1e-3 + c["speeds"][k] * t + AMP * np.sin(2 * np.pi * c["freq"] * t)


def chosen_start(t, start, freq):
    """The rule of the docstring, frame by frame: (position of the window's first frame
    among the analysed times ``t``, its alias per period), or (None, None) without one."""
    best, best_per = None, None
    for k in range(len(t) - 1):
        if t[k] < start - 1e-9 / freq:
            continue
        cycles = (t[-1] - t[k]) * freq
        whole = round(cycles)
        if whole < 1:
            continue
        off = abs(cycles - whole)
        per = (0.0 if off <= 1e-4 else off) / cycles
        if best is None or per < best_per:
            best, best_per = k, per
    return best, best_per


def check_transport(tmp_path, c, exact_periods: bool):
    path = write_conveyor(tmp_path / "c.h5", c["times"], c["lifetimes"], c["speeds"], amp=AMP,
                          freq=c["freq"], seed=c["seed"])
    t = c["times"][c["analysed"]]
    end = t[-1]
    start = t[len(t) // 2] if c["start"] is None else c["start"]
    period = 1 / c["freq"]
    whole = math.floor((end - start) / period + 1e-9)  # periods after start
    k_rule, per_rule = chosen_start(t, start, c["freq"])
    fallback = k_rule is None
    with Result(path) as r:
        tr = Transport(r, start=c["start"])
        if fallback and np.argmin(np.abs(t - start)) == len(t) - 1:
            with pytest.raises(InputError, match="no time window"):
                tr.run(step=c["step"])
            return
        res = tr.run(step=c["step"]).results
    i0, i1 = res.window_frames
    t0, t1 = res.window
    assert i1 == c["analysed"][-1] and t1 == pytest.approx(end, rel=1e-12)  # s
    assert i0 in c["analysed"] and t0 == pytest.approx(c["times"][i0], rel=1e-12)
    cycles = (t1 - t0) / period
    assert res.alias == pytest.approx(abs(cycles - round(cycles)), abs=1e-9)  # periods
    if fallback:   # not a whole period after start: the frame nearest it
        assert abs(t0 - start) == pytest.approx(np.abs(t - start).min(), abs=1e-12)
    else:
        assert i0 == c["analysed"][k_rule] and t0 >= start - 1e-12
        # never farther from whole periods than the frame nearest end - P T
        old = int(np.argmin(np.abs(t - (end - whole * period))))
        old_cycles = (end - t[old]) / period
        if whole >= 1 and t[old] >= start and round(old_cycles) >= 1:
            old_off = abs(old_cycles - round(old_cycles))
            assert per_rule <= (0.0 if old_off <= 1e-4 else old_off) / old_cycles + 1e-12
    alive = (c["lifetimes"][:, 0] <= i0) & (c["lifetimes"][:, 1] >= i1)
    counted = np.nonzero(alive)[0]
    assert res.ids.tolist() == (counted + 1).tolist()
    expected = (position(c, counted, t1) - position(c, counted, t0)) / (t1 - t0)
    assert np.allclose(res.velocities, expected, rtol=1e-9, atol=1e-12)
    if exact_periods and whole >= 1:   # frames that divide the period: the most periods after start
        assert round(cycles) == whole and res.alias == 0.0
    if (exact_periods and whole >= 1) or (not fallback and res.alias == 0.0):
        # whole periods: each part's own speed, to the oscillation's residue over 1e-4 period
        residue = AMP * 2 * np.pi * 1e-4 / (t1 - t0)
        assert np.allclose(res.velocities, c["speeds"][counted], rtol=1e-6, atol=max(residue, 1e-9))
    if len(counted):
        assert res.mean_velocity == pytest.approx(expected.mean(), rel=1e-9, abs=1e-12)
    else:
        assert math.isnan(res.mean_velocity)


@settings(max_examples=40, deadline=None)
@given(c=conveyors(aliasing=False))
def test_whole_periods_give_each_part_its_speed(tmp_path_factory, c):
    check_transport(tmp_path_factory.mktemp("tr"), c, exact_periods=True)


@settings(max_examples=40, deadline=None)
@given(c=conveyors(aliasing=True))
def test_frames_that_alias_the_period(tmp_path_factory, c):
    assume(len(c["analysed"]) >= 2)
    check_transport(tmp_path_factory.mktemp("tr"), c, exact_periods=False)


def test_window_never_starts_before_start(tmp_path):
    """Many parts, a start between frames: 0.1 s - 0.0137 s holds 4.3 periods -> 4."""
    times = np.arange(1001) * 1e-4
    n = 60
    rng = np.random.default_rng(7)
    lifetimes = np.column_stack([rng.integers(0, 300, n), rng.integers(700, 1001, n)])
    lifetimes[:10] = (0, 1000)
    speeds = rng.uniform(-0.02, 0.04, n)
    with Result(write_conveyor(tmp_path / "c.h5", times, lifetimes, speeds, amp=AMP)) as r:
        res = Transport(r, start=0.0137).run().results
        assert res.window == pytest.approx((0.02, 0.1), rel=1e-12) and res.window_frames == (200, 1000)
        alive = np.nonzero((lifetimes[:, 0] <= 200) & (lifetimes[:, 1] >= 1000))[0]
        assert res.ids.tolist() == (alive + 1).tolist()
        assert np.allclose(res.velocities, speeds[alive], rtol=1e-9, atol=1e-15)  # m/s: some near 0
        # default start: the middle frame, 0.05 s; 2.5 periods after it -> 2
        default = Transport(r).run().results
        assert default.window == pytest.approx((0.06, 0.1), rel=1e-12)
        # a start on a period boundary keeps the whole span
        assert Transport(r, start=0.02).run().results.window_frames == (200, 1000)


def test_an_empty_frame_selection_is_refused(tmp_path):
    times = np.arange(11) * 1e-3
    with Result(write_conveyor(tmp_path / "c.h5", times, [(0, 10)], [0.01])) as r:
        with pytest.raises(InputError, match="no frame selected"):
            Transport(r).run(start=5, stop=5)


def test_a_part_numbered_zero_is_a_part(tmp_path):
    """Only the fill value -1 marks an empty slot (FORMAT.md); id 0 moves like any other."""
    from helpers import parts, write_result

    times = np.arange(0, 0.1 + 1e-12, 0.01)
    frames = [(k, t, parts([0, 1], [[0.02 * t, 0, 0], [1e-3 + 0.01 * t, 0, 0]])) for k, t in enumerate(times)]
    with Result(write_result(tmp_path / "zero.h5", frames)) as r:   # 50 Hz
        tr = Transport(r, start=0.0).run().results
    assert tr.ids.tolist() == [0, 1]
    assert tr.velocities == pytest.approx([0.02, 0.01], rel=1e-9)


# -- the whole-period window at its edges: hand-worked frame sets -----------------------
SPEEDS = np.array([0.01, -0.02, 0.005])  # m/s


def transport_on(tmp_path, times, freq, start, amp=AMP):
    """Transport over parts present at every frame of ``times``, moving as ``position``."""
    lifetimes = [(0, len(times) - 1)] * len(SPEEDS)
    path = write_conveyor(tmp_path / "w.h5", np.asarray(times), lifetimes, SPEEDS, amp=amp, freq=freq)
    with Result(path) as r:
        return Transport(r, start=start).run().results


def speed_over(t0, t1, freq, amp=AMP):
    """Each part's displacement over [t0, t1] divided by t1 - t0 (write_conveyor's motion)."""
    w = 2 * np.pi * freq
    return SPEEDS + amp * (math.sin(w * t1) - math.sin(w * t0)) / (t1 - t0)


@pytest.mark.parametrize("freq", [0.5, 100.0])
def test_frames_one_period_apart_start_at_the_first_frame_after_start(tmp_path, freq):
    """Frames every period (a strobe), start 0.2 period after frame 1: frame 2 is the only
    frame at or after start a period before the last (3 T), so the window is (2 T, 3 T),
    whole; frame 1, nearer start, lies before it."""
    period = 1 / freq
    times = np.arange(4) * period
    res = transport_on(tmp_path, times, freq, start=1.2 * period)
    assert res.window_frames == (2, 3) and res.alias == 0.0
    assert res.window == pytest.approx((2 * period, 3 * period), rel=1e-12)  # s
    assert res.velocities == pytest.approx(SPEEDS, abs=1e-12)  # m/s: one whole period


def test_a_start_exactly_on_a_frame_takes_it_and_one_just_after_does_not(tmp_path):
    """100 Hz, frames every T/10 over 3 periods. A start on frame 10 (t = T) keeps the two
    periods from it; a start 1e-8 s (1e-6 period, far above round-off) after it leaves frame 10
    out, and of frames 11..19 none is whole periods before the end (2.9 .. 2.1 periods):
    frame 20, one period before it, is."""
    freq = 100.0
    times = np.arange(31) * 1e-3
    on = transport_on(tmp_path, times, freq, start=float(times[10]))
    assert on.window_frames == (10, 30) and on.alias == 0.0
    assert on.velocities == pytest.approx(SPEEDS, abs=1e-12)  # m/s: two whole periods
    after = transport_on(tmp_path, times, freq, start=float(times[10]) + 1e-8)
    assert after.window_frames == (20, 30) and after.alias == 0.0
    assert after.window[0] >= float(times[10]) + 1e-8
    assert after.velocities == pytest.approx(SPEEDS, abs=1e-12)  # m/s: one whole period


def test_frames_whose_spacing_does_not_divide_the_period(tmp_path):
    """Frames every 0.4 T (5 frames to 2 periods) from 0 to 4 T. From start 0 the window is the
    four periods; from 0.1 T the candidates 0.4 T .. 1.6 T are 3.6, 3.2, 2.8, 2.4 periods
    before the end (off 0.4, 0.2, 0.2, 0.4), and 2 T, two periods before it, is whole."""
    freq = 50.0
    period = 1 / freq
    times = np.arange(11) * 0.4 * period
    res = transport_on(tmp_path, times, freq, start=0.0)
    assert res.window_frames == (0, 10) and res.alias == 0.0
    assert res.velocities == pytest.approx(SPEEDS, abs=1e-12)  # m/s
    res = transport_on(tmp_path, times, freq, start=0.1 * period)
    assert res.window_frames == (5, 10) and res.alias == 0.0
    assert res.window == pytest.approx((2 * period, 4 * period), rel=1e-12)  # s
    assert res.velocities == pytest.approx(SPEEDS, abs=1e-12)  # m/s


def test_an_aliased_window_reports_its_alias_and_the_speed_it_measures(tmp_path):
    """Frames every 0.7 T up to 3.5 T, start 0: the windows to the end span 3.5, 2.8, 2.1, 1.4
    and 0.7 periods, off 0.5, 0.2, 0.1, 0.4, 0.3 from whole ones: per period 0.143, 0.071,
    0.048, 0.29, 0.43. The least is from 1.4 T: alias 0.1 period, and each speed is the
    displacement over 2.1 T, within amp 2 pi alias / window of the part's own."""
    freq = 50.0
    period = 1 / freq
    times = np.arange(6) * 0.7 * period
    res = transport_on(tmp_path, times, freq, start=0.0)
    assert res.window_frames == (2, 5)
    assert res.alias == pytest.approx(0.1, abs=1e-9)  # periods
    t0, t1 = 1.4 * period, 3.5 * period
    assert res.window == pytest.approx((t0, t1), rel=1e-12)  # s
    assert res.velocities == pytest.approx(speed_over(t0, t1, freq), abs=1e-12)  # m/s
    assert np.all(np.abs(res.velocities - SPEEDS) <= AMP * 2 * np.pi * 0.1 / (t1 - t0) + 1e-12)


def test_a_run_stopped_half_a_period_after_a_frame_ends_at_the_frame_before(tmp_path):
    """Three frames: 0, T and 1.5 T (the run stopped half a period after its last output).
    From a start exactly on frame 0, the window to 1.5 T is 0.5 period off whole ones, the
    window to T is whole: it is the one period (0, T), each part at its own speed."""
    freq = 50.0
    period = 1 / freq
    times = np.array([0.0, 1.0, 1.5]) * period
    res = transport_on(tmp_path, times, freq, start=0.0)
    assert res.window_frames == (0, 1) and res.alias == 0.0
    assert res.window == pytest.approx((0.0, period), abs=1e-15)  # s
    assert res.velocities == pytest.approx(SPEEDS, abs=1e-12)  # m/s


def test_the_last_frame_is_kept_when_its_interval_is_the_usual_one(tmp_path):
    """Frames 0, 0.4 T, 0.7 T, T, 1.3 T: the usual interval is 0.3 T, the odd one is the first,
    so the run did not stop between outputs and the window ends at the last frame (not at T,
    whole from 0). To 1.3 T: from 0 1.3 periods (off 0.3), from 0.4 T 0.9 (off 0.1), from 0.7 T
    0.6 (off 0.4): the window is (0.4 T, 1.3 T), alias 0.1 period."""
    freq = 50.0
    period = 1 / freq
    times = np.array([0.0, 0.4, 0.7, 1.0, 1.3]) * period
    res = transport_on(tmp_path, times, freq, start=0.0)
    assert res.window_frames == (1, 4)
    assert res.alias == pytest.approx(0.1, abs=1e-9)  # periods
    t0, t1 = 0.4 * period, 1.3 * period
    assert res.velocities == pytest.approx(speed_over(t0, t1, freq), abs=1e-12)  # m/s


def test_without_a_frequency_the_window_starts_at_the_frame_nearest_start(tmp_path):
    """No vibration (freq 0): no period to fit, the window runs from the frame nearest start."""
    times = np.arange(11) * 1e-3
    res = transport_on(tmp_path, times, 0.0, start=0.0031, amp=0.0)
    assert res.window_frames == (3, 10) and res.alias == 0.0
    assert res.velocities == pytest.approx(SPEEDS, abs=1e-12)  # m/s
    assert transport_on(tmp_path, times, 0.0, start=0.0036, amp=0.0).window_frames == (4, 10)


def test_a_start_after_the_last_frame_names_the_last_frame(tmp_path):
    times = np.arange(11) * 0.125
    with pytest.raises(InputError, match=re.escape("(1.25 s)")):
        transport_on(tmp_path, times, 50.0, start=2.0)
