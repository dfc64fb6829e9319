"""wirecal.gen — code generation only: one backend per controller language (``vplus``),
the controller solver's constant tables, literal formatting and template rendering.
"""
