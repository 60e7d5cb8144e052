"""FLTL model checking of an ``assert`` on an explicit LTS (mtsa-semantics §2.9).

What is checked (the choices are documented in ``docs/semantics.md``, "FLTL choices"):

* Every visible action of the system is a position; actions outside Σφ are the wildcard
  ``*`` (they change no fluent and falsify every action proposition).  ``tau`` is not a
  position: the formula's automaton does not move on it.
* **Infinite runs** (with infinitely many visible actions) must satisfy φ.  Violations are
  searched as accepting lassos of the product of the LTS with the generalised Büchi automaton of
  ¬φ; an extra acceptance bit on visible moves rules out cycles made of ``tau`` alone.
* **Fairness** (default, LTSA's "fair choice": its LTL check only accepts cycles in terminal
  sets): only *strongly fair* infinite runs count -- a run visiting a state infinitely often
  takes each of its transitions infinitely often.  ``fair=False`` checks every infinite run.
* **Finite runs** -- ending in a deadlock, an ``END`` state, a move into ``ERROR`` (the move
  itself is the run's last action), or followed
  only by ``tau`` forever -- are *not* extended by idling: such a run violates φ only if it is a
  *bad prefix* (every infinite continuation violates φ).  So deadlocks never violate liveness
  (LTSA's convention), while a safety violation before a deadlock is still reported.  Searched
  by an on-the-fly subset construction over the live states of φ's automaton; a bad prefix is
  reported as a counterexample with an empty cycle.

The counterexample is a run of the LTS: ``prefix`` then ``cycle`` repeated forever (labels as
in the LTS, ``tau`` included so it can be replayed).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field

from iterplan_compiler import limits
from iterplan_compiler.diagnostics import Diagnostic, error
from iterplan_compiler.fltl.emptiness import (
    Analysis,
    StateLimitExceeded,
    analyse,
    covering_cycle,
    lasso,
    path_to,
)
from iterplan_compiler.fltl.progression import WILDCARD, FormulaAutomaton
from iterplan_compiler.fltl.safety import E_TOO_LARGE, E_UNKNOWN_FLUENT
from iterplan_compiler.fltl.semantics import UnknownFluentError
from iterplan_compiler.ir.formulas import Fluent, Formula, NamedFormula
from iterplan_compiler.ir.lts import ERROR, LTS, TAU

DEFAULT_MAX_STATES = 2_000_000


@dataclass(frozen=True, slots=True)
class Counterexample:
    """A run of the system violating the formula: ``prefix (cycle)^omega``; an empty ``cycle``
    means a finite run that is already a bad prefix."""

    prefix: tuple[str, ...]
    cycle: tuple[str, ...] = ()
    terminal_actions: tuple[str, ...] = ()  # fair checks: every action of the terminal set

    def render(self) -> str:
        """Multi-line, LTSA-like listing of the trace."""
        lines = [f"    {a}" for a in self.prefix]
        if self.cycle:
            lines.append("  Cycle in terminal set:")
            lines += [f"    {a}" for a in self.cycle]
            if self.terminal_actions:
                lines.append("  Actions in terminal set:")
                lines.append("    {" + ", ".join(self.terminal_actions) + "}")
        else:
            lines.append("  (every continuation violates the property)")
        return "\n".join(lines)

    def __str__(self) -> str:
        head = " ".join(self.prefix)
        if not self.cycle:
            return head
        return (head + " " if head else "") + "(" + " ".join(self.cycle) + ")^w"


@dataclass(frozen=True, slots=True)
class CheckResult:
    """Outcome of :func:`model_check`."""

    holds: bool
    counterexample: Counterexample | None = None
    deadlocks: int = 0  # reachable states without moves (END states included)
    stats: dict = field(default_factory=dict, compare=False)
    error_reachable: bool = False  # the LTS itself can move into ERROR (a property violation)


def _visible(a: str, alphabet: frozenset[str]) -> str:
    return a if a in alphabet else WILDCARD


def model_check(
    lts: LTS,
    formula: Formula,
    fluents: Mapping[str, Fluent],
    *,
    fair: bool = True,
    max_states: int = DEFAULT_MAX_STATES,
) -> CheckResult:
    """Check that every run of ``lts`` satisfies ``formula`` (see the module docstring);
    with ``fair`` (the default, LTSA's "fair choice") only strongly fair infinite runs count.

    Raises :class:`~iterplan_compiler.fltl.semantics.UnknownFluentError` for a fluent missing
    from ``fluents`` and :class:`~iterplan_compiler.fltl.emptiness.StateLimitExceeded` when a
    product grows beyond ``max_states``; :func:`check_assert` turns both into diagnostics.
    """
    out = lts.out_edges()
    neg = FormulaAutomaton(formula, fluents, negate=True)
    visible_bit = neg.full_mask + 1
    full = neg.full_mask | visible_bit
    sigma = neg.alphabet

    def succ(node):
        s, q = node
        for a, t in out[s]:
            if t == ERROR:
                continue
            if a == TAU:
                yield a, (t, q), 0
                continue
            for q2, m in neg.step(q, _visible(a, sigma)):
                yield a, (t, q2), m | visible_bit

    an = analyse([(lts.initial, neg.initial)], succ, full, max_nodes=max_states)
    deadlocks, error_reachable = _reachable_ends(lts, out)
    stats: dict = {"product_states": len(an.adj), "fair": fair}
    if fair:
        cex = _fair_counterexample(an, out, full, stats)
    else:
        found = lasso(an, full)
        cex = None if found is None else Counterexample(tuple(found[0]), tuple(found[1]))
    if cex is not None:
        return CheckResult(False, cex, deadlocks, stats, error_reachable)
    bad = _bad_prefix(lts, out, formula, fluents, max_states)
    if bad is not None:
        return CheckResult(False, Counterexample(tuple(bad), ()), deadlocks, stats,
                           error_reachable)
    return CheckResult(True, None, deadlocks, stats, error_reachable)


FAIR_CYCLE_LIMIT = 500
"""Above this many transitions in a terminal set the printed cycle only covers acceptance."""


def _fair_counterexample(
    an: Analysis, out: dict[int, list[tuple[str, int]]], full: int, stats: dict
) -> Counterexample | None:
    """A violating lasso whose cycle stays in a *fair terminal set*, or ``None``.

    A strongly fair run takes, infinitely often, every transition of every system state it
    visits infinitely often.  So a fair violation needs a strongly connected set ``C`` of product
    nodes that is accepting and whose internal edges include every transition of every system
    state in ``C`` (a move into ERROR can never be included: a fair run would take it and end).
    Search: accepting SCCs, minus the nodes whose system state has a transition not covered
    inside, re-split into SCCs, until a set passes or none is left (Streett emptiness).
    """
    order = {v: i for i, v in enumerate(an.adj)}  # discovery order: deterministic choices
    work = [list(comp) for k, comp in enumerate(an.sccs) if an.accepting[k]]
    found: set | None = None
    while work:
        comp = set(work.pop())
        covered = {(v[0], a, w[0]) for v in comp for a, w, _ in an.adj[v] if w in comp}
        states = {v[0] for v in comp}
        bad = {s for s in states if any((s, a, t) not in covered for a, t in out[s])}
        if not bad:
            found = comp
            break
        rest = sorted((v for v in comp if v[0] not in bad), key=order.__getitem__)
        if not rest:
            continue

        def inner(v, rest_set=frozenset(rest)):
            return [e for e in an.adj[v] if e[1] in rest_set]

        sub = analyse(rest, inner, full)
        work.extend(list(c) for k, c in enumerate(sub.sccs) if sub.accepting[k])
    if found is None:
        return None
    prefix = path_to(an, found)
    assert prefix is not None
    start = prefix[-1][2] if prefix else next(s for s in an.initial if s in found)
    states = {v[0] for v in found}
    keys = frozenset((s, a, t) for s in states for a, t in out[s])
    if len(keys) > FAIR_CYCLE_LIMIT:
        keys = frozenset()
        stats["fair_cycle"] = False
    cycle = covering_cycle(an.adj, found, start, full, keys, lambda v, a, w: (v[0], a, w[0]))
    actions = tuple(sorted({a for s in states for a, _ in out[s]}))
    return Counterexample(tuple(a for _, a, _ in prefix), tuple(a for _, a, _ in cycle), actions)


def _reachable_ends(lts: LTS, out: dict[int, list[tuple[str, int]]]) -> tuple[int, bool]:
    """Number of reachable states without moves, and whether ERROR is reachable."""
    seen = {lts.initial}
    queue = deque([lts.initial])
    count = 0
    error_reachable = False
    while queue:
        s = queue.popleft()
        if not out[s]:
            count += 1
        for _, t in out[s]:
            if t == ERROR:
                error_reachable = True
            elif t not in seen:
                seen.add(t)
                queue.append(t)
    return count, error_reachable


def _bad_prefix(
    lts: LTS,
    out: dict[int, list[tuple[str, int]]],
    formula: Formula,
    fluents: Mapping[str, Fluent],
    max_states: int,
) -> list[str] | None:
    """Shortest run of ``lts`` that is a bad prefix of ``formula``, or ``None``."""
    pos = FormulaAutomaton(formula, fluents)
    letters = pos.letters(wildcard=True)

    def succ(q):
        for a in letters:
            for q2, m in pos.step(q, a):
                yield a, q2, m

    live = analyse([pos.initial], succ, pos.full_mask, max_nodes=max_states)
    if len(live.live) == len(live.adj) and all(
        pos.step(q, a) for q in live.adj for a in letters
    ):
        return None  # every state is live and total: φ has no bad prefix at all
    start = (lts.initial, frozenset({pos.initial}) & live.live)
    if not start[1]:
        return []  # unsatisfiable: even the empty run is bad
    parent: dict[tuple, tuple | None] = {start: None}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        s, subset = node
        for a, t in out[s]:
            if a == TAU:
                if t == ERROR:
                    continue  # an empty visible extension cannot be a (new) bad prefix
                nxt = subset
            else:
                letter = _visible(a, pos.alphabet)
                nxt = frozenset(q2 for q in subset for q2, _ in pos.step(q, letter)
                                if q2 in live.live)
            if not nxt:
                path = [a]
                cur = node
                while parent[cur] is not None:
                    cur, b = parent[cur]  # type: ignore[misc]
                    path.append(b)
                return path[::-1]
            child = (t, nxt)
            if t != ERROR and child not in parent:
                if len(parent) >= max_states:
                    raise StateLimitExceeded(max_states)
                parent[child] = (node, a)
                queue.append(child)
    return None


def check_assert(
    lts: LTS,
    named: NamedFormula,
    fluents: Mapping[str, Fluent],
    *,
    fair: bool = True,
    max_states: int = DEFAULT_MAX_STATES,
) -> tuple[CheckResult | None, list[Diagnostic]]:
    """:func:`model_check` with diagnostics instead of exceptions for bad input."""
    too_large = limits.formula_too_large(named.formula)
    if too_large is not None:
        return None, [error("E0603", f"assert {named.name}: {too_large}", named.span)]
    try:
        return model_check(lts, named.formula, fluents, fair=fair, max_states=max_states), []
    except UnknownFluentError as exc:
        return None, [error(E_UNKNOWN_FLUENT, f"assert {named.name}: {exc}", named.span)]
    except StateLimitExceeded:
        return None, [error(E_TOO_LARGE, f"checking assert {named.name} on {lts.name} exceeds "
                                         f"{max_states:,} product states (raise the limit "
                                         "with --max-states)", named.span)]
    except RecursionError:  # see safety_lts: a formula nested ~1000 deep is too large an input
        return None, [error(E_TOO_LARGE, f"assert {named.name}: the formula is nested too "
                                         "deeply to check", named.span)]
