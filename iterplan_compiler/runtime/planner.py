"""Motion planner: the paper's scheme (§V-A "Motion planning and iterator sorting").

For ``go(target)`` the planner computes the shortest path made of a turn at the planning radius,
a straight segment and a turn (CSC: "at most two turns") from the vehicle's current pose to the
target, arriving *parallel to a fixed direction* (the arrival heading or its opposite, whichever
is shorter; or exactly the arrival heading when ``parallel=False``).  The same geometry is what
the Sorter ranks locations by.

Following: the path is sampled every ``ds`` metres and extended straight beyond the target along
the arrival heading.  Each :meth:`MotionPlanner.update` projects the vehicle onto the path and
commands either a course towards a point ``lookahead`` metres further on (``PlannerMode.COURSE``:
ArduPlane GUIDED_CHANGE_HEADING / the simulator's course hold), or a GUIDED fly-to "carrot" far
placed ``carrot_distance`` metres out along that same pursuit course, far enough that the
autopilot never reaches its loiter capture (``PlannerMode.CARROT``: plain MISSION_ITEM_INT fly-to).

Visiting: a fixed wing never stops, and ArduPlane's own "reached" fires 100+ m out, so the
planner decides: the target counts as visited (``arrived``) once the vehicle is within
``lead`` metres *before* the target's finish line (the line through the cell centre perpendicular
to the arrival heading) and within ``accept`` metres of the path's final line (cross-track).
Defaults keep the vehicle inside the cell (``lead`` = 0.25 cell, ``accept`` = 0.45 cell: over the
cell with a 2.5 m margin).  After arrival the vehicle keeps flying straight on the extension, so
the next ``go`` is handed over while flying through the cell.

Re-approach: if the vehicle crosses the finish line outside the corridor the target was missed
(counted in :attr:`misses`) and the planner replans from where it is with a straight *lead-in*
of ``k`` turn radii before the target on the k-th miss (up to ``max_lead`` radii): a longer
straight gives the autopilot's path following time to settle onto the line, so the cross-track
error at the finish line shrinks with every pass (measured on ArduPlane SITL: a second pass
always suffices with the default radius).  Only after ``max_misses`` passes does it report
``stuck``.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from iterplan_compiler.runtime.sorter import Pose
from iterplan_compiler.runtime.vehicle import Vehicle

TWO_PI = 2 * math.pi


def _m(a: float) -> float:
    a = math.fmod(a, TWO_PI)
    if a < 0:
        a += TWO_PI
    return 0.0 if a > TWO_PI - 1e-9 else a


class PlannerMode(enum.Enum):
    """How the planner follows its path (``iterc run --planner``)."""

    COURSE = "course"   # course hold towards the look-ahead point (the simulator's default)
    CARROT = "carrot"   # GUIDED fly-to points far out along that course (MAVLink's default)


class ArrivalHeadings(enum.Enum):
    """Which arrival headings are admissible at a location."""

    PARALLEL = "parallel"   # the paper's: parallel to the map's fixed direction (either way)
    GRID = "grid"           # along either grid axis, either way (4 headings)


class HeadingChoice(enum.Enum):
    """How the planner picks one of the admissible arrival headings for a leg."""

    SHORTEST = "shortest"     # the paper's: the shortest path to the target
    LOOKAHEAD = "lookahead"   # shortest to the target plus the next leg (to the location
    #                           the Iterator offers next): favours flying on straight
    REPEAT = "repeat"         # LOOKAHEAD to the location that followed this one the last
    #                           time the mission went there (patrols); SHORTEST before that
    PREDICT = "predict"       # REPEAT, with the locations a shadow run of the plan predicts
    #                           before the mission has repeated (runtime/shadow.py)


def admissible_headings(arrival_heading: float, parallel: bool,
                        mode: ArrivalHeadings = ArrivalHeadings.PARALLEL) -> tuple[float, ...]:
    """The arrival headings ``mode`` allows (``parallel=False``: exactly the fixed one)."""
    h = arrival_heading
    if mode is ArrivalHeadings.GRID:
        return (h, h + math.pi, h + math.pi / 2, h - math.pi / 2)
    return (h, h + math.pi) if parallel else (h,)


@dataclass(frozen=True)
class DubinsPath:
    """A CSC path: ``word`` like ``"LSR"``, segment lengths in metres (arc lengths for turns)."""

    start: Pose
    word: str
    segments: tuple[float, float, float]
    radius: float

    @property
    def length(self) -> float:
        return sum(self.segments)

    @property
    def end_heading(self) -> float:
        h = self.start.heading
        for seg, ln in zip(self.word, self.segments, strict=False):
            if seg == "L":
                h += ln / self.radius
            elif seg == "R":
                h -= ln / self.radius
        return h

    def sample(self, ds: float = 2.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Points every ~``ds`` metres (x, y, heading), start and end included."""
        xs, ys, hs = [self.start.x], [self.start.y], [self.start.heading]
        x, y, h = self.start.x, self.start.y, self.start.heading
        r = self.radius
        for seg, ln in zip(self.word, self.segments, strict=False):
            if ln <= 1e-9:
                continue
            n = max(1, math.ceil(ln / ds))
            s = np.linspace(ln / n, ln, n)
            if seg == "S":
                px = x + s * math.cos(h)
                py = y + s * math.sin(h)
                ph = np.full(n, h)
            else:
                sgn = 1.0 if seg == "L" else -1.0
                cx, cy = x - sgn * r * math.sin(h), y + sgn * r * math.cos(h)
                ph = h + sgn * s / r
                px = cx + sgn * r * np.sin(ph)
                py = cy - sgn * r * np.cos(ph)
            xs.extend(px)
            ys.extend(py)
            hs.extend(ph)
            x, y, h = float(px[-1]), float(py[-1]), float(ph[-1])
        return np.asarray(xs), np.asarray(ys), np.asarray(hs)


def shortest_csc(start: Pose, x: float, y: float, heading: float, radius: float) -> DubinsPath:
    """Shortest CSC path (float64, scalar) from ``start`` to ``(x, y)`` arriving with
    ``heading``.  Same circle-tangent geometry as the vectorised Sorter kernel."""
    r = radius
    c0, s0 = math.cos(start.heading), math.sin(start.heading)
    c1, s1 = math.cos(heading), math.sin(heading)
    starts = {"L": (start.x - r * s0, start.y + r * c0), "R": (start.x + r * s0, start.y - r * c0)}
    goals = {"L": (x - r * s1, y + r * c1), "R": (x + r * s1, y - r * c1)}
    best: DubinsPath | None = None
    for a in "LR":
        for b in "LR":
            (ax, ay), (bx, by) = starts[a], goals[b]
            dx, dy = bx - ax, by - ay
            d2 = dx * dx + dy * dy
            if a == b:
                straight = math.sqrt(d2)
                psi = math.atan2(dy, dx)
            else:
                if d2 < 4 * r * r:
                    continue
                straight = math.sqrt(d2 - 4 * r * r)
                sgn = 1.0 if a == "L" else -1.0      # LSR: +atan2(2r, L); RSL: -atan2(2r, L)
                psi = math.atan2(dy, dx) + sgn * math.atan2(2 * r, straight)
            t1 = _m(psi - start.heading) if a == "L" else _m(start.heading - psi)
            t2 = _m(heading - psi) if b == "L" else _m(psi - heading)
            cand = DubinsPath(start, f"{a}S{b}", (t1 * r, straight, t2 * r), r)
            if best is None or cand.length < best.length:
                best = cand
    assert best is not None  # LSL and RSR always exist
    return best


class PlannerEventKind(enum.Enum):
    """What :meth:`MotionPlanner.update` reports (the value is what the event log says)."""

    ARRIVED = "arrived"    # crossed the target's finish line within the acceptance width
    MISSED = "missed"      # crossed it outside: replanned
    STUCK = "stuck"        # missed too often: the mission cannot go on


@dataclass
class PlannerEvent:
    kind: PlannerEventKind
    t: float
    target: tuple[float, float]
    detail: str = ""


class MotionPlanner:
    """Plans and follows CSC paths on a :class:`Vehicle`; see the module docstring."""

    def __init__(self, vehicle: Vehicle, *, radius: float, arrival_heading: float,
                 parallel: bool = True, cell_size: float = 50.0, lead: float | None = None,
                 accept: float | None = None, lookahead: float | None = None,
                 mode: PlannerMode = PlannerMode.COURSE, ds: float = 2.0,
                 max_misses: int = 12,
                 carrot_distance: float = 400.0, max_lead: float = 4.0,
                 headings: ArrivalHeadings = ArrivalHeadings.PARALLEL,
                 choice: HeadingChoice = HeadingChoice.SHORTEST):
        if not isinstance(mode, PlannerMode):
            raise TypeError(f"planner mode must be a PlannerMode, not {mode!r}")
        self.admissible = admissible_headings(arrival_heading, parallel, headings)
        self.choice = choice
        self._fixed: tuple[float, ...] | None = None   # the heading chosen for this target
        self.vehicle = vehicle
        self.radius = float(radius)
        self.arrival_heading = float(arrival_heading)
        self.parallel = parallel
        self.lead = 0.25 * cell_size if lead is None else float(lead)
        self.accept = 0.45 * cell_size if accept is None else float(accept)
        self.max_lead = float(max_lead)
        self.lookahead = 0.6 * self.radius if lookahead is None else float(lookahead)
        self.carrot_distance = float(carrot_distance)
        self.mode = mode
        self.ds = ds
        self.max_misses = max_misses
        self.target: tuple[float, float] | None = None
        self.heading: float = arrival_heading
        self.path: DubinsPath | None = None
        self._px = self._py = self._ph = np.zeros(0)
        self._idx = 0
        self._end = 0            # index of the target sample
        self.arrived = True      # no active target
        self.misses = 0
        self._target_misses = 0
        self.planned_length = 0.0
        self.last_cmd: tuple[str, float, float] | None = None

    # -- planning -----------------------------------------------------------------------------
    def path_to(self, start: Pose, x: float, y: float,
                headings: Sequence[float] | None = None) -> DubinsPath:
        """Shortest admissible path (the first of equally long ones: the arrival heading
        before its opposite); ``headings``: the arrival headings to choose from (default: the
        current leg's, which a fixed heading may narrow)."""
        best: DubinsPath | None = None
        for h in (self._headings() if headings is None else headings):
            cand = shortest_csc(start, x, y, h, self.radius)
            if best is None or cand.length < best.length - 1e-9:
                best = cand
        assert best is not None
        return best

    def go(self, x: float, y: float, then: tuple[float, float] | None = None,
           heading: float | None = None, chain: Sequence[tuple[float, float]] = (),
           closes: bool = False) -> Pose:
        """Start flying to ``(x, y)``; returns the predicted arrival pose (for the Sorter).
        ``then``: the location expected next (``HeadingChoice.LOOKAHEAD`` picks the arrival
        heading that minimises this leg plus the next one); ``heading``: an arrival heading
        planned by the Sorter (``tour``), taken as it is under ``LOOKAHEAD``; ``chain``: the
        locations expected after this one (``REPEAT``, ``PREDICT``: the heading minimising the
        legs through them, and back here if ``closes``)."""
        self.target = (float(x), float(y))
        self._target_misses = 0
        self._fixed = None
        if heading is not None and self.choice is HeadingChoice.LOOKAHEAD:
            self._fixed = (float(heading),)
        elif then is not None and self.choice is HeadingChoice.LOOKAHEAD:
            self._fixed = (self._best_heading(x, y, (then,), closes=False),)
        elif chain and self.choice in (HeadingChoice.REPEAT, HeadingChoice.PREDICT):
            self._fixed = (self._best_heading(x, y, chain, closes=closes),)
        self._plan()
        return Pose(x, y, self.heading)

    def _best_heading(self, x: float, y: float, chain: Sequence[tuple[float, float]],
                      closes: bool) -> float:
        """The admissible arrival heading at ``(x, y)`` that minimises this leg plus the legs
        through ``chain`` (and back to ``(x, y)`` if ``closes``: a patrol cycle), each arrival
        heading admissible: a dynamic programme over the headings along the chain."""
        p = self.vehicle.pose()
        start = Pose(p.x, p.y, p.course)
        hs = self.admissible

        def csc(a: tuple[float, float], ha: float, b: tuple[float, float], hb: float) -> float:
            return shortest_csc(Pose(a[0], a[1], ha), b[0], b[1], hb, self.radius).length

        def onward(h: float) -> float:
            best = {h: 0.0}
            here = (x, y)
            for point in chain:
                best = {h2: min(c + csc(here, h1, point, h2) for h1, c in best.items())
                        for h2 in hs}
                here = point
            if closes:
                return min(c + csc(here, h1, (x, y), h) for h1, c in best.items())
            return min(best.values())

        return min(hs, key=lambda h: shortest_csc(start, x, y, h, self.radius).length
                   + onward(h))

    def _plan(self) -> None:
        assert self.target is not None
        p = self.vehicle.pose()
        start = Pose(p.x, p.y, p.course)
        tx, ty = self.target
        # Lead-in after misses: plan to a point k radii before the target, then straight on.
        lead_in = min(self._target_misses, self.max_lead) * self.radius
        if lead_in > 0:
            self.path = min((self._lead_in_path(start, h, lead_in) for h in self._headings()),
                            key=lambda path: path.length)
        else:
            self.path = self.path_to(start, tx, ty)
        self.heading = self.path.end_heading
        self.planned_length += self.path.length + lead_in
        xs, ys, hs = self.path.sample(self.ds)
        # Straight beyond the path's end: through the target (after a lead-in) and on, where the
        # vehicle flies while the plan thinks.
        c, s = math.cos(self.heading), math.sin(self.heading)
        ext = np.arange(1, int((2000 + lead_in) / self.ds) + 1) * self.ds
        self._end = len(xs) - 1 + int(round(lead_in / self.ds))
        self._px = np.concatenate([xs, xs[-1] + ext * c])
        self._py = np.concatenate([ys, ys[-1] + ext * s])
        self._ph = np.concatenate([hs, np.full(len(ext), self.heading)])
        self._idx = 0
        self.arrived = False

    def _headings(self) -> tuple[float, ...]:
        return self._fixed if self._fixed is not None else self.admissible

    def _lead_in_path(self, start: Pose, heading: float, lead_in: float) -> DubinsPath:
        assert self.target is not None
        tx, ty = self.target
        return shortest_csc(start, tx - lead_in * math.cos(heading),
                            ty - lead_in * math.sin(heading), heading, self.radius)

    def stop(self) -> None:
        """Stop following (before land/RTL/loiter, so no further steering overrides them)."""
        self.path = None
        self.target = None
        self.arrived = True

    # -- following ------------------------------------------------------------------------------
    def update(self) -> list[PlannerEvent]:
        """Command the vehicle for its current pose; report arrival/miss events."""
        if self.path is None:
            return []
        p = self.vehicle.pose()
        events: list[PlannerEvent] = []
        # Project onto the path, searching forward from the last index (paths never loop back
        # onto themselves within a short window, so a local search is unambiguous).
        lo = self._idx
        hi = min(len(self._px), lo + int(4 * self.radius / self.ds) + 50)
        d2 = (self._px[lo:hi] - p.x) ** 2 + (self._py[lo:hi] - p.y) ** 2
        self._idx = lo + int(np.argmin(d2))
        if self._idx >= len(self._px) - 10:
            # Ran off the extension (long think time): extend by replanning straight ahead.
            self._extend_from(p)
        near_end = self._idx >= self._end - int((self.lead + 4 * self.ds) / self.ds)
        if not self.arrived and self.target is not None and near_end:
            # Only judge the finish line on the path's final stretch: early on, a looping path
            # can put the vehicle geometrically "beyond" the line without having been there.
            tx, ty = self.target
            c, s = math.cos(self.heading), math.sin(self.heading)
            along = (p.x - tx) * c + (p.y - ty) * s        # < 0 before the finish line
            cross = -(p.x - tx) * s + (p.y - ty) * c
            if along >= -self.lead:
                if abs(cross) <= self.accept:
                    self.arrived = True
                    events.append(PlannerEvent(PlannerEventKind.ARRIVED, p.t, self.target,
                                               f"cross-track {cross:+.1f} m"))
                elif along >= 0:
                    self.misses += 1
                    self._target_misses += 1
                    kind = (PlannerEventKind.STUCK if self._target_misses > self.max_misses
                            else PlannerEventKind.MISSED)
                    events.append(PlannerEvent(kind, p.t, self.target,
                                               f"cross-track {cross:+.1f} m"))
                    if kind is PlannerEventKind.MISSED:
                        self._plan()
                        return events + self.update()
        self._command(p)
        return events

    def _extend_from(self, p) -> None:
        ext = np.arange(0, int(2000 / self.ds) + 1) * self.ds
        c, s = math.cos(self.heading), math.sin(self.heading)
        bx, by = self._px[self._idx], self._py[self._idx]
        self._px = np.concatenate([self._px[:self._idx], bx + ext * c])
        self._py = np.concatenate([self._py[:self._idx], by + ext * s])
        self._ph = np.concatenate([self._ph[:self._idx], np.full(len(ext), self.heading)])

    def _command(self, p) -> None:
        k = min(self._idx + max(1, int(self.lookahead / self.ds)), len(self._px) - 1)
        cx, cy = float(self._px[k]), float(self._py[k])
        course = math.atan2(cy - p.y, cx - p.x)   # pure pursuit of the look-ahead point
        if self.mode is PlannerMode.COURSE:
            self.last_cmd = ("course", course, 0.0)
            self.vehicle.steer(course)
        else:
            # A fly-to point far out along the pursuit course: the autopilot's L1 capture law
            # then steers that course without ever reaching its loiter capture.
            gx = p.x + self.carrot_distance * math.cos(course)
            gy = p.y + self.carrot_distance * math.sin(course)
            self.last_cmd = ("goto", gx, gy)
            self.vehicle.goto(gx, gy)
