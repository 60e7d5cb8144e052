"""The explicit GR(1) solver — a test oracle for tiny slugsin specs (never used by the
compiler; ``tests/gr1`` cross-check the one symbolic engine against it).

Everything is enumerated: states are assignments to inputs and outputs, transitions are
evaluated formula by formula, and the three-nested fixpoint runs on Python sets in its
*transition-based* form ``X := cpre((G_j ∧ Z') ∨ Y' ∨ (¬A_i ∧ X'))`` with plain Z passes (no
feedback, no recycling, no early exits) — deliberately a different route from the symbolic
solver.  Only sensible for a handful of variables (``4^k`` transition evaluations).

:func:`check_strategy` verifies a strategy exhaustively: it builds the graph of
``(state, goal)`` nodes the strategy induces against every legal environment move and
checks that no reachable cycle satisfies all assumptions while missing a guarantee.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from iterplan_compiler.gr1.slugsin import Expr, SlugsSpec
from iterplan_compiler.ir.graphs import strongly_connected

State = tuple[bool, ...]


def evaluate(expr: Expr, cur: dict[str, bool], nxt: dict[str, bool]) -> bool:
    """Value of ``expr`` with unprimed names read from ``cur`` and primed from ``nxt``."""
    memo: dict[int, bool] = {}
    stack: list[tuple[Expr, bool]] = [(expr, False)]
    while stack:
        e, done = stack.pop()
        if id(e) in memo:
            continue
        if e.op == "const":
            memo[id(e)] = e.value
        elif e.op == "var":
            memo[id(e)] = (nxt if e.primed else cur)[e.name]
        elif not done:
            stack.append((e, True))
            stack.extend((a, False) for a in e.args)
        else:
            v = [memo[id(a)] for a in e.args]
            memo[id(e)] = (not v[0]) if e.op == "not" else (
                v[0] and v[1] if e.op == "and" else v[0] or v[1] if e.op == "or"
                else v[0] != v[1])
    return memo[id(expr)]


@dataclass
class ExplicitGame:
    """Enumerated game: ``states`` are (inputs+outputs) value tuples."""

    spec: SlugsSpec
    names: tuple[str, ...]
    nx: int
    states: list[State]

    def asg(self, s: State) -> dict[str, bool]:
        return dict(zip(self.names, s, strict=True))

    def holds(self, section: str, s: State, t: State | None = None) -> bool:
        cur = self.asg(s)
        nxt = self.asg(t) if t is not None else {}
        return all(evaluate(line.expr, cur, nxt) for line in self.spec.lines(section))

    def lives(self, section: str) -> list[Expr | None]:
        return [line.expr for line in self.spec.lines(section)] or [None]


def explicit_game(spec: SlugsSpec) -> ExplicitGame:
    names = tuple(spec.inputs) + tuple(spec.outputs)
    states = [tuple(bits) for bits in itertools.product((False, True), repeat=len(names))]
    return ExplicitGame(spec, names, len(spec.inputs), states)


def _live(game: ExplicitGame, expr: Expr | None, s: State, t: State) -> bool:
    return True if expr is None else evaluate(expr, game.asg(s), game.asg(t))


def _target(g_val: dict[tuple[int, State, State], bool],
            a_val: dict[tuple[int, State, State], bool], j: int, i: int, Z: set[State],
            Y: set[State], X: set[State]) -> Callable[[State, State], bool]:
    """The transition target ``(G_j ∧ Z') ∨ Y' ∨ (¬A_i ∧ X')`` as a predicate."""
    def target(s: State, t: State) -> bool:
        return (g_val[(j, s, t)] and t in Z) or t in Y or (not a_val[(i, s, t)] and t in X)

    return target


def solve_explicit(spec: SlugsSpec) -> tuple[bool, set[State]]:
    """Return ``(realizable, winning states)`` by brute force."""
    game = explicit_game(spec)
    nx = game.nx
    xs = sorted({s[:nx] for s in game.states})
    ys = sorted({s[nx:] for s in game.states})
    env_ok = {(s, xp): game.holds("ENV_TRANS", s, xp + ys[0]) for s in game.states for xp in xs}
    sys_ok = {(s, t): game.holds("SYS_TRANS", s, t) for s in game.states for t in game.states}
    A = game.lives("ENV_LIVENESS")
    G = game.lives("SYS_LIVENESS")
    a_val = {(i, s, t): _live(game, a, s, t) for i, a in enumerate(A)
             for s in game.states for t in game.states}
    g_val = {(j, s, t): _live(game, g, s, t) for j, g in enumerate(G)
             for s in game.states for t in game.states}

    def cpre(target: Callable[[State, State], bool]) -> set[State]:
        out = set()
        for s in game.states:
            if all(not env_ok[(s, xp)] or any(sys_ok[(s, xp + yp)] and target(s, xp + yp)
                                               for yp in ys) for xp in xs):
                out.add(s)
        return out

    Z = set(game.states)
    while True:
        z_new = set(game.states)
        for j in range(len(G)):
            Y: set[State] = set()
            while True:
                y_new: set[State] = set()
                for i in range(len(A)):
                    X = set(Z)
                    while True:
                        x_new = cpre(_target(g_val, a_val, j, i, Z, Y, X))
                        if x_new == X:
                            break
                        X = x_new
                    y_new |= X
                if y_new == Y:
                    break
                Y = y_new
            z_new &= Y
        if z_new == Z:
            break
        Z = z_new
    realizable = all(
        not game.holds("ENV_INIT", x + ys[0])
        or any(game.holds("SYS_INIT", x + y) and (x + y) in Z for y in ys)
        for x in xs)
    return realizable, Z


def check_strategy(spec: SlugsSpec, strategy: Any) -> list[str]:
    """Exhaustively verify ``strategy`` (a :class:`~iterplan_compiler.gr1.strategy.Strategy`)
    on the explicit game; return a list of problems (empty = correct)."""
    game = explicit_game(spec)
    nx = game.nx
    xs = sorted({s[:nx] for s in game.states})
    ys = sorted({s[nx:] for s in game.states})
    problems: list[str] = []
    init: list[tuple[State, int]] = []
    for x in xs:
        if not game.holds("ENV_INIT", x + ys[0]):
            continue
        out = strategy.initial(dict(zip(spec.inputs, x, strict=True)))
        if out is None:
            problems.append(f"no initial output for inputs {x}")
            continue
        s = x + tuple(out[n] for n in spec.outputs)
        if not game.holds("SYS_INIT", s):
            problems.append(f"initial state {s} violates SYS_INIT")
        init.append((s, 0))
    edges: dict[tuple[State, int], list[tuple[State, int]]] = {}
    edge_state: dict[tuple[tuple[State, int], tuple[State, int]], tuple[State, State]] = {}
    seen = set(init)
    work = list(init)
    while work and not problems:
        node = work.pop()
        s, goal = node
        succ = []
        for xp in xs:
            if not game.holds("ENV_TRANS", s, xp + ys[0]):
                continue
            res = strategy.step(game.asg(s), goal, dict(zip(spec.inputs, xp, strict=True)))
            if res is None:
                problems.append(f"no move in {s} (goal {goal}) for inputs {xp}")
                break
            out, g2 = res
            t = xp + tuple(out[n] for n in spec.outputs)
            if not game.holds("SYS_TRANS", s, t):
                problems.append(f"move {s} -> {t} violates SYS_TRANS")
                break
            nxt = (t, g2)
            succ.append(nxt)
            edge_state[(node, nxt)] = (s, t)
            if nxt not in seen:
                seen.add(nxt)
                work.append(nxt)
        edges[node] = succ
    if problems:
        return problems
    A = game.lives("ENV_LIVENESS")
    G = game.lives("SYS_LIVENESS")
    # A bad cycle misses some G_j and visits every A_i: it lies in one SCC of the graph
    # without G_j-edges, and that SCC contains an A_i-edge for every i.
    for j, g in enumerate(G):
        keep = {(u, v) for u in edges for v in edges[u]
                if not _live(game, g, *edge_state[(u, v)])}
        def kept_succ(u: tuple[State, int], keep: set[Any] = keep) -> list[tuple[State, int]]:
            return [v for v in edges[u] if (u, v) in keep]

        for comp in _sccs(edges.keys(), kept_succ):
            inner = [(u, v) for u in comp for v in edges[u] if v in comp and (u, v) in keep]
            if not inner:
                continue
            if all(any(_live(game, a, *edge_state[e]) for e in inner) for a in A):
                problems.append(f"fair cycle through {sorted(comp)[:3]} misses goal {j}")
    return problems


def _sccs(nodes: Iterable[Any], succ: Callable[[Any], list[Any]]) -> list[set[Any]]:
    """Tarjan's SCCs (:func:`~iterplan_compiler.ir.graphs.strongly_connected`)."""
    return [set(c) for c in strongly_connected(nodes, succ)]

