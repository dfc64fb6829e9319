"""wirecal.gen — code generation only.

One generator per registered controller language (``gen/<key>/``, its ``GENERATOR``,
found by :func:`wirecal.gen.backends.generator`), the one request they take
(:mod:`wirecal.gen.request`), what they share (``targets``: limits, joint literals, the
run's steps), the controller solver's constant tables and template rendering.
"""
