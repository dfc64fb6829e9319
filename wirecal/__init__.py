"""wirecal — kinematic calibration of robot arms with a single draw-wire encoder.

The public API (see the README's "Python API" section).
"""

__version__ = "0.1.0"
