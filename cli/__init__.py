"""wirecal.cli — the ``wirecal`` command line: a thin click layer over the Python API."""
