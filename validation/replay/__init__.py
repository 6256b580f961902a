"""Measured trials replayed (``vibrofeed replay``): the part's motion predicted
from the platform's, by the vertical-transport model or by LIGGGHTS.

trials  reader of the published trial files and the platform's spline fit
fit     model replay of a trial, and fitting its friction and normal force
dem     the same replay run in LIGGGHTS

VERTICAL_TRANSPORT_NOTES.md records what limits the prediction
(``studies.vertical_study`` recomputes its numbers).
"""
