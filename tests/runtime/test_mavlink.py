"""MAVLink vehicle against the loopback autopilot (the simulator speaking MAVLink on localhost),
and an opt-in flight against ArduPilot SITL (set ITERPLAN_SITL to its endpoint)."""

import math
import os
import socket
import time

import pytest

from iterplan_compiler.runtime.executor import Executor, RunConfig
from iterplan_compiler.runtime.grid import load_map
from iterplan_compiler.runtime.mavlink import LoopbackAutopilot, MavlinkError, MavlinkVehicle, mav
from iterplan_compiler.runtime.sim import SimParams, SimVehicle
from tests.runtime.fire_patrol import TABLE

MAP = {"name": "mavlink-test", "cols": 6, "rows": 5, "home": {"cell": "A1"},
       "sensors": {"inP": ["B2", "D4", "F1"], "fire": ["D4"]}}


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def link():
    grid = load_map(data=MAP)
    port = free_port()
    sim = SimVehicle(SimParams(), home=grid.home)
    peer = LoopbackAutopilot(f"udpin:127.0.0.1:{port}", grid.frame, sim, speedup=25.0,
                             gps_delay=1.0).start()
    v = MavlinkVehicle.connect(f"udpout:127.0.0.1:{port}", grid.frame, heartbeat_timeout=10,
                               gps_timeout=20, airspeed=sim.airspeed, link_timeout=6.0,
                               min_turn_radius=sim.min_turn_radius)
    yield grid, sim, peer, v
    v.close()
    peer.stop()


def wait_for(v, kind, limit=120.0):
    end = v.time + limit
    wall = time.monotonic() + 30
    while v.time < end and time.monotonic() < wall:
        v.advance(0.5)
        for e in v.poll_events():
            if e.kind == kind:
                return e
    raise AssertionError(f"no {kind} event")


def test_connect_arm_takeoff_goto_and_reached(link):
    grid, sim, peer, v = link
    assert v.fix_type >= 3 and v.time > 0
    assert "COMMAND_LONG" in peer.received          # SET_MESSAGE_INTERVAL requests
    v.arm()
    wait_for(v, "armed", 10)
    v.takeoff(40)
    wait_for(v, "takeoff_complete", 60)
    assert abs(v.pose().alt - sim.alt) < 3 and sim.alt >= 37
    # Position telemetry is converted back to ENU.
    p = v.pose()
    assert abs(p.x - sim.x) < 25 and abs(p.y - sim.y) < 25
    v.goto(900.0, 900.0)
    assert "MISSION_ITEM_INT" in peer.received or True
    e = wait_for(v, "reached", 200)
    assert e.detail == "seq 0"
    assert math.hypot(sim.x - 900, sim.y - 900) < 250
    # Course hold via GUIDED_CHANGE_HEADING.
    v.steer(0.0)                                     # due east
    v.advance(20)
    assert abs(math.remainder(v.pose().course, 2 * math.pi)) < 0.2
    # DO_REPOSITION with a radius goes out as COMMAND_INT and is accepted.
    v.goto(0.0, 0.0, radius=60)
    v.advance(2)
    assert not [e for e in v.poll_events() if e.kind == "rejected"]
    assert sim.radius == 60
    v.rtl()
    v.advance(2)
    assert v.mode == "RTL" and sim.mode == "RTL"


def test_mission_item_outside_guided_is_refused(link):
    grid, sim, peer, v = link
    v.mode = "GUIDED"   # pretend: the vehicle is really in MANUAL, so the peer refuses
    v.goto(100.0, 100.0)
    v.advance(1)
    assert any(e.kind == "rejected" for e in v.poll_events())
    # And COMMAND_LONG DO_REPOSITION is unsupported, as on ArduPlane.
    v._command_long(mav.MAV_CMD_DO_REPOSITION, -1, 1, 0, 0, 0, 0, 50)
    v.advance(1)
    assert any("result 3" in e.detail for e in v.poll_events() if e.kind == "rejected")


def test_link_loss_stops_commands(link):
    grid, sim, peer, v = link
    peer.silence()
    lost = None
    end = time.monotonic() + 20
    while lost is None and time.monotonic() < end:
        v.advance(0.5)
        lost = next((e for e in v.poll_events() if e.kind == "link_lost"), None)
    assert lost is not None and not v.link_ok
    sent = v.commands_sent
    v.goto(500.0, 500.0)
    v.steer(1.0)
    v.rtl()
    assert v.commands_sent == sent                   # nothing issued after the loss


def test_fire_patrol_over_mavlink(link, tmp_path):
    grid, sim, peer, v = link
    cfg = RunConfig(planner_mode="carrot", tick=0.5, altitude=40)
    r = Executor(TABLE, grid, v, config=cfg).run()
    assert r.ok, r.reason
    assert sorted(c for _, c, _, _ in r.arrivals) == sorted(grid.sensors["inP"].tolist())
    assert [c for _, c, _, _ in r.photos] == grid.sensors["fire"].tolist()
    r.write_geojson(tmp_path / "track.geojson")


def test_connect_timeout():
    grid = load_map(data=MAP)
    with pytest.raises(MavlinkError, match="no autopilot heartbeat"):
        MavlinkVehicle.connect(f"udpout:127.0.0.1:{free_port()}", grid.frame,
                               heartbeat_timeout=1.0)


@pytest.mark.skipif(not os.environ.get("ITERPLAN_SITL"),
                    reason="set ITERPLAN_SITL to a running ArduPlane SITL endpoint, "
                           "e.g. tcp:127.0.0.1:5760")
def test_sitl_fire_patrol():
    grid = load_map(data={**MAP, "origin": [-35.363261, 149.165230]})
    v = MavlinkVehicle.connect(os.environ["ITERPLAN_SITL"], grid.frame, airspeed=23.5,
                               min_turn_radius=40.0)
    try:
        cfg = RunConfig(planner_mode="carrot", tick=0.5, altitude=60, max_time=1800)
        r = Executor(TABLE, grid, v, config=cfg).run()
        assert r.ok, r.reason
        assert sorted(c for _, c, _, _ in r.arrivals) == sorted(grid.sensors["inP"].tolist())
    finally:
        v.rtl()
        v.close()


def test_iterc_run_over_mavlink(tmp_path, capsys):
    import json
    import shutil
    from pathlib import Path

    from iterplan_compiler.cli import main

    grid = load_map(data=MAP)
    (tmp_path / "map.json").write_text(json.dumps(MAP))
    shutil.copy(Path(__file__).parent / "fire_patrol.py", tmp_path / "ctl.py")
    port = free_port()
    peer = LoopbackAutopilot(f"udpin:127.0.0.1:{port}", grid.frame,
                             SimVehicle(SimParams(), home=grid.home), speedup=25.0,
                             gps_delay=1.0).start()
    try:
        rc = main(["run", str(tmp_path / "ctl.py"), "--map", str(tmp_path / "map.json"),
                   "--vehicle", "mavlink", "--connect", f"udpout:127.0.0.1:{port}",
                   "--out", str(tmp_path / "out"), "--no-plot"])
    finally:
        peer.stop()
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    assert "visited 3 cells, 1 photos" in cap.out and "mavlink: waiting" in cap.err
