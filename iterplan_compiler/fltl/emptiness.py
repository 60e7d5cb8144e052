"""Emptiness of transition-based generalised Büchi graphs, with lasso witnesses.

A graph is given implicitly by initial nodes and a successor function returning
``(label, target, mask)`` triples; ``full_mask`` is the union of the acceptance bits.  An SCC is
*accepting* iff it has an internal edge and its internal edges together carry every bit of
``full_mask``.  SCCs come from networkx (iterative, so product graphs may be deep).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Hashable, Iterable
from dataclasses import dataclass

import networkx as nx

from iterplan_compiler import limits

Edge = tuple[str, Hashable, int]
Successors = Callable[[Hashable], Iterable[Edge]]


class StateLimitExceeded(Exception):
    """The explored graph grew beyond ``max_nodes``."""


@dataclass
class Analysis:
    """Result of :func:`analyse`: the explored graph and its SCC structure."""

    initial: list[Hashable]
    adj: dict[Hashable, list[Edge]]
    scc_of: dict[Hashable, int]
    sccs: list[list[Hashable]]  # reverse topological: successors' SCCs come first
    accepting: list[bool]
    live: set[Hashable]  # nodes from which an accepting SCC is reachable


def analyse(
    initial: Iterable[Hashable],
    successors: Successors,
    full_mask: int,
    *,
    max_nodes: int | None = None,
) -> Analysis:
    """Explore everything reachable from ``initial`` and classify SCCs.

    Exploration is breadth-first (raising :class:`StateLimitExceeded` past ``max_nodes``
    expanded nodes); the SCC decomposition and its topological order come from networkx's
    iterative algorithms (no recursion limit on deep product graphs).  Orders are made
    deterministic through the breadth-first discovery index, never through hashing, so
    counterexamples do not depend on ``PYTHONHASHSEED``.
    """
    initial = list(dict.fromkeys(initial))
    adj: dict[Hashable, list[Edge]] = {}
    order: dict[Hashable, int] = {v: i for i, v in enumerate(initial)}
    queue: deque[Hashable] = deque(initial)
    while queue:
        v = queue.popleft()
        es = list(successors(v))
        adj[v] = es
        if max_nodes is not None and len(adj) > max_nodes:
            raise StateLimitExceeded(max_nodes)
        if not len(adj) & 0x3F:  # every 64 nodes: progress and --time-limit
            limits.progress("exploring a formula automaton / product", len(adj))
            limits.check_deadline()
        for _, w, _ in es:
            if w not in order:
                order[w] = len(order)
                queue.append(w)

    graph = nx.DiGraph()
    graph.add_nodes_from(adj)
    graph.add_edges_from((v, w) for v, es in adj.items() for _, w, _ in es)
    dag = nx.condensation(graph)
    first = {c: min(order[v] for v in dag.nodes[c]["members"]) for c in dag}
    # Reverse topological order: every SCC reachable from a component is classified first.
    topo = list(nx.lexicographical_topological_sort(dag, key=lambda c: first[c]))
    sccs: list[list[Hashable]] = []
    scc_of: dict[Hashable, int] = {}
    for c in reversed(topo):
        comp = sorted(dag.nodes[c]["members"], key=order.__getitem__)
        for v in comp:
            scc_of[v] = len(sccs)
        sccs.append(comp)

    accepting = []
    live: set[Hashable] = set()
    for k, comp in enumerate(sccs):
        mask = 0
        internal = False
        exits_live = False
        for v in comp:
            for _, w, m in adj[v]:
                if scc_of[w] == k:
                    internal = True
                    mask |= m
                elif w in live:
                    exits_live = True
        acc = internal and (mask & full_mask) == full_mask
        accepting.append(acc)
        if acc or exits_live:
            live.update(comp)
    return Analysis(initial, adj, scc_of, sccs, accepting, live)


def _bfs(
    adj: dict[Hashable, list[Edge]],
    sources: Iterable[Hashable],
    goal: Callable[[Hashable, str, Hashable, int], bool],
    allowed: Callable[[Hashable], bool] = lambda _v: True,
) -> tuple[list[tuple[Hashable, str, Hashable]], Hashable] | None:
    """Shortest path (as edges) from a source whose *last* edge satisfies ``goal``."""
    parent: dict[Hashable, tuple[Hashable, str] | None] = {}
    queue: deque[Hashable] = deque()
    for s in sources:
        if s not in parent:
            parent[s] = None
            queue.append(s)
    while queue:
        v = queue.popleft()
        for a, w, m in adj.get(v, ()):
            if not allowed(w):
                continue
            if goal(v, a, w, m):
                path = [(v, a, w)]
                u = v
                while parent[u] is not None:
                    pu, pa = parent[u]  # type: ignore[misc]
                    path.append((pu, pa, u))
                    u = pu
                path.reverse()
                return path, w
            if w not in parent:
                parent[w] = (v, a)
                queue.append(w)
    return None


def path_to(an: Analysis, targets: set[Hashable]) -> list[tuple[Hashable, str, Hashable]] | None:
    """Shortest edge path from an initial node to a node of ``targets`` (``[]`` if an initial
    node is a target)."""
    if any(s in targets for s in an.initial):
        return []
    found = _bfs(an.adj, an.initial, lambda _v, _a, w, _m: w in targets)
    return None if found is None else found[0]


def lasso(an: Analysis, full_mask: int) -> tuple[list[str], list[str]] | None:
    """An accepting lasso ``(prefix labels, cycle labels)`` if one exists, else ``None``.

    Picks the accepting SCC nearest to an initial node; the cycle visits an edge of every
    acceptance set.
    """
    acc_nodes = {v for k, comp in enumerate(an.sccs) if an.accepting[k] for v in comp}
    if not acc_nodes:
        return None
    prefix = path_to(an, acc_nodes)
    assert prefix is not None
    start = prefix[-1][2] if prefix else next(s for s in an.initial if s in acc_nodes)
    comp = set(an.sccs[an.scc_of[start]])
    cycle = covering_cycle(an.adj, comp, start, full_mask)
    return [a for _, a, _ in prefix], [a for _, a, _ in cycle]


def covering_cycle(
    adj: dict[Hashable, list[Edge]],
    inside: set[Hashable],
    start: Hashable,
    bits: int,
    keys: frozenset = frozenset(),
    key: Callable[[Hashable, str, Hashable], Hashable] | None = None,
) -> list[tuple[Hashable, str, Hashable]]:
    """A non-empty cycle from ``start`` within the strongly connected node set ``inside`` that
    takes an edge of every acceptance bit in ``bits`` and, when ``key`` is given, an edge with
    each key in ``keys`` (greedy: always the nearest edge that settles something pending)."""
    pending_bits = bits
    pending_keys = set(keys)

    def useful(v: Hashable, a: str, w: Hashable, m: int) -> bool:
        if w not in inside:
            return False
        if m & pending_bits:
            return True
        return key is not None and key(v, a, w) in pending_keys

    cycle: list[tuple[Hashable, str, Hashable]] = []
    cur = start
    while pending_bits or pending_keys:
        seg = _bfs(adj, [cur], useful, lambda v: v in inside)
        assert seg is not None, "requirement not reachable inside a strongly connected set"
        for v, a, w in seg[0]:
            pending_bits &= ~_edge_mask(adj, (v, a, w))
            if key is not None:
                pending_keys.discard(key(v, a, w))
        cycle.extend(seg[0])
        cur = seg[1]
    if cur != start or not cycle:
        seg = _bfs(adj, [cur], lambda _v, _a, w, _m: w == start, lambda v: v in inside)
        assert seg is not None
        cycle.extend(seg[0])
    return cycle


def _edge_mask(adj: dict[Hashable, list[Edge]], edge: tuple[Hashable, str, Hashable]) -> int:
    # Parallel edges with the same label and target may carry different acceptance masks; a
    # cycle repeated forever can alternate between them, so their union counts.
    v, a, w = edge
    mask = 0
    for b, x, m in adj[v]:
        if b == a and x == w:
            mask |= m
    return mask
