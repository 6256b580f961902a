"""Feeders: one description for every feeder, and the object the rest of vibrofeed asks
about its geometry.

A feeder is its parts and its elements in conveying order (a bowl, linear sections,
declining chutes and a track from CAD, any number of them), each element with its own drive
and tooling stations.
:class:`Feeder` is built once from the deck's vocabulary (:meth:`Feeder.from_values`);
a description file (docs/feeders.md, :mod:`.description`) produces that vocabulary and
the deck that runs it.
"""

from .bowl import BowlElement
from .feeder import Feeder
from .joints import Joint
from .linear import LinearSection
from .mesh_element import MeshElement
from .records import Drive, Gate, Part, SideDrop, Wiper

__all__ = ["BowlElement", "Drive", "Feeder", "Gate", "Joint", "LinearSection", "MeshElement", "Part",
           "SideDrop", "Wiper"]
