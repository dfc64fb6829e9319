"""A measurement log as the solver takes it: one wire length per plan point.

Its readings, each row placed against the plan, the log's checks as a whole, and the
measurements the solver identifies from.
"""
