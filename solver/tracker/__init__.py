"""A laser tracker's data: joint angles and measured tool points.

The data, its 3-D calibration and its replay through one simulated wire.
"""
