"""The vehicle interface shared by the built-in simulator and the MAVLink link.

Everything is in the map's local ENU frame (metres east/north of the map origin, math angles);
implementations convert to lat/lon at their boundary.  Time is the vehicle's clock in seconds:
simulated time for :mod:`~iterplan_compiler.runtime.sim`, the autopilot's boot time for
:mod:`~iterplan_compiler.runtime.mavlink`.

Commands (all non-blocking; their outcome arrives as :class:`VehicleEvent`):

``arm()``, ``takeoff(alt)``
    ``takeoff_complete`` once the climb is done (then the vehicle loiters).
``goto(x, y, alt=None, radius=None)``
    ArduPlane GUIDED fly-to: head for the point, then loiter around it; ``reached`` fires at the
    loiter capture, well before the point (a fixed wing never stops).
``steer(course)``
    Hold a course over ground (ArduPlane GUIDED_CHANGE_HEADING): the motion planner flies its own
    Dubins paths with it.
``rtl()``, ``land()``, ``loiter(x=None, y=None, radius=None)``
    Return home and circle / land at home (``landed``) / circle ``(x, y)`` (default: where it
    is) at ``radius`` (default: the vehicle's loiter radius).
``advance(dt)``
    Let ``dt`` seconds of vehicle time pass (simulated, or by listening to the link).

Events: ``armed``, ``takeoff_complete``, ``reached``, ``landed``, ``link_restored``,
``message`` (status text), and the *faults* of :data:`FAULTS`, after which the runtime stops
flying the plan: ``link_lost`` (no autopilot heartbeat), ``telemetry_lost`` (heartbeats but no
position), ``gps_lost`` (no 3-D fix), ``mode_changed`` (the pilot or a failsafe changed the
flight mode away from the one the runtime set), ``disarmed`` (disarmed in flight), ``rejected``
(the autopilot refused a command).  After ``link_lost``, ``mode_changed`` and ``disarmed``
somebody else is in charge (the autopilot's failsafe, the pilot): the vehicle then sends no more
commands at all (:attr:`Vehicle.hands_off`).

Blocking start-up steps that can fail (waiting for the autopilot to be ready, arming, a mode
change) raise :class:`VehicleError` with a message for the user.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from enum import Enum

G = 9.80665

#: Event kinds after which the mission cannot go on.
FAULTS = frozenset({"link_lost", "telemetry_lost", "gps_lost", "mode_changed", "disarmed",
                    "rejected"})
#: Faults after which somebody else (pilot, autopilot failsafe) is in charge: no more commands.
HANDS_OFF = frozenset({"link_lost", "mode_changed", "disarmed"})


class VehicleError(RuntimeError):
    """A start-up step or command failed; the message is meant for the user."""


class Start(Enum):
    """How a mission begins: ``ground`` arms and takes off, ``airborne`` takes over a vehicle
    that is already flying, ``auto`` picks by what the vehicle reports (armed and flying)."""

    AUTO = "auto"
    GROUND = "ground"
    AIRBORNE = "airborne"


class VehicleBackend(Enum):
    """Which :class:`Vehicle` ``iterc run --vehicle`` flies: ``sim`` the built-in simulator
    (:class:`sim.SimVehicle`), ``mavlink`` an ArduPlane, SITL or real
    (:class:`mavlink.MavlinkVehicle`)."""

    SIM = "sim"
    MAVLINK = "mavlink"


class SafeAction(Enum):
    """What the runtime commands when it stops flying the plan (``--on-end``/``--on-fault``):
    ``loiter`` circles the map centre at the loiter radius, ``rtl`` returns home (and circles
    there, ArduPlane's RTL), ``land`` lands at home, ``none`` leaves the last command in force."""

    LOITER = "loiter"
    RTL = "rtl"
    LAND = "land"
    NONE = "none"


#: Planning uses at most this bank with ArduPlane's L1 navigation at its reference setting
#: (:data:`L1_REFERENCE`): the L1 path following rarely commands more there, and paths planned
#: with the full ROLL_LIMIT_DEG (65 in SITL) cannot be followed.
PLANNING_BANK_DEG = 45.0
#: (NAVL1_PERIOD, NAVL1_DAMPING) at which :data:`PLANNING_BANK_DEG` was measured on SITL.
L1_REFERENCE = (15.0, 0.75)
#: Planning never uses more bank than this, whatever the L1 setting (SITL's ROLL_LIMIT_DEG;
#: the steepest planned bank flown there, 61.9 deg at NAVL1_PERIOD 8, is below it).
PLANNING_BANK_MAX_DEG = 65.0


@dataclass(frozen=True)
class VehicleModel:
    """What the planner and the Sorter need to know about the aircraft.

    ``airspeed``: cruise speed over ground without wind, i.e. true airspeed (m/s);
    ``bank_limit_deg``: the bank the autopilot may use; ``loiter_radius``: the radius it circles
    a fly-to target at (ArduPlane WP_LOITER_RAD); ``l1_period``, ``l1_damping``: its
    NAVL1_PERIOD and NAVL1_DAMPING.  :attr:`min_turn_radius` is the tightest coordinated turn,
    ``V^2 / (g tan(bank))``."""

    airspeed: float
    bank_limit_deg: float
    loiter_radius: float
    source: str = "default"
    l1_period: float = L1_REFERENCE[0]
    l1_damping: float = L1_REFERENCE[1]

    @property
    def min_turn_radius(self) -> float:
        return turn_radius(self.airspeed, self.bank_limit_deg)


def turn_radius(speed: float, bank_deg: float) -> float:
    """Radius (m) of a coordinated level turn at ``speed`` (m/s) and ``bank_deg``."""
    return speed * speed / (G * math.tan(math.radians(bank_deg)))


#: Planned turns are this much wider than the tightest turn at the planning bank (margin for
#: the autopilot's roll-in lag and path-following error).
PLANNING_MARGIN = 1.4


def planning_bank_deg(l1_period: float, l1_damping: float) -> float:
    """The bank the planner plans turns with under ArduPlane's L1 navigation with this period
    (s) and damping: :data:`PLANNING_BANK_DEG` at :data:`L1_REFERENCE`, and otherwise the bank
    whose tangent scales like the largest lateral acceleration L1 pursuit commands,
    ``4 zeta^2 V^2 / L1`` with ``L1 = zeta P V / pi``, i.e. ``4 pi zeta V / P``: ``tan(bank)
    x (P_ref / P) x (zeta / zeta_ref)``.  A shorter period tracks tighter turns (measured on
    SITL, docs/runtime.md); at most :data:`PLANNING_BANK_MAX_DEG`, and the roll limit caps the
    bank separately (``min_turn_radius``)."""
    p_ref, z_ref = L1_REFERENCE
    scale = (p_ref / max(l1_period, 1.0)) * (max(l1_damping, 0.1) / z_ref)
    bank = math.degrees(math.atan(math.tan(math.radians(PLANNING_BANK_DEG)) * scale))
    return min(bank, PLANNING_BANK_MAX_DEG)


def planning_radius(vehicle: Vehicle, wind: float = 0.0) -> float:
    """The default Dubins radius of the planner and the Sorter for ``vehicle``:
    ``PLANNING_MARGIN x`` the larger of its tightest turn and the turn at the planning bank
    (:func:`planning_bank_deg` of its L1 setting), grown for an expected ``wind`` (m/s) to what
    the aircraft can fly over ground downwind, ``x ((V + wind) / V)^2``."""
    v = max(vehicle.airspeed, 1.0)
    bank = planning_bank_deg(vehicle.l1_period, vehicle.l1_damping)
    r = max(vehicle.min_turn_radius, turn_radius(v, bank))
    return PLANNING_MARGIN * r * (1.0 + max(0.0, wind) / v) ** 2


def cruise_true_airspeed(cruise_eas: float, alt_amsl: float) -> float:
    """ArduPlane holds AIRSPEED_CRUISE as equivalent airspeed; the true airspeed at
    ``alt_amsl`` metres (ISA troposphere) is what the aircraft covers per second in still air."""
    ratio = max(1e-3, 1.0 - 2.25577e-5 * alt_amsl) ** 4.2559
    return cruise_eas / math.sqrt(ratio)


@dataclass(frozen=True)
class VehiclePose:
    """Vehicle state snapshot: ENU position (m), altitude above home (m), course over ground
    (math radians), ground speed (m/s), time (s)."""

    t: float
    x: float
    y: float
    alt: float
    course: float
    groundspeed: float


@dataclass(frozen=True)
class VehicleEvent:
    t: float
    kind: str
    detail: str = ""


class Vehicle(ABC):
    """Abstract vehicle; see the module docstring for the contract."""

    #: cruise true airspeed (m/s) and the tightest turn radius it can fly (m); the planner and
    #: the Sorter size their Dubins paths from these.
    airspeed: float = 18.0
    min_turn_radius: float = 35.0
    #: ArduPlane's NAVL1_PERIOD (s) and NAVL1_DAMPING: how tight a turn its path following
    #: holds (:func:`planning_bank_deg`).
    l1_period: float = L1_REFERENCE[0]
    l1_damping: float = L1_REFERENCE[1]

    @property
    @abstractmethod
    def time(self) -> float: ...

    @abstractmethod
    def pose(self) -> VehiclePose: ...

    @abstractmethod
    def arm(self) -> None: ...

    @abstractmethod
    def takeoff(self, alt: float) -> None: ...

    @abstractmethod
    def goto(self, x: float, y: float, alt: float | None = None,
             radius: float | None = None) -> None: ...

    @abstractmethod
    def steer(self, course: float) -> None: ...

    @abstractmethod
    def rtl(self) -> None: ...

    @abstractmethod
    def land(self) -> None: ...

    @abstractmethod
    def loiter(self, x: float | None = None, y: float | None = None,
               radius: float | None = None) -> None: ...

    @abstractmethod
    def advance(self, dt: float) -> None: ...

    @abstractmethod
    def poll_events(self) -> list[VehicleEvent]: ...

    @property
    def link_ok(self) -> bool:
        return True

    @property
    def hands_off(self) -> bool:
        """True once somebody else is in charge (see :data:`HANDS_OFF`): no commands go out."""
        return False

    @property
    def loiter_radius(self) -> float:
        return 80.0

    @property
    def flying(self) -> bool:
        """Armed and in the air (an ``airborne`` start needs it)."""
        return False

    def prepare(self, start: Start) -> Start:
        """Get ready for a mission (wait for the autopilot, GPS, home, pre-arm checks); returns
        how the mission starts (``ground`` or ``airborne``).  Raises :class:`VehicleError`."""
        if start is Start.AIRBORNE and not self.flying:
            raise VehicleError("--start airborne, but the vehicle is not flying")
        if start is Start.AUTO:
            return Start.AIRBORNE if self.flying else Start.GROUND
        return start

    def disarm(self) -> None:  # noqa: B027 - optional hook
        """Disarm (only ever sent on the ground)."""

    def take_control(self) -> None:  # noqa: B027 - optional hook
        """An airborne start: put the vehicle in the mode the runtime commands in."""

    def settle(self, timeout: float = 3.0) -> str:
        """After a safe command: wait up to ``timeout`` wall seconds for the vehicle to confirm
        it; returns a one-line status for the log."""
        return "ok"

    @property
    def is_simulated(self) -> bool:
        """True when time only passes through :meth:`advance` (compute time must be charged)."""
        return False

    def close(self) -> None:  # noqa: B027 - optional hook
        """Release links/threads (no-op by default)."""


def wrap_pi(a: float) -> float:
    """Angle to (-pi, pi]."""
    a = math.fmod(a + math.pi, 2 * math.pi)
    if a <= 0:
        a += 2 * math.pi
    return a - math.pi
