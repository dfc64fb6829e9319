"""wirecal.twin — the digital twin.

The physical world the programs act on (``world``: true robot, draw-wire encoder, disk,
operator, faults, clock; the one move protocol ``World.move`` and the one run factory),
and per controller language (``vplus``, ``urscript``, ``rapid``) an interpreter of the
programs wirecal generates, the controller that maps the language's instructions onto the
world and the world's refusals onto its own stops, and the language's twin adapter
(``adapters``: a ``TwinAdapter`` declaring its capabilities); what the interpreters share
(``machine``).
"""
