"""The generic GR(1) fixpoint on tiny explicit games encoded by hand."""

from __future__ import annotations

from iterplan_compiler.symbolic.bdd import (
    and_exists,
    declare_interleaved,
    enumerate_values,
    new_manager,
)
from iterplan_compiler.synthesis.fixpoint import gr1_winning


def _game(edges: dict[int, list[int]], env: set[int], width: int = 3):
    """States 0..7; ``env`` states need all successors in T, others some successor."""
    bdd = new_manager()
    cur, nxt = declare_interleaved(bdd, "x", width)
    T = bdd.false
    for s, ts in edges.items():
        for t in ts:
            T |= cur.eq(bdd, s) & nxt.eq(bdd, t)
    envset = bdd.false
    for s in env:
        envset |= cur.eq(bdd, s)
    ren = dict(zip(cur.names, nxt.names, strict=True))

    def cpre(X):
        xn = bdd.let(ren, X)
        has = bdd.exist(set(nxt.names), T)
        bad = and_exists(bdd, T, ~xn, nxt.names)
        good = and_exists(bdd, T, xn, nxt.names)
        return (envset & has & ~bad) | (~envset & good)

    def states(*ss):
        u = bdd.false
        for s in ss:
            u |= cur.eq(bdd, s)
        return u

    return bdd, cur, cpre, states


def test_reach_and_stay():
    # 0 -> 1 | 2 (controller), 1 -> 1, 2 -> 3 (dead end)
    bdd, cur, cpre, S = _game({0: [1, 2], 1: [1], 2: [3]}, env=set())
    fp = gr1_winning(bdd, cpre, [], [S(1)], care=S(0, 1, 2, 3))
    assert enumerate_values(bdd, fp.winning, cur) == [0, 1]


def test_environment_choice_loses():
    bdd, cur, cpre, S = _game({0: [1, 2], 1: [1], 2: [2]}, env={0})
    fp = gr1_winning(bdd, cpre, [], [S(1)], care=S(0, 1, 2))
    assert enumerate_values(bdd, fp.winning, cur) == [1]
    # ... unless visiting 2 forever violates the assumption GF(1)
    fp = gr1_winning(bdd, cpre, [S(1)], [S(1)], care=S(0, 1, 2), keep_iterates=True)
    assert enumerate_values(bdd, fp.winning, cur) == [0, 1, 2]
    assert fp.y_layers and fp.x_sets and fp.complete


def test_two_guarantees_need_alternation():
    # controller at 0 chooses 1 or 2; both return to 0
    bdd, cur, cpre, S = _game({0: [1, 2], 1: [0], 2: [0]}, env=set())
    fp = gr1_winning(bdd, cpre, [], [S(1), S(2)], care=S(0, 1, 2))
    assert enumerate_values(bdd, fp.winning, cur) == [0, 1, 2]
    bdd, cur, cpre, S = _game({0: [1, 2], 1: [0], 2: [2]}, env={0})
    fp = gr1_winning(bdd, cpre, [], [S(1), S(2)], care=S(0, 1, 2))
    assert enumerate_values(bdd, fp.winning, cur) == []


def test_early_stop():
    bdd, cur, cpre, S = _game({0: [1, 2], 1: [1], 2: [2]}, env={0})
    fp = gr1_winning(bdd, cpre, [], [S(1)], care=S(0, 1, 2), must_contain=S(0))
    assert not fp.complete
    assert (fp.winning & S(0)) == bdd.false
