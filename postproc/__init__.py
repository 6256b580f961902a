"""Post-processing of vibrofeed H5MD results: one analysis shape for all.

Every analysis is built with the result it reads and its settings, runs over
a selection of frames and answers in ``results``::

    from vibrofeed.postproc import Flights, Transport

    tr = Transport(result, start=0.1).run()         # mean speed over whole periods
    fl = Flights(result).run(start=100)             # hops of one part, from frame 100
    tr.results.mean_velocity, fl.results.landings

- :mod:`.base`: :class:`AnalysisBase` and :class:`Results`, the shape;
- :mod:`.transport`: :class:`Transport`, conveying speed along the track;
- :mod:`.flights`: :class:`Flights`, lift-offs, landings and impacts of one part;
- :mod:`.feedrate`: :class:`FeedRate`, parts and mass per second at a bulk
  feeder's outlet over the detected steady window, conveying speed profile;
- :mod:`.singulation`: :class:`Singulation`, inter-arrival times, doubles,
  gaps, clusters on the track and chip orientation at the outlet;
- :mod:`.orientation`: :class:`Orientation`, the parts' states (face up, lengthwise) at the
  outlet, through each tooling station and along the path, and the rate of correctly
  oriented single parts;
- :mod:`.clusters`: :func:`cluster_labels`, the contact graph's components.
"""

from __future__ import annotations

from .base import AnalysisBase, Results
from .clusters import cluster_labels, cluster_sizes
from .feedrate import FeedRate
from .flights import Flights
from .orientation import Orientation
from .singulation import Singulation
from .transport import Transport

__all__ = ["AnalysisBase", "Results", "Transport", "Flights", "FeedRate", "Singulation", "Orientation",
           "cluster_labels", "cluster_sizes"]
