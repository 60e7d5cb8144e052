"""Controller extraction (§3.6) and the supervisory non-blocking game (§3.9).

``extract_controller`` follows MTSA's ``GRControllerSynthesis`` rule exactly: memory = index of
the pursued guarantee; from ``(s, j)`` every uncontrollable successor is kept and every
*better* controllable successor (by MTSA's ranks).  The result is an explicit LTS over the
full plant alphabet; it never blocks an uncontrollable action of a winning state.

With the spec's ``permissive`` flag it additionally keeps the controllable moves to *winning*
but not better successors, relabelled ``#w#_<label>`` (:data:`PERMISSIVE_PREFIX`), so that
deleting every ``#w#_`` transition gives back the ordinary controller.
"""

from __future__ import annotations

import enum
from collections import deque

from iterplan_compiler.ir.lts import LTS, make_lts
from iterplan_compiler.synthesis.explicit import ExplicitGame, Ranks

#: label prefix of the extra moves a ``permissive`` controller keeps (MTSA's tests look for
#: ``#w#_c``)
PERMISSIVE_PREFIX = "#w#_"


class StrategyKind(enum.Enum):
    """Which strategy a realizable GR(1) game yields (chosen by ``driver.strategy_kind``).

    ``PERMISSIVE`` — MTSA's controller of §3.6: every uncontrollable move and *every* better
    controllable one (``controller`` composites); ``DIRECTOR`` — the same rule, but of the
    better controllable moves only the one of least rank towards the pursued guarantee
    (``heuristic`` composites: MTSA's DCS returns a director, §3.9)."""

    PERMISSIVE = "permissive"
    DIRECTOR = "director"

    def __str__(self) -> str:
        return self.value

# The symbolic solver (``game.solve_symbolic``) calls :func:`extract_controller` without a
# ``permissive`` argument; the driver sets this variable around the solve so both solvers
# honour the spec flag.  An explicit ``permissive=`` argument always wins.
def extract_controller(game: ExplicitGame, ranks: Ranks, name: str,
                       alphabet: frozenset[str], *, permissive: bool = False,
                       kind: StrategyKind = StrategyKind.PERMISSIVE) -> LTS:
    """MTSA's memoryful controller (§3.6) as an LTS; requires the initial state to win.

    ``permissive`` (the spec's ``permissive`` flag) also keeps, from ``(s, j)``, every controllable move ``s -a-> t`` whose target is not an
    allowed successor but is winning for the next memory (``rank[j'][t] ≠ ∞``), as the
    transition ``(s, j) -#w#_a-> (t, j')``.  Those labels are added to the alphabet.  Without
    the flag the result is exactly the non-permissive controller.

    ``kind=DIRECTOR``: of the better controllable moves only the one of least rank (towards
    ``j'`` from a "may increase" state), ties by label — the director of
    ``symbolic_strategy`` (module doc there), on the explicit game.
    """
    if not ranks.winning(game.initial):
        raise ValueError("initial state is losing: no controller")
    G, F = game.guarantees, game.failures
    n = len(G)
    m = ranks.m
    ctrl = game.controllable
    A = game.assumptions
    rank, inf = ranks.rank, ranks.inf

    def allowed(s: int, j: int) -> tuple[int, set[int], tuple[int, str, int] | None]:
        jn = (j + 1) % n if s in G[j] else j
        may_increase = s in G[j] or s in F
        ok: set[int] = set()
        rs = rank[j][s]
        for a, t in game.edges[s]:
            if a not in ctrl:
                ok.add(t)
            elif may_increase:
                if rank[jn][t] < inf[jn]:
                    ok.add(t)
            else:
                rt = rank[j][t]
                if rt < rs or (rt == rs and s not in A[rs % m]):
                    ok.add(t)
        if kind is StrategyKind.DIRECTOR:  # the one controllable move kept: ``best``
            r = rank[jn] if may_increase else rank[j]
            best = min(((r[t], a, t) for a, t in game.edges[s] if a in ctrl and t in ok),
                       default=None)
            return jn, set(), best
        return jn, ok, None

    start = (game.initial, 0)
    index = {start: 0}
    order = [start]
    trans: list[tuple[int, str, int]] = []
    extra: set[str] = set()
    q = deque([start])
    while q:
        s, j = q.popleft()
        k = index[(s, j)]
        jn, ok, best = allowed(s, j)
        for a, t in game.edges[s]:
            label = a
            if kind is StrategyKind.DIRECTOR:
                if a in ctrl and (best is None or (a, t) != best[1:]):
                    continue
            elif t not in ok:
                # a target reachable by an uncontrollable label is always in ``ok``, so an
                # excluded target is reached only by controllable labels here
                if not (permissive and a in ctrl and rank[jn][t] < inf[jn]):
                    continue
                label = PERMISSIVE_PREFIX + a
                extra.add(label)
            key = (t, jn)
            if key not in index:
                index[key] = len(order)
                order.append(key)
                q.append(key)
            trans.append((k, label, index[key]))
    names = [f"{s}.{j}" for s, j in order]
    return make_lts(name, len(order), trans, alphabet | extra, 0, (), names)


# ---------------------------------------------------------------------------------------------
# §3.9 non-blocking (supervisory) semantics


def nonblocking_region(game: ExplicitGame, marked: frozenset[int]) -> frozenset[int]:
    """Greatest set ``Z`` of states that are safe and co-reachable to ``marked`` inside ``Z``.

    Safe: not a dead end, every uncontrollable successor in ``Z``, and a controller-owned state
    keeps some controllable successor in ``Z``.  Co-reachable: some path inside ``Z`` (any
    labels) reaches a marked state of ``Z`` — non-blocking is a *possibility* requirement.
    """
    ctrl = game.controllable
    Z = {s for s in range(game.num_states) if game.edges[s] and s != game.error}
    while True:
        safe = set()
        for s in Z:
            unc = [t for a, t in game.edges[s] if a not in ctrl]
            if game.env[s]:
                if all(t in Z for t in unc):
                    safe.add(s)
            elif any(t in Z for a, t in game.edges[s] if a in ctrl):
                safe.add(s)
        # co-reachability to marked inside safe
        preds: dict[int, list[int]] = {}
        for s in safe:
            for a, t in game.edges[s]:
                if t in safe and (a not in ctrl or True):
                    preds.setdefault(t, []).append(s)
        co = {s for s in safe if s in marked}
        q = deque(co)
        while q:
            t = q.popleft()
            for p in preds.get(t, ()):
                if p not in co:
                    co.add(p)
                    q.append(p)
        if co == Z:
            return frozenset(Z)
        Z = co


def extract_director(game: ExplicitGame, region: frozenset[int], marked: frozenset[int],
                     name: str, alphabet: frozenset[str]) -> LTS:
    """A director: all uncontrollable moves inside ``region``; in controller-owned states the
    single controllable move (smallest label) towards the closest marked state."""
    ctrl = game.controllable
    dist = {s: 0 for s in region if s in marked}
    frontier = deque(dist)
    rev: dict[int, list[int]] = {}
    for s in region:
        for _, t in game.edges[s]:
            if t in region:
                rev.setdefault(t, []).append(s)
    while frontier:
        t = frontier.popleft()
        for p in rev.get(t, ()):
            if p not in dist:
                dist[p] = dist[t] + 1
                frontier.append(p)
    index = {game.initial: 0}
    order = [game.initial]
    trans = []
    q = deque([game.initial])
    while q:
        s = q.popleft()
        keep = [(a, t) for a, t in game.edges[s] if a not in ctrl and t in region]
        if not game.env[s]:
            cands = sorted((dist.get(t, 1 << 30), a, t) for a, t in game.edges[s]
                           if a in ctrl and t in region)
            if cands:
                keep.append((cands[0][1], cands[0][2]))
        for a, t in keep:
            if t not in index:
                index[t] = len(order)
                order.append(t)
                q.append(t)
            trans.append((index[s], a, index[t]))
    return make_lts(name, len(order), trans, alphabet, 0, (), [str(s) for s in order])
