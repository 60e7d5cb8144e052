"""ir/analysis.py on hand-made LTSs, and against networkx on random ones."""

from __future__ import annotations

import networkx as nx
from hypothesis import given
from hypothesis import strategies as st

from iterplan_compiler.ir.analysis import (
    ProgressProperty,
    check_progress,
    check_safety,
    default_progress,
    terminal_sets,
)
from iterplan_compiler.ir.lts import ERROR, make_lts


def test_deadlock_shortest_trace():
    # 0 -a-> 1 -b-> 2 (STOP); 0 -c-> 3 -d-> 4 -e-> 2; 2 is the only deadlock
    lts = make_lts("M", 5, [(0, "a", 1), (1, "b", 2), (0, "c", 3), (3, "d", 4), (4, "e", 2),
                            (3, "x", 0)])
    r = check_safety(lts)
    assert r.deadlock == ("a", "b")
    assert r.deadlock_state == 2
    assert r.error is None
    assert not r.ok


def test_end_state_is_not_a_deadlock():
    lts = make_lts("M", 2, [(0, "a", 1)], end_states=[1])
    assert check_safety(lts).ok


def test_error_shortest_trace_and_initial_deadlock():
    lts = make_lts("M", 3, [(0, "a", 1), (1, "b", ERROR), (0, "c", 2), (2, "c", 2),
                            (2, "d", ERROR)])
    r = check_safety(lts)
    assert r.error == ("a", "b")  # length 2 either way; BFS order picks a before c
    assert r.deadlock is None
    stop = make_lts("S", 1, [], alphabet={"a"})
    assert check_safety(stop).deadlock == ()


def test_terminal_sets_and_progress():
    # 0 -a-> 1, 1 -b-> 2 -b-> 1 (terminal: {b}); 0 -c-> 3 -a-> 3 (terminal: {a});
    # 0 -d-> 4 (deadlock: no terminal set), 0 is transient
    lts = make_lts("M", 5, [(0, "a", 1), (1, "b", 2), (2, "b", 1), (0, "c", 3),
                            (3, "a", 3), (0, "d", 4)])
    sets = terminal_sets(lts)
    assert [(sorted(ts.states), sorted(ts.actions), ts.trace) for ts in sets] == [
        ([1, 2], ["b"], ("a",)), ([3], ["a"], ("c",))]
    props = [ProgressProperty("PA", frozenset({"a"})),
             ProgressProperty("PB", frozenset({"b"})),
             ProgressProperty("PAB", frozenset({"a", "b"})),
             ProgressProperty("IF", frozenset({"b"}), frozenset({"a"}))]
    v = {x.prop.name: x.terminal.trace for x in check_progress(lts, props)}
    assert v == {"PA": ("a",), "PB": ("c",), "IF": ("c",)}
    missing = [(ts.trace, sorted(m)) for ts, m in default_progress(lts)]
    assert missing == [(("a",), ["a", "c", "d"]), (("c",), ["b", "c", "d"])]


def test_error_edge_makes_a_set_non_terminal():
    lts = make_lts("M", 2, [(0, "a", 1), (1, "b", 0), (1, "e", ERROR)])
    assert terminal_sets(lts) == []


def test_progress_matches_dotted_prefix():
    lts = make_lts("M", 1, [(0, "in.1", 0)])
    assert check_progress(lts, [ProgressProperty("P", frozenset({"in"}))]) == []


_edges = st.lists(st.tuples(st.integers(0, 7), st.sampled_from("abc"),
                            st.integers(-1, 7)), max_size=20)


@given(_edges)
def test_against_networkx(edges):
    lts = make_lts("R", 8, edges)
    g = nx.MultiDiGraph()
    g.add_nodes_from(range(8))
    g.add_node("ERR")
    for s, a, t in lts.transitions:
        g.add_edge(s, "ERR" if t == ERROR else t, label=a)
    reach = nx.descendants(g, 0) | {0}
    dist = nx.single_source_shortest_path_length(g, 0)
    r = check_safety(lts)
    out = lts.out_edges()

    def walk(trace):  # the trace is a path of the (deterministic here or not) machine
        states = {0}
        for a in trace:
            states = {t for s in states if s != ERROR for b, t in out[s] if b == a}
            assert states
        return states

    if r.deadlock is not None:
        assert r.deadlock_state in walk(r.deadlock)
    if r.error is not None:
        assert ERROR in walk(r.error)
    dead = [s for s in reach if s != "ERR" and g.out_degree(s) == 0]
    if dead:
        assert r.deadlock is not None
        assert len(r.deadlock) == min(dist[s] for s in dead)
    else:
        assert r.deadlock is None
    if "ERR" in reach:
        assert r.error is not None and len(r.error) == dist["ERR"]
    else:
        assert r.error is None
    # bottom SCCs of the reachable part with at least one edge, ERROR not among them
    sub = g.subgraph(reach)
    expected = set()
    for comp in nx.attracting_components(sub):
        if "ERR" in comp:
            continue
        if any(t in comp for s in comp for t in sub.successors(s)):
            expected.add(frozenset(comp))
    got = terminal_sets(lts)
    assert {ts.states for ts in got} == expected
    for ts in got:
        assert ts.entry in walk(ts.trace)
        assert len(ts.trace) == min(dist[s] for s in ts.states)
        assert ts.actions == {d["label"] for s, t, d in sub.edges(data=True) if s in ts.states}
