"""MavlinkVehicle against the loopback autopilot (the simulator speaking MAVLink on localhost):
fast checks of the start-up sequence, the checked commands and fault detection.  What flies is
proven against real ArduPlane SITL in tests/sitl/."""

import json
import math
import shutil
import socket
import time
from pathlib import Path

import pytest

from iterplan_compiler.cli import main
from iterplan_compiler.runtime.executor import Executor, RunConfig
from iterplan_compiler.runtime.loopback import LoopbackAutopilot
from iterplan_compiler.runtime.mapfile import load_map
from iterplan_compiler.runtime.mavlink import LinkConfig, MavlinkError, MavlinkVehicle, mav
from iterplan_compiler.runtime.planner import PlannerMode
from iterplan_compiler.runtime.sim import SimParams, SimVehicle
from iterplan_compiler.runtime.vehicle import SafeAction, Start
from tests.runtime.fire_patrol import TABLE

MAP = {"name": "mavlink-test", "cols": 6, "rows": 5, "home": {"cell": "A1"},
       "sensors": {"inP": ["B2", "D4", "F1"], "fire": ["D4"]}}
FAST = LinkConfig(heartbeat_timeout=10, ready_timeout=20, link_timeout=2.0,
                  telemetry_timeout=2.0, command_timeout=2.0)


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_peer(grid, **kw):
    port = free_port()
    sim = SimVehicle(SimParams(), home=grid.home)
    kw.setdefault("gps_delay", 1.0)
    kw.setdefault("prearm_delay", 3.0)
    peer = LoopbackAutopilot(f"udpin:127.0.0.1:{port}", grid.frame, sim, speedup=25.0,
                             **kw).start()
    return peer, sim, f"udpout:127.0.0.1:{port}"


@pytest.fixture
def link():
    grid = load_map(data=MAP)
    peer, sim, url = start_peer(grid)
    v = MavlinkVehicle.connect(url, grid.frame, FAST)
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


def airborne(link):
    grid, sim, peer, v = link
    assert v.prepare(Start.AUTO) is Start.GROUND
    v.arm()
    v.takeoff(40)
    wait_for(v, "takeoff_complete", 60)
    v.goto(900.0, 900.0)         # enters GUIDED (our own change from TAKEOFF)
    v.advance(1)
    assert v.mode == "GUIDED" and peer.mode == "GUIDED"
    return grid, sim, peer, v


def test_parameters_give_the_vehicle_model(link):
    grid, sim, peer, v = link
    assert v.param("AIRSPEED_CRUISE") == 22.0 and v.param("WP_LOITER_RAD") == 80.0
    v.prepare(Start.GROUND)
    # 22 m/s EAS at 584 + 60 m AMSL is ~22.7 m/s TAS; planning bank capped at 45 deg.
    assert 22.5 < v.model.airspeed < 23.0
    assert v.model.bank_limit_deg == 45.0 and v.loiter_radius == 80.0
    assert abs(v.min_turn_radius - v.model.airspeed ** 2 / 9.80665) < 1e-6


def test_a_shorter_l1_period_gives_tighter_planned_turns():
    """NAVL1_PERIOD 8 (ArduPlane's L1 tracks tighter): planning bank 61.9 deg instead of 45,
    under ROLL_LIMIT_DEG 65; the planner and the Sorter plan 1.4 x that turn."""
    from iterplan_compiler.runtime.vehicle import planning_radius

    grid = load_map(data=MAP)
    params = {"AIRSPEED_CRUISE": 17.0, "NAVL1_PERIOD": 8.0, "ROLL_LIMIT_DEG": 65.0}
    peer, sim, url = start_peer(grid, params=params)
    v = MavlinkVehicle.connect(url, grid.frame, FAST)
    try:
        assert (v.l1_period, v.l1_damping) == (8.0, 0.75)
        assert abs(v.model.bank_limit_deg - 61.93) < 0.01
        v_tas = v.model.airspeed
        expect = 1.4 * v_tas ** 2 / (9.80665 * math.tan(math.radians(v.model.bank_limit_deg)))
        assert abs(planning_radius(v) - expect) < 1e-6 and planning_radius(v) < 25.0
    finally:
        v.close()
        peer.stop()


def test_positions_before_home_are_not_poses(link):
    """ArduPlane's GLOBAL_POSITION_INT before its EKF has an origin (SITL: ~9 s near lat/lon
    0, 0) is no pose: a tour planned from there (14,000 km away) overflowed LKH."""
    from types import SimpleNamespace

    grid, sim, peer, v = link
    v.prepare(Start.GROUND)
    before = v.pose()
    msg = SimpleNamespace(time_boot_ms=int(v.time * 1000) + 100, lat=990, lon=-344, alt=584000,
                          relative_alt=0, vx=0, vy=0)
    home = v.home_amsl
    v.home_amsl = None                           # as right after boot
    v._on_position(msg)
    assert (v.pose().x, v.pose().y) == (before.x, before.y)
    v.home_amsl = home
    v._on_position(msg)                          # once home is known, positions count
    assert math.hypot(v.pose().x, v.pose().y) > 1e6


def test_an_airborne_start_waits_for_a_position_after_home(link):
    """Taking over a flying aircraft right after connecting: home may come before the first
    position that counts; 'flying' must be judged from a real position, not the initial one."""
    from iterplan_compiler.runtime.vehicle import VehiclePose

    grid, sim, peer, v = airborne(link)
    v.has_position = False                       # as on a fresh link: home known, no pose yet
    v._pose = VehiclePose(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert v.prepare(Start.AUTO) is Start.AIRBORNE
    assert v.has_position and v.pose().alt > 10.0


def test_old_parameter_names_are_converted():
    grid = load_map(data=MAP)
    params = {"TRIM_ARSPD_CM": 1700.0, "LIM_ROLL_CD": 4000.0, "WP_LOITER_RAD": 60.0}
    peer, sim, url = start_peer(grid, params=params)
    v = MavlinkVehicle.connect(url, grid.frame, FAST)
    try:
        assert v.param("AIRSPEED_CRUISE") == 17.0 and v.param("ROLL_LIMIT_DEG") == 40.0
        assert v.model.bank_limit_deg == 40.0 and v.model.loiter_radius == 60.0
    finally:
        v.close()
        peer.stop()


def test_start_up_waits_for_pre_arm_then_arms_and_takes_off(link):
    grid, sim, peer, v = link
    # The loopback refuses arming for 3 s (pre-arm bit clear), like ArduPlane.
    v._command_sync(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert peer.arm_refusals == 1
    assert v.prepare(Start.AUTO) is Start.GROUND and v.prearm_ok and v.fix_type >= 3
    v.arm()
    assert v.armed and peer.arm_refusals == 1      # armed at the first try once ready
    v.takeoff(40)
    assert peer.params["TKOFF_ALT"] == 40 and peer.mode == "TAKEOFF"
    wait_for(v, "takeoff_complete", 60)
    assert sim.alt >= 37


def test_ready_timeout_names_what_is_missing():
    grid = load_map(data=MAP)
    peer, sim, url = start_peer(grid, gps_delay=1e9)
    v = MavlinkVehicle.connect(url, grid.frame, LinkConfig(ready_timeout=1.5))
    try:
        with pytest.raises(MavlinkError, match="3-D GPS fix.*pre-arm checks"):
            v.prepare(Start.AUTO)
    finally:
        v.close()
        peer.stop()


def test_refused_arm_is_an_error_not_a_wait(link):
    grid, sim, peer, v = link
    v.prepare(Start.GROUND)
    peer.prearm_delay = 1e9       # the autopilot now refuses every arm
    with pytest.raises(MavlinkError, match="arming refused.*TEMPORARILY_REJECTED.*PreArm"):
        v.arm()
    assert peer.arm_refusals == FAST.arm_attempts and not sim.armed


def test_guided_fly_to_steer_reposition_and_rtl(link):
    grid, sim, peer, v = airborne(link)
    e = wait_for(v, "reached", 200)
    assert e.detail == "seq 0" and math.hypot(sim.x - 900, sim.y - 900) < 250
    p = v.pose()
    assert abs(p.x - sim.x) < 25 and abs(p.y - sim.y) < 25
    v.steer(0.0)                                     # due east (GUIDED_CHANGE_HEADING)
    v.advance(20)
    assert abs(math.remainder(v.pose().course, 2 * math.pi)) < 0.2
    v.loiter(0.0, 0.0, 60)                           # DO_REPOSITION as COMMAND_INT
    assert "ok" not in v.settle(2.0) and sim.radius == 60
    assert not [e for e in v.poll_events() if e.kind == "rejected"]
    v.rtl()
    assert v.settle(2.0) == "vehicle in RTL" and sim.mode == "RTL"
    names = [c for _, c, _ in v.command_log]
    assert {"goto", "steer", "loiter", "do_set_mode"} <= set(names)


def test_pilot_mode_change_stops_all_commands(link):
    grid, sim, peer, v = airborne(link)
    peer.pilot_mode("RTL")
    e = wait_for(v, "mode_changed", 10)
    assert "RTL" in e.detail and v.hands_off
    sent = v.commands_sent
    v.goto(100.0, 100.0)
    v.steer(1.0)
    v.loiter(0.0, 0.0, 50)
    v.rtl()
    v.advance(2)
    assert v.commands_sent == sent and peer.mode == "RTL"     # never re-enters GUIDED


def test_our_own_mode_changes_are_not_overrides(link):
    grid, sim, peer, v = airborne(link)
    v.rtl()
    v.advance(3)
    assert not [e for e in v.poll_events() if e.kind == "mode_changed"] and not v.hands_off


@pytest.mark.parametrize("fault, inject", [
    ("link_lost", lambda peer: peer.silence()),
    ("telemetry_lost", lambda peer: peer.freeze_position()),
    ("gps_lost", lambda peer: setattr(peer, "gps_fix", 1)),
    ("disarmed", lambda peer: peer.disarm()),
])
def test_faults_are_detected(link, fault, inject):
    grid, sim, peer, v = airborne(link)
    inject(peer)
    t0 = time.monotonic()
    e = wait_for(v, fault, 60)
    assert time.monotonic() - t0 < 5.0, e
    assert v.hands_off == (fault in ("link_lost", "disarmed"))


def test_fire_patrol_over_mavlink_ends_loitering_over_the_map(link):
    grid, sim, peer, v = link
    cfg = RunConfig(planner_mode=PlannerMode.CARROT, tick=0.5, altitude=40)
    r = Executor(TABLE, grid, v, config=cfg).run()
    assert r.ok, r.reason
    assert sorted(c for _, c, _, _ in r.arrivals) == sorted(grid.sensors["inP"].tolist())
    assert [c for _, c, _, _ in r.photos] == grid.sensors["fire"].tolist()
    assert r.summary["safe_state"].startswith("loiter commanded")
    assert sim.target == pytest.approx(grid.centre_point(), abs=0.01) and sim.radius == 80


def test_fault_mid_mission_ends_with_rtl(link):
    grid, sim, peer, v = link
    n = {"go": 0}

    def on_event(kind, label):
        n["go"] += label == "go.next"
        if n["go"] == 2:
            peer.gps_fix = 1
        return False
    cfg = RunConfig(planner_mode=PlannerMode.CARROT, tick=0.5, altitude=40, on_event=on_event,
                    fault_action=SafeAction.RTL)
    r = Executor(TABLE, grid, v, config=cfg).run()
    assert not r.ok and r.reason.startswith("gps_lost")
    assert r.summary["safe_state"] == "rtl commanded; vehicle in RTL" and sim.mode == "RTL"


def test_connect_timeout():
    grid = load_map(data=MAP)
    with pytest.raises(MavlinkError, match="no autopilot heartbeat"):
        MavlinkVehicle.connect(f"udpout:127.0.0.1:{free_port()}", grid.frame,
                               LinkConfig(heartbeat_timeout=1.0))


def test_iterc_run_over_mavlink(tmp_path, capsys):
    grid = load_map(data=MAP)
    (tmp_path / "map.json").write_text(json.dumps(MAP))
    shutil.copy(Path(__file__).parent / "fire_patrol.py", tmp_path / "ctl.py")
    peer, sim, url = start_peer(grid)
    try:
        rc = main(["run", str(tmp_path / "ctl.py"), "--map", str(tmp_path / "map.json"),
                   "--vehicle", "mavlink", "--connect", url,
                   "--out", str(tmp_path / "out"), "--no-plot"])
    finally:
        peer.stop()
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    assert "visited 3 cells, 1 photos" in cap.out and "mavlink: waiting" in cap.err
    assert "safe state: loiter commanded" in cap.out
    rows = (tmp_path / "out" / "commands.csv").read_text().splitlines()
    assert rows[0] == "t,command,detail" and any(",goto," in r for r in rows)


def _cli_files(tmp_path):
    (tmp_path / "map.json").write_text(json.dumps(MAP))
    shutil.copy(Path(__file__).parent / "fire_patrol.py", tmp_path / "ctl.py")
    return [str(tmp_path / "ctl.py"), "--map", str(tmp_path / "map.json")]


def test_iterc_run_refused_arm_exits_1_with_the_reason(tmp_path, capsys):
    grid = load_map(data=MAP)
    peer, sim, url = start_peer(grid)
    peer.prearm_delay = 0.0
    # Ready by the pre-arm bit, but every arm is refused (e.g. a failing arming check).
    peer._ready = lambda: True
    original = peer._on_command_long

    def refuse(msg):
        if msg.command == mav.MAV_CMD_COMPONENT_ARM_DISARM and msg.param1 == 1:
            peer._text("Arm: Throttle too high")
            peer._ack(msg.command, mav.MAV_RESULT_DENIED)
        else:
            original(msg)
    peer._on_command_long = refuse
    try:
        rc = main(["run", *_cli_files(tmp_path), "--vehicle", "mavlink", "--connect", url,
                   "--out", str(tmp_path / "out"), "--no-plot", "--max-time", "60"])
    finally:
        peer.stop()
    cap = capsys.readouterr()
    assert rc == 1
    assert "arming refused by the autopilot (DENIED) (autopilot: 'Arm: Throttle too high')" \
        in cap.out
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert not s["ok"] and s["safe_state"] == "no command: the vehicle is not flying"


def test_iterc_run_sigterm_commands_the_safe_state_and_writes_outputs(tmp_path):
    import signal
    import subprocess
    import sys

    grid = load_map(data=MAP)
    peer, sim, url = start_peer(grid)
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "iterplan_compiler", "run",
                             *_cli_files(tmp_path), "--vehicle", "mavlink", "--connect", url,
                             "--out", str(out), "--no-plot", "--on-end", "rtl"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while sim.mode not in ("GUIDED", "COURSE") or sim.alt < 30:
            assert time.monotonic() < deadline and proc.poll() is None
            time.sleep(0.1)
        time.sleep(1.0)
        proc.send_signal(signal.SIGTERM)
        so, se = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
        peer.stop()
    assert proc.returncode == 1, se
    assert "mission ended early: interrupted" in so and "rtl commanded" in so
    assert sim.mode == "RTL" and peer.mode == "RTL"
    s = json.loads((out / "summary.json").read_text())
    assert s["reason"] == "interrupted" and s["safe_state"] == "rtl commanded; vehicle in RTL"
    for f in ("events.csv", "track.csv", "track.geojson", "commands.csv"):
        assert (out / f).stat().st_size > 0


def test_frozen_vehicle_clock_cannot_hang_a_run():
    """Wall-clock bound: a vehicle whose clock never moves still ends within max_wall."""
    grid = load_map(data=MAP)

    class Frozen(SimVehicle):
        def advance(self, dt):
            time.sleep(0.01)

    t0 = time.monotonic()
    r = Executor(TABLE, grid, Frozen(SimParams(), home=grid.home),
                 config=RunConfig(max_wall=1.0, ideal_compute=True)).run()
    assert not r.ok and "wall-clock limit of 1 s" in r.reason
    assert time.monotonic() - t0 < 5


def test_refused_mode_change_ends_the_mission(link):
    grid, sim, peer, v = link
    original = peer._set_mode
    peer._set_mode = lambda custom: False if int(custom) == 13 else original(custom)  # TAKEOFF
    cfg = RunConfig(planner_mode=PlannerMode.CARROT, tick=0.5)
    r = Executor(TABLE, grid, v, config=cfg).run()
    assert not r.ok and r.reason.startswith("mode change to TAKEOFF refused (FAILED)")
    assert "vehicle is in MANUAL" in r.reason
    assert r.summary["safe_state"] == "disarmed on the ground" and not sim.armed


def test_land_uploads_a_landing_mission_and_reports_landed(link):
    grid, sim, peer, v = airborne(link)
    v.advance(5)                       # an ACCEPTED fly-to ack may still be in flight: ignored
    v.land()
    assert [m.command for m in peer._mission] == [mav.MAV_CMD_NAV_WAYPOINT,
                                                  mav.MAV_CMD_NAV_WAYPOINT, mav.MAV_CMD_NAV_LAND]
    assert peer.mode == "AUTO" and sim.mode == "LAND"
    e = wait_for(v, "landed", 400)
    assert "disarmed" in e.detail or "on the ground" in e.detail
    assert not [x for x in v.poll_events() if x.kind in ("mode_changed", "disarmed")]


def test_close_reads_what_is_queued_first():
    """A TCP close with unread data is a reset, which froze SITL (MavlinkLink.close)."""
    from iterplan_compiler.runtime.mavlink_link import MavlinkLink

    class Conn:
        def __init__(self):
            self.queued, self.closed_with = 5, None

        def recv_msg(self):
            if self.queued == 0:
                return None
            self.queued -= 1
            return object()

        def close(self):
            self.closed_with = self.queued

    conn = Conn()
    MavlinkLink(conn).close()
    assert conn.closed_with == 0

    class Endless(Conn):
        def recv_msg(self):
            return object()

    slow = Endless()
    t0 = time.monotonic()
    MavlinkLink(slow).close(drain_s=0.2)
    assert slow.closed_with is not None and time.monotonic() - t0 < 1.0
