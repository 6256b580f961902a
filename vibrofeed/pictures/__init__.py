"""Pictures of a result: rendered images and movies, and ParaView time series.

- :mod:`.scene`: what one frame shows (numpy only): the parts present, the
  triangle meshes of their real shapes (spheres; chips as boxes; discs as
  cylinders) oriented by their quaternions, the track mesh placed at the
  frame's surface position;
- :mod:`.render`: PNG of one frame, MP4 of many, drawn off-screen with pyvista;
- :mod:`.export`: a ParaView ``.pvd`` series of VTK files, one set per frame.

pyvista (and VTK) load only inside the functions that draw or write VTK files,
so importing this package costs numpy alone.
"""

from __future__ import annotations
