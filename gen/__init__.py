"""wirecal.gen — code generation only.

One backend per controller language (``vplus``, ``urscript``), what they share
(``targets``: limits, joint literals, the run's steps), the controller solver's constant
tables and template rendering.
"""
