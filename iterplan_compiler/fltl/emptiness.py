"""Emptiness of transition-based generalised Büchi graphs, with lasso witnesses.

A graph is given implicitly by initial nodes and a successor function returning
``(label, target, mask)`` triples; ``full_mask`` is the union of the acceptance bits.  An SCC is
*accepting* iff it has an internal edge and its internal edges together carry every bit of
``full_mask``.  SCCs come from the compiler's one SCC routine
(:mod:`iterplan_compiler.ir.graphs`, no recursion limit on deep product graphs) and are
ordered by Kahn's algorithm with a heap (:func:`_topological`).  These
were networkx's ``condensation`` and ``lexicographical_topological_sort``; importing networkx
cost 0.15-0.3 s, paid by every ``iterc`` run with an ``ltl_property``, for 40 lines of graph
code (the order produced is the same: ties broken by the breadth-first discovery index).
"""

from __future__ import annotations

import heapq
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from iterplan_compiler import limits
from iterplan_compiler.ir.graphs import strongly_connected

#: a graph node: any hashable value (the callers' product states are tuples, which they
#: unpack, so the alias is ``Any`` rather than ``Hashable``)
Node = Any
Edge = tuple[str, Node, int]
Successors = Callable[[Node], Iterable[Edge]]


class StateLimitExceeded(Exception):
    """The explored graph grew beyond ``max_nodes``."""


@dataclass
class Analysis:
    """Result of :func:`analyse`: the explored graph and its SCC structure."""

    initial: list[Node]
    adj: dict[Node, list[Edge]]
    scc_of: dict[Node, int]
    sccs: list[list[Node]]  # reverse topological: successors' SCCs come first
    accepting: list[bool]
    live: set[Node]  # nodes from which an accepting SCC is reachable


def analyse(
    initial: Iterable[Node],
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
    adj: dict[Node, list[Edge]] = {}
    order: dict[Node, int] = {v: i for i, v in enumerate(initial)}
    queue: deque[Node] = deque(initial)
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

    members, comp_of = _sccs(list(adj), adj)
    first = [min(order[v] for v in m) for m in members]
    # Reverse topological order: every SCC reachable from a component is classified first.
    topo = _topological(members, comp_of, adj, first)
    sccs: list[list[Node]] = []
    scc_of: dict[Node, int] = {}
    for c in reversed(topo):
        comp = sorted(members[c], key=order.__getitem__)
        for v in comp:
            scc_of[v] = len(sccs)
        sccs.append(comp)

    accepting = []
    live: set[Node] = set()
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


def _sccs(nodes: list[Node], adj: dict[Node, list[Edge]]
          ) -> tuple[list[list[Node]], dict[Node, int]]:
    """Strongly connected components (:func:`~iterplan_compiler.ir.graphs.strongly_connected`):
    ``(members, comp_of)``."""
    members = strongly_connected(nodes, lambda v: [e[1] for e in adj[v]])
    comp_of = {v: k for k, comp in enumerate(members) for v in comp}
    return members, comp_of


def _topological(members: list[list[Node]], comp_of: dict[Node, int],
                 adj: dict[Node, list[Edge]], key: list[int]) -> list[int]:
    """The components in topological order of the condensation, ties broken by smallest
    ``key`` (Kahn's algorithm with a heap)."""
    succ: list[set[int]] = [set() for _ in members]
    indegree = [0] * len(members)
    for c, m in enumerate(members):
        for v in m:
            for _, w, _ in adj[v]:
                d = comp_of[w]
                if d != c and d not in succ[c]:
                    succ[c].add(d)
                    indegree[d] += 1
    heap = [(key[c], c) for c in range(len(members)) if indegree[c] == 0]
    heapq.heapify(heap)
    out: list[int] = []
    while heap:
        _, c = heapq.heappop(heap)
        out.append(c)
        for d in succ[c]:
            indegree[d] -= 1
            if indegree[d] == 0:
                heapq.heappush(heap, (key[d], d))
    return out


def _bfs(
    adj: dict[Node, list[Edge]],
    sources: Iterable[Node],
    goal: Callable[[Node, str, Node, int], bool],
    allowed: Callable[[Node], bool] = lambda _v: True,
) -> tuple[list[tuple[Node, str, Node]], Node] | None:
    """Shortest path (as edges) from a source whose *last* edge satisfies ``goal``."""
    parent: dict[Node, tuple[Node, str] | None] = {}
    queue: deque[Node] = deque()
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


def path_to(an: Analysis, targets: set[Node]) -> list[tuple[Node, str, Node]] | None:
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
    adj: dict[Node, list[Edge]],
    inside: set[Node],
    start: Node,
    bits: int,
    keys: frozenset = frozenset(),
    key: Callable[[Node, str, Node], Node] | None = None,
) -> list[tuple[Node, str, Node]]:
    """A non-empty cycle from ``start`` within the strongly connected node set ``inside`` that
    takes an edge of every acceptance bit in ``bits`` and, when ``key`` is given, an edge with
    each key in ``keys`` (greedy: always the nearest edge that settles something pending)."""
    pending_bits = bits
    pending_keys = set(keys)

    def useful(v: Node, a: str, w: Node, m: int) -> bool:
        if w not in inside:
            return False
        if m & pending_bits:
            return True
        return key is not None and key(v, a, w) in pending_keys

    cycle: list[tuple[Node, str, Node]] = []
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


def _edge_mask(adj: dict[Node, list[Edge]], edge: tuple[Node, str, Node]) -> int:
    # Parallel edges with the same label and target may carry different acceptance masks; a
    # cycle repeated forever can alternate between them, so their union counts.
    v, a, w = edge
    mask = 0
    for b, x, m in adj[v]:
        if b == a and x == w:
            mask |= m
    return mask
