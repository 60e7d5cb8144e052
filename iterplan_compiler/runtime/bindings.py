"""Action bindings: what each controllable label *does* on the aircraft, and which uncontrollable
label answers it.

Labels are matched in a canonical form (lower case, ``_`` -> ``.``, a trailing ``?`` dropped), so
``has.next``, ``has_next`` and ``has.next?`` all bind the same way; answers are mapped back to the
exact spelling in the controller's alphabet.  Standard bindings (paper §III-B, §IV):

===================================  ==============================================================
controllable (canonical)             effect -> answer
===================================  ==============================================================
``has.next``                         ``y.next`` / ``yes.next`` if the iterator's n is not null,
                                     else ``n.next`` / ``no.next``
``remove.next``                      iterator ``remove_next`` (no answer)
``reset`` / ``reset.iterator``       iterator ``reset`` from the current (predicted) pose
``go.next``                          motion planner flies to n; ``arrived`` when the planner
                                     counts the cell as visited (durative)
``is.next.X`` / ``next.X``           sensor X about the iterator's n -> ``yes.next.X`` /
                                     ``no.next.X``
``is.X`` / ``X``                     sensor X about the current location (the cell of the last
                                     arrival) -> ``yes.X`` / ``no.X``
``take.photo`` / ``photo``           records a photo (time, pose, cell)
``takeoff`` / ``land``               vehicle take-off / landing; answered by ``takeoff.ended``
                                     (``.complete``, ``.done``, ``airborne``) / ``landed`` when the
                                     vehicle reports
anything else                        instantaneous: logged, no answer
===================================  ==============================================================

Sensor cell sets come from the map (``GridMap.sensors``).  The map's sensor *rules* are served
by :func:`map_rule_bindings` (the executor applies it to every mission, with fresh state):

* ``GridMap.dynamic[X]`` (:class:`~iterplan_compiler.runtime.grid.DynamicSensor`): sensor X
  answers yes at each of its cells at most ``yes_answers`` times per mission, then no;
* ``GridMap.derived[X]`` (:class:`~iterplan_compiler.runtime.grid.DerivedSensor`): the action
  ``neighbours_of`` (e.g. ``store.target``) adds the current cell to a shared set, and sensor X
  answers yes for cells equal or adjacent (4/8-connectivity) to a stored cell.

Users extend or override with :meth:`Bindings.bind` (any canonical label) and
:meth:`Bindings.sensor` (a predicate over cell ids); a user's binding of a rule's sensor or
action takes precedence over the map's rule.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from iterplan_compiler.runtime.executor import MissionContext
    from iterplan_compiler.runtime.grid import DerivedSensor, DynamicSensor, GridMap


def canon(label: str) -> str:
    """Canonical form used for matching labels to bindings."""
    return label.strip().lower().rstrip("?").replace("_", ".")


class BindingError(ValueError):
    """The controller uses a label the runtime cannot serve (message is for the user)."""


#: A handler runs after the controller took ``label``; it returns canonical answer label(s).
Handler = Callable[["MissionContext", str], "str | Iterable[str] | None"]

YES_NEXT = ("y.next", "yes.next")
NO_NEXT = ("n.next", "no.next")
ARRIVED = ("arrived",)
TAKEOFF_DONE = ("takeoff.ended", "takeoff.complete", "takeoff.done", "airborne")
LANDED = ("landed",)


class BindingKind(enum.Enum):
    """What a controllable label is bound to (:meth:`Bindings.resolve`); the executor, its
    fast skip and the shadow run dispatch on it."""

    CUSTOM = "custom"                  # a handler given with Bindings.bind
    HAS_NEXT = "has.next"
    REMOVE_NEXT = "remove.next"
    RESET = "reset"
    GO_NEXT = "go.next"
    PHOTO = "photo"
    TAKEOFF = "takeoff"
    LAND = "land"
    SENSOR_NEXT = "sensor.next"        # a sensor queried at the next location
    SENSOR_CURRENT = "sensor.current"  # a sensor queried here
    INSTANT = "instant"                # no effect: answered at once


@dataclass
class Binding:
    """A resolved binding: the handler and, for durative actions, which vehicle/planner event
    completes it (``"arrived"``, ``"takeoff_complete"``, ``"landed"``) and the answer label."""

    kind: BindingKind
    handler: Handler
    completes_on: str | None = None
    answer: str | None = None
    #: for ``sensor.next`` on a static map sensor: the yes-mask over cell ids and the two
    #: answers (what the executor's fast skip needs to predict the answer for many cells)
    mask: np.ndarray | None = None
    yes: str | None = None
    no: str | None = None


@dataclass
class Bindings:
    """Registry of handlers and sensors; :meth:`resolve` builds the per-label table."""

    custom: dict[str, Handler] = field(default_factory=dict)
    sensors: dict[str, Callable[[int], bool]] = field(default_factory=dict)

    def bind(self, label: str, handler: Handler) -> Bindings:
        """Override/add the handler of a controllable label (any spelling)."""
        self.custom[canon(label)] = handler
        return self

    def sensor(self, name: str, predicate: Callable[[int], bool]) -> Bindings:
        """Sensor ``name`` answers yes for the cells where ``predicate(cell_id)`` holds."""
        self.sensors[name.lower()] = predicate
        return self

    # -- resolution ---------------------------------------------------------------------------
    def resolve(self, controllable: Iterable[str], uncontrollable: Iterable[str],
                map_sensors: dict[str, np.ndarray], num_cells: int) -> dict[str, Binding]:
        """One :class:`Binding` per controllable label, or :class:`BindingError`."""
        unc = {canon(u): u for u in uncontrollable}
        sensor_names = {k.lower(): k for k in map_sensors}
        out: dict[str, Binding] = {}

        def answer(options: tuple[str, ...]) -> str | None:
            return next((o for o in options if o in unc), None)

        def static_mask(name: str) -> np.ndarray | None:
            key = name.lower()
            if key in self.sensors or key not in sensor_names:
                return None
            mask = np.zeros(num_cells, dtype=bool)
            mask[map_sensors[sensor_names[key]]] = True
            return mask

        def sensor_pred(name: str, label: str) -> Callable[[int], bool]:
            key = name.lower()
            if key in self.sensors:
                return self.sensors[key]
            mask = static_mask(name)
            if mask is not None:
                return lambda cell: bool(mask[cell])
            raise BindingError(
                f"controller action {label!r} queries sensor {name!r}, but the map defines no "
                f"cells for it (map sensors: {', '.join(sorted(map_sensors)) or 'none'})")

        for label in sorted(controllable):
            c = canon(label)
            if c in self.custom:
                out[label] = Binding(BindingKind.CUSTOM, self.custom[c])
                continue
            if c == "has.next":
                y, n = answer(YES_NEXT), answer(NO_NEXT)
                if y is None or n is None:
                    raise BindingError(f"{label!r} needs answers y.next/n.next in the alphabet")
                out[label] = Binding(BindingKind.HAS_NEXT, _has_next(unc[y], unc[n]), yes=unc[y],
                                     no=unc[n])
            elif c == "remove.next":
                out[label] = Binding(BindingKind.REMOVE_NEXT, _remove_next)
            elif c in ("reset", "reset.iterator"):
                out[label] = Binding(BindingKind.RESET, _reset)
            elif c == "go.next":
                a = answer(ARRIVED)
                if a is None:
                    raise BindingError(f"{label!r} needs the answer 'arrived' in the alphabet")
                out[label] = Binding(BindingKind.GO_NEXT, _go_next, "arrived", unc[a])
            elif c in ("take.photo", "photo"):
                out[label] = Binding(BindingKind.PHOTO, _photo)
            elif c == "takeoff":
                a = answer(TAKEOFF_DONE)
                out[label] = Binding(BindingKind.TAKEOFF, _takeoff, "takeoff_complete",
                                     unc[a] if a else None)
            elif c == "land":
                a = answer(LANDED)
                out[label] = Binding(BindingKind.LAND, _land, "landed", unc[a] if a else None)
            elif (m := re.fullmatch(r"(?:is\.)?next\.(.+)", c)) and (
                    f"yes.next.{m.group(1)}" in unc and f"no.next.{m.group(1)}" in unc):
                x = m.group(1)
                yes_l, no_l = unc[f"yes.next.{x}"], unc[f"no.next.{x}"]
                out[label] = Binding(BindingKind.SENSOR_NEXT, _sensor_next(sensor_pred(x, label), yes_l,
                                                                 no_l),
                                     mask=static_mask(x), yes=yes_l, no=no_l)
            elif (m := re.fullmatch(r"(?:is\.)?(.+)", c)) and (
                    f"yes.{m.group(1)}" in unc and f"no.{m.group(1)}" in unc):
                x = m.group(1)
                out[label] = Binding(BindingKind.SENSOR_CURRENT, _sensor_current(
                    sensor_pred(x, label), unc[f"yes.{x}"], unc[f"no.{x}"]))
            else:
                out[label] = Binding(BindingKind.INSTANT, _instant)
        return out


# -- standard handlers ------------------------------------------------------------------------

def _has_next(yes: str, no: str) -> Handler:
    def h(ctx: MissionContext, label: str) -> str:
        return yes if ctx.iterator.has_next() else no
    return h


def _remove_next(ctx: MissionContext, label: str) -> None:
    if not ctx.iterator.has_next():
        raise BindingError("remove.next while the iterator has no next location")
    ctx.iterator.remove_next()


def _reset(ctx: MissionContext, label: str) -> None:
    ctx.iterator.reset(ctx.predicted_pose())


def _go_next(ctx: MissionContext, label: str) -> None:
    cell = ctx.iterator.next
    if cell is None:
        raise BindingError("go.next while the iterator has no next location")
    ctx.go(cell)


def _photo(ctx: MissionContext, label: str) -> None:
    ctx.record_photo()


def _takeoff(ctx: MissionContext, label: str) -> None:
    if ctx.vehicle.flying:           # an airborne start: nothing to do, answered at once
        ctx.note("already airborne: take-off skipped")
        ctx.done_now("takeoff_complete")
        return
    ctx.vehicle.arm()
    ctx.vehicle.takeoff(ctx.altitude)


def _land(ctx: MissionContext, label: str) -> None:
    if not ctx.vehicle.flying:
        ctx.note("not flying: landing skipped")
        ctx.done_now("landed")
        return
    ctx.planner.stop()   # otherwise the next planner update steers the aircraft out of LAND
    ctx.vehicle.land()


def _instant(ctx: MissionContext, label: str) -> None:
    ctx.note(f"action {label}")


def _sensor_next(pred: Callable[[int], bool], yes: str, no: str) -> Handler:
    def h(ctx: MissionContext, label: str) -> str:
        cell = ctx.iterator.next
        if cell is None:
            raise BindingError(f"{label}: sensing the next location, but it is null")
        return yes if pred(cell) else no
    return h


def _sensor_current(pred: Callable[[int], bool], yes: str, no: str) -> Handler:
    def h(ctx: MissionContext, label: str) -> str:
        cell = ctx.current_cell()
        return yes if cell is not None and cell >= 0 and pred(cell) else no
    return h


# -- map sensor rules -------------------------------------------------------------------------

def dynamic_sensor(cells: np.ndarray, num_cells: int, yes_answers: int) -> Callable[[int], bool]:
    """Predicate for a :class:`~iterplan_compiler.runtime.grid.DynamicSensor`: yes at a cell of
    ``cells`` until it has answered yes there ``yes_answers`` times.  The state (answers given)
    lives in the returned closure, so build one per mission."""
    mask = np.zeros(num_cells, dtype=bool)
    mask[np.asarray(cells, dtype=np.int64)] = True
    given: dict[int, int] = {}

    def pred(cell: int) -> bool:
        cell = int(cell)
        if not (0 <= cell < num_cells and mask[cell]) or given.get(cell, 0) >= yes_answers:
            return False
        given[cell] = given.get(cell, 0) + 1
        return True
    return pred


def derived_sensor(grid: GridMap, connectivity: int) -> tuple[Handler, Callable[[int], bool]]:
    """(store action handler, sensor predicate) for a
    :class:`~iterplan_compiler.runtime.grid.DerivedSensor`.  Storing marks the stored cell's
    neighbourhood in a boolean mask over the grid, so a query is O(1) however many cells have
    been stored (maps have up to 10^6 cells)."""
    cols, rows = grid.cols, grid.rows
    near = np.zeros(grid.num_cells, dtype=bool)
    stored: set[int] = set()
    offsets = ([(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1)] if connectivity == 8
               else [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)])

    def store(ctx: MissionContext, label: str) -> None:
        cell = ctx.current_cell()
        if cell is None or cell < 0:
            raise BindingError(f"{label}: no current location to store")
        cell = int(cell)
        if cell not in stored:
            stored.add(cell)
            r, c = divmod(cell, cols)
            for dr, dc in offsets:
                if 0 <= r + dr < rows and 0 <= c + dc < cols:
                    near[(r + dr) * cols + c + dc] = True
        ctx.note(f"stored {ctx.grid.cell_name(cell)}")

    def pred(cell: int) -> bool:
        return 0 <= int(cell) < len(near) and bool(near[int(cell)])
    return store, pred


def map_rule_bindings(grid: GridMap, bindings: Bindings | None = None, *,
                      dynamic: dict[str, DynamicSensor] | None = None,
                      derived: dict[str, DerivedSensor] | None = None) -> Bindings:
    """A copy of ``bindings`` plus fresh handlers for the map's sensor rules (default:
    ``grid.dynamic`` / ``grid.derived``).  A rule whose sensor (or, for a derived sensor, whose
    action) the caller already bound is left to the caller's binding.  Call once per mission:
    the returned bindings hold the mission's state (answers given, cells stored)."""
    out = Bindings(dict(bindings.custom) if bindings else {},
                   dict(bindings.sensors) if bindings else {})
    dynamic = grid.dynamic if dynamic is None else dynamic
    derived = grid.derived if derived is None else derived
    for name, rule in dynamic.items():
        if name.lower() in out.sensors:
            continue
        if name not in grid.sensors:
            raise BindingError(f"dynamic sensor {name!r} has no cells in the map")
        out.sensor(name, dynamic_sensor(grid.sensors[name], grid.num_cells, rule.yes_answers))
    for name, drule in derived.items():
        if name.lower() in out.sensors or canon(drule.neighbours_of) in out.custom:
            continue
        store, pred = derived_sensor(grid, drule.connectivity)
        out.bind(drule.neighbours_of, store)
        out.sensor(name, pred)
    return out


def answers_of(result: Any) -> list[str]:
    """Normalise a handler's return value to a list of labels."""
    if result is None:
        return []
    if isinstance(result, str):
        return [result]
    return list(result)
