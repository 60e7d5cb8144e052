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


# --- the one engine: typed predecessors, goal kinds, option switches ----------------------

import itertools  # noqa: E402

import pytest  # noqa: E402

from iterplan_compiler.synthesis.fixpoint import (  # noqa: E402
    EngineOptions,
    GoalKind,
    Predecessor,
    TransitionPredecessor,
    solve_gr1,
)


class _Pre:
    """A hand-made game as a :class:`Predecessor` (state goals only)."""

    def __init__(self, cpre):
        self._cpre = cpre

    def cpre(self, states):
        return self._cpre(states)


ALL_OPTIONS = [EngineOptions(feedback=f, recycle=r, chained=c, memo=m)
               for f, r, c, m in itertools.product((True, False), (True, False),
                                                   (True, False), (None, 0, 2))]


@pytest.mark.parametrize("opts", ALL_OPTIONS)
def test_every_option_combination_gives_the_same_region(opts):
    """Each optimisation must keep the result exact: the env loop 2→2 violates the second
    assumption (so 2 wins), the loop 3→3 satisfies both and misses the goals (3 and the env
    state 4, which may move there, lose), 5 is a dead end; 0 wins by alternating 0→1→0."""
    edges = {0: [1, 2, 4], 1: [0], 2: [2, 0], 3: [3], 4: [3, 0], 5: []}
    bdd, cur, cpre, S = _game(edges, env={2, 4})
    pre = _Pre(cpre)
    assert isinstance(pre, Predecessor) and not isinstance(pre, TransitionPredecessor)
    care = S(0, 1, 2, 3, 4, 5)
    for keep in (False, True):
        fp = solve_gr1(bdd, pre, [S(0, 1, 2, 3), S(0, 1, 3)], [S(1), S(0)], care=care,
                       keep_iterates=keep, options=opts)
        assert enumerate_values(bdd, fp.winning, cur) == [0, 1, 2], (opts, keep)
        assert bool(fp.y_layers) == keep


def test_transition_goals_need_a_transition_predecessor():
    bdd, cur, cpre, S = _game({0: [0]}, env=set())
    with pytest.raises(TypeError):
        solve_gr1(bdd, _Pre(cpre), [], [S(0)], goals=GoalKind.TRANSITION)


def test_lost_stops_early_and_is_reported():
    bdd, cur, cpre, S = _game({0: [1, 2], 1: [1], 2: [2]}, env={0})
    seen = []

    def lost(Z):
        seen.append(Z)
        return (Z & S(0)) == bdd.false

    fp = solve_gr1(bdd, _Pre(cpre), [], [S(1)], care=S(0, 1, 2), lost=lost)
    assert not fp.complete and seen
    fp = solve_gr1(bdd, _Pre(cpre), [], [S(1)], care=S(0, 1, 2))
    assert fp.complete and enumerate_values(bdd, fp.winning, cur) == [1]
