"""wirecal.app — application workflows built from the solver, the generator and the twin.

The one-command demo, the HTML report, the Ψ table view and the controller comparison.
"""
