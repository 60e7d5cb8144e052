"""The frontier νX and μY (fixpoint_ops.FrontierPredecessor, SymbolicGame.cpre_lost and
cpre_gained): both against their definitions on random sets, and the engine with and without
them (same winning region, same iteration counts)."""

from __future__ import annotations

import random

from hypothesis import HealthCheck, given, settings
from test_agreement import problems
from test_symbolic_bdd import _door_patrol

from iterplan_compiler.synthesis.encode import prepare
from iterplan_compiler.synthesis.fixpoint import gr1_winning
from iterplan_compiler.synthesis.recode import recode_leaves
from iterplan_compiler.synthesis.symbolic_game import SymbolicGame


def _random_subset(g, u, rng):
    """A random subset of ``u`` (each satisfying assignment kept with probability 1/2)."""
    out = g.bdd.false
    for a in g.bdd.pick_iter(u, care_vars=g.cur_vars):
        if rng.random() < 0.5:
            out |= g.bdd.cube(a)
    return out


def _shrunk_sets(prob, seed):
    """Per encoding of ``prob`` (plain and recoded), 4 random ``(g, old, X ⊆ old, within ⊆
    CPre(old))`` of reachable states: a νX step that shrank ``old`` to ``X``."""
    for spec in (prepare(prob), recode_leaves(prepare(prob))):
        g = SymbolicGame(spec)
        reach = g.reachable() & g.live
        rng = random.Random(seed)
        for _ in range(4):
            old = _random_subset(g, reach, rng)
            X = _random_subset(g, old, rng)
            yield g, old, X, _random_subset(g, g.cpre(old) & reach, rng)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_cpre_lost_is_the_difference_of_cpres(prob):
    """``cpre_lost(X, D, W) = W \\ CPre(X)`` for every ``W ⊆ CPre(X ∪ D)``."""
    for g, old, X, within in _shrunk_sets(prob, seed=0):
        got = g.cpre_lost(X, old & ~X, within)
        assert got == within & ~g.cpre(X)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_chained_cpre_lost_removes_the_env_states_first(prob):
    """``cpre_lost_chained(X, D, W) = E ∪ (W ∩ ctrl ∖ CPre(X ∖ E))``, ``E = W ∩ env ∖ CPre(X)``."""
    for g, old, X, within in _shrunk_sets(prob, seed=1):
        E = within & g.env & ~g.cpre(X)
        got = g.cpre_lost_chained(X, old & ~X, within)
        assert got == E | (within & g.ctrl_owned & ~g.cpre(X & ~E))
        assert within & ~g.cpre(X) <= got  # at least what cpre_lost removes


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_chained_frontier_keeps_the_winning_region(prob):
    """The Gauss–Seidel frontier νX (game.py's default) reaches the same fixpoints."""
    for spec in (prepare(prob), recode_leaves(prepare(prob))):
        g = SymbolicGame(spec)
        reach = g.reachable() & g.live
        goals = [gj | g.failures for gj in (g.guarantees or [g.live])]
        plain = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach)
        for ratio in (1, 8):
            fast = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach,
                               cpre_lost=g.cpre_lost_chained, cpre_gained=g.cpre_gained,
                               frontier_ratio=ratio)
            assert fast.winning == plain.winning
            assert fast.iterations["x"] <= plain.iterations["x"]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_frontier_keeps_the_winning_region(prob):
    g = SymbolicGame(prepare(prob))
    reach = g.reachable() & g.live
    goals = [gj | g.failures for gj in (g.guarantees or [g.live])]
    plain = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach)
    for ratio in (1, 8):
        for gained in (None, g.cpre_gained):
            fast = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach,
                               cpre_lost=g.cpre_lost, cpre_gained=gained,
                               frontier_ratio=ratio)
            assert fast.winning == plain.winning
            assert fast.iterations == plain.iterations  # the same iterates, step by step


def test_frontier_on_door_patrol():
    g = SymbolicGame(prepare(_door_patrol(4)))
    reach = g.reachable()
    goals = [gj | g.failures for gj in g.guarantees]
    plain = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach, frontier_ratio=0)
    fast = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach,
                       cpre_lost=g.cpre_lost, cpre_gained=g.cpre_gained, frontier_ratio=1)
    assert fast.winning == plain.winning and fast.iterations == plain.iterations
    assert (fast.winning & g.init) != g.bdd.false


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_cpre_gained_is_the_growth_of_cpre(prob):
    """``CPre(Y) ∪ cpre_gained(Y, A, W) = (CPre(Y) ∪ W) ∩ CPre(Y ∪ A)`` on ``W``, and it
    stays inside ``W ∩ CPre(Y ∪ A)`` (the frontier μY's contract)."""
    for spec in (prepare(prob), recode_leaves(prepare(prob))):
        g = SymbolicGame(spec)
        reach = g.reachable() & g.live
        rng = random.Random(1)
        for _ in range(4):
            grown = _random_subset(g, reach, rng)
            Y = _random_subset(g, grown, rng)
            within = _random_subset(g, reach, rng) | reach & ~g.cpre(Y)
            got = g.cpre_gained(Y, grown & ~Y, within)
            want = within & g.cpre(grown)
            assert got & ~want == g.bdd.false  # sound
            assert (within & ~g.cpre(Y)) & want & ~got == g.bdd.false  # complete
