"""wirecal.solver — the robot model and the mathematics of draw-wire calibration.

Functions over numpy arrays, vectorised over configurations: the robot model
(:mod:`~wirecal.solver.robot`, :mod:`~wirecal.solver.kinematics`), Ψ, identifiability,
planning, simulation, identification, accuracy and validation analysis. Reading and writing
files is :mod:`wirecal.formats`, the layer above (docs/architecture.md). Angles are
degrees at every boundary (files, CLI) and radians inside the maths.
"""
