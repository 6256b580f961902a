"""--target-error: when the worker stops a bulk run (vibrofeed.engine.worker: judge_feed_rate,
TargetError), on synthetic outlet events whose statistics are known, and how the result
records it (writer, reader, check, the run's summary).

The decision is FeedRate's own relative error of the rate over the frames so far, so a run
it stops is one that `vibrofeed feedrate` reports at or below the target: each stop below is
also judged on a file that ends at the stop frame, as the worker's does.
"""

import math
import types

import numpy as np
import pytest

from bulk_synthetic import OUTLET_X, bed, feeder, poisson_times
from helpers import vibrofeed
from vibrofeed.engine.runner import RunResult, check_target_error, run_id
from vibrofeed.engine.worker import CHECK_FRACTION, TargetError, judge_feed_rate
from vibrofeed.errors import UsageError
from vibrofeed.postproc.feedrate import FeedRate
from vibrofeed.results import layout as L
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import ResultWriter

FREQ = 100.0                # Hz: a period of 10 ms
FRAME_DT = 0.005            # s: two frames per period
TRACK = 0.005               # m: the parts' path, 0.25 s at SPEED
SPEED = 0.02                # m/s
BATCHES = 10                # FeedRate's default, what `vibrofeed feedrate` uses


def fed(path, exits, t_end, frame_dt=FRAME_DT, rate=100.0):
    """A track fed at ``rate`` whose part k leaves over the edge at ``exits[k]``, every part at
    the same speed (a steady bed), frames every ``frame_dt`` from 0 to ``t_end``."""
    frames = np.arange(0.0, t_end + 1e-9, frame_dt)
    return feeder(path, frames, exits, speed=SPEED, outlet_x=TRACK, freq=FREQ,
                  variables={"inlet_rate": (repr(rate), "1/s", "parts fed per second", "0")})


def first_stop(result, target, every=1):
    """The first frame count (checking every ``every`` frames) at which the run stops, and its verdict."""
    for stop in range(2, result.n_frames + 1, every):
        verdict = judge_feed_rate(result, target, stop=stop)
        if verdict.reached:
            return stop, verdict
    return None, verdict


def reported(path, exits, stop, frame_dt=FRAME_DT, rate=100.0):
    """What FeedRate (its defaults: `vibrofeed feedrate`) reports on the file a run stopped
    after frame ``stop`` leaves: (relative error, exits in the steady window)."""
    with Result(fed(path, exits, (stop - 1) * frame_dt, frame_dt, rate)) as r:
        fr = FeedRate(r, model=False).run().results
    inside = (fr.event_times >= fr.steady_from) & (fr.event_times < fr.steady_to)
    return fr.parts_per_s_err / fr.parts_per_s, int(inside.sum())


# -- the decision ----------------------------------------------------------------------------
def test_regular_arrivals_stop_as_soon_as_the_window_holds_its_batches(tmp_path):
    # three exits per period, evenly spaced: every batch of whole periods holds the same
    # count, so the batch-means error is 0 (to round-off) once there are batches at all.
    # Ten exits come after 3.3 periods; ten batches of a whole period each only after 10.
    exits = (np.arange(400) + 0.5) / 300.0
    with Result(fed(tmp_path / "regular.h5", exits, 0.3, rate=300.0)) as r:
        stop, verdict = first_stop(r, 0.01)
        before = judge_feed_rate(r, 0.01, stop=stop - 1)
    assert verdict.t == pytest.approx(BATCHES / FREQ, abs=1e-9)        # s: 10 periods
    assert verdict.error == pytest.approx(0.0, abs=1e-9)
    assert not before.reached
    assert before.why == "the steady window (0.09 s) holds 9 of the 10 batches"
    # what `vibrofeed feedrate` reports on the file that ends there: the error judged
    error, _ = reported(tmp_path / "stopped.h5", exits, stop, rate=300.0)
    assert error == pytest.approx(verdict.error, abs=1e-12) and error <= 0.01


@pytest.mark.parametrize("seed", range(8))
def test_poisson_arrivals_stop_when_sqrt_n_says_so(tmp_path, seed):
    """Poisson exits at 200/s: the rate's relative error over a window of N exits is
    1/sqrt(N), so a target of 0.2 wants N ~ 1/0.2^2 = 25. A 10-batch estimate scatters by
    about 1/sqrt(2 x 9) = 24 % of itself, and the run stops at the first check where it is at
    or below the target, so on its low side: the reported error at the stop lies within
    0.6 .. 1.4 times 1/sqrt(N) (about -1.7 .. +1.7 of its scatter; seeds 0-11 give 0.74 ..
    1.22), and N within 0.5 .. 2 times 1/target^2 (seeds 0-11: 0.68 .. 1.68)."""
    target = 0.2
    exits = poisson_times(200.0, 0.0, 1.0, np.random.default_rng(seed))
    with Result(fed(tmp_path / "poisson.h5", exits, 0.8, frame_dt=0.01, rate=200.0)) as r:
        stop, verdict = first_stop(r, target)
    assert stop is not None, verdict.why
    error, n = reported(tmp_path / "stopped.h5", exits, stop, frame_dt=0.01, rate=200.0)
    assert error == pytest.approx(verdict.error, abs=1e-12) and error <= target
    assert 0.6 <= error * math.sqrt(n) <= 1.4, (error, n)
    assert 0.5 <= n * target ** 2 <= 2.0, n


def test_a_bed_that_is_not_steady_never_stops(tmp_path):
    # a fed track whose pre-filled bed drains (all parts at 16 mm/s, nobody enters): the
    # rate's error falls below 0.5 within the run, but the hold-up falls: not steady
    n = 200
    x0 = OUTLET_X - 1e-4 * (np.arange(n) + 1)
    frames = np.arange(0.0, 0.5 + 1e-9, FRAME_DT)
    variables = {"inlet_rate": ("50.0", "1/s", "parts fed per second", "0")}
    path = bed(tmp_path / "drain.h5", frames, lambda t: x0 + 0.016 * t, np.full(n, -np.inf),
               (OUTLET_X - x0) / 0.016, amp=3e-5, freq=FREQ, variables=variables)
    with Result(path) as r:
        stop, verdict = first_stop(r, 0.5, every=20)
        fr = FeedRate(r, model=False).run().results
    assert fr.parts_per_s_err / fr.parts_per_s < 0.5
    assert stop is None and verdict.why.startswith("not steady: the hold-up on section 1 falls")


def test_too_few_exits_measure_nothing(tmp_path):
    # 300 exits/s from 0.2 s on: before ten, no window can hold enough (the frames are not
    # read); then FeedRate's own reason, for the exits in its window
    exits = (np.arange(60) + 0.5) / 300.0 + 0.2
    with Result(fed(tmp_path / "late.h5", exits, 0.3, rate=300.0)) as r:
        none = judge_feed_rate(r, 0.5, stop=30)
        some = judge_feed_rate(r, 0.5, stop=48)
    assert not none.reached and math.isnan(none.error)
    assert none.why == "too few exits to measure (0 so far; need ≥ 10 in the window)"
    assert not some.reached and some.why == "too few exits to measure (6 in the window; need ≥ 10)"


def test_exits_are_counted_up_to_the_judged_frame_inclusive(tmp_path):
    # exits exactly at frame times (k x 5 ms): the frame at 25 ms has seen 5 of them; at 50 ms
    # ten, which is enough to read the frames (FeedRate then counts those in its window)
    exits = FRAME_DT * np.arange(1, 60)
    with Result(fed(tmp_path / "a.h5", exits, 0.3, rate=200.0)) as r:
        five = judge_feed_rate(r, 0.5, stop=6)
        ten = judge_feed_rate(r, 0.5, stop=11)
    assert five.t == 0.025 and five.why == "too few exits to measure (5 so far; need ≥ 10 in the window)"
    assert ten.t == 0.05 and not ten.reached and math.isnan(ten.error)
    assert ten.why == "too few exits to measure (8 in the window; need ≥ 10)"  # FeedRate's own


def test_the_first_frame_alone_measures_nothing(tmp_path):
    # ten parts over the edge at t = 0: enough exits, but FeedRate refuses a single frame
    exits = np.concatenate([np.zeros(10), 2e-4 * np.arange(1, 40)])
    with Result(fed(tmp_path / "a.h5", exits, 0.1, rate=1000.0)) as r:
        v = judge_feed_rate(r, 0.5, stop=1)
    assert (v.reached, v.t, v.why) == (False, 0.0, "feed rate: at least two frames are needed")


def test_a_target_equal_to_the_error_is_reached(tmp_path):
    """At or below the target: the error itself reaches it, the next float below does not."""
    exits = (np.arange(400) + 0.5) / 300.0
    with Result(fed(tmp_path / "a.h5", exits, 0.3, rate=300.0)) as r:
        error = judge_feed_rate(r, 0.5).error
        at = judge_feed_rate(r, error)
        below = judge_feed_rate(r, float(np.nextafter(error, 0.0)))
    assert at.reached and at.error == error and at.why == ""
    assert not below.reached and below.error == error and below.why == f"relative error {error:.3g}"


def test_a_feed_rate_below_one_part_per_second_is_measured(tmp_path):
    # 0.8 parts/s, evenly spaced (every 1.25 s) for 50 s: a rate, its batch-means error 0
    exits = (np.arange(40) + 0.5) / 0.8
    with Result(fed(tmp_path / "slow.h5", exits, 50.0, frame_dt=0.5, rate=0.8)) as r:
        v = judge_feed_rate(r, 0.01)
    assert v.reached and v.error == pytest.approx(0.0, abs=1e-9) and v.t == 50.0


def test_a_window_that_opens_late_says_its_own_length(tmp_path):
    # exits from 0.1 s on, three per period; judged at the frame at 0.185 s: 26 exits, so
    # FeedRate's bins are whole periods, 18 // 10 -> two each, the last whole one ending at
    # 0.18 s; the window opens with the feed at 0.1 s: 0.08 s, 8 periods, 8 of 10 batches
    exits = (np.arange(400) + 0.5) / 300.0 + 0.1
    with Result(fed(tmp_path / "late.h5", exits, 0.3, rate=300.0)) as r:
        stop = int(np.searchsorted(r.time, 0.185 - 1e-9)) + 1
        v = judge_feed_rate(r, 0.5, stop=stop)
    assert not v.reached and v.t == pytest.approx(0.185, abs=1e-12) and math.isnan(v.error)
    assert v.why == "the steady window (0.08 s) holds 8 of the 10 batches"


def test_too_few_frames_to_judge_the_bed_never_stop(tmp_path):
    # a frame every 3 periods up to 0.12 s: the window (12 periods, 36 exits, error 0) holds
    # its ten batches, but its 5 frames give the bed fewer batch values than a drift needs
    from vibrofeed.postproc.line import DRIFT_MIN_BATCHES

    exits = (np.arange(400) + 0.5) / 300.0
    with Result(fed(tmp_path / "coarse.h5", exits, 0.12, frame_dt=0.03, rate=300.0)) as r:
        assert r.n_frames == 5 < DRIFT_MIN_BATCHES
        v = judge_feed_rate(r, 0.5)
    assert (v.reached, v.why) == (False, "too few frames in the window to judge the bed steady")
    assert math.isnan(v.error)


def test_a_result_without_a_frequency_is_judged_as_feedrate_judges_it(tmp_path):
    """Without a vibration frequency FeedRate cuts the window into 200 units, its batches 20
    each: the judge takes the same batches (not periods of some other frequency)."""
    import h5py

    exits = (np.arange(400) + 0.5) / 300.0
    path = fed(tmp_path / "a.h5", exits, 0.3, rate=300.0)
    with h5py.File(path, "r+") as f:
        del f[L.VARIABLES]["freq"]
    with Result(path) as r:
        assert "freq" not in r.parameters
        v = judge_feed_rate(r, 0.01)
        fr = FeedRate(r, model=False).run().results
    # evenly spaced exits: every batch of 0.03 s holds 9 of them, the error is 0
    assert v.reached and v.error == pytest.approx(0.0, abs=1e-9)
    assert v.error == pytest.approx(fr.parts_per_s_err / fr.parts_per_s, abs=1e-12)


def test_judging_does_not_run_the_single_part_model(tmp_path, monkeypatch):
    """Rank 0 judges during the run while the other ranks wait: it spares the single-part
    model (which does not touch the rate), an integration of its own."""
    from vibrofeed.postproc import feedrate

    monkeypatch.setattr(feedrate, "dilute_limit", lambda *a: pytest.fail("the model was run"))
    exits = (np.arange(400) + 0.5) / 300.0
    with Result(fed(tmp_path / "a.h5", exits, 0.3, rate=300.0)) as r:
        assert judge_feed_rate(r, 0.01).reached


# -- the worker's checks ---------------------------------------------------------------------
class Replay:
    """Rank 0's writer of a run, frame by frame: the frames and events of a synthetic result
    handed to a ResultWriter as the worker hands them over."""

    def __init__(self, source: Result, path, target=None):
        self.src = source
        self.writer = ResultWriter(path, deck_name="synthetic_bulk", deck_path="synthetic.liggghts",
                                   deck_text="# synthetic\n", variables=self._variables(),
                                   derived={"dt_used": 1e-6}, engine_version="LIGGGHTS (synthetic)",
                                   seed=1, outlet=source.outlet_plane, target_error=target)
        self._t = -math.inf

    def _variables(self) -> dict:
        return {name: (repr(v) if isinstance(v, float) else v, "", "", "")
                for name, v in self.src.parameters.items()}

    def frame(self, k: int) -> float:
        src, t = self.src, float(self.src.time[k])
        ev = src.outlet
        new = (ev["time"] > self._t) & (ev["time"] <= t)
        self.writer.write_events({name: values[new] for name, values in ev.items()})
        self._t = t
        f = src.frame(k, fields=("position", "velocity", "radius", "mass"))
        parts = {"id": f.ids, "species": np.ones(len(f), int), "radius": f["radius"],
                 "mass": f["mass"], "position": f["position"], "velocity": f["velocity"],
                 "angular_velocity": np.zeros((len(f), 3)), "force": np.zeros((len(f), 3))}
        counts = {name: int(v[k]) for name, v in src.mass_balance.items()}
        self.writer.write_frame(int(src.step[k]), t, parts, src.surface_position[k],
                                src.surface_velocity[k], counts=counts)
        return t


ONE_RANK = types.SimpleNamespace(size=1, rank=0)


def test_the_worker_stops_at_the_first_check_that_reaches_the_target(tmp_path):
    """TargetError over a file being written (read through the writer's own handle): it
    checks the frames so far at the spacing CHECK_FRACTION allows, stops at the first
    check that reaches the target, and the file it leaves reports what it judged."""
    exits = (np.arange(400) + 0.5) / 300.0
    with Result(fed(tmp_path / "source.h5", exits, 0.3, rate=300.0)) as src:
        run = Replay(src, tmp_path / "run.h5", target=0.01)
        target, checked = TargetError(0.01, ONE_RANK), []
        for k in range(src.n_frames):
            t = run.frame(k)
            before = target.verdict
            if target.reached(run.writer, t):
                break
            if target.verdict is not before:
                checked.append(t)
        reason = target.stop_reason(at_end=False)
        run.writer.finish(L.STATUS_COMPLETE, wall_seconds=1.0, stop_reason=reason)
    # each check at least CHECK_FRACTION of the time run (from the first frame, t = 0) after
    # the one before; up to 0.1 s that is one frame at most: every frame is checked, and the
    # run stops where judge_feed_rate first says so (10 periods, as above)
    later = np.array(checked[1:])
    assert (later - checked[:-1] >= CHECK_FRACTION * later - 1e-12).all()
    assert len(checked) == 19 and t == pytest.approx(BATCHES / FREQ, abs=1e-9)
    assert reason == f"target error 0.01 reached: {target.verdict.error:.3g} at t = {t:.4g} s"
    with Result(tmp_path / "run.h5") as r:
        assert r.time[-1] == t and r.stop_reason == reason and r.target_error == 0.01
        fr = FeedRate(r).run().results
    assert fr.parts_per_s_err / fr.parts_per_s == pytest.approx(target.verdict.error, abs=1e-12)
    report = check_file(tmp_path / "run.h5")
    assert report.ok, [str(p) for p in report.problems]


def test_a_run_that_never_reaches_its_target_says_so_at_t_end(tmp_path):
    exits = poisson_times(200.0, 0.0, 0.5, np.random.default_rng(1))
    with Result(fed(tmp_path / "source.h5", exits, 0.3, frame_dt=0.01, rate=200.0)) as src:
        run = Replay(src, tmp_path / "run.h5", target=1e-3)
        target = TargetError(1e-3, ONE_RANK)
        stops = [target.reached(run.writer, run.frame(k), last=k == src.n_frames - 1)
                 for k in range(src.n_frames)]
        reason = target.stop_reason(at_end=True)
        run.writer.finish(L.STATUS_COMPLETE, stop_reason=reason)
    assert not any(stops)
    v = target.verdict
    assert v.t == pytest.approx(0.3, abs=1e-12) and 1e-3 < v.error < 1
    assert reason == f"t_end (target error 0.001 not reached at t = 0.3 s: relative error {v.error:.3g})"
    assert not L.stopped_early(reason) and check_file(tmp_path / "run.h5").ok


def test_every_rank_takes_rank_0s_decision():
    """Only rank 0 has a writer; the others get its decision by broadcast, at the same frames."""
    class Comm:
        size, rank = 2, 1

        def __init__(self):
            self.calls = 0

        def bcast(self, value, root):
            assert root == 0 and value is None  # rank 1 has nothing to say
            self.calls += 1
            return True

    comm = Comm()
    target = TargetError(0.05, comm)
    assert not target.reached(None, 0.0)            # the first frame: nothing to judge
    assert target.reached(None, 0.01) and comm.calls == 1
    assert not target.reached(None, 0.0101) and comm.calls == 1   # too soon after the last check


# -- the record ------------------------------------------------------------------------------
def test_check_accepts_the_stop_record_and_refuses_a_malformed_one(tmp_path):
    import h5py

    exits = (np.arange(100) + 0.5) / 100.0
    path = fed(tmp_path / "a.h5", exits, 0.2)
    with Result(path) as r:      # written without: "" and None, and valid
        assert r.stop_reason == "" and r.target_error is None
    for attrs, ok in [({"stop_reason": "t_end"}, True),
                      ({"stop_reason": "target error 0.1 reached: 0.09 at t = 0.2 s",
                        "target_error": 0.1}, True),
                      ({"stop_reason": "target error 0.1 reached: 0.09 at t = 0.2 s"}, False),
                      ({"stop_reason": "tired"}, False),
                      ({"stop_reason": "t_end", "target_error": 1.5}, False)]:
        with h5py.File(path, "r+") as f:
            for name in ("stop_reason", "target_error"):
                f[L.RUN].attrs.pop(name, None)
            f[L.RUN].attrs.update(attrs)
        report = check_file(path)
        assert report.ok == ok, (attrs, [str(p) for p in report.problems])


def test_the_target_is_refused_outside_0_1_and_for_a_deck_without_an_outlet():
    from vibrofeed.decks import Deck

    bulk = Deck.find("bulk_feeder")
    assert check_target_error(None, bulk) is None and check_target_error("0.03", bulk) == 0.03
    for bad in (0, 1, -0.1, 1.5, math.nan, "x"):
        with pytest.raises(UsageError, match="target error"):
            check_target_error(bad, bulk)
    with pytest.raises(UsageError, match="deck single_part has no outlet"):
        check_target_error(0.03, Deck.find("single_part"))
    # a target changes where the run ends: another run id; none keeps the old ids
    values = {"t_end": "1"}
    assert run_id(bulk, values) == run_id(bulk, values, target_error=None)
    assert run_id(bulk, values, target_error=0.03) != run_id(bulk, values)


@pytest.mark.parametrize("args, message", [
    (["single_part", "--target-error", "0.03"], "deck single_part has no outlet"),
    (["bulk_feeder", "--target-error", "1.5"], "target error 1.5 is outside (0, 1)"),
])
def test_the_command_refuses_in_one_line_before_running(tmp_path, args, message):
    proc = vibrofeed("run", *args, "-q", "-o", tmp_path / "x.h5")
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1
    assert proc.stderr.startswith("vibrofeed: error: ") and message in proc.stderr
    assert not list(tmp_path.iterdir())


def test_the_summary_says_when_a_run_stopped_early(tmp_path):
    from vibrofeed.run_summary import run_summary

    path = fed(tmp_path / "a.h5", (np.arange(100) + 0.5) / 100.0, 0.2)
    run = RunResult(output=path, log=tmp_path / "a.log", deck="bulk_feeder", ranks=1, n_steps=200,
                    dt=1e-3, frames=41, sim_time=0.2, wall=2.0, target_error=0.05,
                    stop_reason="target error 0.05 reached: 0.041 at t = 0.2 s")
    line = run_summary(run)
    assert line.startswith("bulk_feeder: 0.2 s simulated (stopped early: target error 0.05 "
                           "reached: 0.041 at t = 0.2 s) in 2.0 s")
    run.stop_reason = "t_end (target error 0.001 not reached at t = 1 s: relative error 0.02)"
    assert "s simulated (t_end (target error 0.001 not reached" in run_summary(run)
    run.target_error, run.stop_reason = None, "t_end"
    assert run_summary(run).startswith("bulk_feeder: 0.2 s simulated in 2.0 s")
