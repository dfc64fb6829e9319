"""wirecal.twin — the digital twin.

Per controller language a parser, checker and interpreter of the programs wirecal
generates (``vplus``), and the simulated cell (true robot, draw-wire encoder, disk,
terminal, faults, clock) they run against.
"""
