"""The feeder-line comparisons of `vibrofeed validate` (kinds line_transport and line_continuity)
on inputs whose answers are known by hand: the lag of whole periods of two drives, the span of
a part, the closest approach of two parts, each section's speed, and Little's law (hold-up,
speed, rho v) with the inlet's rate on synthetic lines."""

import math

import numpy as np
import pytest

from bulk_synthetic import JOINT, S2_LENGTH, bed, line_feeder
from helpers import parts, write_bulk_result
from vibrofeed.errors import CaseError
from vibrofeed.postproc import FeedRate
from vibrofeed.results.reader import Result
from vibrofeed.validation.crosscheck import (
    batch_error,
    closest_approach,
    drive_freqs,
    inlet_flux,
    little_flows,
    part_span,
    section_speeds,
    whole_period_stride,
)


def test_the_drive_frequencies_of_a_lines_sections():
    p = {"freq": 100.0, "s2_freq": 150.0}
    assert drive_freqs(p, 2) == [100.0, 150.0] and drive_freqs(p, 1) == [100.0]


@pytest.mark.parametrize("frame_dt, freqs, stride", [
    (0.01, [100.0], 1),            # one period
    (0.005, [100.0], 2),           # two frames per period
    (0.01, [100.0, 150.0], 2),     # 20 ms: 2 and 3 periods (10 ms would be 1.5 of 150 Hz)
    (0.005, [100.0, 150.0], 4),
    (0.004, [100.0, 125.0], 10),   # 40 ms: 4 and 5 periods (20 ms would be 2.5 of 125 Hz)
])
def test_the_lag_spans_whole_periods_of_every_drive(frame_dt, freqs, stride):
    assert whole_period_stride(frame_dt, freqs) == stride


def test_no_lag_of_whole_periods_is_refused():
    with pytest.raises(CaseError, match="whole periods"):
        whole_period_stride(0.01, [100.0, 100.0 * math.sqrt(2)], max_stride=20)


@pytest.mark.parametrize("p, span", [
    ({"shape": 0, "part_size": 3e-4}, 3e-4),
    ({"shape": 0, "part_size": 3e-4, "size_spread": 0.1}, 3.3e-4),        # the largest sphere
    ({"shape": 1, "part_size": 3e-4, "part_thickness": 1.5e-4}, 4.5e-4),  # box diagonal
    ({"shape": 2, "part_size": 4e-4, "part_thickness": 3e-4}, 5e-4),      # cylinder: 3-4-5
])
def test_part_span(p, span):
    assert part_span(p) == pytest.approx(span, rel=1e-12)


def test_the_closest_approach_of_two_parts_on_the_line(tmp_path):
    # parts 1 and 2 side by side 0.5 mm apart in y at x = 1 mm, part 3 at 3 mm, and at the
    # second frame part 2 moves to x = 1.3 mm (then 0.3 and 0.5 mm from 1: 0.583 mm), part 4
    # beyond the outlet edge (4 mm) falling just 0.1 mm from part 3's x: not on the line
    frames = [(0, 0.0, parts([1, 2, 3], [[1e-3, 0, 1e-4], [1e-3, 5e-4, 1e-4], [3e-3, 0, 1e-4]])),
              (1, 0.01, parts([1, 2, 3, 4], [[1e-3, 0, 1e-4], [1.3e-3, 5e-4, 1e-4],
                                             [3.95e-3, 0, 1e-4], [4.05e-3, 0, 1e-4]]))]
    path = write_bulk_result(tmp_path / "r.h5", frames, outlet={"outlet_x": 4e-3, "catch_z": -3e-4,
                                                                "method": "synthetic"})
    with Result(path) as r:
        assert closest_approach(r, 4e-3) == pytest.approx(5e-4, rel=1e-12)
        assert closest_approach(r, 5e-3) == pytest.approx(1e-4, rel=1e-9)  # part 4 counted


def two_drive_line(path, v1=0.01, v2=0.03, a1=4e-5, a2=3e-5):
    """A line (joint 4 mm, outlet 9 mm; section 1 at 100 Hz, section 2 at 150 Hz), frames every
    5 ms: part 1 on section 1 from x = 1 mm at v1, part 2 on section 2 from 5 mm at v2, each
    swinging with its own section's sine (amplitudes a1, a2), part 3 at rest 0.2 mm before the
    joint (within a part size of it: never counted)."""
    t = np.arange(0, 0.2 + 1e-9, 0.005)
    x1 = 1e-3 + v1 * t + a1 * np.sin(2 * np.pi * 100 * t)
    x2 = 5e-3 + v2 * t + a2 * np.sin(2 * np.pi * 150 * t)
    frames = [(k, tk, parts([1, 2, 3], [[x1[k], 0, 1e-4], [x2[k], 0, 1e-4], [3.8e-3, 0, 1e-4]]))
              for k, tk in enumerate(t)]
    variables = {name: (repr(value), "", "", repr(value)) for name, value in
                 {"freq": 100.0, "sections": 2.0, "track_length": 4e-3, "s2_length": 5e-3,
                  "s2_freq": 150.0, "part_size": 3e-4}.items()}
    return write_bulk_result(path, frames, variables=variables,
                             outlet={"outlet_x": 9e-3, "catch_z": -3e-4, "method": "synthetic"})


def test_each_sections_speed_over_whole_periods_of_both_drives(tmp_path):
    with Result(two_drive_line(tmp_path / "line.h5")) as r:
        (s1, n1), (s2, n2) = section_speeds(r, t_from=0.02, joint_margin=5e-4, edge_margin=3e-4)
    # 20 ms intervals (2 periods of 100 Hz, 3 of 150 Hz): the swings cancel exactly
    assert s1 == pytest.approx(0.01, rel=1e-9) and s2 == pytest.approx(0.03, rel=1e-9)
    # from 0.02 s, 9 intervals of 20 ms to 0.2 s: part 1 on section 1 (x <= 3.7 mm) in all,
    # part 2 (5.6 mm at 0.02 s, past the joint margin of 4.5 mm) in the 5 up to 0.12 s, when it
    # is at 8.6 mm: at 0.14 s it is at 9.2 mm, past 8.7 mm (a part size before the edge)
    assert (n1, n2) == (9, 5)


def test_a_part_held_at_the_joint_is_left_out(tmp_path):
    # part 3 at rest 0.2 mm before the joint is within a part size of it: with no margin it
    # would pull section 1's mean speed down to (9 x 0.01 + 9 x 0) / 18
    with Result(two_drive_line(tmp_path / "line.h5")) as r:
        (s1, n1), _ = section_speeds(r, t_from=0.02, joint_margin=5e-4, edge_margin=0.0)
    assert (s1, n1) == (pytest.approx(0.005, rel=1e-9), 18)


# -- Little's law on a synthetic line ---------------------------------------------------------
FRAMES = np.arange(0, 0.6 + 1e-9, 0.005)
# a part crosses the joint every 10 ms, 2.1 ms after a frame: 100 parts/s; section 1 at
# 20 mm/s (parts 0.2 mm apart), section 2 at 50 mm/s (0.5 mm apart: 10 parts on its 5 mm)
TJ = -0.3979 + 0.01 * np.arange(130)
V1, V2 = 0.02, 0.05


def test_line_density_times_speed_is_the_flux(tmp_path):
    with Result(line_feeder(tmp_path / "line.h5", FRAMES, TJ, v1=V1, v2=V2)) as r:
        fr = FeedRate(r, start=0.2, end=0.5).run().results
        flows = little_flows(r, fr, x_from=2e-3, batches=10)
        feed, feed_error = inlet_flux(r, 0.2, 0.5)
    s1, s2 = flows
    # section 1 from 2 mm to the 6 mm joint: 20 parts 0.2 mm apart at every frame
    assert s1["hold_up"] == pytest.approx(20, abs=1e-12)
    assert s1["hold_up_error"] == pytest.approx(0, abs=1e-12)
    assert s1["rho"] == pytest.approx(20 / 4e-3, rel=1e-12) and s1["speed"] == pytest.approx(V1, rel=1e-9)
    assert s2["hold_up"] == pytest.approx(10, abs=1e-12) and s2["speed"] == pytest.approx(V2, rel=1e-9)
    for s in flows:
        assert s["flow"] == pytest.approx(100.0, rel=1e-9) and s["flow_error"] == pytest.approx(0, abs=1e-9)
    # the line density falls by the speed ratio
    assert s1["rho"] / s2["rho"] == pytest.approx(V2 / V1, rel=1e-9)
    # the inlet: a part enters (at x = 0) every 10 ms; 30 in the 0.3 s window, exact to one
    assert feed == pytest.approx(100.0, rel=1e-9) and feed_error == pytest.approx(1 / 0.3, rel=1e-9)
    assert S2_LENGTH == 5e-3 and JOINT == 6e-3  # what the counts above assume


def test_over_the_whole_section_1_rho_v_misses_where_parts_enter(tmp_path):
    # parts fed onto section 1 at x = 1.6 mm (as an inlet drops them, not at its start) travel
    # 4.4 of its 6 mm: 22 of them on it at every frame, so over the whole section rho v =
    # 22 / 6 mm x 20 mm/s = J x 4.4 / 6; from 2 mm on (a stretch every part crosses) it is J
    def x_at(t):
        return np.where(t < TJ, JOINT - V1 * (TJ - t), JOINT + V2 * (t - TJ))

    path = bed(tmp_path / "line.h5", FRAMES, x_at, enter=TJ - (JOINT - 1.6e-3) / V1,
               leave=TJ + S2_LENGTH / V2, outlet_x=JOINT + S2_LENGTH, line=True, joint=JOINT)
    with Result(path) as r:
        fr = FeedRate(r, start=0.2, end=0.5).run().results
        whole = little_flows(r, fr, x_from=0.0, batches=10)[0]
        past = little_flows(r, fr, x_from=2e-3, batches=10)[0]
    assert whole["hold_up"] == pytest.approx(22, abs=1e-12)
    assert whole["flow"] == pytest.approx(100.0 * 4.4 / 6, rel=1e-9)
    assert past["flow"] == pytest.approx(100.0, rel=1e-9)


def test_batch_error_leaves_out_empty_batches():
    assert batch_error([1.0, 2.0, 3.0, np.nan]) == pytest.approx(1 / math.sqrt(3), rel=1e-12)
    assert math.isnan(batch_error([2.0, np.nan]))
