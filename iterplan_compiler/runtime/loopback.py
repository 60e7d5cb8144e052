"""A loopback autopilot: the built-in simulator behind a MAVLink endpoint on localhost.

For fast unit tests of :class:`~iterplan_compiler.runtime.mavlink.MavlinkVehicle` only — it
answers the subset of ArduPlane's MAVLink the runtime uses, the way ArduPlane does on the points
where a mock that "always says yes" would hide bugs:

* arming is refused (COMMAND_ACK ``TEMPORARILY_REJECTED`` + a ``PreArm:`` STATUSTEXT) until the
  pre-arm bit of SYS_STATUS is set, ``prearm_delay`` simulated seconds after boot, and GPS has no
  3-D fix for the first ``gps_delay`` seconds; HOME_POSITION only once the fix is there;
* PARAM_REQUEST_READ / PARAM_SET answered from :attr:`LoopbackAutopilot.params` (ArduPlane
  names, SITL's plane defaults);
* MISSION_ITEM_INT ``current=2`` only in GUIDED, COMMAND_LONG DO_REPOSITION unsupported,
  MISSION_ITEM_REACHED at the loiter capture; mode changes reported by HEARTBEAT;
* a landing mission (MISSION_COUNT handshake) flown in AUTO, disarm on touchdown.

Fault injection for tests: :meth:`~LoopbackAutopilot.pilot_mode` (a mode change from a "pilot"),
:meth:`~LoopbackAutopilot.silence` (dead link), :meth:`~LoopbackAutopilot.freeze_position`
(heartbeats without position), ``gps_fix`` (set to 1 to lose the fix), :meth:`disarm`.
It is not an ArduPilot emulator: what flies is proven against ArduPilot SITL (``tests/sitl``).
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any

from iterplan_compiler.runtime.grid import LocalFrame, compass_to_math, math_to_compass
from iterplan_compiler.runtime.mavlink import MODE_NAMES, MODES, mav, mavutil
from iterplan_compiler.runtime.sim import SimVehicle

PLANE_PARAMS = {"AIRSPEED_CRUISE": 22.0, "ROLL_LIMIT_DEG": 65.0, "WP_LOITER_RAD": 80.0,
                "WP_RADIUS": 50.0, "NAVL1_PERIOD": 15.0, "NAVL1_DAMPING": 0.75, "AIRSPEED_MIN": 10.0,
                "AIRSPEED_MAX": 30.0, "TKOFF_ALT": 50.0, "SYSID_MYGCS": 255.0,
                "FS_GCS_ENABL": 0.0}


class LoopbackAutopilot:
    """``url`` is the listening side, e.g. ``udpin:127.0.0.1:14561``; the vehicle connects with
    ``udpout:127.0.0.1:14561``.  Runs in a daemon thread; :meth:`stop` ends it.  ``speedup``
    simulated seconds pass per wall second."""

    def __init__(self, url: str, frame: LocalFrame, sim: SimVehicle, *, speedup: float = 20.0,
                 gps_delay: float = 2.0, prearm_delay: float = 4.0, system_id: int = 1,
                 params: dict[str, float] | None = None):
        self.frame = frame
        self.sim = sim
        self.speedup = speedup
        self.gps_delay = gps_delay
        self.prearm_delay = prearm_delay
        self.params = dict(PLANE_PARAMS if params is None else params)
        self.conn = mavutil.mavlink_connection(url, source_system=system_id, source_component=1)
        self.mode = "MANUAL"
        self.received: list[str] = []
        self.silent = False
        self.position_frozen = False
        self.gps_fix: int | None = None      # None: by gps_delay; else the fix type sent
        self.arm_refusals = 0
        self._mission: list[Any] = []
        self._mission_count = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True,
                                        name="iterplan-loopback-autopilot")

    def start(self) -> LoopbackAutopilot:
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        self.conn.close()

    # -- fault injection ----------------------------------------------------------------------
    def silence(self) -> None:
        """A dead link: stop sending anything (the sim keeps flying)."""
        self.silent = True

    def freeze_position(self) -> None:
        """Heartbeats go on, position telemetry stops."""
        self.position_frozen = True

    def pilot_mode(self, name: str) -> None:
        """A pilot (or failsafe) changes the flight mode."""
        self._set_mode(MODES[name])

    def disarm(self) -> None:
        self.sim.armed = False

    # -- internals ----------------------------------------------------------------------------
    def _ready(self) -> bool:
        return self.sim.time >= self.prearm_delay

    def _fix(self) -> int:
        if self.gps_fix is not None:
            return self.gps_fix
        return 3 if self.sim.time >= self.gps_delay else 1

    def _run(self) -> None:
        last = time.monotonic()
        next_hb = next_pos = next_gps = next_status = 0.0
        connected = False
        while not self._stop.is_set():
            now = time.monotonic()
            self.sim.advance(min(now - last, 0.2) * self.speedup)
            last = now
            while True:
                msg = self.conn.recv_match(blocking=False)
                if msg is None:
                    break
                connected = True
                self._handle(msg)
            self._follow_sim()
            t = self.sim.time
            if connected and not self.silent:
                if t >= next_hb:
                    self._heartbeat()
                    next_hb = t + 0.5
                if t >= next_pos and not self.position_frozen:
                    self._send_position()
                    next_pos = t + 0.1
                if t >= next_gps:
                    self._send_gps()
                    next_gps = t + 0.5
                if t >= next_status:
                    self._send_status()
                    next_status = t + 1.0
            time.sleep(0.002)

    def _follow_sim(self) -> None:
        # ArduPlane's TAKEOFF mode loiters when the climb is done and stays in TAKEOFF: the
        # simulator's own mode is not reported.
        s = self.sim
        for e in s.poll_events():
            if e.kind == "reached" and not self.silent:
                self.conn.mav.mission_item_reached_send(0)
            if e.kind == "landed":
                s.armed = False

    def _heartbeat(self) -> None:
        base = mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (
            mav.MAV_MODE_FLAG_SAFETY_ARMED if self.sim.armed else 0)
        self.conn.mav.heartbeat_send(mav.MAV_TYPE_FIXED_WING, mav.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                     base, MODES.get(self.mode, 0), mav.MAV_STATE_ACTIVE)

    def _send_status(self) -> None:
        bit = mav.MAV_SYS_STATUS_PREARM_CHECK
        health = bit if self._ready() and self._fix() >= 3 else 0
        self.conn.mav.sys_status_send(bit, bit, health, 0, 12000, -1, -1, 0, 0, 0, 0, 0, 0)
        if self._fix() >= 3:
            lat, lon = self.frame.to_latlon(*self.sim.home)
            self.conn.mav.home_position_send(int(lat * 1e7), int(lon * 1e7), 584000, 0, 0, 0,
                                             [1, 0, 0, 0], 0, 0, 0)

    def _send_gps(self) -> None:
        lat, lon = self.frame.to_latlon(self.sim.x, self.sim.y)
        self.conn.mav.gps_raw_int_send(int(self.sim.time * 1e6), self._fix(), int(lat * 1e7),
                                       int(lon * 1e7), 0, 100, 100, 0, 0, 10)

    def _send_position(self) -> None:
        p = self.sim.pose()
        lat, lon = self.frame.to_latlon(p.x, p.y)
        vn = p.groundspeed * math.sin(p.course)
        ve = p.groundspeed * math.cos(p.course)
        hdg = int(math_to_compass(p.course) * 100) % 36000
        self.conn.mav.global_position_int_send(int(p.t * 1000), int(lat * 1e7), int(lon * 1e7),
                                               int((584 + p.alt) * 1000), int(p.alt * 1000),
                                               int(vn * 100), int(ve * 100), 0, hdg)

    def _ack(self, cmd: int, result: int) -> None:
        self.conn.mav.command_ack_send(cmd, result)

    def _text(self, text: str) -> None:
        self.conn.mav.statustext_send(mav.MAV_SEVERITY_CRITICAL, text.encode())

    def _set_mode(self, custom: int) -> bool:
        name = MODE_NAMES.get(int(custom))
        if name not in ("MANUAL", "RTL", "LOITER", "TAKEOFF", "GUIDED", "AUTO", "FBWA"):
            return False
        s = self.sim
        if name == "TAKEOFF":
            if not s.armed:
                return False
            s.takeoff(self.params.get("TKOFF_ALT", 50.0))
        elif name == "RTL":
            s.rtl()
        elif name == "LOITER":
            s.loiter()
        elif name == "GUIDED" and s.mode not in ("GUIDED", "COURSE"):
            s.loiter()
        elif name == "AUTO" and len(self._mission) > 1:
            s.land()
        self.mode = name
        return True

    def _handle(self, msg: Any) -> None:
        t = msg.get_type()
        if t in ("HEARTBEAT", "BAD_DATA"):
            return
        self.received.append(t)
        handler = getattr(self, f"_on_{t.lower()}", None)
        if handler is not None:
            handler(msg)

    def _on_command_long(self, msg: Any) -> None:
        ok, cmd = mav.MAV_RESULT_ACCEPTED, msg.command
        if cmd == mav.MAV_CMD_COMPONENT_ARM_DISARM:
            if msg.param1 != 1:
                self.sim.armed = False
                self._ack(cmd, ok)
            elif not self._ready() or self._fix() < 3:
                self.arm_refusals += 1
                self._text("PreArm: AHRS: waiting for home")
                self._ack(cmd, mav.MAV_RESULT_TEMPORARILY_REJECTED)
            else:
                self.sim.arm()
                self._ack(cmd, ok)
        elif cmd == mav.MAV_CMD_DO_SET_MODE:
            self._ack(cmd, ok if self._set_mode(msg.param2) else mav.MAV_RESULT_FAILED)
        elif cmd in (mav.MAV_CMD_SET_MESSAGE_INTERVAL, mav.MAV_CMD_REQUEST_MESSAGE,
                     mav.MAV_CMD_DO_CHANGE_SPEED, mav.MAV_CMD_DO_SET_MISSION_CURRENT):
            self._ack(cmd, ok)
        else:   # includes DO_REPOSITION as COMMAND_LONG, like ArduPlane
            self._ack(cmd, mav.MAV_RESULT_UNSUPPORTED)

    def _on_command_int(self, msg: Any) -> None:
        cmd = msg.command
        if cmd == mav.MAV_CMD_DO_REPOSITION:
            if msg.param2 and int(msg.param2) & mav.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE:
                self.mode = "GUIDED"
            if self.mode != "GUIDED":
                self._ack(cmd, mav.MAV_RESULT_FAILED)
                return
            x, y = self.frame.to_enu(msg.x / 1e7, msg.y / 1e7)
            self.sim.goto(x, y, radius=msg.param3 if msg.param3 > 0 else None)
            self._ack(cmd, mav.MAV_RESULT_ACCEPTED)
        elif cmd == mav.MAV_CMD_GUIDED_CHANGE_HEADING:
            if self.mode != "GUIDED":
                self._ack(cmd, mav.MAV_RESULT_FAILED)
                return
            self.sim.steer(compass_to_math(msg.param2))
            self._ack(cmd, mav.MAV_RESULT_ACCEPTED)
        else:
            self._ack(cmd, mav.MAV_RESULT_UNSUPPORTED)

    def _on_mission_item_int(self, msg: Any) -> None:
        src = (msg.get_srcSystem(), msg.get_srcComponent())
        if msg.current == 2:
            if self.mode == "GUIDED":
                x, y = self.frame.to_enu(msg.x / 1e7, msg.y / 1e7)
                self.sim.goto(x, y)
                self.conn.mav.mission_ack_send(*src, mav.MAV_MISSION_ACCEPTED)
            else:
                self.conn.mav.mission_ack_send(*src, mav.MAV_MISSION_ERROR)
            return
        self._mission.append(msg)
        if len(self._mission) < self._mission_count:
            self.conn.mav.mission_request_int_send(*src, len(self._mission))
        else:
            self.conn.mav.mission_ack_send(*src, mav.MAV_MISSION_ACCEPTED)

    def _on_mission_count(self, msg: Any) -> None:
        self._mission, self._mission_count = [], msg.count
        self.conn.mav.mission_request_int_send(msg.get_srcSystem(), msg.get_srcComponent(), 0)

    def _on_param_request_read(self, msg: Any) -> None:
        pid = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
        pid = pid.rstrip("\x00")
        if pid in self.params:
            self.conn.mav.param_value_send(pid.encode(), self.params[pid],
                                           mav.MAV_PARAM_TYPE_REAL32, len(self.params), 0)

    def _on_param_set(self, msg: Any) -> None:
        pid = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
        pid = pid.rstrip("\x00")
        self.params[pid] = float(msg.param_value)
        self.conn.mav.param_value_send(pid.encode(), msg.param_value,
                                       mav.MAV_PARAM_TYPE_REAL32, len(self.params), 0)
