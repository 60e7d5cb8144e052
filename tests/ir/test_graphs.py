"""ir/graphs.py: the one SCC routine, against networkx on random graphs."""

from __future__ import annotations

import networkx as nx
from hypothesis import given
from hypothesis import strategies as st

from iterplan_compiler.ir.graphs import strongly_connected

edges = st.lists(st.tuples(st.integers(0, 12), st.integers(0, 12)), max_size=40)


@given(edges)
def test_same_components_as_networkx(es):
    succ: dict[int, list[int]] = {v: [] for v in range(13)}
    for u, v in es:
        succ[u].append(v)
    ours = strongly_connected(range(13), lambda v: succ[v])
    g = nx.DiGraph()
    g.add_nodes_from(range(13))
    g.add_edges_from(es)
    assert sorted(map(sorted, ours)) == sorted(map(sorted, nx.strongly_connected_components(g)))
    # completion order: a component comes after every component it reaches
    pos = {v: k for k, comp in enumerate(ours) for v in comp}
    for u, v in es:
        assert pos[v] <= pos[u]


def test_deep_chain_has_no_recursion_limit():
    n = 200_000
    comps = strongly_connected([0], lambda v: [v + 1] if v + 1 < n else [0])
    assert len(comps) == 1 and len(comps[0]) == n
