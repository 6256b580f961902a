"""The layout of a vibrofeed result file: H5MD 1.1 plus a few agreed paths.

This module is the single description of the format: the writer creates these
paths, the reader reads them and ``vibrofeed check`` validates them. FORMAT.md
documents the same layout for people.
"""

from __future__ import annotations

H5MD_VERSION = (1, 1)
UNITS_MODULE_VERSION = (1, 0)
FORMAT_NAME = "vibrofeed-result"
# 1.1: parameters/run@id, parameters/includes; 1.2: bulk feeder additions; 1.3: the outlet
# table moves out of observables/ (H5MD observables are quantities sampled in time, the table is
# one row per event), the box gets its edges, unit and system become variable-length strings
# (H5MD units module). Files of 1.0 to 1.2 still read: READ_OUTLETS lists where they keep it.
# 1.4: a feeder line records each section's motion (observables/surface_s<k>, k >= 2) and which
# section each vertex of parameters/track belongs to (parameters/track/section); 1.3 files of
# a line (section 2's motion unrecorded) still read, and check only warns about them.
# 1.5: a line that recirculates its rejects counts them back (mass balance ``returned``);
# optional in 1.5 (files without them stay valid): parameters/run@stop_reason, why the engine
# ended the run, and @target_error, the feed rate's relative error a run was told to stop at.
# 1.6: a rotating surface (the bowl feeder) also records its rotation about the z axis through
# the origin in SURFACE: ``angle`` and ``angular_velocity`` (optional elements: files without
# them are valid, their surface does not rotate).
FORMAT_VERSION = (1, 6)
SECTIONS_SINCE = (1, 4)  # the first format that records a line's sections

PARTS = "particles/parts"
SURFACE = "observables/surface"  # the (first) section's motion: every run has it
OUTLET = "vibrofeed/outlet"   # a non-H5MD group: H5MD allows unspecified groups at the root
OUTLET_BEFORE_1_3 = "observables/outlet"
REJECTS = "vibrofeed/rejects"  # a feeder line's reject table, beside the outlet's
MASS_BALANCE = "observables/mass_balance"
PARAMETERS = "parameters"
RUN = "parameters/run"
VARIABLES = "parameters/variables"
DERIVED = "parameters/derived"
TRACK = "parameters/track"
BODY_TEMPLATE = "parameters/body_template"

# Fill values for the slots of particles that do not exist at a frame.
ID_FILL = -1
SPECIES_FILL = -1

# Time-dependent per-particle elements: name -> (dtype, components, unit).
# components = 0 means a scalar per particle.
PART_ELEMENTS = {
    "position": ("f8", 3, "m"),
    "velocity": ("f8", 3, "m s-1"),
    "angular_velocity": ("f8", 3, "rad s-1"),
    "force": ("f8", 3, "N"),  # total force on the part at the frame's step (contacts + body forces)
    "radius": ("f8", 0, "m"),
    "mass": ("f8", 0, "kg"),
    "species": ("i4", 0, None),
    "id": ("i8", 0, None),
}

# Optional per-particle elements, written only by runs that have them (bulk
# feeders): a file without them stays a valid result. The orientation is a unit
# quaternion (w, x, y, z) rotating the body template into the simulation frame;
# plain spheres have (1, 0, 0, 0).
OPTIONAL_PART_ELEMENTS = {
    "orientation": ("f8", 4, None),
}
IDENTITY_QUATERNION = (1.0, 0.0, 0.0, 0.0)

# The outlet event table (one row per part leaving the track, not a time
# series): name -> (dtype, components, unit).
OUTLET_ELEMENTS = {
    "time": ("f8", 0, "s"),
    "id": ("i8", 0, None),
    "position": ("f8", 3, "m"),
    "velocity": ("f8", 3, "m s-1"),
    "orientation": ("f8", 4, None),
}
OUTLET_ATTRIBUTES = ("outlet_x", "catch_z", "method")


def outlet_path(f) -> str | None:
    """Where an open result file keeps its outlet table (format 1.3 or earlier), or None."""
    for path in (OUTLET, OUTLET_BEFORE_1_3):
        if path in f:
            return path
    return None


# The box is open along every axis (boundary "none"), so H5MD reads its edges
# as placeholders; they are written (zeros, a time series hard-linked to the
# positions' step and time) because readers such as znh5md and ASE expect them.
BOX_BOUNDARY = ("none", "none", "none")
BOX_EDGES_PLACEHOLDER = (0.0, 0.0, 0.0)
# box/pbc: the boundary as booleans (periodic or not) per axis, a time series sampled with the
# positions. Not an H5MD item (H5MD allows others): znh5md takes the periodicity from it, and
# without it reads the fixed-length `boundary` strings H5MD prescribes as periodic.
BOX_PBC = tuple(b == "periodic" for b in BOX_BOUNDARY)

# A feeder line's reject table: as the outlet's, plus the section a part fell from
# (its position tells which tooling: the side drop's stretch, or before the wiper).
REJECT_ELEMENTS = {**OUTLET_ELEMENTS, "section": ("i4", 0, None)}
# A line's air jets (orienting stations, vibrofeed.engine.jets): one row per firing, a part
# sensed in a state the jet does not keep (or too soon after the last it passed: its
# headway). Optional (a line with a jet has it; no new format version): time sensed (its
# crossing of the sensing point), the body, the section, its state
# (index into vibrofeed.orientation.STATES), the window the jet fired in, late (1: the window
# would have started before the frame that sensed the part, and started at that frame).
JET = "vibrofeed/jet"
JET_ELEMENTS = {
    "time": ("f8", 0, "s"),
    "id": ("i8", 0, None),
    "section": ("i4", 0, None),
    "state": ("i4", 0, None),
    "start": ("f8", 0, "s"),
    "end": ("f8", 0, "s"),
    "late": ("i1", 0, None),
}
OUTLET_TABLES = (OUTLET, REJECTS)  # the event tables with the outlet's attributes
EVENT_TABLES = {OUTLET: OUTLET_ELEMENTS, REJECTS: REJECT_ELEMENTS, JET: JET_ELEMENTS}

# The mass balance, one H5MD time series of int64 per count: inserted = on_track
# + exited + lost, where exited counts the outlet events so far (parts that left
# the track, including those still falling to the box floor) and lost the parts
# that disappeared without an event (must stay 0).
MASS_BALANCE_COUNTS = ("inserted", "on_track", "exited", "lost")
# A run whose feeder has rejects (vibrofeed.feeders.Feeder.has_rejects, a line) also counts
# them, the parts that fell off a side (one event each in REJECTS):
# inserted = on_track + exited + rejected + lost.
LINE_COUNTS = MASS_BALANCE_COUNTS + ("rejected",)
# A line that returns its rejects (Feeder.returns_rejects: recirculate=1) also counts the
# parts returned to the inlet so far, each a new part and part of inserted (format 1.5):
# returned <= rejected.
RETURN_COUNTS = LINE_COUNTS + ("returned",)

# Time-dependent observables of the vibrating surface, shape (frames, 3).
SURFACE_ELEMENTS = {
    "position": ("f8", 3, "m"),
    "velocity": ("f8", 3, "m s-1"),
}
# A rotating surface (a bowl: its deck defines ROTATION_VARIABLES) also records its rotation
# about the z axis through the origin as a rotation vector (0, 0, angle) and its rate, in
# SURFACE beside position and velocity: the surface at frame k is its rest mesh turned by the
# angle about z, then moved by the position.
ROTATION_ELEMENTS = {
    "angle": ("f8", 3, "rad"),
    "angular_velocity": ("f8", 3, "rad s-1"),
}
ROTATION_VARIABLES = ("surface_angle", "surface_wz")  # [rad], [rad/s] about +z
ROTATION_SINCE = (1, 6)
# A feeder line (parameter `sections` > 1) records each further section's motion as its own
# observable beside SURFACE, with the same elements: section k >= 2 under surface_s<k> (the
# s<k>_* names of its parameters). Section 1 stays SURFACE, so what reads a single track reads
# a line's first section unchanged. parameters/track/section then gives each vertex's section.
TRACK_SECTION = "parameters/track/section"


def surface_path(section: int) -> str:
    """The observable of section ``section``'s motion (1-based): SURFACE for the first."""
    if section < 1:
        raise ValueError(f"sections count from 1, got {section}")
    return SURFACE if section == 1 else f"{SURFACE}_s{section}"


def surface_variables(section: int) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The deck's equal-style variables of a section's motion: (x, y, z), (vx, vy, vz)."""
    prefix = "" if section == 1 else f"s{section}_"
    return (tuple(f"{prefix}surface_{c}" for c in "xyz"),
            tuple(f"{prefix}surface_v{c}" for c in "xyz"))


# The sine drive of section k >= 2 (a line's sections are sine-driven): the parameters
# s<k>_freq [Hz], s<k>_amp_t, s<k>_amp_n [m], s<k>_phase [deg].
SECTION_DRIVE = ("freq", "amp_t", "amp_n", "phase")
# ... and, where the section moves across its track too, s<k>_amp_c [m] and s<k>_phase_c [deg]
# (absent: 0, as in the files written before cross strokes existed).
SECTION_CROSS = ("amp_c", "phase_c")

TIME_UNIT = "s"

# Run states recorded in parameters/run@status.
STATUS_RUNNING = "running"
STATUS_COMPLETE = "complete"
STATUS_FAILED = "failed"
STATUS_INTERRUPTED = "interrupted"
STATUSES = (STATUS_RUNNING, STATUS_COMPLETE, STATUS_FAILED, STATUS_INTERRUPTED)

# Why the engine ended a run that reached its end (parameters/run@stop_reason): the text starts
# with STOP_AT_END (t_end, or a schedule's end: "t_end", or "t_end (target error 0.03 not
# reached: ...)") or with STOP_AT_TARGET (the feed rate's relative error fell to the run's
# target_error first: "target error 0.03 reached: 0.028 at t = 1.42 s").
STOP_AT_END = "t_end"
STOP_AT_TARGET = "target error"


def stopped_early(stop_reason: str) -> bool:
    """Whether a run stopped before its end because its target error was reached."""
    return stop_reason.startswith(STOP_AT_TARGET)


# Names every deck must define for vibrofeed to drive it (equal-style
# variables evaluated by the engine at each frame, or once at the start).
DECK_CONTRACT = (
    "n_steps",
    "output_every",
    "dt_used",
    "surface_x",
    "surface_y",
    "surface_z",
    "surface_vx",
    "surface_vy",
    "surface_vz",
)

# A feeder line's deck defines each further section's motion too: surface_variables(k) for
# section k = 2, ... (s2_surface_x ... s2_surface_vz), evaluated at each frame as surface_* are.

# A bulk feeder's deck defines these too (all or none): the outlet edge and the
# catch plane [m], the parts inserted so far and the spheres per part. The
# worker then writes bodies, outlet events and the mass balance.
BULK_CONTRACT = (
    "outlet_x",
    "catch_z",
    "n_inserted",
    "body_spheres",
)
