"""The figures of one finished job, as a summary row holds them.

A bulk-feeder result (one with an outlet table) gets the feed-rate and the
singulation figures of ``vibrofeed feedrate`` and ``vibrofeed singulation``
at their defaults (steady window detected, doubles = no clear track between
consecutive parts); any other deck gets its part count and the mean conveying
velocity of the ``Transport`` analysis (``vibrofeed run``'s summary). Both get
the single-part model's speed for the same vibration (the dilute limit of Khan
& Sarma, §2.3.2, as ``vibrofeed feedrate`` reports it) and the measured /
model ratio. Lists and tables (the velocity profile, the cluster sizes) stay
in the result file; the row keeps scalars, NaN turned into None.
"""

from __future__ import annotations

from ..values import to_json

FEEDRATE = ("parts_per_s", "parts_per_s_err", "mass_per_s", "mass_per_s_err", "mean_velocity",
            "mean_velocity_err", "steady_from", "steady_to", "n_events", "inserted", "exited",
            "on_track", "lost")
SINGULATION = ("cv_interarrival", "doubles_rate", "singulated_fraction", "mean_gap", "n_arrivals",
               "doubles_per_s", "mean_interarrival", "edge_velocity", "track_singulated_fraction",
               "face_up_fraction", "aligned_fraction")
MODEL = ("model_velocity", "velocity_ratio")


def _scalar(value):
    value = to_json(value)  # NaN: None
    if isinstance(value, bool):
        return int(value)
    return value if isinstance(value, int | float) or value is None else None


def metrics(path) -> dict:
    """The figures of the result at ``path`` (module docstring)."""
    from ..postproc import Transport
    from ..postproc.feedrate import FeedRate, dilute_limit, velocity_ratio
    from ..postproc.singulation import Singulation
    from ..results.reader import Result

    out: dict = {}
    with Result(path) as r:
        if r.outlet_plane is not None:
            fr = FeedRate(r).run().summary()
            out.update({k: _scalar(fr.get(k)) for k in FEEDRATE})
            sg = Singulation(r).run().summary()
            out.update({k: _scalar(sg.get(k)) for k in SINGULATION})
            out.update({k: _scalar(fr.get(k)) for k in MODEL})
        else:
            out["n_parts"] = len(r.part_ids)
            v = Transport(r).run().results.mean_velocity if out["n_parts"] and r.n_frames > 2 else None
            out["mean_velocity"] = _scalar(None if v is None else float(v))
            model, _ = dilute_limit(r.parameters)
            out["model_velocity"] = _scalar(model)
            out["velocity_ratio"] = _scalar(velocity_ratio(out["mean_velocity"], model))
    return out
