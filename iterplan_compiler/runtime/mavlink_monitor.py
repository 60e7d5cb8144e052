"""What ArduPlane tells us: the vehicle state from its telemetry, and the faults it implies.

:class:`MavlinkMonitor` is the receiving half of
:class:`~iterplan_compiler.runtime.mavlink.MavlinkVehicle` (the commanding half): HEARTBEAT
(mode, armed flag, link health), GLOBAL_POSITION_INT (pose, vehicle clock, take-off and landing
progress), GPS_RAW_INT, SYS_STATUS (pre-arm health), HOME_POSITION, MISSION_ACK and
MISSION_ITEM_REACHED; and the faults of :data:`~iterplan_compiler.runtime.vehicle.FAULTS`
(``mode_changed``, ``disarmed``, ``link_lost``, ``telemetry_lost``, ``gps_lost``, ``rejected``),
each reported once, from the start of the mission on.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from iterplan_compiler.runtime.grid import LocalFrame
from iterplan_compiler.runtime.mavlink_link import (
    MODE_NAMES,
    LinkConfig,
    MavlinkLink,
    mav,
    result_name,
)
from iterplan_compiler.runtime.vehicle import HANDS_OFF, VehiclePose

#: Commands whose refusal is a fault while flying (others, e.g. message intervals, are logged).
FLIGHT_COMMANDS = frozenset({mav.MAV_CMD_DO_REPOSITION, mav.MAV_CMD_GUIDED_CHANGE_HEADING,
                             mav.MAV_CMD_DO_SET_MODE, mav.MAV_CMD_DO_CHANGE_SPEED,
                             mav.MAV_CMD_COMPONENT_ARM_DISARM, mav.MAV_CMD_DO_SET_MISSION_CURRENT})


class MavlinkMonitor(MavlinkLink):
    """Vehicle state and faults from ArduPlane's telemetry; see the module docstring."""

    def __init__(self, conn: Any, frame: LocalFrame, config: LinkConfig | None = None,
                 progress: Callable[[str], None] | None = None):
        MavlinkLink.__init__(self, conn, config, progress)
        self.frame = frame
        self._pose = VehiclePose(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        self.has_position = False         # a real position (after home) has been seen
        self._last_pos_wall = time.monotonic()
        self._monitoring = False          # faults are reported once the mission starts
        self._reported: set[str] = set()
        self.mode = "UNKNOWN"
        self.expected_mode: str | None = None
        self._mode_req: tuple[str, str, float] | None = None   # (wanted, previous, wall)
        self.armed = False
        self.fix_type = 0
        self._nofix_since: float | None = None
        self.home_amsl: float | None = None
        self.alt_amsl = 0.0
        self.prearm_ok = False
        self._takeoff_alt: float | None = None
        self._takeoff_done = False
        self._landing = False
        self._ground_since: float | None = None
        self._speeds: deque[float] = deque(maxlen=600)

    # -- faults ------------------------------------------------------------------------------
    def _fault(self, kind: str, detail: str) -> None:
        if not self._monitoring or kind in self._reported:
            return
        self._reported.add(kind)
        if kind in HANDS_OFF:
            self._hands_off = True
        self._emit(kind, detail)
        self._say(f"{kind}: {detail}")

    def _on_link_failure(self, detail: str) -> None:
        self._monitoring = self._monitoring or self.armed
        self._fault("link_lost", detail)

    def _on_refused(self, command: int, result: int) -> None:
        if command in FLIGHT_COMMANDS and self._monitoring:
            e = mav.enums["MAV_CMD"].get(command)
            name = e.name if e else str(command)
            self._fault("rejected", f"{name} refused ({result_name(result)})"
                                    f"{self._autopilot_says()}")

    # -- internals: receiving -----------------------------------------------------------------
    def _check(self) -> None:
        now = time.monotonic()
        age = now - self._last_hb_wall
        if self._link_ok and age > self.cfg.link_timeout:
            self._link_ok = False
            self._monitoring = self._monitoring or self.armed
            self._fault("link_lost", f"no autopilot heartbeat for {age:.1f} s; the autopilot's "
                                     f"failsafe is in charge")
        pos_age = now - self._last_pos_wall
        if self._link_ok and pos_age > self.cfg.telemetry_timeout:
            self._fault("telemetry_lost", f"heartbeats but no position for {pos_age:.1f} s")
        if self._nofix_since is not None and self._boot_t - self._nofix_since \
                >= self.cfg.gps_loss_s:
            self._fault("gps_lost", f"no 3-D GPS fix for {self._boot_t - self._nofix_since:.1f}"
                                    f" s (fix type {self.fix_type})")
        req = self._mode_req
        if req and not self._hands_off and now - req[2] > self.cfg.command_timeout:
            self._mode_req = None
            if self.mode != req[0]:
                self._fault("rejected", f"mode change to {req[0]} not confirmed; the vehicle "
                                        f"is in {self.mode}")

    def _on_heartbeat(self, msg: Any) -> None:
        if msg.get_srcComponent() != self.tc or msg.type in (mav.MAV_TYPE_GCS,
                                                             mav.MAV_TYPE_ONBOARD_CONTROLLER):
            return
        self._last_hb_wall = time.monotonic()
        if not self._link_ok:
            self._link_ok = True
            self._emit("link_restored")
        mode = MODE_NAMES.get(msg.custom_mode, str(msg.custom_mode))
        self.mode = mode
        req = self._mode_req
        if req and mode == req[0]:
            self._mode_req = None
        elif self.expected_mode and mode != self.expected_mode and not self._hands_off:
            # Tolerate the old mode while our own request is in flight; anything else is the
            # pilot or a failsafe.
            if not (req and mode == req[1]):
                self._fault("mode_changed", f"flight mode changed to {mode} (iterplan set "
                                            f"{self.expected_mode}): the pilot or a failsafe "
                                            f"took over; iterplan stopped commanding")
        armed = bool(msg.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
        if armed and not self.armed:
            self._emit("armed")
        if self.armed and not armed:
            if self._landing:
                self._landed("disarmed after landing")
            else:
                self._fault("disarmed", "the vehicle was disarmed")
        self.armed = armed

    def _on_position(self, msg: Any) -> None:
        self._last_pos_wall = time.monotonic()
        self._boot_t = max(self._boot_t, msg.time_boot_ms / 1000.0)
        if self.home_amsl is None:
            # ArduPlane reports positions before its EKF has an origin: for ~9 s after boot
            # SITL sends lat/lon within metres of (0, 0), 14,000 km from its field.  Home is
            # set only once the position is real; until then the pose stays where it was.
            return
        self.has_position = True
        x, y = self.frame.to_enu(msg.lat / 1e7, msg.lon / 1e7)
        vn, ve = msg.vx / 100.0, msg.vy / 100.0
        alt = msg.relative_alt / 1000.0
        self.alt_amsl = msg.alt / 1000.0
        gs = math.hypot(vn, ve)
        self._pose = VehiclePose(self._boot_t, x, y, alt, math.atan2(vn, ve), gs)
        if self.mode == "GUIDED" and self.armed and alt > 20.0:
            self._speeds.append(gs)
        if self._takeoff_alt is not None and not self._takeoff_done \
                and self.mode == "TAKEOFF" and alt >= self._takeoff_alt - 2.0:
            self._takeoff_done = True
            self._emit("takeoff_complete", f"alt {alt:.0f} m")
        if self._landing:
            if alt < 2.0 and gs < 1.5:
                self._ground_since = self._ground_since if self._ground_since is not None \
                    else self._boot_t
                if self._boot_t - self._ground_since >= 2.0:
                    self._landed(f"on the ground {math.hypot(x, y):.0f} m from home")
            else:
                self._ground_since = None

    def _landed(self, detail: str) -> None:
        if self._landing:
            self._landing = False
            self.expected_mode = None
            self._emit("landed", detail)

    def _on_gps(self, msg: Any) -> None:
        self.fix_type = msg.fix_type
        if msg.fix_type >= 3:
            self._nofix_since = None
        elif self._nofix_since is None and self._monitoring:
            self._nofix_since = self._boot_t

    def _on_sys_status(self, msg: Any) -> None:
        bit = mav.MAV_SYS_STATUS_PREARM_CHECK
        present = msg.onboard_control_sensors_present & bit
        self.prearm_ok = bool(msg.onboard_control_sensors_health & bit) or not present

    def _on_home(self, msg: Any) -> None:
        self.home_amsl = msg.altitude / 1000.0

    def _on_mission_ack(self, msg: Any) -> None:
        self._mission_acks.append(msg.type)
        if msg.type != mav.MAV_MISSION_ACCEPTED and self.expected_mode == "GUIDED" \
                and not self._landing:
            self._fault("rejected", f"fly-to refused (MISSION_ACK {msg.type})")

    def _on_reached(self, msg: Any) -> None:
        self._emit("reached", f"seq {msg.seq}")


MavlinkMonitor.HANDLERS = {
    **MavlinkLink.HANDLERS,
    "HEARTBEAT": MavlinkMonitor._on_heartbeat,
    "GLOBAL_POSITION_INT": MavlinkMonitor._on_position,
    "GPS_RAW_INT": MavlinkMonitor._on_gps,
    "SYS_STATUS": MavlinkMonitor._on_sys_status,
    "HOME_POSITION": MavlinkMonitor._on_home,
    "MISSION_ACK": MavlinkMonitor._on_mission_ack,
    "MISSION_ITEM_REACHED": MavlinkMonitor._on_reached,
}
