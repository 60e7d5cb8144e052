"""The MAVLink link under :class:`~iterplan_compiler.runtime.mavlink.MavlinkVehicle`.

:class:`MavlinkLink` owns the pymavlink connection and knows the protocol, not the flight: a
GCS heartbeat (1 Hz of wall time from a daemon thread, 1 Hz of vehicle time from the main loop,
so SITL speed-ups keep it alive), serialised sends recorded in :attr:`MavlinkLink.command_log`,
COMMAND_LONG with a waited-for COMMAND_ACK, PARAM_REQUEST_READ / PARAM_SET with the echo
checked, the mission upload handshake, STATUSTEXT kept for messages, and a failed connection
(TCP reset, serial unplugged) turned into link loss at once.  Everything that is about flying
(modes, arming, faults) is the vehicle's.
"""

from __future__ import annotations

import functools
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from iterplan_compiler.runtime.vehicle import VehicleError, VehicleEvent

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402  (after MAVLINK20 so MAVLink 2 is used)

mav = mavutil.mavlink

#: ArduPlane flight modes (custom_mode numbers), from pymavlink's table.
MODE_NAMES: dict[int, str] = dict(mavutil.mode_mapping_apm)
MODES: dict[str, int] = {v: k for k, v in MODE_NAMES.items()}


def result_name(result: int) -> str:
    e = mav.enums["MAV_RESULT"].get(result)
    return e.name.replace("MAV_RESULT_", "") if e else str(result)


@dataclass(frozen=True)
class LinkConfig:
    """Time-outs (wall seconds unless said otherwise) and overrides of a MAVLink vehicle."""

    heartbeat_timeout: float = 30.0   # to the first autopilot heartbeat
    ready_timeout: float = 180.0      # for GPS fix, home and pre-arm checks
    link_timeout: float = 5.0         # no autopilot heartbeat -> link_lost (ArduPilot's own
    telemetry_timeout: float = 5.0    # FS_LONG_TIMEOUT); no GLOBAL_POSITION_INT -> telemetry_lost
    gps_loss_s: float = 1.0           # vehicle seconds without a 3-D fix -> gps_lost
    command_timeout: float = 3.0      # for an ACK or a mode confirmation
    arm_attempts: int = 3
    airspeed: float | None = None     # cruise airspeed to command (DO_CHANGE_SPEED) and plan with
    loiter_radius: float | None = None  # radius of the end-of-mission loiter (default WP_LOITER_RAD)
    system_id: int = 255
    component_id: int = 190


class MavlinkError(VehicleError):
    """Connecting to / preparing the vehicle failed (message for the user)."""


class MavlinkLink:
    """Protocol layer over a pymavlink connection ``conn``; see the module docstring.
    Subclasses add message handlers to :attr:`HANDLERS` and override the hooks
    :meth:`_on_link_failure` and :meth:`_on_refused`."""

    HANDLERS: dict[str, Callable[[Any, Any], None]] = {}

    def __init__(self, conn: Any, config: LinkConfig | None = None,
                 progress: Callable[[str], None] | None = None):
        self.conn = conn
        self.cfg = config or LinkConfig()
        self.progress = progress
        self.ts, self.tc = 1, 1
        self._lock = threading.Lock()
        self._events: list[VehicleEvent] = []
        self._boot_t = 0.0
        self._last_hb_wall = time.monotonic()
        self._last_beat_t = -1e9
        self._link_ok = True
        self._dead = False                # the connection itself failed
        self._hands_off = False           # no commands at all (set by the vehicle)
        self.params: dict[str, float] = {}
        self._acks: dict[int, int] = {}
        self._mission_acks: list[int] = []
        self._mission_requests: list[int] = []
        self.commands_sent = 0
        self.command_log: list[tuple[float, str, str]] = []
        self.statustexts: deque[str] = deque(maxlen=50)
        self._stop = threading.Event()
        self._hb = threading.Thread(target=self._heartbeat_loop, daemon=True,
                                    name="iterplan-mavlink-heartbeat")
        self._hb.start()

    # -- hooks --------------------------------------------------------------------------------
    def _on_link_failure(self, detail: str) -> None:
        """The connection failed (called once)."""

    def _on_refused(self, command: int, result: int) -> None:
        """A COMMAND_ACK said no."""

    def _wait_heartbeat(self, url: str) -> None:
        self._say(f"waiting for a heartbeat on {url}")
        deadline = time.monotonic() + self.cfg.heartbeat_timeout
        while time.monotonic() < deadline:
            self._send_heartbeat()
            msg = self.conn.recv_match(type="HEARTBEAT", blocking=True, timeout=0.5)
            if msg is not None and msg.type not in (mav.MAV_TYPE_GCS,
                                                    mav.MAV_TYPE_ONBOARD_CONTROLLER) \
                    and msg.autopilot != mav.MAV_AUTOPILOT_INVALID:
                self.ts, self.tc = msg.get_srcSystem(), msg.get_srcComponent()
                self._handle(msg)
                return
        raise MavlinkError(f"no autopilot heartbeat on {url} within "
                           f"{self.cfg.heartbeat_timeout:.0f} s")

    def close(self, drain_s: float = 2.0) -> None:
        """Stop the heartbeat, read what the autopilot has already sent (at most ``drain_s``
        wall seconds), then close.  Closing a TCP socket with unread data sends a reset
        instead of an orderly close; ArduPilot SITL's SERIAL0 then stops its simulation for
        good (measured: after 6 s unread at speed-up 10, a plain close froze SITL's clock,
        a drained close of 4,390 queued messages in 0.09 s did not; tests/sitl)."""
        self._stop.set()
        # Only a pymavlink connection owns a socket to drain (``recv_msg``); MAVProxy's
        # ModuleLink reads nothing of its own.
        recv_msg = getattr(self.conn, "recv_msg", None)
        try:
            deadline = time.monotonic() + drain_s
            while recv_msg is not None and time.monotonic() < deadline \
                    and recv_msg() is not None:
                pass
        except Exception:  # noqa: BLE001 - a dead link has nothing left to read
            pass
        try:
            self.conn.close()
        except Exception:  # noqa: BLE001 - closing a dead link must not fail a mission report
            pass

    def _autopilot_says(self) -> str:
        for text in reversed(self.statustexts):
            if text.startswith(("PreArm", "Arm", "AHRS", "EKF", "GPS")):
                return f" (autopilot: {text!r})"
        return ""

    def _say(self, text: str) -> None:
        if self.progress:
            self.progress(f"mavlink: {text}")

    def _emit(self, kind: str, detail: str = "") -> None:
        self._events.append(VehicleEvent(self._boot_t, kind, detail))

    def _mission_item(self, seq: int, frame: int, cmd: int, lat: float, lon: float, alt: float,
                      m: Any) -> None:
        m.mission_item_int_send(self.ts, self.tc, seq, frame, cmd, 0, 1, 0, 0, 0, 0,
                                int(lat * 1e7), int(lon * 1e7), alt)

    def _send(self, fn: Callable[[Any], None], *, detail: str = "", log: bool = True) -> None:
        if (self._hands_off and log) or self._dead:
            return   # somebody else is in charge: no commands at all
        try:
            with self._lock:
                fn(self.conn.mav)
        except OSError as exc:
            self._link_dead(exc)
            return
        if log:
            self.commands_sent += 1
            self.command_log.append((self._boot_t, detail.split(" ")[0], detail))

    def _send_heartbeat(self) -> None:
        if self._dead:
            return
        try:
            with self._lock:
                self.conn.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0,
                                             mav.MAV_STATE_ACTIVE)
        except OSError as exc:
            self._link_dead(exc)

    def _heartbeat_loop(self) -> None:
        while not self._stop.wait(1.0) and not self._dead:
            try:
                self._send_heartbeat()
            except Exception:  # noqa: BLE001 - socket closed underneath us: just stop
                return

    def _link_dead(self, exc: BaseException) -> None:
        """The connection itself failed (TCP reset, serial unplugged): link loss, at once."""
        if self._dead:
            return
        self._dead = True
        self._link_ok = False
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        self._on_link_failure(f"connection failed ({why}); the autopilot's failsafe is in charge")

    def _command_long(self, cmd: int, *params: float, log: bool = True) -> None:
        p = list(params) + [0.0] * (7 - len(params))
        name = mav.enums["MAV_CMD"][cmd].name.replace("MAV_CMD_", "").lower() \
            if cmd in mav.enums["MAV_CMD"] else str(cmd)
        self._send(lambda m: m.command_long_send(self.ts, self.tc, cmd, 0, *p),
                   detail=f"{name} {' '.join(f'{v:g}' for v in params)}", log=log)

    def _command_sync(self, cmd: int, *params: float) -> int:
        """Send a COMMAND_LONG and wait for its ACK; returns the MAV_RESULT (-1: no answer)."""
        self._acks.pop(cmd, None)
        self._command_long(cmd, *params)
        self._wait_until(lambda: cmd in self._acks)
        return self._acks.get(cmd, -1)

    def _wait_until(self, cond: Callable[[], bool], timeout: float | None = None) -> bool:
        deadline = time.monotonic() + (self.cfg.command_timeout if timeout is None else timeout)
        while not cond():
            if time.monotonic() > deadline:
                return False
            if self._dead:
                raise MavlinkError("lost the connection to the autopilot")
            self._pump(0.05)
        return True

    def _set_param(self, name: str, value: float) -> None:
        self.params.pop(name, None)
        self._send(lambda m: m.param_set_send(self.ts, self.tc, name.encode(), value,
                                              mav.MAV_PARAM_TYPE_REAL32),
                   detail=f"param_set {name} {value:g}")
        if not self._wait_until(lambda: name in self.params) \
                or abs(self.params[name] - value) > 1e-3 * max(1.0, abs(value)):
            raise MavlinkError(f"setting {name} = {value:g} was not confirmed by the autopilot")

    def _upload_mission(self, items: list[tuple[int, tuple[float, float], float]]) -> None:
        """MISSION_COUNT / MISSION_REQUEST(_INT) / MISSION_ITEM_INT / MISSION_ACK handshake."""
        self._mission_acks.clear()
        self._mission_requests.clear()
        self._send(lambda m: m.mission_count_send(self.ts, self.tc, len(items)),
                   detail=f"mission_count {len(items)}")
        sent: set[int] = set()
        deadline = time.monotonic() + 10.0
        while True:
            if time.monotonic() > deadline:
                raise MavlinkError("landing: mission upload timed out")
            self._pump(0.05)
            while self._mission_requests:
                seq = self._mission_requests.pop(0)
                if not 0 <= seq < len(items):
                    continue
                cmd, (lat, lon), alt = items[seq]
                frame = mav.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT if seq else mav.MAV_FRAME_GLOBAL_INT
                self._send(functools.partial(self._mission_item, seq, frame, cmd, lat, lon, alt),
                           detail=f"mission_item {seq}")
                sent.add(seq)
            refused = [a for a in self._mission_acks if a != mav.MAV_MISSION_ACCEPTED]
            if refused:
                raise MavlinkError(f"landing: mission refused (MISSION_ACK {refused[0]})")
            if len(sent) == len(items) and self._mission_acks:
                return
            # An ACCEPTED ack before the last item went out answers an earlier GUIDED fly-to.
            self._mission_acks.clear()

    def _pump(self, timeout: float) -> None:
        first = True
        while not self._dead:
            try:
                msg = self.conn.recv_match(blocking=first and timeout > 0,
                                           timeout=timeout or None)
            except OSError as exc:
                self._link_dead(exc)
                time.sleep(min(timeout, 0.05))
                return
            first = False
            if msg is None:
                break
            self._handle(msg)
        if self._boot_t - self._last_beat_t >= 1.0:   # 1 Hz of vehicle time, too
            self._last_beat_t = self._boot_t
            self._send_heartbeat()

    def _handle(self, msg: Any) -> None:
        t = msg.get_type()
        if t == "BAD_DATA" or msg.get_srcSystem() != self.ts:
            return
        handler = self.HANDLERS.get(t)
        if handler is not None:
            handler(self, msg)

    def _on_param(self, msg: Any) -> None:
        pid = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
        self.params[pid.rstrip("\x00")] = float(msg.param_value)

    def _on_command_ack(self, msg: Any) -> None:
        self._acks[msg.command] = msg.result
        if msg.result not in (mav.MAV_RESULT_ACCEPTED, mav.MAV_RESULT_IN_PROGRESS):
            self._on_refused(msg.command, msg.result)

    def _on_mission_request(self, msg: Any) -> None:
        self._mission_requests.append(msg.seq)

    def _on_statustext(self, msg: Any) -> None:
        text = msg.text if isinstance(msg.text, str) else msg.text.decode(errors="replace")
        self.statustexts.append(text)
        self._emit("message", text)


MavlinkLink.HANDLERS = {
    "PARAM_VALUE": MavlinkLink._on_param,
    "COMMAND_ACK": MavlinkLink._on_command_ack,
    "MISSION_REQUEST": MavlinkLink._on_mission_request,
    "MISSION_REQUEST_INT": MavlinkLink._on_mission_request,
    "STATUSTEXT": MavlinkLink._on_statustext,
}
