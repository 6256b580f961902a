"""The one-line summary printed at the end of ``vibrofeed run``."""

from __future__ import annotations

from .errors import InputError
from .postproc import Flights, Transport
from .results.reader import Result


def _si(x: float, unit: str) -> str:
    for factor, prefix in ((1, ""), (1e-3, "m"), (1e-6, "u")):
        if abs(x) >= factor or factor == 1e-6:
            return f"{x / factor:.3g} {prefix}{unit}"
    return f"{x:g} {unit}"


def _stopped(run) -> str:
    """Why a run given a target error ended, in parentheses ('' without one)."""
    if run.target_error is None or not run.stop_reason:
        return ""
    return f" ({'stopped early: ' * run.stopped_early}{run.stop_reason})"


def run_summary(run) -> str:
    """``deck: t simulated (why it ended, with a target error) in wall (rate) -> file |
    physics of the parts`` (or, for a result kept by ``--reuse``, where it is and its run id
    instead of a speed)."""
    if run.reused:  # nothing ran now: no speed to report
        head = (f"{run.deck}: reused {run.output} (run id {run.run_id[:12]}..., not run again): "
                f"{run.sim_time:.4g} s simulated{_stopped(run)}, {run.frames} frames")
    else:
        head = (f"{run.deck}: {run.sim_time:.4g} s simulated{_stopped(run)} in {run.wall:.1f} s "
                f"({run.steps_per_second / 1e3:.0f}k steps/s, {run.ranks} rank{'s' * (run.ranks > 1)}), "
                f"{run.frames} frames -> {run.output}")
    with Result(run.output) as r:
        n = len(r.part_ids)
        bits = [f"{n} part{'s' * (n != 1)}"]
        balance = r.mass_balance
        if balance is not None:  # a feeder: where its parts went (the analyses say how fast)
            last = {k: int(v[-1]) for k, v in balance.items()}
            rejected = f", {last['rejected']} rejected" if "rejected" in last else ""
            returned = last.get("returned")
            fed = (f"{last['inserted'] - returned} parts fed + {returned} returned"
                   if returned is not None else f"{last['inserted']} parts fed")
            bits = [f"{fed}: {last['exited']} exited{rejected}, "
                    f"{last['on_track']} on the track, {last['lost']} lost"]
        elif n and r.n_frames > 2:
            v = Transport(r).run().results.mean_velocity
            bits.append(f"mean speed {_si(v, 'm/s')} along x" if v == v  # NaN: no part stayed
                        else "no part on the track through the second half (mean speed n/a)")
        if n == 1 and r.n_frames > 2:
            try:
                fl = Flights(r).run().results
            except InputError as exc:  # frames too far apart to follow the hops: say so, not fail
                bits.append(f"hops not counted ({exc})")
            else:
                period = 1.0 / float(r.parameters.get("freq", 1.0))
                hops = int((fl.durations >= 0.05 * period).sum())  # shorter: rebounds
                rebounds = fl.n_hops - hops
                flying = (f", in flight from t = {fl.in_flight_at_end:.3g} s to the end"
                          if fl.in_flight_at_end is not None else "")  # a flight not landed
                bits.append(f"{hops} hops" + (f" (+{rebounds} short rebounds)" if rebounds else "")
                            + f"{flying}, airborne {fl.airborne_fraction:.0%} of the time, "
                            f"highest {_si(fl.max_gap, 'm')}")
    return head + " | " + ", ".join(bits)
