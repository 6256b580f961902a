"""Everything drawn: plots of the analyses, rendered images and movies, ParaView series.

- :mod:`.plots`: matplotlib set up without a display and :func:`~.plots.save`
  (the one way the package and the validation figures write PNGs), and the
  feed-rate and singulation plots; :mod:`.sweep_maps`: the sweep report's maps;
- :mod:`.caption`: the line that names the run a figure shows;
- :mod:`.scene`: what one frame shows (numpy only): the parts present, the
  triangle meshes of their real shapes (spheres; chips as boxes; discs as
  cylinders) oriented by their quaternions, the track mesh placed at the
  frame's surface position;
- :mod:`.render`: PNG of one frame, MP4 of many, drawn off-screen with pyvista;
- :mod:`.export`: a ParaView ``.pvd`` series of VTK files, one set per frame.

matplotlib, pyvista and VTK load only inside the functions that draw or write
files, so importing this package costs numpy alone.
"""

from __future__ import annotations
