"""Real ArduPlane SITL tests: skipped (with the reason) only when the SITL kit is absent."""

import subprocess
import sys

import pytest

from tests.sitl.harness import ROOT, sitl_dir

EXAMPLES = {
    # name: extra `iterc run` arguments that make the mission end
    "fire_patrol": [],
    "cover": [],
    "find_nemo": [],
    "ordered_patrol": ["--until", "visited.p.0:3"],
    "search_and_map": ["--until", "restart"],
}


def pytest_collection_modifyitems(config, items):
    if sitl_dir() is None:
        skip = pytest.mark.skip(reason="ArduPilot SITL kit not found (../shared/sitl beside "
                                       "the clone, or $ITERPLAN_SITL_DIR)")
        for item in items:
            if "tests/sitl" in str(item.fspath):
                item.add_marker(skip)


@pytest.fixture(scope="session")
def controllers(tmp_path_factory):
    """The five examples compiled once with `iterc compile`."""
    d = tmp_path_factory.mktemp("sitl-controllers")
    out = {}
    for name in EXAMPLES:
        target = d / f"{name}.py"
        subprocess.run([sys.executable, "-m", "iterplan_compiler", "compile",
                        str(ROOT / "examples" / f"{name}.lts"), "-o", str(target)],
                       check=True, capture_output=True, cwd=ROOT)
        out[name] = (str(target), str(ROOT / "examples" / f"{name}.json"))
    return out
