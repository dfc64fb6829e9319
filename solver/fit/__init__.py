"""``wirecal fit``: calibrating from a cable-length table taken without wirecal.

The table, the model, the sessions, the units, the choice of parameters, the held-out
check, the gate, the result and the synthetic tables of the tests and the bench.
"""
