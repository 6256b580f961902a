"""The analytic theory: the project's second engine, independent of LIGGGHTS.

constants        gravity and the other shared numbers, defined once
surface          the surface-motion protocol and every concrete motion
roots            bracketed event-root searches shared by the integrators
part_on_surface  one part on a vibrating track: stick, slip, flight, impacts
hopping          Gamma > 1: flights, period-one limits, bifurcations
subhopping       Gamma < 1: stick/slip transport on flat and inclined tracks
inplane          horizontal-only waveforms (stick-slip, Coulomb pump)
vertical         a part squeezed against a vertically vibrating wall
adhesion         van der Waals attraction between a part and the track
squeeze_film     the air film's squeeze damping under a part
rocking          a block rocking, tipping or sliding on a vibrating or inclined plate
deck             a deck's parameters -> these models' objects (the same numbers as the DEM)

Sources: K. A. Khan, S. E. Sarma, "Vibratory Assembly Update: Part
Transportation Mechanics Analysis" (MIT Auto-ID Center), sections 2.1-2.4, for
the part on a track; C. Yako, J. Nowak, S. Yuan, K. Salisbury, "Vertical
Vibratory Transport of Grasped Parts Using Impacts" (ICRA 2024), section
"Dynamics", for the vertical model; G. W. Housner, "The behavior of inverted
pendulum structures during earthquakes" (Bull. Seismol. Soc. Am. 53(2), 1963),
for rocking. Importing this package loads numpy and
scipy only: no deck, engine or result machinery.
"""
