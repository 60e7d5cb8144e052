"""Fast skip: the controller's "not this one" cycles run for many locations in one pass.

While the plan walks through locations it will not visit (``has.next``, ``y.next``,
``is.next.S``, ``no.next.S``, ..., ``remove.next``) the aircraft flies on: on a map of 700,000
locations that is seconds of flight per pass (the paper's iteration overhead).  Stepping that
cycle one event at a time is deterministic given the location: the executor picks the first
enabled controllable label, ``has.next`` answers yes, a next-location sensor on a *static* map
sensor answers from its mask.  So for a controller state ``s`` and a location *class* (the
answers of the static next-sensors at that location) the events until the controller is back in
``s`` are fixed.  :func:`cycle` computes them by stepping the table exactly as the executor
would; a class whose cycle contains only ``has.next``, static next-sensor questions, their
answers and exactly one ``remove.next``, and ends in ``s``, is a *skip* class.  The executor
(``RunConfig.fast_skip``) then finds the run of upcoming locations (in the Iterator's order) whose
classes are skips with one vectorised mask lookup, removes them from the iterator at once and adds
their events to the counters; the controller's state and everything it observes afterwards are
exactly those of stepping one event at a time (``tests/runtime/test_skip.py``).

Not skipped: anything else (a visit, a photo, a sensor about the current cell, a dynamic or
derived map sensor — they have state —, a user binding), and any event the ``on_event`` hook asks
for (``RunConfig.on_event_labels``).
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from dataclasses import dataclass

import numpy as np

from iterplan_compiler.runtime.bindings import Binding, BindingKind
from iterplan_compiler.runtime.controller import ControllerTable
from iterplan_compiler.runtime.iterator import Iterator

MAX_CYCLE = 64


@dataclass(frozen=True)
class Cycle:
    """The events of one skip cycle, as (kind, label) with kind "c"/"u"."""

    events: tuple[tuple[str, str], ...]

    @property
    def controllable(self) -> int:
        return sum(1 for k, _ in self.events if k == "c")


@dataclass(frozen=True)
class Sensors:
    """The static next-location sensors of a controller: label -> (mask, yes, no)."""

    labels: tuple[str, ...]
    masks: tuple[np.ndarray, ...]

    def codes(self, cells: np.ndarray) -> np.ndarray:
        """Class code per cell: bit i = sensor i answers yes."""
        code = np.zeros(len(cells), dtype=np.int64)
        for i, m in enumerate(self.masks):
            code |= m[cells].astype(np.int64) << i
        return code


def static_sensors(bindings: Mapping[str, Binding]) -> Sensors:
    labels = tuple(sorted(a for a, b in bindings.items()
                          if b.kind is BindingKind.SENSOR_NEXT and b.mask is not None))
    masks = tuple(np.asarray(bindings[a].mask) for a in labels)
    return Sensors(labels, masks)


def cycle(state: int, code: int, delta: Mapping[int, Mapping[str, int]],
          controllable: Collection[str], bindings: Mapping[str, Binding], sensors: Sensors,
          wanted: Collection[str]) -> Cycle | None:
    """The events from ``state`` for a location of class ``code`` until the controller is back in
    ``state`` after one ``remove.next`` — or None if that is not a pure skip (see module
    docstring).  ``wanted``: labels that must not be skipped (the ``on_event`` hook's)."""
    bit = {label: i for i, label in enumerate(sensors.labels)}
    events: list[tuple[str, str]] = []
    pending: list[str] = []
    s = state
    removed = False
    for _ in range(MAX_CYCLE):
        moves = delta[s]
        if pending:
            label = pending.pop(0)
            if label not in moves or label in wanted:
                return None
            events.append(("u", label))
            s = moves[label]
        else:
            if removed:
                return Cycle(tuple(events)) if s == state else None
            enabled = sorted(a for a in moves if a in controllable)
            if not enabled:
                return None
            label = enabled[0]
            b = bindings[label]
            if label in wanted:
                return None
            if b.kind is BindingKind.HAS_NEXT:
                assert b.yes is not None
                pending.append(b.yes)
            elif b.kind is BindingKind.SENSOR_NEXT and label in bit:
                yes = (code >> bit[label]) & 1
                pending.append(b.yes if yes else b.no)  # type: ignore[arg-type]
            elif b.kind is BindingKind.REMOVE_NEXT:
                if removed:
                    return None
                removed = True
            else:
                return None
            events.append(("c", label))
            s = moves[label]
    return None


def fast_skip(it: Iterator, state: int, cache: dict[int, Cycle | None], sensors: Sensors,
              table: ControllerTable, bindings: Mapping[str, Binding],
              wanted: Collection[str], counts: dict[str, int]) -> int:
    """Skip the run of upcoming locations of ``it`` whose cycle from controller ``state`` is a
    pure skip (module docstring); their events go to ``counts``.  ``cache`` maps a location
    class to its cycle from ``state`` (filled lazily).  Returns the number skipped."""
    if not it.has_next():
        return 0
    n = it.next
    assert n is not None
    first = sum(int(m[n]) << i for i, m in enumerate(sensors.masks))

    def lookup(code: int) -> Cycle | None:
        if code not in cache:
            cache[code] = cycle(state, code, table.delta, table.controllable, bindings,
                                sensors, wanted)
        return cache[code]

    if lookup(first) is None:           # cheap exit: the next location is not a skip
        return 0
    total = 0
    k = 64
    while it.has_next():
        cells = np.concatenate([[it.next], it.peek_order(k)])
        codes = sensors.codes(cells)
        # A map has few location classes: decide each class once, then index (a Python call
        # per location was ~60 % of a 700,000-location pass).
        classes, which = np.unique(codes, return_inverse=True)
        ok = np.array([lookup(int(c)) is not None for c in classes.tolist()], bool)[which]
        j = int(np.argmin(ok)) if not ok.all() else len(codes)
        if j == 0:
            break
        for code, reps in zip(*np.unique(codes[:j], return_counts=True), strict=True):
            cyc = cache[int(code)]
            assert cyc is not None
            c = cyc.controllable
            counts["steps"] += int(reps) * len(cyc.events)
            counts["controllable"] += int(reps) * c
            counts["uncontrollable"] += int(reps) * (len(cyc.events) - c)
        it.skip_run(j)
        total += j
        if j < len(codes):
            break
        k = min(4 * k, 1 << 20)
    counts["skipped"] += total
    return total
