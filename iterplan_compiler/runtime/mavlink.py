"""MAVLink vehicle: ArduPlane over pymavlink, with ArduPilot's companion-computer conventions.

:class:`MavlinkVehicle` implements the :class:`~iterplan_compiler.runtime.vehicle.Vehicle` API.

Link
    ``mavutil.mavlink_connection(url, source_system=255)``: a GCS system id, so our heartbeats
    feed ArduPlane's GCS failsafe when SYSID_MYGCS = 255 (its default).  We beat at 1 Hz of wall
    time from a daemon thread and at 1 Hz of *vehicle* time from the main loop (SITL speed-ups);
    all sends share one lock.  Messages we need are requested with SET_MESSAGE_INTERVAL.

Start-up (:meth:`MavlinkVehicle.connect`, then :meth:`MavlinkVehicle.prepare`)
    wait for the autopilot's heartbeat; read the parameters the plan depends on
    (PARAM_REQUEST_READ: AIRSPEED_CRUISE, ROLL_LIMIT_DEG, WP_LOITER_RAD, ... with their pre-4.5
    names as fall-backs); then wait, bounded by ``ready_timeout``, for a 3-D GPS fix, the home
    position and the pre-arm-check health bit of SYS_STATUS (a vehicle already flying needs no
    pre-arm).  A time-out names what is missing and quotes ArduPlane's latest ``PreArm:`` text.

Arming and take-off (blocking, checked)
    ``arm``: MAV_CMD_COMPONENT_ARM_DISARM, its COMMAND_ACK awaited and the armed flag confirmed
    by HEARTBEAT; a refusal is retried ``arm_attempts`` times 2 s apart (a check that is still
    settling), then :class:`~iterplan_compiler.runtime.vehicle.VehicleError` with ArduPlane's
    reason.  ``takeoff``: PARAM_SET TKOFF_ALT (echo checked), then mode TAKEOFF (confirmed);
    ``takeoff_complete`` when the relative altitude is within 2 m of it.

Flying
    ``goto``: MISSION_ITEM_INT ``current=2`` (GUIDED fly-to, frame GLOBAL_RELATIVE_ALT_INT),
    only while the vehicle is in GUIDED because *we* put it there (entering GUIDED from our own
    TAKEOFF is a checked mode change); ``loiter(x, y, r)``: MAV_CMD_DO_REPOSITION as COMMAND_INT
    with param3 = r (COMMAND_LONG is UNSUPPORTED on ArduPlane); ``steer``: GUIDED_CHANGE_HEADING;
    ``rtl``: mode RTL; ``land``: uploads a landing mission (approach waypoint, NAV_LAND at home)
    and switches to AUTO; ``landed`` once on the ground or disarmed after landing.

Monitoring (faults, see :data:`~iterplan_compiler.runtime.vehicle.FAULTS`)
    ``mode_changed``: a HEARTBEAT shows a mode other than the one we set (the pilot or a
    failsafe took over) -> from then on nothing is sent but heartbeats (:attr:`hands_off`);
    ``disarmed`` in flight (hands off); ``link_lost``: no autopilot heartbeat for
    ``link_timeout`` wall seconds (hands off: ArduPlane's failsafe is in charge; configure
    FS_GCS_ENABL = 1, FS_LONG_ACTN = 1 and SYSID_MYGCS = 255 on the aircraft);
    ``telemetry_lost``: heartbeats but no GLOBAL_POSITION_INT for ``telemetry_timeout`` wall
    seconds (the vehicle clock would freeze); ``gps_lost``: no 3-D fix for ``gps_loss_s``;
    ``rejected``: a failed COMMAND_ACK/MISSION_ACK for a flight command.

Time is the autopilot's ``time_boot_ms`` (so SITL speed-ups work); ``advance(dt)`` listens until
the vehicle clock moved on by ``dt``, or a wall-time bound passes (a frozen clock cannot hang a
mission).  Every command sent is recorded in :attr:`MavlinkVehicle.command_log`.

:class:`~iterplan_compiler.runtime.loopback.LoopbackAutopilot` is a fast stand-in peer for unit
tests; what flies is proven against ArduPilot SITL (``tests/sitl/``).
"""

from __future__ import annotations

import functools
import math
import statistics
import time
from collections.abc import Callable
from typing import Any

from iterplan_compiler.runtime.grid import LocalFrame, math_to_compass
from iterplan_compiler.runtime.mavlink_link import (  # re-exported for users and tests
    MODE_NAMES,
    MODES,
    LinkConfig,
    MavlinkError,
    mav,
    mavutil,
    result_name,
)
from iterplan_compiler.runtime.mavlink_monitor import MavlinkMonitor
from iterplan_compiler.runtime.vehicle import (
    L1_REFERENCE,
    PLANNING_BANK_DEG,
    Start,
    Vehicle,
    VehicleEvent,
    VehicleModel,
    VehiclePose,
    cruise_true_airspeed,
    planning_bank_deg,
)

__all__ = ["MODES", "MODE_NAMES", "LinkConfig", "MavlinkError", "MavlinkVehicle", "mav",
           "mavutil"]

#: Parameters read at connection: name -> (fall-back name on older firmware, its scale).
PARAMS: dict[str, tuple[str | None, float]] = {
    "AIRSPEED_CRUISE": ("TRIM_ARSPD_CM", 0.01),
    "ROLL_LIMIT_DEG": ("LIM_ROLL_CD", 0.01),
    "WP_LOITER_RAD": (None, 1.0),
    "WP_RADIUS": (None, 1.0),
    "NAVL1_PERIOD": (None, 1.0),
    "NAVL1_DAMPING": (None, 1.0),
    "AIRSPEED_MIN": ("ARSPD_FBW_MIN", 1.0),
    "AIRSPEED_MAX": ("ARSPD_FBW_MAX", 1.0),
    "TKOFF_ALT": (None, 1.0),
    "SYSID_MYGCS": (None, 1.0),
    "FS_GCS_ENABL": (None, 1.0),
}



class MavlinkVehicle(MavlinkMonitor, Vehicle):
    """ArduPlane through pymavlink; see the module docstring."""

    def __init__(self, conn: Any, frame: LocalFrame, config: LinkConfig | None = None,
                 progress: Callable[[str], None] | None = None):
        MavlinkMonitor.__init__(self, conn, frame, config, progress)
        self._last_goto: tuple[float, float, float] | None = None   # course, alt, vehicle time
        self._last_course: tuple[float, float] | None = None
        self.model = VehicleModel(18.0, PLANNING_BANK_DEG, 80.0)
        self._confirmed: Callable[[], bool] = lambda: True   # is the last safe command in force?

    # -- connection ---------------------------------------------------------------------------
    @classmethod
    def connect(cls, url: str, frame: LocalFrame, config: LinkConfig | None = None,
                progress: Callable[[str], None] | None = None) -> MavlinkVehicle:
        """Open ``url`` and :meth:`attach` to it; raises :class:`MavlinkError`."""
        cfg = config or LinkConfig()
        try:
            conn = mavutil.mavlink_connection(url, source_system=cfg.system_id,
                                              source_component=cfg.component_id)
        except Exception as exc:  # noqa: BLE001 - pymavlink raises assorted OSErrors/ValueErrors
            raise MavlinkError(f"cannot open {url}: {exc}") from None
        return cls.attach(conn, frame, cfg, progress, name=url)

    @classmethod
    def attach(cls, conn: Any, frame: LocalFrame, config: LinkConfig | None = None,
               progress: Callable[[str], None] | None = None,
               name: str = "the link") -> MavlinkVehicle:
        """A vehicle over an open connection ``conn`` (anything with pymavlink's
        ``recv_match``, ``mav`` and ``close``, e.g. MAVProxy's link): wait for the autopilot,
        request telemetry, read the parameters; raises :class:`MavlinkError`."""
        v = cls(conn, frame, config, progress)
        try:
            v.start_link(name)
        except BaseException:
            v.close()
            raise
        return v

    def start_link(self, name: str = "the link") -> None:
        """The steps of :meth:`attach` on an existing instance (a caller that needs the object
        while it waits, e.g. to stop it)."""
        self._wait_heartbeat(name)
        self._request_streams()
        self._read_params()
        self.model = self._derive_model()

    def _request_streams(self) -> None:
        for msg_id, hz in ((mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 10.0),
                           (mav.MAVLINK_MSG_ID_GPS_RAW_INT, 2.0),
                           (mav.MAVLINK_MSG_ID_SYS_STATUS, 1.0),
                           (mav.MAVLINK_MSG_ID_HOME_POSITION, 0.5),
                           (mav.MAVLINK_MSG_ID_HEARTBEAT, 2.0)):
            self._command_long(mav.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id, 1e6 / hz, log=False)

    def _read_params(self, timeout: float = 6.0) -> None:
        names = list(PARAMS) + [alt for alt, _ in PARAMS.values() if alt]
        deadline = time.monotonic() + timeout
        asked = 0.0
        while time.monotonic() < deadline:
            missing = [n for n in PARAMS if n not in self.params
                       and (PARAMS[n][0] is None or PARAMS[n][0] not in self.params)]
            if not missing:
                break
            if time.monotonic() - asked > 2.0:
                for n in names:
                    if n not in self.params:
                        self._send(functools.partial(self._param_request, n), log=False)
                asked = time.monotonic()
            self._pump(0.1)

    def _param_request(self, name: str, m: Any) -> None:
        m.param_request_read_send(self.ts, self.tc, name.encode(), -1)

    def param(self, name: str) -> float | None:
        """A parameter read at connection (by its current name; older names are converted)."""
        if name in self.params:
            return self.params[name]
        alt, scale = PARAMS.get(name, (None, 1.0))
        if alt and alt in self.params:
            return self.params[alt] * scale
        return None

    def _derive_model(self) -> VehicleModel:
        """Cruise true airspeed, planning bank and loiter radius from the vehicle's parameters
        (a command-line ``airspeed``/``loiter_radius`` wins)."""
        cruise = self.cfg.airspeed or self.param("AIRSPEED_CRUISE")
        source = "parameters"
        if cruise is None or cruise <= 0:
            cruise, source = 18.0, "default (AIRSPEED_CRUISE unreadable)"
        alt = (self.home_amsl or 0.0) + 60.0
        tas = cruise_true_airspeed(cruise, alt)
        roll = self.param("ROLL_LIMIT_DEG") or 45.0
        loiter = self.cfg.loiter_radius or self.param("WP_LOITER_RAD") or 80.0
        period = self.param("NAVL1_PERIOD") or L1_REFERENCE[0]
        damping = self.param("NAVL1_DAMPING") or L1_REFERENCE[1]
        bank = min(roll, planning_bank_deg(period, damping))
        return VehicleModel(tas, bank, abs(loiter), source, period, damping)

    # -- Vehicle API: state -------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self._boot_t

    def pose(self) -> VehiclePose:
        return self._pose

    @property
    def airspeed(self) -> float:  # type: ignore[override]
        """Cruise speed: the measured median ground speed in GUIDED once known, else the
        parameters' true airspeed."""
        if len(self._speeds) >= 20:
            return float(statistics.median(self._speeds))
        return self.model.airspeed

    @property
    def min_turn_radius(self) -> float:  # type: ignore[override]
        return self.model.min_turn_radius

    @property
    def l1_period(self) -> float:  # type: ignore[override]
        return self.model.l1_period

    @property
    def l1_damping(self) -> float:  # type: ignore[override]
        return self.model.l1_damping

    @property
    def loiter_radius(self) -> float:
        return self.model.loiter_radius

    @property
    def link_ok(self) -> bool:
        return self._link_ok

    @property
    def hands_off(self) -> bool:
        return self._hands_off

    @property
    def flying(self) -> bool:
        return self.armed and self._pose.alt > 10.0 and self._pose.groundspeed > 5.0

    # -- Vehicle API: start-up ----------------------------------------------------------------
    def prepare(self, start: Start) -> Start:
        """Wait (bounded) for GPS fix, home and pre-arm checks; see the module docstring."""
        deadline = time.monotonic() + self.cfg.ready_timeout
        next_say = next_home = 0.0
        while True:
            missing = self._not_ready(start)
            if not missing:
                break
            if self._dead:
                raise MavlinkError("lost the connection to the autopilot while waiting for it "
                                   "to get ready")
            now = time.monotonic()
            if now > deadline:
                why = self._autopilot_says()
                raise MavlinkError(f"vehicle not ready after {self.cfg.ready_timeout:.0f} s: "
                                   f"waiting for {', '.join(missing)}{why}")
            if now >= next_home and "home position" in missing:
                self._command_long(mav.MAV_CMD_REQUEST_MESSAGE,
                                   mav.MAVLINK_MSG_ID_HOME_POSITION, log=False)
                next_home = now + 2.0
            if now >= next_say:
                self._say(f"waiting for {', '.join(missing)}{self._autopilot_says()}")
                next_say = now + 10.0
            self._pump(0.1)
        start = super().prepare(start)
        self.model = self._derive_model()        # home altitude is known now
        self._monitoring = True
        self._say(f"ready ({'flying' if self.flying else 'on the ground'}, mode {self.mode}); "
                  f"cruise {self.model.airspeed:.1f} m/s TAS, planning bank "
                  f"{self.model.bank_limit_deg:.0f} deg, loiter radius "
                  f"{self.model.loiter_radius:.0f} m")
        return start

    def _not_ready(self, start: Start) -> list[str]:
        missing = []
        if self.fix_type < 3:
            missing.append(f"a 3-D GPS fix (fix type {self.fix_type})")
        if self.home_amsl is None:
            missing.append("the home position")
        elif not self.has_position:       # positions count from home on (mavlink_monitor)
            missing.append("a position")
        if not self.prearm_ok and not (start is not Start.GROUND and self.flying):
            missing.append("the pre-arm checks")
        return missing

    def arm(self) -> None:
        """Arm, checked (see the module docstring); raises :class:`MavlinkError`."""
        if self.armed:
            return
        cmd = mav.MAV_CMD_COMPONENT_ARM_DISARM
        result = -1
        for attempt in range(1, self.cfg.arm_attempts + 1):
            result = self._command_sync(cmd, 1)
            if result == mav.MAV_RESULT_ACCEPTED and self._wait_until(lambda: self.armed):
                self._monitoring = True
                return
            if attempt < self.cfg.arm_attempts:
                self._say(f"arming refused ({result_name(result)}{self._autopilot_says()}); "
                          f"retrying in 2 s")
                self._wait_until(lambda: False, 2.0)
        raise MavlinkError(f"arming refused by the autopilot ({result_name(result)})"
                           f"{self._autopilot_says()}")

    def disarm(self) -> None:
        """Disarm, only when clearly on the ground (below 3 m, slower than 2 m/s); ArduPlane
        itself also refuses an unforced disarm while it thinks it is flying."""
        p = self._pose
        if self.armed and not self._hands_off and p.alt < 3.0 and p.groundspeed < 2.0:
            self._command_sync(mav.MAV_CMD_COMPONENT_ARM_DISARM, 0)
            self._wait_until(lambda: not self.armed)

    def takeoff(self, alt: float) -> None:
        self._set_param("TKOFF_ALT", float(alt))
        self._takeoff_alt = float(alt)
        self._takeoff_done = False
        self._request_mode("TAKEOFF")

    def take_control(self) -> None:
        self._enter_guided()

    # -- Vehicle API: flying ------------------------------------------------------------------
    def goto(self, x: float, y: float, alt: float | None = None,
             radius: float | None = None) -> None:
        if not self._may_fly():
            return
        if radius:
            self.loiter(x, y, radius)
            return
        p = self._pose
        course = math.atan2(y - p.y, x - p.x)
        z = float(alt if alt is not None else (self._takeoff_alt or p.alt or 60.0))
        if self._last_goto is not None:
            lc, lz, lt = self._last_goto
            # A carrot moves with the aircraft: re-send when its bearing changed, or every
            # second of vehicle time (not wall time: SITL runs faster than real time).
            if abs(math.remainder(course - lc, 2 * math.pi)) < math.radians(3) \
                    and abs(z - lz) < 1 and self._boot_t - lt < 1.0:
                return
        self._last_goto = (course, z, self._boot_t)
        self._last_course = None
        lat, lon = self.frame.to_latlon(x, y)
        self._send(lambda m: m.mission_item_int_send(
            self.ts, self.tc, 0, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, mav.MAV_CMD_NAV_WAYPOINT,
            2, 0, 0, 0, 0, 0, int(lat * 1e7), int(lon * 1e7), z),
            detail=f"goto {x:.0f} {y:.0f} {z:.0f}")

    def steer(self, course: float) -> None:
        if not self._may_fly():
            return
        if self._last_course:
            lc, lt = self._last_course
            if abs(math.remainder(course - lc, 2 * math.pi)) < math.radians(2) \
                    and self._boot_t - lt < 1.0:
                return
        self._last_course = (course, self._boot_t)
        self._last_goto = None
        self._send(lambda m: m.command_int_send(
            self.ts, self.tc, 0, mav.MAV_CMD_GUIDED_CHANGE_HEADING, 0, 0,
            0, math_to_compass(course), 10.0, 0, 0, 0, 0), detail=f"steer {course:.2f}")

    def loiter(self, x: float | None = None, y: float | None = None,
               radius: float | None = None) -> None:
        if self._hands_off:
            return
        if x is None or y is None:
            self._request_mode("LOITER", wait=False)
            return
        r = float(radius or self.model.loiter_radius)
        lat, lon = self.frame.to_latlon(x, y)
        z = float(self._takeoff_alt or self._pose.alt or 60.0)
        self.expected_mode = "GUIDED"
        self._mode_req = ("GUIDED", self.mode, time.monotonic())
        self._acks.pop(mav.MAV_CMD_DO_REPOSITION, None)
        self._confirmed = lambda: self._acks.get(mav.MAV_CMD_DO_REPOSITION) \
            == mav.MAV_RESULT_ACCEPTED and self.mode == "GUIDED"
        self._send(lambda m: m.command_int_send(
            self.ts, self.tc, mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            mav.MAV_CMD_DO_REPOSITION, 0, 0, -1, mav.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE,
            r, 0, int(lat * 1e7), int(lon * 1e7), z), detail=f"loiter {x:.0f} {y:.0f} r {r:.0f}")

    def rtl(self) -> None:
        if not self._hands_off:
            self._request_mode("RTL", wait=False)

    def land(self) -> None:
        """Upload a landing mission (approach waypoint 600 m out on the aircraft's side of home,
        NAV_LAND at home) and fly it in AUTO; ``landed`` follows."""
        if self._hands_off:
            return
        p = self._pose
        d = math.hypot(p.x, p.y) or 1.0
        home = self.frame.to_latlon(0.0, 0.0)
        ax, ay = 600.0 * p.x / d, 600.0 * p.y / d
        approach = self.frame.to_latlon(ax, ay)
        items = [(mav.MAV_CMD_NAV_WAYPOINT, home, 0.0),
                 (mav.MAV_CMD_NAV_WAYPOINT, approach, 40.0),
                 (mav.MAV_CMD_NAV_LAND, home, 0.0)]
        try:
            self._upload_mission(items)
            result = self._command_sync(mav.MAV_CMD_DO_SET_MISSION_CURRENT, 1)
            if result != mav.MAV_RESULT_ACCEPTED:
                raise MavlinkError(f"landing: mission start refused ({result_name(result)})")
            self._landing = True
            self._request_mode("AUTO")
        except MavlinkError as exc:
            self._emit("rejected", str(exc))

    def advance(self, dt: float) -> None:
        """Listen until the autopilot clock moved on by ``dt`` (wall-bounded)."""
        target = self._boot_t + dt
        wall_end = time.monotonic() + max(dt, 0.05) * 1.5 + 0.05
        while self._boot_t < target and time.monotonic() < wall_end:
            self._pump(0.02)
        self._check()

    def poll_events(self) -> list[VehicleEvent]:
        self._pump(0.0)
        self._check()
        ev, self._events = self._events, []
        return ev

    def settle(self, timeout: float = 3.0) -> str:
        """Wait for the last safe command to be confirmed (mode shown by HEARTBEAT, or the
        DO_REPOSITION ACK)."""
        if self._hands_off:
            return "no command sent: " + ("link lost" if not self._link_ok else
                                          f"vehicle in {self.mode}, not under iterplan's control")
        want = self.expected_mode
        ok = self._wait_until(self._confirmed, timeout)
        return f"vehicle in {self.mode}" + ("" if ok else f" (wanted {want}, not confirmed)")

    # -- internals: commands ------------------------------------------------------------------
    def _may_fly(self) -> bool:
        """Fly-to/steer commands go out only in the GUIDED mode we set ourselves."""
        if self._hands_off:
            return False
        if self.expected_mode in (None, "TAKEOFF") and not self._landing:
            self._enter_guided()
        return self.expected_mode == "GUIDED" and self.mode == "GUIDED"

    def _enter_guided(self) -> None:
        self._request_mode("GUIDED")
        self._monitoring = True
        if self.cfg.airspeed:
            self._command_long(mav.MAV_CMD_DO_CHANGE_SPEED, 0, float(self.cfg.airspeed), -1)

    def _request_mode(self, name: str, wait: bool = True) -> None:
        """Ask for mode ``name``; with ``wait``, raise :class:`MavlinkError` unless HEARTBEAT
        confirms it within ``command_timeout``."""
        if self._hands_off:
            return
        self.expected_mode = name
        self._mode_req = (name, self.mode, time.monotonic())
        self._acks.pop(mav.MAV_CMD_DO_SET_MODE, None)
        self._confirmed = lambda: self.mode == name
        self._command_long(mav.MAV_CMD_DO_SET_MODE, mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                           MODES[name])
        if not wait:
            return
        ok = self._wait_until(lambda: self.mode == name
                              or self._acks.get(mav.MAV_CMD_DO_SET_MODE, 0) > 0)
        if self.mode == name:
            self._mode_req = None
            return
        res = self._acks.get(mav.MAV_CMD_DO_SET_MODE)
        why = f"refused ({result_name(res)})" if ok and res else "not confirmed"
        raise MavlinkError(f"mode change to {name} {why}; the vehicle is in {self.mode}"
                           f"{self._autopilot_says()}")
