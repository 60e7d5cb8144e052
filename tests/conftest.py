"""Suite-wide test settings.

Hypothesis runs *derandomized* by default, so the suite (and CI) is reproducible: a property
test fails on a given commit every time or never.  To explore new random examples locally, run
``HYPOTHESIS_PROFILE=explore python -m pytest -q`` (random seeds, more examples); any
counterexample it finds should become an explicit regression test.
"""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile

from hypothesis import settings

# The compiler's per-user caches (Lark tables, compiled safety LTSs: outputs.user_cache_dir) go
# to a fresh folder per test session, also for the iterc subprocesses the tests start: a run
# never reads an entry written by other code, and the user's ~/.cache is left alone.
if "ITERPLAN_TEST_KEEP_CACHE" not in os.environ:
    os.environ["XDG_CACHE_HOME"] = tempfile.mkdtemp(prefix="iterplan-test-cache-")
    atexit.register(shutil.rmtree, os.environ["XDG_CACHE_HOME"], ignore_errors=True)

settings.register_profile("default", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("explore", derandomize=False, deadline=None, max_examples=500)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))
