"""Built-in kinematic fixed-wing simulator: a stand-in for ArduPlane in GUIDED.

Model (see ``docs/runtime.md`` and the project's UAV research notes, section 4.2):

* state: east/north position, altitude, air heading ``psi``, bank ``phi``;
* true airspeed ``V`` constant in straight flight (optionally faster in banked turns:
  ``turn_speedup``); ground velocity = V (cos psi, sin psi) + wind;
* turn rate ``psi' = eta * g tan(phi) / V`` (``eta`` = turn efficiency, 1 = ideal);
* bank follows the commanded bank with a first-order lag ``bank_tau`` and a roll-rate limit,
  clipped to ``bank_limit``;
* guidance copies ArduPlane's L1 loiter law for fly-to points: pursuit of the target with
  lateral acceleration ``4 zeta^2 V^2 sin(nu) / L1`` (``L1 = zeta P V / pi``) until the loiter
  capture, then a PD law on the circle radius plus the centripetal term; ``reached`` fires at the
  capture, like ArduPlane's MISSION_ITEM_REACHED in GUIDED;
* ``steer(course)``: course hold (ArduPlane GUIDED_CHANGE_HEADING) with a proportional law.

Deterministic: optional gusts come from a seeded generator; no wall-clock anywhere.  A pure-Python
step costs ~10 us, i.e. thousands of times faster than real time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from iterplan_compiler.runtime.vehicle import (
    G,
    Vehicle,
    VehicleEvent,
    VehiclePose,
    turn_radius,
    wrap_pi,
)


@dataclass(frozen=True)
class SimParams:
    """Tunable model constants (defaults ~ the paper's UAV: 17 m/s EAS ~ 18.2 m/s TAS)."""

    airspeed: float = 18.2
    #: The true airspeed flown is ``speed_factor x airspeed`` in straight flight, plus
    #: ``turn_speedup x (n - 1) / airspeed`` in a turn at load factor ``n = 1 / cos(bank)``:
    #: ``airspeed`` is what the runtime plans with (like the MAVLink vehicle's model from
    #: AIRSPEED_CRUISE), the rest what the aircraft really does (:data:`SITL_SPEED_FACTOR`,
    #: :data:`SITL_TURN_SPEEDUP`).
    speed_factor: float = 1.0
    turn_speedup: float = 0.0     # m^2/s^2
    bank_limit_deg: float = 45.0
    bank_tau: float = 0.5
    roll_rate_deg: float = 90.0
    turn_efficiency: float = 1.0
    l1_period: float = 15.0
    l1_damping: float = 0.75
    loiter_radius: float = 80.0
    course_gain: float = 1.0      # commanded turn rate per radian of course error (1/s)
    climb_rate: float = 3.0
    sink_rate: float = 2.0
    step: float = 0.05            # integration step (s)
    wind_east: float = 0.0
    wind_north: float = 0.0
    gust_std: float = 0.0         # m/s, white-ish gusts (seeded)
    seed: int = 0

    def flown_airspeed(self, bank: float = 0.0) -> float:
        """The true airspeed flown (m/s) at ``bank`` (radians)."""
        v = self.airspeed * self.speed_factor
        if self.turn_speedup:
            v += self.turn_speedup * (1.0 / max(math.cos(bank), 0.05) - 1.0) / self.airspeed
        return v

    @property
    def min_turn_radius(self) -> float:
        phi = math.radians(self.bank_limit_deg)
        return self.flown_airspeed(phi) ** 2 / (G * math.tan(phi) * self.turn_efficiency)

    @classmethod
    def from_arduplane(cls, params: dict[str, float], *, home_amsl: float = 584.0,
                       altitude: float = 60.0, **overrides: float) -> SimParams:
        """The simulator calibrated to ArduPlane SITL's plane model with these parameters
        (AIRSPEED_CRUISE, ROLL_LIMIT_DEG, WP_LOITER_RAD, NAVL1_PERIOD, NAVL1_DAMPING,
        RLL2SRV_TCONST, RLL2SRV_RMAX; missing ones take the SITL plane.parm values).
        ``airspeed`` (what the runtime plans with) is AIRSPEED_CRUISE x EAS2TAS, as the MAVLink
        vehicle derives it, so both plan the same Dubins radius.  Calibration (the ``SITL_*``
        constants below; ``benchmarks/sitl_vs_sim.py``, docs/sitl-calibration.md): SITL's
        plane flies :data:`SITL_SPEED_FACTOR` faster than that in straight flight and faster
        still in banked turns (:data:`SITL_TURN_SPEEDUP`), turns at
        :data:`SITL_TURN_EFFICIENCY` of the ideal ``g tan(bank) / V`` rate, and ends its
        take-off climb :data:`SITL_TAKEOFF_GRADIENT` (altitude / distance) from the start.
        An explicit ``airspeed`` override is the speed flown (no speed calibration)."""
        from iterplan_compiler.runtime.vehicle import cruise_true_airspeed

        def get(name: str, default: float) -> float:
            return float(params.get(name, default))

        tas = cruise_true_airspeed(get("AIRSPEED_CRUISE", 22.0), home_amsl + altitude)
        kw: dict[str, float] = {
            # Plan with what the MAVLink vehicle's model says (same Dubins radius on both), fly
            # what SITL flies.
            "airspeed": tas,
            "speed_factor": SITL_SPEED_FACTOR,
            "turn_speedup": SITL_TURN_SPEEDUP,
            "bank_limit_deg": get("ROLL_LIMIT_DEG", 65.0),
            "roll_rate_deg": get("RLL2SRV_RMAX", 90.0) or 90.0,
            "loiter_radius": abs(get("WP_LOITER_RAD", 80.0)),
            "l1_period": get("NAVL1_PERIOD", 15.0),
            "l1_damping": get("NAVL1_DAMPING", 0.75),
            "bank_tau": get("RLL2SRV_TCONST", 0.25),
            "turn_efficiency": SITL_TURN_EFFICIENCY,
            "climb_rate": SITL_TAKEOFF_GRADIENT * tas * SITL_SPEED_FACTOR,
        }
        if "airspeed" in overrides:          # an explicit airspeed is the speed flown
            kw["speed_factor"], kw["turn_speedup"] = 1.0, 0.0
        kw.update(overrides)
        return cls(**kw)  # type: ignore[arg-type]


#: Calibration against ArduPlane SITL 4.6 (``benchmarks/sitl_vs_sim.py``,
#: docs/sitl-calibration.md), fitted to SITL's own dataflash logs (EKF velocity, roll, 25 Hz)
#: of the benchmark's missions.  Speed: ground speed / (AIRSPEED_CRUISE x EAS2TAS) =
#: 1.015 + 33 m^2/s^2 x (n - 1) / TAS^2 at load factor n = 1 / cos(bank), the same law at 22
#: and at 17 m/s cruise: 1.5 % faster straight, 4-6 % faster at 45-55 deg bank, ~3 % faster
#: on average over a mission (the median ground speed the MAVLink summaries report).
SITL_SPEED_FACTOR = 1.015
SITL_TURN_SPEEDUP = 33.0
#: Achieved / ideal ``g tan(bank) / V`` turn rate: SITL's aircraft turns wider than its bank
#: says.  0.72 is the value with which the simulator, fed the commands SITL was given, stays
#: closest to SITL's track (median 0.9 m, 90th percentile 2.5 m after 10 s, 206 windows in
#: 5 missions; 0.75 doubles that), consistent with 0.74-0.77 from the turn rate vs bank.
SITL_TURN_EFFICIENCY = 0.72
#: Climb gradient (m of altitude per m over ground): the simulator climbs at cruise speed from
#: the start; SITL's TAKEOFF (ground roll, then the climb at the pitch limit) reaches 60 m
#: ~190 m from the start (in ~10 s) at both cruise speeds, which is where the mission's first
#: leg, and with it the visiting order, begins.
SITL_TAKEOFF_GRADIENT = 60.0 / 190.0


class SimVehicle(Vehicle):
    """The kinematic simulator behind the :class:`Vehicle` API."""

    def __init__(self, params: SimParams | None = None, home: tuple[float, float] = (0.0, 0.0),
                 heading: float = math.pi / 2):
        self.p = params or SimParams()
        self.airspeed = self.p.airspeed
        # What the autopilot may command (planning speed, bank limit), as the MAVLink
        # vehicle's model says: both then plan the same Dubins radius.  The turn actually
        # flown (``SimParams.min_turn_radius``: calibrated speed and turn efficiency) is wider;
        # the planning margin covers that (vehicle.planning_radius).
        self.min_turn_radius = turn_radius(self.p.airspeed, self.p.bank_limit_deg)
        self.l1_period, self.l1_damping = self.p.l1_period, self.p.l1_damping
        self.home = (float(home[0]), float(home[1]))
        self._rng = np.random.default_rng(self.p.seed)
        self._t = 0.0
        self.x, self.y = self.home
        self.alt = 0.0
        self.psi = heading
        self.phi = 0.0
        self.armed = False
        self.mode = "IDLE"         # IDLE, TAKEOFF, GUIDED, COURSE, RTL, LAND, LANDED
        self.target: tuple[float, float] = self.home
        self.target_alt = 0.0
        self.radius = self.p.loiter_radius
        self.captured = False
        self.course_cmd = heading
        self._events: list[VehicleEvent] = []
        self._gust = (0.0, 0.0)
        self.distance_flown = 0.0

    # -- Vehicle API ------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self._t

    @property
    def is_simulated(self) -> bool:
        return True

    def pose(self) -> VehiclePose:
        vx, vy = self._ground_velocity()
        return VehiclePose(self._t, self.x, self.y, self.alt, math.atan2(vy, vx),
                           math.hypot(vx, vy))

    def arm(self) -> None:
        self.armed = True
        self._emit("armed")

    def disarm(self) -> None:
        if self.mode in ("IDLE", "LANDED"):
            self.armed = False

    def takeoff(self, alt: float) -> None:
        if not self.armed:
            self._emit("rejected", "takeoff: not armed")
            return
        self.mode = "TAKEOFF"
        self.target_alt = float(alt)
        self.course_cmd = self.psi

    def goto(self, x, y, alt=None, radius=None) -> None:
        # Allowed during the take-off climb (GUIDED takes over; the climb continues).
        if self.mode in ("IDLE", "LANDED"):
            self._emit("rejected", f"goto refused in mode {self.mode}")
            return
        self.mode = "GUIDED"
        self.target = (float(x), float(y))
        if alt is not None:
            self.target_alt = float(alt)
        self.radius = float(radius) if radius else self.p.loiter_radius
        self.captured = False

    def steer(self, course: float) -> None:
        if self.mode in ("IDLE", "LANDED"):
            self._emit("rejected", f"steer refused in mode {self.mode}")
            return
        self.mode = "COURSE"
        self.course_cmd = float(course)

    def rtl(self) -> None:
        if self.mode in ("IDLE", "LANDED"):
            return
        self.mode = "RTL"
        self.target = self.home
        self.radius = self.p.loiter_radius
        self.captured = False

    def land(self) -> None:
        if self.mode in ("IDLE", "LANDED"):
            return
        self.mode = "LAND"
        self.target = self.home
        self.radius = self.p.loiter_radius
        self.captured = False

    def loiter(self, x: float | None = None, y: float | None = None,
               radius: float | None = None) -> None:
        if self.mode in ("IDLE", "LANDED"):
            return
        r = float(radius) if radius else self.p.loiter_radius
        self.mode = "GUIDED"
        self.radius = r
        if x is None or y is None:
            # Circle a point one radius to the right of the current track.
            self.target = (self.x + r * math.sin(self.psi), self.y - r * math.cos(self.psi))
            self.captured = True
        else:
            self.target = (float(x), float(y))
            self.captured = False

    @property
    def loiter_radius(self) -> float:
        return self.p.loiter_radius

    def settle(self, timeout: float = 3.0) -> str:
        return f"vehicle in {self.mode}"

    @property
    def bank_limit_deg(self) -> float:
        return self.p.bank_limit_deg

    @property
    def flying(self) -> bool:
        return self.armed and self.mode not in ("IDLE", "LANDED") and self.alt > 5.0

    def advance(self, dt: float) -> None:
        """Integrate ``dt`` seconds (any non-negative value; the last step is shortened)."""
        remaining = float(dt)
        h = self.p.step
        while remaining > 1e-12:
            step = h if remaining > h else remaining
            self._step(step)
            remaining -= step

    def poll_events(self) -> list[VehicleEvent]:
        ev, self._events = self._events, []
        return ev

    # -- model ------------------------------------------------------------------------------
    def _emit(self, kind: str, detail: str = "") -> None:
        self._events.append(VehicleEvent(self._t, kind, detail))

    def _ground_velocity(self) -> tuple[float, float]:
        if self.mode in ("IDLE", "LANDED"):
            return 0.0, 0.0
        V = self.p.flown_airspeed(self.phi)
        return (V * math.cos(self.psi) + self.p.wind_east + self._gust[0],
                V * math.sin(self.psi) + self.p.wind_north + self._gust[1])

    def _lateral_accel(self) -> float:
        """Commanded lateral acceleration (m/s^2, positive = turn left)."""
        V = self.p.flown_airspeed(self.phi)
        vx, vy = self._ground_velocity()
        gs = max(math.hypot(vx, vy), 1.0)
        course = math.atan2(vy, vx)
        if self.mode in ("COURSE", "TAKEOFF"):
            err = wrap_pi(self.course_cmd - course)
            return V * self.p.course_gain * err
        # Fly-to / loiter (GUIDED, RTL, LAND): ArduPlane's L1 loiter law, simplified.
        tx, ty = self.target
        dx, dy = tx - self.x, ty - self.y
        dist = math.hypot(dx, dy)
        zeta = self.p.l1_damping
        l1 = max(zeta * self.p.l1_period * gs / math.pi, 1.0)
        nu = wrap_pi(math.atan2(dy, dx) - course)
        nu = max(-math.pi / 2, min(math.pi / 2, nu))
        capture = 4 * zeta * zeta * gs * gs / l1 * math.sin(nu)
        R = self.radius
        # Circle regime (clockwise, ArduPlane's default): PD on the radial error + centripetal.
        omega = 2 * math.pi / self.p.l1_period
        radial_v = -(vx * dx + vy * dy) / max(dist, 1e-6)   # rate of change of dist
        circle = -(gs * gs / max(R / 2, dist) + omega * omega * (dist - R)
                   + 2 * zeta * omega * radial_v)
        # Sign: for a clockwise circle the demand turns right (negative), pulled in by the PD.
        if not self.captured:
            if dist < R or (abs(circle) > abs(capture) and dist < R + l1):
                self.captured = True
                if self.mode in ("GUIDED", "RTL"):
                    self._emit("reached", f"{dist:.0f} m from target")
            else:
                return capture
        return circle

    def _step(self, h: float) -> None:
        if self.mode in ("IDLE", "LANDED"):
            self._t += h
            return
        p = self.p
        if p.gust_std > 0:
            # First-order filtered noise keeps gusts smooth and reproducible from the seed.
            a = min(h / 2.0, 1.0)
            gx, gy = self._rng.normal(0.0, p.gust_std, 2)
            self._gust = (self._gust[0] + a * (gx - self._gust[0]),
                          self._gust[1] + a * (gy - self._gust[1]))
        acc = self._lateral_accel()
        phi_lim = math.radians(p.bank_limit_deg)
        phi_cmd = max(-phi_lim, min(phi_lim, math.atan2(acc, G)))
        rate = (phi_cmd - self.phi) / max(p.bank_tau, h)
        rmax = math.radians(p.roll_rate_deg)
        self.phi += max(-rmax, min(rmax, rate)) * h
        self.psi = wrap_pi(self.psi + p.turn_efficiency * G * math.tan(self.phi)
                           / self.p.flown_airspeed(self.phi) * h)
        vx, vy = self._ground_velocity()
        self.x += vx * h
        self.y += vy * h
        self.distance_flown += math.hypot(vx, vy) * h
        if self.mode == "TAKEOFF":
            self.alt = min(self.target_alt, self.alt + p.climb_rate * h)
            if self.alt >= self.target_alt - 1e-9:
                # Like ArduPlane's TAKEOFF mode: climb done, loiter ahead of the aircraft.
                self.mode = "GUIDED"
                r = p.loiter_radius
                self.target = (self.x + r * math.sin(self.psi), self.y - r * math.cos(self.psi))
                self.radius = r
                self.captured = True
                self._emit("takeoff_complete", f"alt {self.alt:.0f} m")
        elif self.mode == "LAND":
            if math.hypot(self.x - self.home[0], self.y - self.home[1]) < 2 * p.loiter_radius:
                self.alt = max(0.0, self.alt - p.sink_rate * h)
                if self.alt <= 0.0:
                    self.mode = "LANDED"
                    self.armed = False
                    self._emit("landed")
        elif self.alt < self.target_alt:
            self.alt = min(self.target_alt, self.alt + p.climb_rate * h)
        self._t += h
