"""Determinisation, minimisation and bisimulation."""

from __future__ import annotations

import pytest
from helpers_lts import E, cycle, lts, moves

from iterplan_compiler.ir.alphabet_ops import NotDeterministic, hide, property_complete
from iterplan_compiler.ir.lts import TAU
from iterplan_compiler.ir.minimise import (
    bisimilar,
    determinise,
    deterministic,
    minimise,
    strong_minimise,
    tau_closure,
    weak_minimise,
)


def test_tau_closure_includes_error():
    p = lts("P", 3, [(0, TAU, 1), (1, TAU, E), (2, "a", 0)])
    c = tau_closure(p)
    assert c[0] == {0, 1, E} and c[2] == {2}


def test_determinise_subset_construction():
    # (a -> b -> STOP | a -> c -> STOP)
    p = lts("P", 5, [(0, "a", 1), (0, "a", 2), (1, "b", 3), (2, "c", 4)])
    d = determinise(p)
    assert d.num_states == 4
    assert moves(d, 0) == [("a", 1)]
    assert [a for a, _ in moves(d, 1)] == ["b", "c"]


def test_determinise_removes_tau_and_error_dominates():
    p = lts("P", 3, [(0, TAU, 1), (0, "a", 2), (1, "a", E), (2, "b", 0)])
    d = determinise(p)
    assert moves(d, 0) == [("a", E)]
    assert TAU not in d.labels_used()


def test_determinise_of_error_process():
    d = determinise(lts("P", 1, [(0, TAU, E)]))
    assert d.transitions == ((0, TAU, E),)


def test_hide_property_example():
    # P = (a -> b -> P)\{a}. property ||C = P.  gives Q0 = (b -> Q0)
    c = property_complete(deterministic(hide(cycle("P", "a", "b"), {"a"})))
    assert c.num_states == 1 and c.transitions == ((0, "b", 0),)


def test_minimise_merges_equivalent_states():
    # a -> b -> a -> b ... unrolled 4 times
    p = cycle("P", "a", "b", "a", "b")
    m = minimise(p)
    assert m.num_states == 2
    assert bisimilar(m, cycle("Q", "a", "b"))


def test_minimise_keeps_error_and_end_distinct():
    p = lts("P", 3, [(0, "a", 1), (0, "b", 2)], end={2})
    m = minimise(p)
    assert m.num_states == 3  # STOP (1) and END (2) are not merged
    q = lts("Q", 2, [(0, "a", 1), (0, "b", E)])
    assert minimise(q).num_states == 2 and minimise(q).has_error


def test_minimise_rejects_nondeterminism():
    with pytest.raises(NotDeterministic):
        minimise(lts("P", 3, [(0, "a", 1), (0, "a", 2)]))


def test_strong_minimise_nondeterministic():
    # a.(b + c) vs a.b + a.c are not bisimilar; duplicated branches merge
    p = lts("P", 5, [(0, "a", 1), (0, "a", 2), (1, "b", 3), (2, "b", 4)])
    m = strong_minimise(p)
    assert m.num_states == 3
    q = lts("Q", 5, [(0, "a", 1), (0, "a", 2), (1, "b", 3), (2, "c", 4)])
    r = lts("R", 4, [(0, "a", 1), (1, "b", 2), (1, "c", 3)])
    assert not bisimilar(q, r)
    assert bisimilar(determinise(q), strong_minimise(r))


def test_weak_minimise_absorbs_tau():
    p = lts("P", 3, [(0, TAU, 1), (1, "a", 2), (2, TAU, 0)])
    w = weak_minimise(p)
    assert bisimilar(w, cycle("Q", "a"), weak=True)
    assert w.num_states == 1 and w.transitions == ((0, "a", 0),)


def test_weak_bisimulation_distinguishes_tau_choice():
    # tau.a + b is not weakly bisimilar to a + b
    p = lts("P", 4, [(0, TAU, 1), (1, "a", 2), (0, "b", 3)])
    q = lts("Q", 3, [(0, "a", 1), (0, "b", 2)])
    assert not bisimilar(p, q, weak=True)
    assert bisimilar(determinise(p), q)


def test_bisimilar_alphabet_and_error():
    a = cycle("A", "a")
    b = lts("B", 1, [(0, "a", 0)], alphabet={"z"})
    assert not bisimilar(a, b)
    assert bisimilar(a, b, same_alphabet=False)
    e1 = lts("E1", 1, [(0, "a", E)])
    s1 = lts("S1", 2, [(0, "a", 1)])
    assert not bisimilar(e1, s1)
    assert bisimilar(e1, lts("E2", 2, [(0, "a", E), (1, "a", 0)]))


def test_property_example_bisimilar_to_expected():
    expected = lts("PL", 2, [(0, "a", 1), (0, "b", E), (1, "b", 0), (1, "a", E)])
    obtained = property_complete(deterministic(cycle("LOWER", "a", "b")))
    assert bisimilar(obtained, expected)


def test_trace_difference():
    from iterplan_compiler.ir.minimise import trace_difference

    p = cycle("P", "a", "b")
    q = lts("Q", 3, [(0, "a", 1), (1, "b", 2), (2, "a", 1), (1, "c", E)])
    assert trace_difference(p, q) == (("a",), frozenset(), frozenset({"c->ERROR"}))
    assert trace_difference(p, cycle("P2", "a", "b", "a", "b")) is None
    # trace-equivalent but not bisimilar: no trace difference
    r = lts("R", 5, [(0, "a", 1), (0, "a", 2), (1, "b", 3), (2, "c", 4)])
    s = lts("S", 4, [(0, "a", 1), (1, "b", 2), (1, "c", 3)])
    assert trace_difference(r, s) is None and not bisimilar(r, s)
    end = lts("E", 2, [(0, "a", 1)], end={1})
    stop = lts("S", 2, [(0, "a", 1)])
    assert trace_difference(end, stop) == (("a",), frozenset({"END"}), frozenset())
