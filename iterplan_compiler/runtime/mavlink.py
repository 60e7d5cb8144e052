"""MAVLink vehicle (ArduPlane over pymavlink) and a loopback autopilot for tests.

:class:`MavlinkVehicle` implements the :class:`~iterplan_compiler.runtime.vehicle.Vehicle` API:

* link: ``mavutil.mavlink_connection(url, source_system=255)`` (a GCS id, so heartbeats feed
  ArduPlane's GCS failsafe when SYSID_MYGCS = 255); a daemon thread sends HEARTBEAT at 1 Hz (type
  GCS, autopilot INVALID) even while the plan is busy; all sends share one lock;
* start-up (:meth:`MavlinkVehicle.connect`): wait for the autopilot's heartbeat, request
  GLOBAL_POSITION_INT at 10 Hz and GPS_RAW_INT/HEARTBEAT at 1 Hz (SET_MESSAGE_INTERVAL only: the
  research notes show that is what lets SITL run fast), wait for a 3-D GPS fix;
* ``arm``: MAV_CMD_COMPONENT_ARM_DISARM; ``takeoff``: PARAM_SET TKOFF_ALT, then TAKEOFF mode (13),
  ``takeoff_complete`` when the relative altitude is within 2 m of the target;
* ``goto``: GUIDED (mode 15) then MISSION_ITEM_INT ``current=2`` (frame GLOBAL_RELATIVE_ALT_INT);
  with a radius, MAV_CMD_DO_REPOSITION as COMMAND_INT with the CHANGE_MODE flag and param3 =
  radius (ArduPlane answers COMMAND_LONG DO_REPOSITION with UNSUPPORTED);
* ``steer``: COMMAND_INT MAV_CMD_GUIDED_CHANGE_HEADING (course over ground, lateral acceleration
  limit); it stays in force until GUIDED is re-entered, which ``goto`` therefore does;
* ``rtl``/``loiter``: modes RTL (11) / LOITER (12); ``land``: MAV_CMD_DO_LAND_START (needs a
  landing sequence in the vehicle's mission and RTL_AUTOLAND);
* events: MISSION_ITEM_REACHED -> ``reached``; failed COMMAND_ACK/MISSION_ACK -> ``rejected``;
  STATUSTEXT -> ``message``; armed flag -> ``armed``;
* time is the autopilot's ``time_boot_ms`` (so SITL speed-ups work); ``advance(dt)`` listens until
  the vehicle clock moved on by ``dt`` (or a wall-time bound passes);
* link loss: no vehicle heartbeat for ``link_timeout`` wall seconds -> ``link_lost`` once; from
  then on no commands are sent (heartbeats continue), and the autopilot's own failsafe is in
  charge — configure FS_GCS_ENABL = 1, FS_LONG_TIMEOUT (5 s), FS_LONG_ACTN = 1 (RTL) and
  SYSID_MYGCS = 255 on the aircraft.

:class:`LoopbackAutopilot` runs the built-in simulator behind a MAVLink endpoint on localhost,
answering the subset above the way ArduPlane does (MISSION_ITEM_INT current=2 only in GUIDED,
COMMAND_LONG DO_REPOSITION unsupported, MISSION_ITEM_REACHED at the loiter capture), faster than
real time by ``speedup``.  It exists for tests and demos; it is not an ArduPilot emulator.
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Callable

from iterplan_compiler.runtime.grid import LocalFrame, compass_to_math, math_to_compass
from iterplan_compiler.runtime.sim import SimVehicle
from iterplan_compiler.runtime.vehicle import Vehicle, VehicleEvent, VehiclePose

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402  (after MAVLINK20 so MAVLink 2 is used)

mav = mavutil.mavlink

MODES = {"MANUAL": 0, "CIRCLE": 1, "FBWA": 5, "AUTO": 10, "RTL": 11, "LOITER": 12,
         "TAKEOFF": 13, "GUIDED": 15}
MODE_NAMES = {v: k for k, v in MODES.items()}


class MavlinkError(RuntimeError):
    """Connecting to / preparing the vehicle failed (message for the user)."""


class MavlinkVehicle(Vehicle):
    """ArduPlane through pymavlink; see the module docstring."""

    def __init__(self, conn, frame: LocalFrame, *, target_system: int = 1,
                 target_component: int = 1, link_timeout: float = 3.0,
                 airspeed: float = 18.0, min_turn_radius: float = 35.0,
                 progress: Callable[[str], None] | None = None):
        self.conn = conn
        self.frame = frame
        self.ts, self.tc = target_system, target_component
        self.link_timeout = link_timeout
        self.airspeed = airspeed
        self.min_turn_radius = min_turn_radius
        self.progress = progress
        self._lock = threading.Lock()
        self._events: list[VehicleEvent] = []
        self._pose = VehiclePose(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        self._boot_t = 0.0
        self._last_hb_wall = time.monotonic()
        self._link_ok = True
        self.mode = "UNKNOWN"
        self.armed = False
        self.fix_type = 0
        self._takeoff_alt: float | None = None
        self._last_goto: tuple[float, float, float] | None = None   # x, y, wall time
        self._last_course: tuple[float, float] | None = None        # course, wall time
        self.commands_sent = 0
        self.statustexts: list[str] = []
        self._stop = threading.Event()
        self._hb = threading.Thread(target=self._heartbeat_loop, daemon=True,
                                    name="iterplan-mavlink-heartbeat")
        self._hb.start()

    # -- connection -------------------------------------------------------------------------
    @classmethod
    def connect(cls, url: str, frame: LocalFrame, *, heartbeat_timeout: float = 30.0,
                gps_timeout: float = 120.0, **kw) -> MavlinkVehicle:
        """Open ``url``, wait for the autopilot and a GPS fix; raises :class:`MavlinkError`."""
        try:
            conn = mavutil.mavlink_connection(url, source_system=255, source_component=190)
        except Exception as exc:  # pymavlink raises assorted OSErrors/ValueErrors
            raise MavlinkError(f"cannot open {url}: {exc}") from None
        v = cls(conn, frame, **kw)
        v._say(f"waiting for a heartbeat on {url}")
        deadline = time.monotonic() + heartbeat_timeout
        while time.monotonic() < deadline:
            v._send_heartbeat()
            msg = conn.recv_match(type="HEARTBEAT", blocking=True, timeout=0.5)
            if msg is not None and msg.get_srcComponent() == 1 and msg.type != mav.MAV_TYPE_GCS:
                v.ts, v.tc = msg.get_srcSystem(), msg.get_srcComponent()
                v._handle(msg)
                break
        else:
            v.close()
            raise MavlinkError(f"no autopilot heartbeat on {url} within {heartbeat_timeout:.0f} s")
        for msg_id, hz in ((mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 10.0),
                           (mav.MAVLINK_MSG_ID_GPS_RAW_INT, 1.0),
                           (mav.MAVLINK_MSG_ID_HEARTBEAT, 1.0)):
            v._command_long(mav.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, 1e6 / hz)
        v._say("waiting for a 3-D GPS fix")
        deadline = time.monotonic() + gps_timeout
        while v.fix_type < 3:
            if time.monotonic() > deadline:
                v.close()
                raise MavlinkError(f"no GPS fix within {gps_timeout:.0f} s")
            v._pump(0.2)
        return v

    def close(self) -> None:
        self._stop.set()
        try:
            self.conn.close()
        except Exception:  # noqa: BLE001 - closing a dead link must not fail a mission report
            pass

    # -- Vehicle API ------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self._boot_t

    def pose(self) -> VehiclePose:
        return self._pose

    @property
    def link_ok(self) -> bool:
        return self._link_ok

    def arm(self) -> None:
        self._command_long(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)

    def takeoff(self, alt: float) -> None:
        self._takeoff_alt = float(alt)
        self._send(lambda m: m.param_set_send(self.ts, self.tc, b"TKOFF_ALT", float(alt),
                                              mav.MAV_PARAM_TYPE_REAL32))
        self._set_mode("TAKEOFF")

    def goto(self, x, y, alt=None, radius=None) -> None:
        now = time.monotonic()
        if self._last_goto and radius is None:
            lx, ly, lt = self._last_goto
            # Re-sending an unchanged target floods the link; refresh at most every second.
            if math.hypot(x - lx, y - ly) < 5.0 and now - lt < 1.0:
                return
        self._last_goto = (x, y, now)
        self._last_course = None
        lat, lon = self.frame.to_latlon(x, y)
        z = float(alt if alt is not None else (self._takeoff_alt or self._pose.alt or 60.0))
        if radius:
            self._send(lambda m: m.command_int_send(
                self.ts, self.tc, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                mav.MAV_CMD_DO_REPOSITION, 0, 0, -1, mav.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE,
                float(radius), 0, int(lat * 1e7), int(lon * 1e7), z))
            return
        if self.mode != "GUIDED":
            self._set_mode("GUIDED")
        self._send(lambda m: m.mission_item_int_send(
            self.ts, self.tc, 0, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, mav.MAV_CMD_NAV_WAYPOINT,
            2, 0, 0, 0, 0, 0, int(lat * 1e7), int(lon * 1e7), z))

    def steer(self, course: float) -> None:
        now = time.monotonic()
        if self._last_course:
            lc, lt = self._last_course
            if abs(math.remainder(course - lc, 2 * math.pi)) < math.radians(2) and now - lt < 1:
                return
        if self.mode != "GUIDED":
            self._set_mode("GUIDED")
        self._last_course = (course, now)
        self._last_goto = None
        self._send(lambda m: m.command_int_send(
            self.ts, self.tc, 0, mav.MAV_CMD_GUIDED_CHANGE_HEADING, 0, 0,
            0, math_to_compass(course), 10.0, 0, 0, 0, 0))

    def rtl(self) -> None:
        self._set_mode("RTL")

    def loiter(self) -> None:
        self._set_mode("LOITER")

    def land(self) -> None:
        self._command_long(mav.MAV_CMD_DO_LAND_START)

    def advance(self, dt: float) -> None:
        """Listen until the autopilot clock moved on by ``dt`` (wall-bounded)."""
        target = self._boot_t + dt
        wall_end = time.monotonic() + max(dt, 0.05) * 1.5 + 0.05
        while self._boot_t < target and time.monotonic() < wall_end:
            self._pump(0.02)
        self._check_link()

    def poll_events(self) -> list[VehicleEvent]:
        self._pump(0.0)
        self._check_link()
        ev, self._events = self._events, []
        return ev

    # -- internals ----------------------------------------------------------------------------
    def _say(self, text: str) -> None:
        if self.progress:
            self.progress(f"mavlink: {text}")

    def _emit(self, kind: str, detail: str = "") -> None:
        self._events.append(VehicleEvent(self._boot_t, kind, detail))

    def _send(self, fn) -> None:
        if not self._link_ok:
            return  # after link loss the autopilot's failsafe is in charge: no commands
        with self._lock:
            fn(self.conn.mav)
        self.commands_sent += 1

    def _send_heartbeat(self) -> None:
        with self._lock:
            self.conn.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0,
                                         mav.MAV_STATE_ACTIVE)

    def _heartbeat_loop(self) -> None:
        while not self._stop.wait(1.0):
            try:
                self._send_heartbeat()
            except Exception:  # noqa: BLE001 - socket closed underneath us: just stop
                return

    def _command_long(self, cmd: int, *params: float) -> None:
        p = list(params) + [0.0] * (7 - len(params))
        self._send(lambda m: m.command_long_send(self.ts, self.tc, cmd, 0, *p))

    def _set_mode(self, name: str) -> None:
        self._command_long(mav.MAV_CMD_DO_SET_MODE, mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                           MODES[name])
        self.mode = name  # optimistic; corrected by the next HEARTBEAT

    def _pump(self, timeout: float) -> None:
        first = True
        while True:
            msg = self.conn.recv_match(blocking=first and timeout > 0, timeout=timeout or None)
            first = False
            if msg is None:
                return
            self._handle(msg)

    def _check_link(self) -> None:
        age = time.monotonic() - self._last_hb_wall
        if self._link_ok and age > self.link_timeout:
            self._link_ok = False
            self._emit("link_lost", f"no autopilot heartbeat for {age:.1f} s")
            self._say("link lost; commands stopped, the autopilot's failsafe takes over")

    def _handle(self, msg) -> None:
        t = msg.get_type()
        if msg.get_srcSystem() != self.ts and t != "BAD_DATA":
            return
        if t == "HEARTBEAT":
            if msg.type == mav.MAV_TYPE_GCS:
                return
            self._last_hb_wall = time.monotonic()
            if not self._link_ok:
                self._link_ok = True
                self._emit("link_restored")
            self.mode = MODE_NAMES.get(msg.custom_mode, str(msg.custom_mode))
            armed = bool(msg.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
            if armed and not self.armed:
                self._emit("armed")
            self.armed = armed
        elif t == "GLOBAL_POSITION_INT":
            self._boot_t = max(self._boot_t, msg.time_boot_ms / 1000.0)
            x, y = self.frame.to_enu(msg.lat / 1e7, msg.lon / 1e7)
            vn, ve = msg.vx / 100.0, msg.vy / 100.0
            alt = msg.relative_alt / 1000.0
            self._pose = VehiclePose(self._boot_t, x, y, alt, math.atan2(vn, ve),
                                     math.hypot(vn, ve))
            if self._takeoff_alt is not None and alt >= self._takeoff_alt - 2.0:
                self._takeoff_alt_reached()
        elif t == "GPS_RAW_INT":
            self.fix_type = msg.fix_type
        elif t == "MISSION_ITEM_REACHED":
            self._emit("reached", f"seq {msg.seq}")
        elif t == "COMMAND_ACK":
            if msg.result not in (mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_IN_PROGRESS):
                self._emit("rejected", f"command {msg.command} result {msg.result}")
        elif t == "MISSION_ACK":
            if msg.type != mav.MAV_MISSION_ACCEPTED:
                self._emit("rejected", f"mission item refused ({msg.type})")
        elif t == "STATUSTEXT":
            text = msg.text if isinstance(msg.text, str) else msg.text.decode(errors="replace")
            self.statustexts.append(text)
            self._emit("message", text)

    def _takeoff_alt_reached(self) -> None:
        if not getattr(self, "_takeoff_done", False):
            self._takeoff_done = True
            self._emit("takeoff_complete", f"alt {self._pose.alt:.0f} m")


class LoopbackAutopilot:
    """The built-in simulator speaking (a subset of) ArduPlane's MAVLink on localhost.

    ``url`` is the listening side, e.g. ``udpin:127.0.0.1:14561``; the vehicle connects with
    ``udpout:127.0.0.1:14561``.  Runs in a daemon thread; :meth:`silence` stops all output (for
    link-loss tests); :meth:`stop` ends it.  ``speedup`` simulated seconds pass per wall second.
    """

    def __init__(self, url: str, frame: LocalFrame, sim: SimVehicle, *, speedup: float = 20.0,
                 gps_delay: float = 2.0, system_id: int = 1):
        self.frame = frame
        self.sim = sim
        self.speedup = speedup
        self.gps_delay = gps_delay
        self.conn = mavutil.mavlink_connection(url, source_system=system_id, source_component=1)
        self.mode = "MANUAL"
        self.tkoff_alt = 50.0
        self.received: list[str] = []
        self.silent = False
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

    def silence(self) -> None:
        """Simulate a dead link: stop sending anything (the sim keeps flying)."""
        self.silent = True

    # -- internals ----------------------------------------------------------------------------
    def _custom_mode(self) -> int:
        return MODES.get(self.mode, 0)

    def _run(self) -> None:
        last = time.monotonic()
        next_hb = next_pos = next_gps = 0.0
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
            if self.mode == "TAKEOFF" and self.sim.mode == "GUIDED":
                self.mode = "LOITER"     # ArduPlane's TAKEOFF mode loiters when done, too
            for e in self.sim.poll_events():
                if e.kind == "reached" and connected and not self.silent:
                    self.conn.mav.mission_item_reached_send(0)
            t = self.sim.time
            if connected and not self.silent:
                if t >= next_hb:
                    base = mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (
                        mav.MAV_MODE_FLAG_SAFETY_ARMED if self.sim.armed else 0)
                    self.conn.mav.heartbeat_send(mav.MAV_TYPE_FIXED_WING,
                                                 mav.MAV_AUTOPILOT_ARDUPILOTMEGA, base,
                                                 self._custom_mode(), mav.MAV_STATE_ACTIVE)
                    next_hb = t + 1.0
                if t >= next_pos:
                    self._send_position()
                    next_pos = t + 0.1
                if t >= next_gps:
                    fix = 3 if t >= self.gps_delay else 1
                    lat, lon = self.frame.to_latlon(self.sim.x, self.sim.y)
                    self.conn.mav.gps_raw_int_send(int(t * 1e6), fix, int(lat * 1e7),
                                                   int(lon * 1e7), 0, 100, 100, 0, 0, 10)
                    next_gps = t + 1.0
            time.sleep(0.002)

    def _send_position(self) -> None:
        p = self.sim.pose()
        lat, lon = self.frame.to_latlon(p.x, p.y)
        vn = p.groundspeed * math.sin(p.course)
        ve = p.groundspeed * math.cos(p.course)
        hdg = int(math_to_compass(p.course) * 100) % 36000
        self.conn.mav.global_position_int_send(int(p.t * 1000), int(lat * 1e7), int(lon * 1e7),
                                               int(p.alt * 1000), int(p.alt * 1000),
                                               int(vn * 100), int(ve * 100), 0, hdg)

    def _ack(self, cmd: int, result: int) -> None:
        self.conn.mav.command_ack_send(cmd, result)

    def _set_mode(self, custom: int) -> bool:
        name = MODE_NAMES.get(int(custom))
        if name is None:
            return False
        self.mode = name
        s = self.sim
        if name == "TAKEOFF":
            if not s.armed:
                self.mode = "MANUAL"
                return False
            s.takeoff(self.tkoff_alt)
        elif name == "RTL":
            s.rtl()
        elif name == "LOITER":
            s.loiter()
        elif name == "GUIDED" and s.mode not in ("GUIDED", "COURSE"):
            s.loiter()
        return True

    def _handle(self, msg) -> None:
        t = msg.get_type()
        if t in ("HEARTBEAT", "BAD_DATA"):
            return
        self.received.append(t)
        ok, unsupported = mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_UNSUPPORTED
        if t == "COMMAND_LONG":
            cmd = msg.command
            if cmd == mav.MAV_CMD_COMPONENT_ARM_DISARM:
                if msg.param1 == 1:
                    self.sim.arm()
                else:
                    self.sim.armed = False
                self._ack(cmd, ok)
            elif cmd == mav.MAV_CMD_DO_SET_MODE:
                self._ack(cmd, ok if self._set_mode(msg.param2) else mav.MAV_RESULT_FAILED)
            elif cmd == mav.MAV_CMD_SET_MESSAGE_INTERVAL:
                self._ack(cmd, ok)
            elif cmd == mav.MAV_CMD_DO_LAND_START:
                self.mode = "AUTO"
                self.sim.land()
                self._ack(cmd, ok)
            else:   # includes DO_REPOSITION as COMMAND_LONG, like ArduPlane
                self._ack(cmd, unsupported)
        elif t == "COMMAND_INT":
            cmd = msg.command
            if cmd == mav.MAV_CMD_DO_REPOSITION:
                if msg.param2 and int(msg.param2) & mav.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE:
                    self.mode = "GUIDED"
                if self.mode != "GUIDED":
                    self._ack(cmd, mav.MAV_RESULT_FAILED)
                    return
                x, y = self.frame.to_enu(msg.x / 1e7, msg.y / 1e7)
                self.sim.goto(x, y, radius=msg.param3 if msg.param3 > 0 else None)
                self._ack(cmd, ok)
            elif cmd == mav.MAV_CMD_GUIDED_CHANGE_HEADING:
                if self.mode != "GUIDED":
                    self._ack(cmd, mav.MAV_RESULT_FAILED)
                    return
                self.sim.steer(compass_to_math(msg.param2))
                self._ack(cmd, ok)
            else:
                self._ack(cmd, unsupported)
        elif t == "MISSION_ITEM_INT":
            if msg.current == 2 and self.mode == "GUIDED":
                x, y = self.frame.to_enu(msg.x / 1e7, msg.y / 1e7)
                self.sim.goto(x, y)
                self.conn.mav.mission_ack_send(msg.get_srcSystem(), msg.get_srcComponent(),
                                               mav.MAV_MISSION_ACCEPTED)
            else:
                self.conn.mav.mission_ack_send(msg.get_srcSystem(), msg.get_srcComponent(),
                                               mav.MAV_MISSION_ERROR)
        elif t == "PARAM_SET":
            pid = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
            if pid.rstrip("\x00") == "TKOFF_ALT":
                self.tkoff_alt = float(msg.param_value)
            self.conn.mav.param_value_send(msg.param_id.encode() if isinstance(msg.param_id, str)
                                           else msg.param_id, msg.param_value,
                                           mav.MAV_PARAM_TYPE_REAL32, 1, 0)
