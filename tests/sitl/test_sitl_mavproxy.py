"""The paper's deployment style: Fire Patrol flown by the MAVProxy module (`module load
iterplan`, `iterplan run/status/stop`) inside a real MAVProxy against real ArduPlane SITL.

Skipped (with the reason) when MAVProxy is not installed (`pip install iterplan[mavproxy]`, or
`pip install MAVProxy`) or the SITL kit is absent (conftest.py).  Each scenario runs in a
private network namespace (mavproxy_scenario.py) on SITL instance 3 (tcp 5790..), so it does not
meet the other SITL tests' instances.
"""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

from iterplan_compiler.runtime.mapfile import load_map
from tests.examples.behaviour import check_fire_patrol
from tests.sitl.harness import ROOT, log_events, run_scenario

pytestmark = pytest.mark.skipif(importlib.util.find_spec("MAVProxy") is None,
                                reason="MAVProxy is not installed (pip install MAVProxy, or "
                                       "pip install -e '.[mavproxy]')")

MAP = str(ROOT / "examples" / "fire_patrol.json")


@pytest.fixture(scope="module")
def controller(tmp_path_factory):
    target = tmp_path_factory.mktemp("mavproxy-controller") / "fire_patrol.py"
    subprocess.run([sys.executable, "-m", "iterplan_compiler", "compile",
                    str(ROOT / "examples" / "fire_patrol.lts"), "-o", str(target)],
                   check=True, capture_output=True, cwd=ROOT)
    return str(target)


def run_mavproxy(tmp: Path, **spec) -> dict:
    return run_scenario(tmp, module="tests.sitl.mavproxy_scenario",
                        **{"instance": 3, "map": MAP, **spec})


def describe(res: dict) -> str:
    console = "\n".join(ln for ln in res.get("console", "").splitlines()
                        if "Got MISSION_ACK" not in ln)
    return (f"summary={json.dumps(res.get('summary'))}\n--- MAVProxy console (no MISSION_ACKs, "
            f"tail)\n{console[-5000:]}")


def test_fire_patrol_flies_through_mavproxy(controller, tmp_path):
    res = run_mavproxy(tmp_path, controller=controller)
    assert res["loaded"], describe(res)
    s = res.get("summary")
    assert s, describe(res)
    assert s["ok"] and s["reason"] == "completed" and s["arrivals"] == 9, describe(res)
    assert s["vehicle"] == "MavlinkVehicle" and 21 < s["speed_mps"] < 26, describe(res)
    assert s["safe_state"] == "loiter commanded; vehicle in GUIDED", describe(res)
    console = res["console"]
    # the runtime's start-up ran over MAVProxy's link: pre-arm wait, arm, take-off, GUIDED
    assert "iterplan: mavlink: waiting for" in console and "pre-arm" in console
    assert "iterplan: mission flying" in console          # `iterplan status` answered mid-flight
    assert "iterplan: mission completed" in console
    assert "commands.csv" in res and "arm" in res["commands.csv"]
    check_fire_patrol(log_events(res, load_map(MAP)), load_map(MAP))


def test_iterplan_stop_ends_the_mission_safely(controller, tmp_path):
    res = run_mavproxy(tmp_path, controller=controller, action="stop", action_after=2)
    s = res.get("summary")
    assert s and "action_wall" in res, describe(res)
    assert not s["ok"] and s["reason"] == "interrupted", describe(res)
    assert 2 <= s["arrivals"] < 9, describe(res)
    assert s["safe_state"] == "loiter commanded; vehicle in GUIDED", describe(res)
    # it ended promptly: within a few wall seconds of the command
    assert res["mission_wall"] - res["action_wall"] < 10, describe(res)


def test_quitting_mavproxy_mid_mission_ends_it_safely_with_outputs(controller, tmp_path):
    res = run_mavproxy(tmp_path, controller=controller, action="quit", action_after=2)
    s = res.get("summary")
    assert s, describe(res)              # outputs written although MAVProxy was exiting
    assert s["reason"] == "interrupted" and s["safe_state"].startswith("loiter commanded"), \
        describe(res)
    assert not res.get("mavproxy_killed"), describe(res)
