"""The MAVProxy module's machinery without MAVProxy: ModuleLink (the pymavlink-style connection
fed by ``mavlink_packet``) and Mission (the mission thread behind ``iterplan run/stop``), flown
against the loopback autopilot with a miniature MAVProxy main loop.  The real thing (MAVProxy +
ArduPlane SITL) is tests/sitl/test_sitl_mavproxy.py."""

import json
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from iterplan_compiler.mavproxy.link import ModuleLink
from iterplan_compiler.mavproxy.mission import Mission, UsageError, parse_run
from iterplan_compiler.runtime.loopback import LoopbackAutopilot
from iterplan_compiler.runtime.mapfile import load_map
from iterplan_compiler.runtime.mavlink import mav, mavutil
from iterplan_compiler.runtime.sim import SimParams, SimVehicle

ROOT = Path(__file__).resolve().parents[2]
CONTROLLER = str(ROOT / "tests" / "runtime" / "fire_patrol.py")
MAP = {"name": "mavproxy-test", "cols": 6, "rows": 5, "home": {"cell": "A1"},
       "sensors": {"inP": ["B2", "D4", "F1"], "fire": ["D4"]}}


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class MiniProxy:
    """What MAVProxy does around a module: owns the link, reads it in its own thread, hands
    every message to the module (here: the mission), sends its own heartbeats."""

    def __init__(self, url: str):
        self.master = mavutil.mavlink_connection(url, source_system=255, source_component=0)
        self.mission: Mission | None = None
        self.stop_event = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()

    def _loop(self) -> None:
        beat = 0.0
        while not self.stop_event.is_set():
            if time.monotonic() - beat > 1.0:
                self.master.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID,
                                               0, 0, 0)
                beat = time.monotonic()
            msg = self.master.recv_match(blocking=True, timeout=0.05)
            if msg is not None and msg.get_type() != "BAD_DATA" and self.mission is not None:
                self.mission.feed(msg)

    def close(self) -> None:
        self.stop_event.set()
        self._thread.join(timeout=5)
        self.master.close()


@pytest.fixture
def proxy(tmp_path):
    grid = load_map(data=MAP)
    port = free_port()
    sim = SimVehicle(SimParams(), home=grid.home)
    peer = LoopbackAutopilot(f"udpin:127.0.0.1:{port}", grid.frame, sim, speedup=25.0,
                             gps_delay=1.0, prearm_delay=3.0).start()
    px = MiniProxy(f"udpout:127.0.0.1:{port}")
    map_path = tmp_path / "map.json"
    map_path.write_text(json.dumps(MAP))
    yield px, peer, str(map_path)
    px.close()
    peer.stop()


def start_mission(px, map_path, out, *extra):
    lines: list[str] = []
    args = parse_run([CONTROLLER, map_path, "--out", str(out), "--ready-timeout", "30", *extra])
    m = Mission(args, lambda: px.master, lines.append, stop_event=px.stop_event)
    px.mission = m
    m.start()
    return m, lines


def test_mission_flies_over_a_link_it_does_not_own(proxy, tmp_path):
    px, peer, map_path = proxy
    m, lines = start_mission(px, map_path, tmp_path / "out")
    m.thread.join(timeout=90)
    assert not m.running, lines[-20:]
    assert m.result is not None and m.result.ok, (m.error, lines[-20:])
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert s["arrivals"] == 3 and s["photos"] == 1 and s["vehicle"] == "MavlinkVehicle"
    assert s["safe_state"].startswith("loiter commanded")
    assert (tmp_path / "out" / "commands.csv").read_text().count("\n") > 5
    assert peer.mode == "GUIDED"
    # all senders on that link (the proxy's heartbeats too) share one lock now
    assert getattr(px.master.mav, "_iterplan_send_lock", None) is not None
    assert m.phase == "done" and any("mission completed" in ln for ln in m.status())
    # the link is ours no more: the proxy's connection stays open
    assert m.link.closed and px.master.port.fileno() >= 0


def test_stop_ends_the_mission_with_the_end_action(proxy, tmp_path):
    px, peer, map_path = proxy
    m, lines = start_mission(px, map_path, tmp_path / "out", "--on-end", "rtl")
    end = time.monotonic() + 60
    while time.monotonic() < end and (m.executor is None or m.executor.counts["arrived"] < 1):
        time.sleep(0.05)
    assert m.executor is not None and m.executor.counts["arrived"] >= 1, lines[-20:]
    assert "mission flying" in m.status()[0]
    assert m.stop() and not m.stop()          # a second stop is a no-op
    m.thread.join(timeout=30)
    assert not m.running
    s = m.result.summary
    assert s["reason"] == "interrupted" and s["safe_state"].startswith("rtl commanded"), s
    assert (tmp_path / "out" / "summary.json").exists()
    time.sleep(0.3)
    assert peer.mode == "RTL"


def test_stop_before_the_vehicle_answers_commands_nothing(tmp_path):
    map_path = tmp_path / "map.json"
    map_path.write_text(json.dumps(MAP))
    args = parse_run([CONTROLLER, str(map_path), "--out", str(tmp_path / "out")])
    m = Mission(args, lambda: None, lambda line: None)      # no link at all
    m.start()
    time.sleep(0.5)
    assert m.phase == "connecting"
    m.stop()
    m.thread.join(timeout=10)
    assert not m.running and m.phase == "failed" and m.result is None
    assert "nothing was commanded" in m.error


def test_bad_inputs_fail_in_the_thread_with_a_message(tmp_path):
    m = Mission(parse_run([CONTROLLER, str(tmp_path / "missing.json")]), lambda: None,
                lambda line: None)
    m.start()
    m.thread.join(timeout=10)
    assert m.phase == "failed" and "missing.json" in m.error


def test_parse_run_raises_instead_of_exiting():
    with pytest.raises(UsageError, match="required"):
        parse_run([])
    with pytest.raises(UsageError, match="LABEL or LABEL:K"):
        parse_run(["a.py", "b.json", "--until", "x:0"])
    with pytest.raises(UsageError, match="usage: iterplan run"):
        parse_run(["--help"])
    a = parse_run(["a.py", "b.json", "--until", "n.next:2", "--on-end", "land"])
    assert a.until_spec == ("n.next", 2) and a.on_end == "land" and a.planner == "carrot"


class Msg:
    def __init__(self, t):
        self.t = t

    def get_type(self):
        return self.t


def test_module_link_recv_match_semantics():
    link = ModuleLink(lambda: None)
    assert link.recv_match(blocking=False) is None
    t0 = time.monotonic()
    assert link.recv_match(blocking=True, timeout=0.2) is None
    assert 0.15 < time.monotonic() - t0 < 1.0
    for t in ("SYS_STATUS", "HEARTBEAT", "GPS_RAW_INT"):
        link.feed(Msg(t))
    assert link.recv_match(type="HEARTBEAT", blocking=True, timeout=0.1).t == "HEARTBEAT"
    assert link.recv_match().t == "GPS_RAW_INT"
    link.feed(Msg("HEARTBEAT"))
    assert link.interrupt()
    with pytest.raises(KeyboardInterrupt):
        link.recv_match(blocking=True, timeout=1)
    assert link.recv_match().t == "HEARTBEAT"            # once only, nothing lost
    assert not link.interrupt()                          # never a second time (safe end)
    assert link.recv_match() is None
    link.mav.heartbeat_send(1, 2, 3, 4, 5)               # no master: dropped, not raised
    stop = threading.Event()
    link2 = ModuleLink(lambda: None, stop_event=stop)
    threading.Timer(0.1, stop.set).start()
    with pytest.raises(KeyboardInterrupt):
        link2.recv_match(blocking=True, timeout=2)
    # MAVProxy shutting down and then unloading the module: still only one interrupt
    assert not link2.interrupt()
    assert link2.recv_match(blocking=True, timeout=0.05) is None
    link.close()
    link.feed(Msg("HEARTBEAT"))
    assert link.recv_match(blocking=True, timeout=5) is None     # closed: at once


def test_the_package_imports_without_mavproxy():
    code = ("import sys; sys.modules['MAVProxy'] = None\n"      # as if not installed
            "import iterplan_compiler.mavproxy, iterplan_compiler.mavproxy.mission\n"
            "import iterplan_compiler.runtime.executor, iterplan_compiler.commands.run\n"
            "try:\n    import iterplan_compiler.mavproxy.mavproxy_iterplan\n"
            "except ImportError:\n    print('ok')\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT)
    assert out.stdout.strip() == "ok", out.stderr
