"""Shadow run: predict the next ``go.next`` targets of the plan before the mission flies them
(``HeadingChoice.PREDICT``).

The plan's visiting order is in the controller; the hybrid layer only sees it one ``go.next``
at a time.  ``REPEAT`` learns a patrol's loop by watching, so its first loop is flown without
knowing what comes next.  At a ``go.next`` decision a :class:`Shadow` instead runs a copy of the
controller (its state only: the table is immutable) on a fork of the Iterator
(:meth:`Iterator.fork`) ahead of the real one, exactly as the executor would step it — the first
enabled controllable label, ``has.next`` answered from the fork, ``remove.next``/``reset`` on the
fork, a next-location sensor on a *static* map sensor answered from its mask, the skip cycles in
one vectorised pass (``runtime/skip.py``), ``go.next`` answered ``arrived`` at once with the
fork re-sorted from the predicted arrival pose — and records the targets it flies to.

It stops at what it cannot predict honestly (:class:`ShadowStop`): a sensor whose answers are
not a static mask (a dynamic or derived map sensor, a user's sensor), a sensor about the current
location, an action with an effect (take-off, landing, photo, a user's binding), an answer the
environment gives on its own, or a step budget.  Nothing of the real mission is touched: the
controller, Iterator, bindings' state, vehicle and log are only read, so the controller-observable
events of a mission are those it would have without the shadow (``tests/runtime/test_shadow.py``).
The caller charges the shadow's think time to the mission clock like any other computation.
"""

from __future__ import annotations

import enum
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from iterplan_compiler.runtime.bindings import Binding, BindingKind
from iterplan_compiler.runtime.controller import ControllerTable
from iterplan_compiler.runtime.iterator import Iterator
from iterplan_compiler.runtime.skip import Cycle, Sensors, fast_skip
from iterplan_compiler.runtime.sorter import Pose

#: The predicted arrival pose at a cell, flying from a pose.
ArrivalModel = Callable[[Pose, int], Pose]


class ShadowStop(enum.Enum):
    """Why a shadow run stopped."""

    CLOSED = "closed"             # the plan came back to the target it started from
    LIMIT = "limit"               # as many targets as asked for
    SENSOR = "sensor"             # a sensor whose answers are not a static next-location mask
    EFFECT = "effect"             # an action with a side effect (take-off, land, photo, ...)
    ENVIRONMENT = "environment"   # the plan waits for an answer only the environment gives
    EXHAUSTED = "exhausted"       # go.next or remove.next with a null next location
    STEPS = "steps"               # the step budget ran out


@dataclass(frozen=True)
class Prediction:
    """The targets the plan flies to after ``start`` (in order), whether the next one after them
    is ``start`` again (a patrol cycle), why the shadow stopped, and its controller steps (those
    skipped in a pass included)."""

    start: int
    targets: tuple[int, ...]
    closes: bool
    stop: ShadowStop
    steps: int


class Shadow:
    """Shadow runs of ``table`` with the mission's ``bindings`` (read only) and static
    next-location ``sensors`` (module docstring).  ``arrival``: the predicted arrival pose at a
    cell from a pose (the Sorter orders the fork from it); ``limit``: targets per prediction;
    ``max_steps``: controller steps per prediction, skipped ones excluded."""

    def __init__(self, table: ControllerTable, bindings: Mapping[str, Binding],
                 sensors: Sensors, arrival: ArrivalModel, *, limit: int = 8,
                 max_steps: int = 200_000):
        self.table = table
        self.bindings = bindings
        self.sensors = sensors
        self.arrival = arrival
        self.limit = limit
        self.max_steps = max_steps
        ctl = table.controllable
        self._choices = {s: sorted(a for a in m if a in ctl) for s, m in table.delta.items()}
        self._cycles: dict[int, dict[int, Cycle | None]] = {}   # the shadow's own skip cache
        self.runs = 0

    def predict(self, state: int, iterator: Iterator, target: int, pose: Pose) -> Prediction:
        """The controller is in ``state`` just after ``go.next`` to ``target``, the vehicle at
        ``pose``, the real Iterator as it is at that moment (it is forked, never changed)."""
        self.runs += 1
        it = iterator.fork()
        here = self.arrival(pose, target)
        it.resort(here)
        go = next((b for b in self.bindings.values() if b.kind is BindingKind.GO_NEXT), None)
        if go is None or go.answer is None:
            return Prediction(target, (), False, ShadowStop.ENVIRONMENT, 0)
        run = _Run(self, it, here, state, go.answer)
        stop = run.until(target)
        return Prediction(target, tuple(run.targets), stop is ShadowStop.CLOSED, stop,
                          run.steps + run.counts["steps"])


class _Run:
    """One shadow run's state: the controller state, the forked Iterator, the pending answers
    and the predicted pose."""

    def __init__(self, shadow: Shadow, it: Iterator, pose: Pose, state: int, answer: str):
        self.sh = shadow
        self.it = it
        self.pose = pose
        self.state = state
        self.pending: deque[str] = deque([answer])
        self.targets: list[int] = []
        self.steps = 0
        self.counts = {"steps": 0, "controllable": 0, "uncontrollable": 0, "skipped": 0}
        self.skipping = bool(shadow.sensors.labels)

    def until(self, start: int) -> ShadowStop:
        sh, delta = self.sh, self.sh.table.delta
        while self.steps < sh.max_steps:
            self.steps += 1
            if self.pending:
                label = self.pending.popleft()
                if label not in delta[self.state]:
                    return ShadowStop.ENVIRONMENT
                self.state = delta[self.state][label]
                continue
            if self.skipping and fast_skip(self.it, self.state,
                                           sh._cycles.setdefault(self.state, {}), sh.sensors,
                                           sh.table, sh.bindings, frozenset(), self.counts):
                continue
            enabled = sh._choices[self.state]
            if not enabled:
                return ShadowStop.ENVIRONMENT
            stop = self._take(enabled[0], start)
            if stop is not None:
                return stop
        return ShadowStop.STEPS

    def _take(self, label: str, start: int) -> ShadowStop | None:
        """Take the controllable ``label`` as the executor would, on the fork; a reason to stop
        instead, or None."""
        b = self.sh.bindings[label]
        it = self.it
        kind = b.kind
        if kind is BindingKind.HAS_NEXT:
            answer = b.yes if it.has_next() else b.no
            if answer is None:
                return ShadowStop.ENVIRONMENT
            self.pending.append(answer)
        elif kind is BindingKind.SENSOR_NEXT:
            if b.mask is None or b.yes is None or b.no is None:
                return ShadowStop.SENSOR
            cell = it.next
            if cell is None:
                return ShadowStop.EXHAUSTED
            self.pending.append(b.yes if b.mask[cell] else b.no)
        elif kind is BindingKind.REMOVE_NEXT:
            if not it.has_next():
                return ShadowStop.EXHAUSTED
            it.remove_next()
        elif kind is BindingKind.RESET:
            it.reset(self.pose)
        elif kind is BindingKind.GO_NEXT:
            return self._go(label, b, start)
        elif kind is BindingKind.SENSOR_CURRENT:
            return ShadowStop.SENSOR
        elif kind is not BindingKind.INSTANT:             # photo, takeoff, land, a user's binding
            return ShadowStop.EFFECT
        self.state = self.sh.table.delta[self.state][label]
        return None

    def _go(self, label: str, b: Binding, start: int) -> ShadowStop | None:
        cell = self.it.next
        if cell is None or b.answer is None:
            return ShadowStop.EXHAUSTED
        if cell == start:
            return ShadowStop.CLOSED
        self.targets.append(cell)
        if len(self.targets) >= self.sh.limit:
            return ShadowStop.LIMIT
        self.state = self.sh.table.delta[self.state][label]
        self.pose = self.sh.arrival(self.pose, cell)
        self.it.resort(self.pose)
        self.pending.append(b.answer)
        return None
