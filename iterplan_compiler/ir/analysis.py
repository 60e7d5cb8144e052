"""LTSA's analyses of a composed LTS: safety (deadlock, ERROR) and progress (``docs/ltsa.md``).

Pure functions over an explicit :class:`~iterplan_compiler.ir.lts.LTS` (the composite that
``Model.build_lts`` returns); no front-end knowledge.  ``iterc check --safety/--progress``
(``commands/ltsa_check.py``) turns the results into diagnostics.

* **Safety** (:func:`check_safety`): breadth-first search from the initial state for (a) a
  *deadlock* — a reachable state without outgoing transitions that is not the END state — and
  (b) a transition into ERROR (a ``property``/``ltl_property`` or an explicit ``ERROR`` was
  violated).  BFS gives the shortest trace to each (ties broken by the sorted
  ``(label, target)`` order of the moves, so traces are stable).
* **Progress** (:func:`terminal_sets`, :func:`check_progress`): LTSA's semantics with fair
  choice.  A *terminal set* is a reachable bottom strongly connected component with at least
  one transition (every state reaches every other and nothing leaves it).  Under fair choice
  every action of a terminal set occurs infinitely often once a run is trapped in it, so
  ``progress P = {a, b}`` is violated iff some terminal set contains neither ``a`` nor ``b``;
  ``progress P = if {c} then {a}`` iff some terminal set contains an action of ``{c}`` but none
  of ``{a}``.  ERROR counts as a state outside every set (a component that can move to ERROR is
  not terminal; reaching ERROR is reported by the safety check), and deadlock/END states have
  no transition, so they form no terminal set either (deadlocks are the safety check's
  business, as in LTSA).

Action sets match as in every MTSA label set (exactly or as a dotted prefix:
``{a}`` matches ``a.1``, :func:`~iterplan_compiler.ir.compose.label_matcher`).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass

from .compose import label_matcher
from .graphs import strongly_connected
from .lts import ERROR, LTS, TAU

__all__ = [
    "SafetyResult", "TerminalSet", "ProgressProperty", "ProgressViolation",
    "shortest_paths", "trace_to", "check_safety", "terminal_sets", "check_progress",
    "default_progress", "tau_closure",
]


@dataclass(frozen=True)
class SafetyResult:
    """Shortest traces (action labels) to a deadlock and to ERROR; ``None`` when unreachable."""

    deadlock: tuple[str, ...] | None
    deadlock_state: int | None
    error: tuple[str, ...] | None
    states: int

    @property
    def ok(self) -> bool:
        return self.deadlock is None and self.error is None


@dataclass(frozen=True)
class TerminalSet:
    """A reachable bottom SCC with a transition: its states, actions and the trace to it."""

    states: frozenset[int]
    actions: frozenset[str]
    trace: tuple[str, ...]
    entry: int  # the state of the set the trace ends in


@dataclass(frozen=True)
class ProgressProperty:
    """An elaborated ``progress`` property: ``actions`` must occur in every terminal set (in
    those that contain an action of ``condition``, when it is given)."""

    name: str
    actions: frozenset[str]
    condition: frozenset[str] | None = None


@dataclass(frozen=True)
class ProgressViolation:
    prop: ProgressProperty
    terminal: TerminalSet


def tau_closure(out, states: Iterable[int]) -> frozenset[int]:
    """``states`` and every state reachable from them by ``tau`` moves (``out``: a state's
    ``[(label, target), ...]``, as :meth:`LTS.out_edges`); ERROR has no moves."""
    seen = set(states)
    todo = list(seen)
    while todo:
        s = todo.pop()
        if s == ERROR:
            continue
        for a, t in out[s] if isinstance(out, list) else out.get(s, ()):
            if a == TAU and t not in seen:
                seen.add(t)
                todo.append(t)
    return frozenset(seen)


def _out_edges(lts: LTS) -> list[list[tuple[str, int]]]:
    out: list[list[tuple[str, int]]] = [[] for _ in range(lts.num_states)]
    for s, a, t in lts.transitions:  # sorted: each list is in (label, target) order
        out[s].append((a, t))
    return out


def shortest_paths(lts: LTS, out: list[list[tuple[str, int]]] | None = None
                   ) -> dict[int, tuple[int, str] | None]:
    """BFS from the initial state: ``{state: (predecessor, label) or None for the initial}``
    for every reachable state (ERROR excluded)."""
    out = _out_edges(lts) if out is None else out
    parent: dict[int, tuple[int, str] | None] = {lts.initial: None}
    queue = deque([lts.initial])
    while queue:
        s = queue.popleft()
        for a, t in out[s]:
            if t != ERROR and t not in parent:
                parent[t] = (s, a)
                queue.append(t)
    return parent


def trace_to(parent: dict[int, tuple[int, str] | None], state: int) -> tuple[str, ...]:
    """The labels of the BFS path from the initial state to ``state``."""
    labels: list[str] = []
    link = parent[state]
    while link is not None:
        s, a = link
        labels.append(a)
        link = parent[s]
    return tuple(reversed(labels))


def check_safety(lts: LTS) -> SafetyResult:
    """Shortest traces to a deadlock and to ERROR (module doc)."""
    out = _out_edges(lts)
    parent = shortest_paths(lts, out)
    # BFS order = parent's insertion order: the first hit of each kind is a shortest one.
    deadlock = deadlock_state = error = None
    for s in parent:
        if deadlock is None and not out[s] and s not in lts.end_states:
            deadlock, deadlock_state = trace_to(parent, s), s
        if error is None:
            for a, t in out[s]:
                if t == ERROR:
                    error = (*trace_to(parent, s), a)
                    break
        if deadlock is not None and error is not None:
            break
    return SafetyResult(deadlock, deadlock_state, error, len(parent))


def _sccs(nodes: Iterable[int], out: list[list[tuple[str, int]]]) -> list[list[int]]:
    """Strongly connected components of the graph restricted to ``nodes``, ERROR left out
    (:func:`~iterplan_compiler.ir.graphs.strongly_connected`)."""
    return strongly_connected(nodes, lambda v: [t for _, t in out[v] if t != ERROR])


def terminal_sets(lts: LTS) -> list[TerminalSet]:
    """The reachable terminal sets, each with a shortest trace to it, ordered by trace length
    then smallest state (module doc)."""
    out = _out_edges(lts)
    parent = shortest_paths(lts, out)
    order = {s: k for k, s in enumerate(parent)}  # BFS rank
    found: list[TerminalSet] = []
    for comp in _sccs(parent, out):
        members = set(comp)
        actions: set[str] = set()
        bottom = True
        has_move = False
        for s in comp:
            for a, t in out[s]:
                if t == ERROR or t not in members:
                    bottom = False
                    break
                has_move = True
                actions.add(a)
            if not bottom:
                break
        if not bottom or not has_move:
            continue
        entry = min(comp, key=order.__getitem__)
        found.append(TerminalSet(frozenset(comp), frozenset(actions),
                                 trace_to(parent, entry), entry))
    found.sort(key=lambda ts: order[ts.entry])
    return found


def _hits(labels: frozenset[str], actions: Iterable[str]) -> bool:
    matches = label_matcher(labels)
    return any(matches(a) for a in actions if a != TAU)


def check_progress(lts: LTS, props: Iterable[ProgressProperty],
                   sets: list[TerminalSet] | None = None) -> list[ProgressViolation]:
    """For each property, the first terminal set (shortest trace) that violates it."""
    sets = terminal_sets(lts) if sets is None else sets
    violations: list[ProgressViolation] = []
    for p in props:
        for ts in sets:
            if p.condition is not None and not _hits(p.condition, ts.actions):
                continue
            if not _hits(p.actions, ts.actions):
                violations.append(ProgressViolation(p, ts))
                break
    return violations


def default_progress(lts: LTS, sets: list[TerminalSet] | None = None
                     ) -> list[tuple[TerminalSet, frozenset[str]]]:
    """LTSA's check when no progress property is declared: every action of the alphabet must
    occur in every terminal set.  Returns ``(terminal set, missing actions)`` for the sets that
    miss some action."""
    sets = terminal_sets(lts) if sets is None else sets
    return [(ts, frozenset(lts.alphabet - ts.actions)) for ts in sets
            if lts.alphabet - ts.actions]
