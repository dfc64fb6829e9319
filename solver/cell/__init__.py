"""The cell and collisions: what the arm must not touch.

The arm's own body, the floor and the keep-out volumes, a plan's moves checked
against them, and the wire's clearance from the links.
"""
