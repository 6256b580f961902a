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

What an analysis could not measure is missing, never a number: with too few
exits in the window, or a bed still drifting (the feed-rate analysis'
``reason``), the rates are None and ``feedrate_reason`` says why (as
``vibrofeed feedrate`` prints n/a and the reason); with too few arrivals, the
arrival statistics are None and ``singulation_reason`` says why. A feeder
line (``sections`` = 2) adds its sections' figures, flattened with the
section's number: ``joint_flux_K`` and ``joint_flux_K_err`` (through the joint
after section K: the last section's is ``parts_per_s``), ``speed_K``,
``hold_up_K`` (every section) and ``reject_rate_K`` (sections past the first,
where the tooling is); the rates among them are missing with the feed rate. A bowl
has the same columns: section 1 is its helix, 2 its chute.
Chips and discs get their ``orientation_yield`` (face up and aligned). Parts that are clumps
(chips, discs, boxes) also get the figures of ``vibrofeed orientation`` at its defaults (correct
= the run's own parameter ``correct``, "up, lengthwise" unless the feeder or the study says
otherwise; lengthwise within 20 degrees), over the same window: ``correct_fraction``,
``lengthwise_fraction``, ``correct_rate`` and ``oriented_rate`` (correct single parts per
second) with their errors ``*_err``, and ``recirculation_per_s`` (the parts sent back); None
for spheres, and the fractions and rates None with too few arrivals (``singulation_reason``:
the same exits).
"""

from __future__ import annotations

from ..values import to_json

FEEDRATE = ("parts_per_s", "parts_per_s_err", "mass_per_s", "mass_per_s_err", "mean_velocity",
            "mean_velocity_err", "steady_from", "steady_to", "n_events", "inserted", "exited",
            "on_track", "lost")
SINGULATION = ("cv_interarrival", "doubles_rate", "singulated_fraction", "mean_gap", "n_arrivals",
               "doubles_per_s", "mean_interarrival", "edge_velocity", "track_singulated_fraction",
               "face_up_fraction", "aligned_fraction", "orientation_yield")
ORIENTATION = ("correct_fraction", "lengthwise_fraction", "correct_rate", "correct_rate_err",
               "oriented_rate", "oriented_rate_err", "recirculation_per_s")
# What too few arrivals void of them (the command voids the same: vibrofeed.cli.orientation RATE_KEYS).
ORIENTATION_UNMEASURED = ORIENTATION[:-1]
MODEL = ("model_velocity", "velocity_ratio")
# What a reason for measuring nothing voids (the commands void the same: vibrofeed.cli.feedrate
# RATE_KEYS and SECTION_RATE_KEYS, vibrofeed.cli.singulation ARRIVAL_KEYS).
FEEDRATE_UNMEASURED = ("parts_per_s", "parts_per_s_err", "mass_per_s", "mass_per_s_err")
SINGULATION_UNMEASURED = ("mean_interarrival", "cv_interarrival", "mean_gap", "doubles_rate",
                          "doubles_per_s", "singulated_fraction")
# A line's per-section figures: column stem -> (key in FeedRate's sections, key of its error
# or None, a rate over the window (voided with the feed rate), which sections have it).
SECTIONS = {
    "joint_flux": ("joint_flux", "joint_flux_error", True, "joints"),
    "speed": ("speed", None, False, "all"),
    "hold_up": ("hold_up", None, False, "all"),
    "reject_rate": ("reject_rate", None, True, "downstream"),
}


def _scalar(value):
    value = to_json(value)  # NaN: None
    if isinstance(value, bool):
        return int(value)
    return value if isinstance(value, int | float) or value is None else None


def section_columns(sections: list[dict], measured: bool) -> dict:
    """A line's ``sections`` (FeedRate.summary()) as flat columns (module docstring); the
    rates None when the feed rate is not ``measured``."""
    out = {}
    last = len(sections)
    for s in sections:
        k = int(s["section"])
        for stem, (key, err_key, rate, which) in SECTIONS.items():
            if (which == "joints" and k == last) or (which == "downstream" and k == 1):
                continue
            keep = measured or not rate
            out[f"{stem}_{k}"] = _scalar(s.get(key)) if keep else None
            if err_key is not None:
                out[f"{stem}_{k}_err"] = _scalar(s.get(err_key)) if keep else None
    return out


def metrics(path) -> dict:
    """The figures of the result at ``path`` (module docstring)."""
    from ..postproc import Transport
    from ..postproc.feedrate import FeedRate, dilute_limit, velocity_ratio
    from ..postproc.orientation import Orientation
    from ..postproc.singulation import Singulation
    from ..results.reader import Result

    out: dict = {}
    with Result(path) as r:
        if r.outlet_plane is not None:
            feedrate = FeedRate(r).run()
            fr = feedrate.summary()
            out.update({k: _scalar(fr.get(k)) for k in FEEDRATE})
            out["feedrate_reason"] = fr.get("reason") or None
            if out["feedrate_reason"]:
                out.update(dict.fromkeys(FEEDRATE_UNMEASURED))
            out.update(section_columns(fr.get("sections") or [], not out["feedrate_reason"]))
            # over feed rate's window, found once (Singulation would search it again)
            singulation = Singulation(r, start=fr["steady_from"], end=fr["steady_to"]).run()
            sg = singulation.summary()
            out.update({k: _scalar(sg.get(k)) for k in SINGULATION})
            out["singulation_reason"] = sg.get("reason") or None
            if out["singulation_reason"]:
                out.update(dict.fromkeys(SINGULATION_UNMEASURED))
            if r.body_template is not None:  # the same window, feed rate and arrivals
                o = Orientation(r, start=fr["steady_from"], end=fr["steady_to"], feedrate=feedrate.results,
                                singulation=singulation.results).run().results
                out.update({k: _scalar(o.get(k)) for k in ORIENTATION})
                if out["singulation_reason"]:
                    out.update(dict.fromkeys(ORIENTATION_UNMEASURED))
            else:
                out.update(dict.fromkeys(ORIENTATION))
            out.update({k: _scalar(fr.get(k)) for k in MODEL})
        else:
            out["n_parts"] = len(r.part_ids)
            v = Transport(r).run().results.mean_velocity if out["n_parts"] and r.n_frames > 2 else None
            out["mean_velocity"] = _scalar(None if v is None else float(v))
            model, _ = dilute_limit(r.parameters)
            out["model_velocity"] = _scalar(model)
            out["velocity_ratio"] = _scalar(velocity_ratio(out["mean_velocity"], model))
    return out
