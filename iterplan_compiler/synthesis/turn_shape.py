"""The shape of a turn-based game, from its explicit machines: conditions 1–3 of
:mod:`turns` (a turn component, chain moves that commute and where the last one wins, a turn
budget) and the turn groups of each side in their canonical order."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from iterplan_compiler.ir.lts import ERROR, LTS
from iterplan_compiler.synthesis.partition import Group, group_over
from iterplan_compiler.synthesis.symbolic_game import SymbolicGame

__all__ = ["TurnShape", "find_turns"]

Node = Any
#: a budget machine is a small counter (``Turns(N)``: N + 1 states); larger machines are
#: not tried (the path search below is recursive)
MAX_BUDGET_STATES = 512


@dataclass(frozen=True)
class TurnShape:
    """What :func:`find_turns` found on the explicit machines."""

    clock: int
    env_states: frozenset[int]   # the clock's environment-turn states
    env_chain: tuple[Group, ...]
    sys_chain: tuple[Group, ...]
    env_exit: tuple[Group, ...]
    sys_exit: tuple[Group, ...]
    budget: tuple[int, ...]      # the budget machines (``Turns``)
    env_once: tuple[bool, ...]   # per environment group: "last wins" holds (one step)


def _succ(c: LTS) -> dict[tuple[int, str], frozenset[int]]:
    out: dict[tuple[int, str], set[int]] = {}
    for s, a, t in c.transitions:
        out.setdefault((s, a), set()).add(t)
    return {k: frozenset(v) for k, v in out.items()}


def _clock_sides(c: LTS, ctrl: frozenset[str]) -> frozenset[int] | None:
    """The environment-turn states of a turn component, or None if ``c`` is not one."""
    env: set[int] = set()
    for s in range(c.num_states):
        kinds = {a in ctrl for s2, a, _ in c.transitions if s2 == s}
        if len(kinds) != 1:
            return None
        if kinds == {False}:
            env.add(s)
    return frozenset(env)


def _action_kinds(c: LTS, env: frozenset[int]) -> dict[str, bool] | None:
    """``{action: crosses}`` for the turn component ``c`` (None if an action does both)."""
    kinds: dict[str, set[bool]] = {}
    for s, a, t in c.transitions:
        if t == ERROR:
            return None
        kinds.setdefault(a, set()).add((s in env) != (t in env))
    if any(len(k) != 1 for k in kinds.values()):
        return None
    return {a: next(iter(k)) for a, k in kinds.items()}


def _live(succ: dict[tuple[int, str], frozenset[int]], s: int, a: str) -> frozenset[int]:
    return succ.get((s, a), frozenset()) - {ERROR}


def _then(succ: dict[tuple[int, str], frozenset[int]], c: LTS, s: int,
          a: str, b: str) -> frozenset[int]:
    """States of ``c`` after ``a`` then ``b`` from ``s`` (an action ``c`` does not own
    leaves it where it is), ERROR left out."""
    mid = _live(succ, s, a) if a in c.alphabet else frozenset([s])
    out: set[int] = set()
    for m in mid:
        out |= _live(succ, m, b) if b in c.alphabet else {m}
    return frozenset(out)


def _commuting(comps: Sequence[LTS], acts: Sequence[str]) -> str | set[tuple[str, str]]:
    """The pairs of ``acts`` (``a < b``) that do *not* commute in some machine (condition
    2; ERROR moves left out), or why the check fails (a nondeterministic chain action)."""
    bad: set[tuple[str, str]] = set()
    for c in comps:
        mine = sorted(set(acts) & c.alphabet)
        if not mine:
            continue
        succ = _succ(c)
        if any(len(_live(succ, s, a)) > 1 for s in range(c.num_states) for a in mine):
            return f"{c.name}: a chain action is nondeterministic"
        # a pair with one action outside ``c``'s alphabet commutes in ``c`` (the other
        # one leaves it where it is), so only pairs of ``c``'s own are checked
        for a, b in itertools.combinations(mine, 2):
            if (a, b) not in bad and any(_then(succ, c, s, a, b) != _then(succ, c, s, b, a)
                                         for s in range(c.num_states)):
                bad.add((a, b))
    return bad


def _last_wins(comps: Sequence[LTS], grp: Group) -> str | None:
    """Condition 2 inside a group: ``a;a'`` reaches only states ``a'`` reaches (or why
    not)."""
    for c in comps:
        mine = [a for a in grp.actions if a in c.alphabet]
        if not mine:
            continue
        succ = _succ(c)
        # ``a`` outside the alphabet: ``a;b`` is ``b`` alone in ``c``
        for a, b in itertools.product(mine, mine):
            for s in range(c.num_states):
                if not _then(succ, c, s, a, b) <= _live(succ, s, b):
                    return f"{c.name}: {a} then {b} is not {b} alone"
    return None


def _merged(g: SymbolicGame, groups: Sequence[Group], apart: set[tuple[str, str]]
            ) -> list[Group]:
    """The turn groups of one side: partition groups with actions that do not commute
    merged (so every two turn groups commute); a merged relation frames each part's
    relation to the union of their variables."""
    b = g.bdd
    root = list(range(len(groups)))

    def find(i: int) -> int:
        while root[i] != i:
            i = root[i]
        return i

    where = {a: i for i, grp in enumerate(groups) for a in grp.actions}
    for a, c in sorted(apart):
        root[find(where[a])] = find(where[c])
    classes: dict[int, list[Group]] = {}
    for i, grp in enumerate(groups):
        classes.setdefault(find(i), []).append(grp)
    out = []
    for parts in classes.values():
        if len(parts) == 1:
            out.append(parts[0])
            continue
        owners = tuple(sorted({k for grp in parts for k in grp.owners}))
        allv = {v for k in owners for v in g.cur[k].names}
        rel = b.false
        for grp in parts:
            frame = b.true
            for v in sorted(allv - grp.cur_vars):
                frame &= b.var(v).equiv(b.var(g.prime[v]))
            rel |= grp.rel & frame
        out.append(group_over(g.vars, owners, parts[0].controllable,
                              tuple(a for grp in parts for a in grp.actions), rel))
    return out


def _longest(step: Sequence[frozenset[int]], s: int, seen: frozenset[int],
             depth: dict[int, int]) -> int | None:
    """The longest ``step`` path from ``s`` (memo ``depth``: every state met), or None on
    a cycle."""
    if s in seen:
        return None
    if s not in depth:
        best = 0
        for t in step[s]:
            d = _longest(step, t, seen | {s}, depth)
            if d is None:
                return None
            best = max(best, d + 1)
        depth[s] = best
    return depth[s]


def _budget(comps: Sequence[LTS], ctrl: frozenset[str], chain: set[str],
            exits: set[str], m: int) -> tuple[int, ...]:
    """Condition 3: the budget machines (usually one, ``Turns``)."""
    out = []
    for k, c in enumerate(comps):
        if c.alphabet - ctrl or not (chain | exits) <= c.alphabet or \
                c.num_states > MAX_BUDGET_STATES:
            continue
        succ = _succ(c)
        moves = [{_live(succ, s, a) for a in chain} for s in range(c.num_states)]
        if any(len(mv) != 1 for mv in moves):
            continue
        step = [next(iter(mv)) for mv in moves]
        depth: dict[int, int] = {}
        n = _longest(step, c.initial, frozenset(), depth)
        inside = set(depth)
        if n is None or n < m:
            continue
        if all(_live(succ, s, x) == {c.initial} for s in inside for x in exits):
            out.append(k)
    return tuple(out)


def _clock(comps: Sequence[LTS], ctrl: frozenset[str], acts: set[str]
           ) -> tuple[int, frozenset[int], dict[str, bool]] | None:
    """Condition 1: the turn component, its environment-turn states, its action kinds."""
    for k, c in enumerate(comps):
        if not acts <= c.alphabet:
            continue
        env = _clock_sides(c, ctrl)
        kinds = _action_kinds(c, env) if env is not None else None
        if env is not None and kinds is not None and acts <= set(kinds):
            return k, env, kinds
    return None


def find_turns(g: SymbolicGame) -> TurnShape | str:
    """Conditions 1–3 of the module doc on the game's machines and partition groups;
    the shape, or why it does not apply."""
    spec = g.spec
    comps = spec.components
    ctrl = frozenset(spec.controllable)
    acts = {a for grp in g.owner_groups for a in grp.actions}
    found = _clock(comps, ctrl, acts)
    if found is None:
        return "no turn component"
    clock, env, kinds = found
    sides: dict[tuple[bool, bool], list[Group]] = {}
    for grp in g.owner_groups:
        ks = {kinds[a] for a in grp.actions}
        if len(ks) != 1:
            return "a partition group mixes chain and exit moves"
        sides.setdefault((grp.controllable, ks.pop()), []).append(grp)
    env_exit, sys_exit = sides.get((False, True), []), sides.get((True, True), [])
    chains = []
    for side in (False, True):
        groups = sides.get((side, False), [])
        apart = _commuting(comps, [a for grp in groups for a in grp.actions])
        if isinstance(apart, str):
            return apart
        chains.append(_merged(g, groups, apart))
    env_chain, sys_chain = chains
    chain = {a for grp in sys_chain for a in grp.actions}
    exits = {a for grp in sys_exit for a in grp.actions}
    budget = _budget(comps, ctrl, chain, exits, len(sys_chain)) if chain else ()
    if chain and not budget:
        return "no turn budget (a system turn could go on for ever)"
    # the budget moves alike on every chain action (so they commute there); its own
    # "last wins" is not needed: its variables are projected (condition 3)
    rest = [c for k, c in enumerate(comps) if k not in budget]
    for grp in sys_chain:
        why = _last_wins(rest, grp)
        if why is not None:
            return why
    env_order = _canonical(env_chain)
    env_once = tuple(_last_wins(rest, grp) is None for grp in env_order)
    others = {v for k, vec in enumerate(g.cur) if k not in budget for v in vec.names}
    if any(v in others for k in budget for v in g.cur[k].names):
        return "the turn budget shares a variable with another machine"
    return TurnShape(clock, env, env_order, _canonical(sys_chain),
                     tuple(env_exit), tuple(sys_exit), budget, env_once)


def _canonical(groups: list[Group]) -> tuple[Group, ...]:
    """The canonical order of a side's chain groups (any order is exact, condition 2): the
    largest relation last, so that the backward steps start with it while the set is
    still small (GyroLTL_595 measured, see docs/synthesis.md)."""
    return tuple(sorted(groups, key=lambda grp: len(grp.rel)))
