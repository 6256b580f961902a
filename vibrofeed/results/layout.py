"""The layout of a vibrofeed result file: H5MD 1.1 plus a few agreed paths.

This module is the single description of the format: the writer creates these
paths, the reader reads them and ``vibrofeed check`` validates them. FORMAT.md
documents the same layout for people.
"""

from __future__ import annotations

H5MD_VERSION = (1, 1)
UNITS_MODULE_VERSION = (1, 0)
FORMAT_NAME = "vibrofeed-result"
FORMAT_VERSION = (1, 1)  # 1.1: parameters/run@id, parameters/includes

PARTS = "particles/parts"
SURFACE = "observables/surface"
PARAMETERS = "parameters"
RUN = "parameters/run"
VARIABLES = "parameters/variables"
DERIVED = "parameters/derived"

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

# Time-dependent observables of the vibrating surface, shape (frames, 3).
SURFACE_ELEMENTS = {
    "position": ("f8", 3, "m"),
    "velocity": ("f8", 3, "m s-1"),
}

TIME_UNIT = "s"

# Run states recorded in parameters/run@status.
STATUS_RUNNING = "running"
STATUS_COMPLETE = "complete"
STATUS_FAILED = "failed"
STATUS_INTERRUPTED = "interrupted"
STATUSES = (STATUS_RUNNING, STATUS_COMPLETE, STATUS_FAILED, STATUS_INTERRUPTED)

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
