"""wirecal.solver — the robot model and the mathematics of draw-wire calibration.

Pure functions over numpy arrays; file formats live in :mod:`robot` and :mod:`plan`.
Angles are degrees at every boundary (files, CLI) and radians inside the maths.
"""
