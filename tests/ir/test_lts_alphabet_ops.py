"""Alphabet operators (MTSA §2.3, §2.4, sequential composition)."""

from __future__ import annotations

import pytest
from helpers_lts import E, cycle, lts, moves

from iterplan_compiler.ir.alphabet_ops import (
    NotDeterministic,
    NotSequential,
    apply_priority,
    expose,
    extend_alphabet,
    hide,
    is_deterministic,
    prefix_labels,
    property_complete,
    sequential,
    share_labels,
)
from iterplan_compiler.ir.lts import TAU


def test_hide_uses_dotted_prefix():
    p = lts("P", 3, [(0, "a.1", 1), (1, "ab", 2), (2, "a", 0)])
    h = hide(p, {"a"})
    assert h.alphabet == {"ab"}
    assert moves(h, 0) == [(TAU, 1)] and moves(h, 2) == [(TAU, 0)]
    assert moves(h, 1) == [("ab", 2)]


def test_expose_hides_complement_and_unused_labels():
    p = lts("P", 2, [(0, "a", 1), (1, "b", 0)], alphabet={"c", "a.x"})
    x = expose(p, {"a"})
    assert x.alphabet == {"a", "a.x"}
    assert moves(x, 1) == [(TAU, 0)]


def test_extend_alphabet():
    p = cycle("P", "a")
    assert extend_alphabet(p, {"z", TAU}).alphabet == {"a", "z"}


def test_prefix_and_share():
    p = lts("P", 2, [(0, "a", 1), (1, TAU, 0)])
    q = prefix_labels(p, "one")
    assert q.alphabet == {"one.a"} and moves(q, 1) == [(TAU, 0)]
    s = share_labels(p, ["x", "y"])
    assert s.alphabet == {"x.a", "y.a"}
    assert moves(s, 0) == [("x.a", 1), ("y.a", 1)]
    assert moves(s, 1) == [(TAU, 0)]


def test_property_completion_matches_mtsa_example():
    # property ||PL = LOWER, LOWER = (a -> b -> LOWER): 2 states + ERROR, 4 transitions.
    pl = property_complete(cycle("LOWER", "a", "b"))
    assert pl.num_states == 2 and pl.num_transitions == 4
    assert moves(pl, 0) == [("a", 1), ("b", E)]
    assert moves(pl, 1) == [("a", E), ("b", 0)]
    assert pl.end_states == frozenset()


def test_property_completion_with_error_set():
    p = lts("P", 1, [(0, "a", 0)], alphabet={"b", "c"})
    pc = property_complete(p, error_set={"b"})
    assert moves(pc, 0) == [("a", 0), ("b", E)]


def test_property_rejects_nondeterminism_and_tau():
    with pytest.raises(NotDeterministic):
        property_complete(lts("P", 2, [(0, "a", 0), (0, "a", 1)]))
    with pytest.raises(NotDeterministic) as exc:
        property_complete(lts("P", 2, [(0, TAU, 1)]))
    assert "tau" in str(exc.value)
    assert not is_deterministic(lts("P", 2, [(0, TAU, 1)]))
    assert is_deterministic(cycle("P", "a", "b"))


def test_sequential_glues_end_to_start():
    p = lts("P", 2, [(0, "a", 1)], end={1})
    q = lts("Q", 2, [(0, "b", 1)], end={1})
    s = sequential(p, q, "S")
    assert s.name == "S" and s.num_states == 3
    assert moves(s, 0) == [("a", 1)] and moves(s, 1) == [("b", 2)]
    assert s.end_states == {2}
    assert s.alphabet == {"a", "b"}
    with pytest.raises(NotSequential):
        sequential(cycle("L", "x"), q)


def test_sequential_of_immediate_end():
    p = lts("P", 1, [], end={0})
    q = cycle("Q", "b")
    s = sequential(p, q)
    assert s.num_states == 1 and moves(s, 0) == [("b", 0)]


def test_apply_priority():
    p = lts("P", 4, [(0, "a", 1), (0, "b", 2), (2, "c", 3)])
    hi = apply_priority(p, {"a"}, high=True)
    assert hi.num_states == 2 and moves(hi, 0) == [("a", 1)]
    lo = apply_priority(p, {"a"}, high=False)
    assert moves(lo, 0) == [("b", 1)] and lo.num_states == 3
    assert lo.alphabet == p.alphabet
