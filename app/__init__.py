"""wirecal.app — application workflows built from the solver, the generator and the twin.

The one-command demo, the HTML report, the Ψ table view, the controller comparison, the
measurement runs in the twin (``twin_runs``; ``twin_simulate`` for ``wirecal simulate
--controller``), ``wirecal receive``'s server and the progress bar. The layer above
generation and the twin, below the API and the command line (docs/architecture.md).
"""
