"""Parallel composition (MTSA §2.5): hand-built machines with known products."""

from __future__ import annotations

import pytest
from helpers_lts import E, cycle, lts, moves

from iterplan_compiler.ir.compose import StateExplosion, compose, explore_product
from iterplan_compiler.ir.lts import TAU, make_lts


def test_shared_labels_synchronise_private_interleave():
    # P = (a -> b -> P), Q = (b -> c -> Q): b is shared.
    p = cycle("P", "a", "b")
    q = cycle("Q", "b", "c")
    r = compose([p, q], "R")
    assert r.name == "R"
    assert r.alphabet == {"a", "b", "c"}
    # (0,0) -a-> (1,0) -b-> (0,1) -a-> (1,1) -c-> (1,0); (0,1) -c-> (0,0)
    assert r.num_states == 4
    assert moves(r, 0) == [("a", 1)]
    assert moves(r, 1) == [("b", 2)]
    assert sorted(a for a, _ in moves(r, 2)) == ["a", "c"]


def test_shared_label_blocked_when_partner_cannot_move():
    p = lts("P", 2, [(0, "a", 1)])
    q = lts("Q", 1, [], alphabet={"a"})  # a in alphabet, never enabled: blocks
    r = compose([p, q], "R")
    assert r.num_states == 1 and r.transitions == ()
    assert "a" in r.alphabet


def test_tau_never_synchronises():
    p = lts("P", 2, [(0, TAU, 1)])
    q = lts("Q", 2, [(0, TAU, 1)])
    r = compose([p, q], "R")
    assert r.num_states == 4
    assert len([t for t in r.transitions if t[1] == TAU]) == 4
    assert TAU not in r.alphabet


def test_error_propagates_to_single_error_state():
    p = lts("P", 1, [(0, "a", E), (0, "b", 0)])
    q = lts("Q", 2, [(0, "a", 1), (1, "a", 0)])
    r = compose([p, q], "R")
    assert (0, "a", E) in r.transitions
    assert r.has_error
    # ERROR is not a counted state
    assert r.num_states == 1


def test_nondeterministic_synchronisation_takes_all_combinations():
    p = lts("P", 3, [(0, "a", 1), (0, "a", 2)])
    q = lts("Q", 3, [(0, "a", 1), (0, "a", 2)])
    r = compose([p, q], "R")
    assert r.num_states == 5
    assert len(moves(r, 0)) == 4


def test_end_only_when_all_components_end():
    p = lts("P", 2, [(0, "a", 1)], end={1})
    q = lts("Q", 2, [(0, "b", 1)], end={1})
    r = compose([p, q], "R")
    assert r.num_states == 4
    assert len(r.end_states) == 1
    (e,) = r.end_states
    assert moves(r, e) == []
    q_stop = lts("Q", 2, [(0, "b", 1)])  # ends in STOP, not END
    assert compose([p, q_stop], "R").end_states == frozenset()


def test_end_rule_for_non_terminating_components():
    # P = (a -> END); Q = (a -> Q) never terminates but its alphabet is inside P's: END.
    p = lts("P", 2, [(0, "a", 1)], end={1})
    q = lts("Q", 1, [(0, "a", 0)])
    r = compose([p, q], "R")
    assert r.num_states == 2 and r.end_states == {1}
    # a non-terminating component with a label of its own prevents END (it is a deadlock)
    q2 = lts("Q", 2, [(0, "a", 0), (0, "b", 1)])
    assert compose([p, q2], "R").end_states == frozenset()
    # ... so END is not associative: nested, (P || Q2) has no END and then no terminating part
    s = lts("S", 2, [(0, "b", 1)], end={1})
    assert compose([p, q2, s], "F").end_states
    assert not compose([compose([p, q2], "PQ"), s], "N").end_states


def test_end_tuples_are_merged():
    # (a -> END | b -> END) || (c -> END | d -> END): four END tuples, one END state
    p = lts("P", 3, [(0, "a", 1), (0, "b", 2)], end={1, 2})
    q = lts("Q", 3, [(0, "c", 1), (0, "d", 2)], end={1, 2})
    r = compose([p, q], "R")
    assert len(r.end_states) == 1
    (e,) = r.end_states
    assert r.num_states == 6  # initial, a, b, c, d, END
    assert [t for _, _, t in r.transitions].count(e) == 8  # 4 intermediate states x 2 moves
    assert r == make_lts("R", r.num_states, r.transitions, r.alphabet, 0, r.end_states)


def test_numbering_is_canonical_bfs():
    p = lts("P", 3, [(0, "b", 1), (0, "a", 2)])
    r = compose([p], "R")
    assert moves(r, 0) == [("a", 1), ("b", 2)]


def test_three_way_synchronisation_needs_all_owners():
    a = cycle("A", "x", "y")
    b = cycle("B", "x", "z")
    c = lts("C", 1, [(0, "x", 0)])
    r = compose([a, b, c], "R")
    assert moves(r, 0) == [("x", 1)]
    # after x: A offers y, B offers z; x needs all three again
    assert sorted(a for a, _ in moves(r, 1)) == ["y", "z"]


def test_priority_high_and_low():
    p = lts("P", 3, [(0, "a", 1), (0, "b", 2), (0, TAU, 0)])
    hi = compose([p], "R", priority=({"a"}, True))
    assert [a for a, _ in moves(hi, 0)] == ["a"]
    lo = compose([p], "R", priority=({"a"}, False))
    assert sorted(a for a, _ in moves(lo, 0)) == ["b", TAU]
    only_a = lts("P", 2, [(0, "a", 1)])
    assert [a for a, _ in moves(compose([only_a], "R", priority=({"a"}, False)), 0)] == ["a"]


def test_priority_prefix_matching():
    p = lts("P", 3, [(0, "a.1", 1), (0, "b", 2)])
    hi = compose([p], "R", priority=({"a"}, True))
    assert [a for a, _ in moves(hi, 0)] == ["a.1"]


def test_state_explosion():
    comps = [cycle(f"P{i}", f"a{i}", f"b{i}") for i in range(12)]
    with pytest.raises(StateExplosion) as exc:
        compose(comps, "BIG", max_states=1000)
    assert "BIG" in str(exc.value)
    assert compose(comps[:3], "S", max_states=8).num_states == 8


def test_explore_product_reports_tuples():
    p = cycle("P", "a", "b")
    q = cycle("Q", "c")
    tuples, _, _ = explore_product([p, q])
    assert tuples[0] == (0, 0)
    assert set(tuples) == {(0, 0), (1, 0)}


def test_empty_composition():
    r = compose([], "EMPTY")
    assert r.num_states == 1 and r.alphabet == frozenset()


def test_noninitial_start_state():
    p = lts("P", 2, [(1, "a", 0)], initial=1)
    r = compose([p], "R")
    assert moves(r, 0) == [("a", 1)] and r.initial == 0
