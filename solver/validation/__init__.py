"""The paper's validation procedures (§3.6) and a third of wire lengths.

Their design and their analyses.
"""
