"""Explicit-state game construction and MTSA's rank-based GR(1) solver (§3.3–3.6).

This is the small, obviously-correct reference: it composes the :class:`GameSpec` components
explicitly (§2.5 product with ERROR propagation), computes MTSA's least rank function
(§3.5) and its winning region.  :mod:`strategy` extracts controllers from the ranks; the
symbolic engine reuses that extraction on the winning subgame it enumerates, so both solvers
produce MTSA's controller.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from itertools import product as _cartesian

from iterplan_compiler.ir.lts import ERROR, LTS, TAU, make_lts
from iterplan_compiler.synthesis.encode import GameSpec, evaluate
from iterplan_compiler.synthesis.options import GameMode

Edge = tuple[str, int]  # (label, target game state)


class StateExplosion(Exception):
    """The explicit product exceeded ``max_states``."""


@dataclass
class ExplicitGame:
    """A game graph (§3.3).  State ``error`` (if not None) is the single ERROR dead end.

    ``tuples[s]`` is the component-state tuple of game state ``s`` (None for ERROR);
    ``edges[s]`` lists ``(label, target)``; ``env[s]`` is True iff ``s`` has an uncontrollable
    outgoing edge; ``assumptions[i]``/``guarantees[j]``/``failures`` are state sets (never
    containing ERROR); empty assumption/guarantee lists are already replaced by one
    all-states set.
    """

    num_states: int
    initial: int
    edges: list[list[Edge]]
    env: list[bool]
    controllable: frozenset[str]
    assumptions: list[frozenset[int]]
    guarantees: list[frozenset[int]]
    failures: frozenset[int]
    alphabet: frozenset[str]
    tuples: list[tuple[int, ...] | None] = field(default_factory=list)
    error: int | None = None
    mode: GameMode = GameMode.GR1


def _component_index(c: LTS) -> dict[int, dict[str, list[int]]]:
    out: dict[int, dict[str, list[int]]] = {}
    for s, a, t in c.transitions:
        out.setdefault(s, {}).setdefault(a, []).append(t)
    return out


class ProductMoves:
    """The moves of a synchronous product (§2.5) from one component-state tuple, computed from
    the components' own transition lists — no product is built.  ``moves(cur)`` lists
    ``(label, next tuple)`` with ``None`` for a move into ERROR."""

    def __init__(self, components: Sequence[LTS]) -> None:
        self.idx = [_component_index(c) for c in components]
        alphabet: set[str] = set()
        self.owners: dict[str, list[int]] = {}
        for k, c in enumerate(components):
            alphabet |= c.alphabet
            for a in c.alphabet:
                self.owners.setdefault(a, []).append(k)
        self.alphabet = frozenset(alphabet)
        self.actions = sorted(alphabet)
        self.n = len(components)
        self.start = tuple(c.initial for c in components)

    def moves(self, cur: tuple[int, ...]) -> list[tuple[str, tuple[int, ...] | None]]:
        """Unsorted moves of ``cur``: only the actions its first owner enables are tried."""
        idx = self.idx
        owners = self.owners
        out: list[tuple[str, tuple[int, ...] | None]] = []
        for k0 in range(self.n):
            for a in idx[k0].get(cur[k0], ()):
                if a == TAU:
                    continue
                parts = owners[a]
                if parts[0] != k0:
                    continue
                self._sync(cur, a, parts, out)
        self._tau_moves(cur, out)
        return out

    def _tau_moves(self, cur: tuple[int, ...],
                   out: list[tuple[str, tuple[int, ...] | None]]) -> None:
        """Each component's own ``tau`` moves from ``cur`` (after the synchronised ones)."""
        for k in range(self.n):
            for t in self.idx[k].get(cur[k], {}).get(TAU, ()):
                out.append((TAU, None if t == ERROR else with_locals(cur, (k,), (t,))))

    def _sync(self, cur: tuple[int, ...], a: str, parts: list[int],
              out: list[tuple[str, tuple[int, ...] | None]]) -> None:
        idx = self.idx
        choices = []
        for k in parts:
            ts = idx[k].get(cur[k], {}).get(a)
            if not ts:
                return
            choices.append(ts)
        for combo in _cartesian(*choices):
            out.append((a, None if ERROR in combo else with_locals(cur, parts, combo)))


def with_locals(cur: tuple[int, ...], parts: Sequence[int], local: Sequence[int]
                ) -> tuple[int, ...]:
    """``cur`` with component ``parts[i]`` in local state ``local[i]``."""
    nxt = list(cur)
    for k, t in zip(parts, local, strict=True):
        nxt[k] = t
    return tuple(nxt)


def explore_product(
    components: Sequence[LTS], *, max_states: int | None = None,
    expand: Callable[[tuple[int, ...]], bool] | None = None,
) -> tuple[list[tuple[int, ...]], list[list[tuple[str, int]]], frozenset[str]]:
    """Reachable synchronous product (§2.5), BFS order; target ``ERROR`` (-1) for error moves.

    Returns ``(tuples, edges, alphabet)`` where ``edges[k]`` holds ``(label, target_index)``.
    With ``expand``, only tuples for which it is True are expanded (the others get an index
    but no edges) — used to explore just the winning part of a game.
    """
    pm = ProductMoves(components)
    tuples = [pm.start]
    index = {pm.start: 0}
    edges: list[list[tuple[str, int]]] = []
    i = 0
    while i < len(tuples):
        cur = tuples[i]
        i += 1
        out: list[tuple[str, int]] = []
        if expand is not None and not expand(cur):
            edges.append(out)
            continue
        for a, tgt in pm.moves(cur):
            if tgt is None:
                out.append((a, ERROR))
                continue
            j = index.get(tgt)
            if j is None:
                j = len(tuples)
                if max_states is not None and j >= max_states:
                    raise StateExplosion(f"more than {max_states} states")
                index[tgt] = j
                tuples.append(tgt)
            out.append((a, j))
        edges.append(sorted(set(out)))
    return tuples, edges, pm.alphabet


def compose_explicit(components: Sequence[LTS], name: str, *,
                     max_states: int | None = None) -> LTS:
    """Parallel composition of ``components`` as an :class:`LTS` (reachable part)."""
    tuples, edges, alphabet = explore_product(components, max_states=max_states)
    trans = [(s, a, t) for s, out in enumerate(edges) for a, t in out]
    return make_lts(name, len(tuples), trans, alphabet)


def build_game(spec: GameSpec, *, max_states: int | None = None) -> ExplicitGame:
    """The explicit game graph of ``spec`` (reachable states + one ERROR state)."""
    tuples, pedges, alphabet = explore_product(spec.components, max_states=max_states)
    n = len(tuples)
    has_error = any(t == ERROR for out in pedges for _, t in out)
    error = n if has_error else None
    all_tuples: list[tuple[int, ...] | None] = list(tuples)
    edges: list[list[Edge]] = [[(a, error if t == ERROR else t) for a, t in out]  # type: ignore[misc]
                               for out in pedges]
    if has_error:
        all_tuples.append(None)
        edges.append([])
    total = len(edges)
    ctrl = spec.controllable
    env = [any(a not in ctrl for a, _ in edges[s]) for s in range(total)]
    fl_idx = {name: spec.fluent_component(name) for name in spec.fluent_names}

    def state_set(formulas: Sequence) -> list[frozenset[int]]:
        out = []
        for f in formulas:
            members = set()
            for s, tup in enumerate(tuples):
                val = {name: tup[k] == 1 for name, k in fl_idx.items()}
                if evaluate(f, val):
                    members.add(s)
            out.append(frozenset(members))
        return out

    everything = frozenset(range(n))
    assumptions = state_set(spec.assumptions) or [everything]
    guarantees = state_set(spec.guarantees) or [everything]
    fails = state_set(spec.failures)
    failures = frozenset().union(*fails) if fails else frozenset()
    return ExplicitGame(total, 0, edges, env, ctrl, assumptions, guarantees, failures,
                        alphabet, all_tuples, error, spec.mode)


# ---------------------------------------------------------------------------------------------
# §3.5 — least rank function


@dataclass
class Ranks:
    """MTSA's ranks: ``rank[j][s]`` is an int ``v*m + a`` (0-based ``a``); ``inf[j]`` is ∞_j."""

    rank: list[list[int]]
    inf: list[int]
    m: int

    def winning(self, s: int) -> bool:
        return self.rank[0][s] < self.inf[0]


def solve_ranks(game: ExplicitGame, *, candidates: Callable[[int], bool] | None = None,
                heights: Sequence[int] | None = None) -> Ranks:
    """Compute MTSA's least rank function (§3.5) by a work-list iteration.

    Encoding ranks ``(v, a)`` as ``v*m + a`` makes ``inc`` an integer increment and the
    lexicographic order the integer order; ∞_j = ``H_j * m``.  ``candidates(s)`` False puts
    ``s`` at ∞ from the start (known losing); ``heights`` overrides ``H_j`` (the symbolic
    path ranks a subgame but must use the full game's ``H_j`` to reproduce MTSA).
    """
    n_st = game.num_states
    A, G, F = game.assumptions, game.guarantees, game.failures
    m, n = len(A), len(G)
    goal = [G[j] | F for j in range(n)]
    H = list(heights) if heights is not None else \
        [1 + max(len(a - goal[j]) for a in A) for j in range(n)]
    inf = [H[j] * m for j in range(n)]
    ctrl = game.controllable
    # the edges that matter for the owner of each state (§3.3)
    succ: list[list[int]] = []
    for s in range(n_st):
        if game.env[s]:
            succ.append(sorted({t for a, t in game.edges[s] if a not in ctrl}))
        else:
            succ.append(sorted({t for a, t in game.edges[s] if a in ctrl}))
    preds: list[list[int]] = [[] for _ in range(n_st)]
    for s in range(n_st):
        for t in succ[s]:
            preds[t].append(s)
    in_a = [[s in A[i] for s in range(n_st)] for i in range(m)]
    rank = [[0] * n_st for _ in range(n)]
    for s in range(n_st):
        if not succ[s] or (candidates is not None and not candidates(s)):
            for j in range(n):
                rank[j][s] = inf[j]

    def best(s: int, j: int) -> int:
        jn = (j + 1) % n if s in goal[j] else j
        rs = rank[jn]
        if game.env[s]:
            b = max(rs[t] for t in succ[s])
        else:
            b = min(rs[t] for t in succ[s])
        if s in goal[j]:
            return inf[j] if b >= inf[jn] else 0
        if b >= inf[j]:
            return inf[j]
        if in_a[b % m][s]:
            return b + 1
        return b

    work = list(range(n_st))
    queued = [True] * n_st
    while work:
        s = work.pop()
        queued[s] = False
        if rank[0][s] >= inf[0] or not succ[s]:
            continue
        changed = False
        for j in range(n):
            if rank[j][s] >= inf[j]:
                continue
            b = best(s, j)
            if b > rank[j][s]:
                changed = True
                if b >= inf[j]:
                    for jj in range(n):
                        rank[jj][s] = inf[jj]
                    break
                rank[j][s] = b
        if changed:
            for p in preds[s]:
                if not queued[p]:
                    queued[p] = True
                    work.append(p)
            if not queued[s]:  # own other j's may depend on the new value via self-loops
                queued[s] = True
                work.append(s)
    return Ranks(rank, inf, m)


def winning_region(game: ExplicitGame) -> frozenset[int]:
    """Winning states of the GR(1) game (via ranks)."""
    r = solve_ranks(game)
    return frozenset(s for s in range(game.num_states) if r.winning(s))
