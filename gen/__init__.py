"""wirecal.gen — code generation only.

One generator per registered controller language (``gen/<key>/``, its ``GENERATOR``, a
:class:`wirecal.gen.backends.Generator` that renders only, found by
:func:`wirecal.gen.backends.generator`), the duties every generation has
(:mod:`wirecal.gen.preflight`: the pre-flight and the language's checker over the output),
the one request they take (:mod:`wirecal.gen.request`), what they share (``targets``:
joint literals, the run's steps), the controller solver's constant tables and template
rendering.
"""
