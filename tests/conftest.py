"""Suite-wide test settings.

Hypothesis runs *derandomized* by default, so the suite (and CI) is reproducible: a property
test fails on a given commit every time or never.  To explore new random examples locally, run
``HYPOTHESIS_PROFILE=explore python -m pytest -q`` (random seeds, more examples); any
counterexample it finds should become an explicit regression test.
"""

from __future__ import annotations

import os

from hypothesis import settings

settings.register_profile("default", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("explore", derandomize=False, deadline=None, max_examples=500)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))
