"""wirecal.gen — code generation only.

One backend per controller language (``vplus``), the controller solver's constant tables,
literal formatting and template rendering.
"""
