"""The Hypothesis profiles, selected on import by ``tests/conftest.py``.

``HYPOTHESIS_PROFILE`` names the profile; without it, ``ci`` when ``CI=true`` and
Hypothesis's own default otherwise:

* ``ci`` — derandomized (the examples follow from each test alone, the same on every run
  and machine) and no example database: a red CI run is the code's change, never a new draw;
* ``explore`` — fresh random examples on every run, failures kept in the local database
  and replayed first, and 1000 examples for the tests that do not set their own number:
  the run that looks for new failures (``.ci/explore``), not a gate.
"""

from __future__ import annotations

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, database=None, deadline=None, print_blob=True)
settings.register_profile("explore", derandomize=False, max_examples=1000, deadline=None)

PROFILE = os.environ.get("HYPOTHESIS_PROFILE") or (
    "ci" if os.environ.get("CI", "").lower() == "true" else None
)
if PROFILE is not None:
    settings.load_profile(PROFILE)
