"""Strongly connected components of an implicit graph: the one SCC routine of the compiler.

Used by the FLTL emptiness check (:mod:`iterplan_compiler.fltl.emptiness`), LTSA's terminal sets
(:mod:`iterplan_compiler.ir.analysis`) and the explicit GR(1) oracle.  Tarjan's algorithm with
an explicit stack, so a long chain of states (a 100 k-step product) cannot hit Python's
recursion limit.  Components come out in Tarjan's completion order (every component after
all the components it reaches: reverse topological order); within the search, roots are
taken in the order given and successors in the order ``successors`` yields them, so the
result is deterministic.  (networkx's ``strongly_connected_components`` does the same job; it
is not used here because importing networkx costs 0.15-0.3 s per ``iterc`` run.)
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Iterator
from typing import TypeVar

N = TypeVar("N", bound=Hashable)


def strongly_connected(roots: Iterable[N], successors: Callable[[N], Iterable[N]]
                       ) -> list[list[N]]:
    """The SCCs of the part of the graph reachable from ``roots``, in completion order
    (module doc); each component lists its states in the order they left Tarjan's stack."""
    index: dict[N, int] = {}
    low: dict[N, int] = {}
    on_stack: set[N] = set()
    stack: list[N] = []
    out: list[list[N]] = []

    def enter(v: N) -> tuple[N, Iterator[N]]:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        return v, iter(successors(v))

    for root in roots:
        if root in index:
            continue
        work = [enter(root)]
        while work:
            v, it = work[-1]
            for w in it:
                if w not in index:
                    work.append(enter(w))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    u = work[-1][0]
                    low[u] = min(low[u], low[v])
                if low[v] == index[v]:
                    out.append(_pop_component(v, stack, on_stack))
    return out


def _pop_component(v: N, stack: list[N], on_stack: set[N]) -> list[N]:
    comp: list[N] = []
    while True:
        w = stack.pop()
        on_stack.discard(w)
        comp.append(w)
        if w == v:
            return comp
