"""Table-driven controller execution: the base every generated controller module uses.

A generated module builds a :class:`ControllerTable` (states, transitions, alphabets) and a
:class:`Controller` steps through it.  Lookups are dict-of-dict so a step is one or two dict
accesses.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path


class RefusedEvent(Exception):
    """The controller does not allow ``event`` in its current state."""

    def __init__(self, state: int, event: str, enabled: Iterable[str]):
        self.state = state
        self.event = event
        self.enabled = tuple(sorted(enabled))
        super().__init__(
            f"controller refuses {event!r} in state {state}; enabled: {', '.join(self.enabled) or '(none)'}"
        )


@dataclass(frozen=True)
class ControllerTable:
    """An immutable controller automaton.

    ``delta[state][label] = next_state``; the controller is deterministic.  ``controllable``
    and ``uncontrollable`` partition the alphabet.
    """

    name: str
    num_states: int
    initial: int
    delta: Mapping[int, Mapping[str, int]]
    controllable: frozenset[str]
    uncontrollable: frozenset[str]

    @classmethod
    def from_transitions(
        cls,
        name: str,
        num_states: int,
        transitions: Iterable[tuple[int, str, int]],
        controllable: Iterable[str],
        uncontrollable: Iterable[str],
        initial: int = 0,
    ) -> ControllerTable:
        delta: dict[int, dict[str, int]] = {s: {} for s in range(num_states)}
        for s, a, t in transitions:
            if a in delta[s] and delta[s][a] != t:
                raise ValueError(f"nondeterministic controller: state {s} label {a!r}")
            delta[s][a] = t
        return cls(name, num_states, initial, delta, frozenset(controllable),
                   frozenset(uncontrollable))


class Controller:
    """A running instance of a :class:`ControllerTable`."""

    __slots__ = ("table", "state", "_delta")

    def __init__(self, table: ControllerTable):
        self.table = table
        self.state = table.initial
        self._delta = table.delta

    def enabled(self) -> frozenset[str]:
        """Labels allowed in the current state."""
        return frozenset(self._delta[self.state])

    def enabled_controllable(self) -> list[str]:
        """Controllable labels allowed now, in sorted order (deterministic choice)."""
        c = self.table.controllable
        return sorted(a for a in self._delta[self.state] if a in c)

    def step(self, event: str) -> int:
        """Take ``event``; return the new state or raise :class:`RefusedEvent`."""
        try:
            self.state = self._delta[self.state][event]
        except KeyError:
            raise RefusedEvent(self.state, event, self._delta[self.state]) from None
        return self.state

    def reset(self) -> None:
        self.state = self.table.initial


def run_bindings(controller: Controller, bindings, *, max_steps: int | None = None,
                 choose=None, events=None) -> dict:
    """Simple synchronous run loop for generated modules' ``run(bindings)``.

    ``bindings`` maps each controllable label to a callable taking no arguments that performs
    the action and returns the uncontrollable answer label(s) (a string, an iterable of strings,
    or None).  Answers are fed to :meth:`Controller.step` in order.  When no controllable action
    is enabled and no answer is pending, ``events()`` (if given) supplies the next uncontrollable
    label (None stops the run).  ``choose(enabled)`` picks among enabled controllable labels
    (default: the first in sorted order).

    Returns ``{"steps": n, "trace": [labels], "stopped": reason}``; a refused answer raises
    :class:`RefusedEvent`.  (The full mission executor with iterator, planner and vehicle is
    :class:`iterplan_compiler.runtime.executor.Executor`.)
    """
    from collections import deque

    pending: deque[str] = deque()
    trace: list[str] = []
    steps = 0
    stopped = "max_steps"
    while max_steps is None or steps < max_steps:
        if pending:
            label = pending.popleft()
        else:
            enabled = controller.enabled_controllable()
            if enabled:
                label = choose(enabled) if choose else enabled[0]
                controller.step(label)
                trace.append(label)
                steps += 1
                fn = bindings.get(label)
                out = fn() if fn is not None else None
                if isinstance(out, str):
                    pending.append(out)
                elif out is not None:
                    pending.extend(out)
                continue
            answer = events() if events is not None else None
            if answer is None:
                stopped = "no_event" if controller.enabled() else "deadlock"
                break
            label = answer
        controller.step(label)
        trace.append(label)
        steps += 1
    return {"steps": steps, "trace": trace, "stopped": stopped}


def load_controller(path: str | Path) -> ControllerTable:
    """Import a controller module from ``path`` and return its :class:`ControllerTable`.

    Accepted (first match): module-level ``TABLE`` (what ``iterc compile`` emits), ``CONTROLLER``
    (a table or a Controller), ``make_controller()`` (its ``.table``), or the only module-level
    ControllerTable.  Raises ``ValueError`` with a user-facing message otherwise.
    """
    import importlib.util
    import sys

    p = Path(path)
    if not p.is_file():
        raise ValueError(f"controller module {path} not found")
    name = f"_iterplan_controller_{abs(hash(str(p.resolve())))}"
    spec = importlib.util.spec_from_file_location(name, p)
    if spec is None or spec.loader is None:
        raise ValueError(f"{path} is not a Python module")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    try:
        spec.loader.exec_module(mod)
    except (Exception, SystemExit) as exc:  # a broken module is the user's input, not our bug
        raise ValueError(f"cannot import {path}: {type(exc).__name__}: {exc}") from None
    for attr in ("TABLE", "CONTROLLER"):
        obj = getattr(mod, attr, None)
        if isinstance(obj, ControllerTable):
            return checked(obj, path)
        if isinstance(obj, Controller):
            return checked(obj.table, path)
    mk = getattr(mod, "make_controller", None)
    if callable(mk):
        c = mk()
        if isinstance(c, Controller):
            return checked(c.table, path)
    tables = [v for v in vars(mod).values() if isinstance(v, ControllerTable)]
    if len(tables) == 1:
        return checked(tables[0], path)
    raise ValueError(f"{path} defines no controller: expected a module-level TABLE "
                     f"(ControllerTable), CONTROLLER or make_controller()")


def checked(table: ControllerTable, path: str | Path) -> ControllerTable:
    """``table`` if it is a well-formed automaton (initial state and every target defined,
    every label in exactly one alphabet), else ``ValueError`` naming the first problem."""
    states = set(table.delta)
    if table.initial not in states:
        raise ValueError(f"{path}: the controller's initial state {table.initial} has no entry")
    both = table.controllable & table.uncontrollable
    if both:
        raise ValueError(f"{path}: {sorted(both)[0]!r} is both controllable and uncontrollable")
    for s, moves in table.delta.items():
        for label, t in moves.items():
            if t not in states:
                raise ValueError(f"{path}: state {s} --{label}--> {t}, a state the controller "
                                 f"does not define")
            if label not in table.controllable and label not in table.uncontrollable:
                raise ValueError(f"{path}: label {label!r} of state {s} is in neither alphabet")
    return table
