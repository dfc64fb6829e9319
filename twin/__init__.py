"""wirecal.twin — the digital twin.

Per controller language a parser, checker and interpreter of the programs wirecal
generates (``vplus``, ``urscript``), what the interpreters share (``machine``), and the
simulated cell (true robot, draw-wire encoder, disk, terminal, faults, clock) they run
against: ``cell`` for V+, ``ur_cell`` the same cell behind the URScript API (sockets to
``wirecal receive``, the pulse decoder, movej timing).
"""
