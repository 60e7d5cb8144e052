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
``rtl()``, ``land()``, ``loiter()``
    Return home and circle / land at home (``landed``) / circle where it is.
``advance(dt)``
    Let ``dt`` seconds of vehicle time pass (simulated, or by listening to the link).

Events: ``armed``, ``takeoff_complete``, ``reached``, ``landed``, ``link_lost``,
``link_restored``, ``rejected`` (a command was refused), ``message`` (status text).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass


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
    def loiter(self) -> None: ...

    @abstractmethod
    def advance(self, dt: float) -> None: ...

    @abstractmethod
    def poll_events(self) -> list[VehicleEvent]: ...

    @property
    def link_ok(self) -> bool:
        return True

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
