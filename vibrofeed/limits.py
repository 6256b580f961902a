"""The physical limits a result is held to (FORMAT.md, "What check checks"), in one place for
``vibrofeed check`` (vibrofeed.results.check), which rejects a run beyond them, and for the
parameter rules (vibrofeed.parameters), which say before a run that it would go beyond them.
"""

# No part of a vibratory feeder moves faster than a hundred times the surface's peak speed
# plus the free fall from the height of the scene, nor than MIN_SPEED_LIMIT whatever the drive.
SPEED_FACTOR = 100.0
MIN_SPEED_LIMIT = 1.0  # m/s
# A run whose air jets fired: its parts may fly this many track sizes from the track (blown
# off over the wall, they fall to the catch plane on a ballistic path) before they count as
# escaped.
JET_THROW = 4.0
