"""wirecal.twin — the digital twin.

The physical world the programs act on (``world``: true robot, draw-wire encoder, disk,
operator, faults, clock), and per controller language (``vplus``, ``urscript``) a parser,
checker and interpreter of the programs wirecal generates, the controller that maps the
language's instructions onto the world, and the language's twin adapter (``adapters``);
what the interpreters share (``machine``).
"""
