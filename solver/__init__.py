"""wirecal.solver — the robot model and the mathematics of draw-wire calibration.

Functions over numpy arrays, vectorised over configurations: the robot model
(:mod:`~wirecal.solver.robot`, :mod:`~wirecal.solver.kinematics`), Ψ, identifiability,
planning, simulation, identification, accuracy and validation analysis. The model every
part shares and the solver's steps are modules at this level; the rest is in sub-packages
by concern: :mod:`~wirecal.solver.plan`, :mod:`~wirecal.solver.cell`,
:mod:`~wirecal.solver.ik`, :mod:`~wirecal.solver.log`, :mod:`~wirecal.solver.fit`,
:mod:`~wirecal.solver.tracker`, :mod:`~wirecal.solver.validation`. Reading and writing
files is :mod:`wirecal.formats`, the layer above (docs/architecture.md). Angles are
degrees at every boundary (files, CLI) and radians inside the maths.
"""
