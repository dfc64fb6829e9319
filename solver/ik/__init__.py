"""Inverse kinematics: every solution for a flange pose.

The industrial 6R structure analytically, others numerically, and the closed form of
UR-type arms.
"""
