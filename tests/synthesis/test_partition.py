"""The partitioned relation (synthesis/partition.py): merging the groups of one
controllability into a framed relation (``cluster``) keeps the relation, shared fluent
variables included; restricting the groups to the reachable states keeps the game there;
a deferred action (``DEFER_NODES``) is the same relation, built when first read."""

from __future__ import annotations

from unittest.mock import patch

import pytest
from hypothesis import HealthCheck, given, settings
from test_agreement import problems

from iterplan_compiler.ir.lts import TAU
from iterplan_compiler.synthesis import partition, symbolic_game
from iterplan_compiler.synthesis.encode import prepare
from iterplan_compiler.synthesis.fixpoint import gr1_winning
from iterplan_compiler.synthesis.partition import cluster, framed_to, is_framed, owner_groups
from iterplan_compiler.synthesis.recode import recode_leaves
from iterplan_compiler.synthesis.symbolic_game import SymbolicGame


def _relation(g: SymbolicGame, groups, controllable: bool):
    """The full relation of one controllability: every group framed on what it keeps."""
    b = g.bdd
    out = b.false
    for grp in groups:
        if grp.controllable == controllable:
            out |= grp.rel & framed_to(b, g.vars, grp.cur_vars)
    return out


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_cluster_keeps_the_relation(prob):
    for spec in (prepare(prob), recode_leaves(prepare(prob))):
        g = SymbolicGame(spec)
        # the partitioned groups, as they are before clustering
        rels = [g._component_relation(k, c) for k, c in enumerate(spec.components)]
        parts = owner_groups(g.bdd, g.vars, spec.components, spec.controllable, rels)
        merged = cluster(g.bdd, g.vars, parts, 10**9)
        for c in (True, False):
            assert _relation(g, merged, c) == _relation(g, parts, c)
            if sum(grp.controllable == c for grp in parts) > 1:
                framed = [grp for grp in merged if grp.controllable == c]
                assert len(framed) == 1 and is_framed(g.vars, framed[0])


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_deferred_actions_are_the_same_relation(prob):
    """With ``DEFER_NODES = 0`` every action with two or more owners is kept as factors:
    the group is marked deferred, ``cluster`` leaves it alone, and its relation, read
    (built) later or restricted by ``within``, is the one built at once."""
    for spec in (prepare(prob), recode_leaves(prepare(prob))):
        g = SymbolicGame(spec)
        rels = [g._component_relation(k, c) for k, c in enumerate(spec.components)]
        eager = owner_groups(g.bdd, g.vars, spec.components, spec.controllable, rels)
        with patch.object(partition, "DEFER_NODES", 0):
            lazy = owner_groups(g.bdd, g.vars, spec.components, spec.controllable, rels)
        owners = {a: [k for k, c in enumerate(spec.components) if a in c.alphabet]
                  for a in spec.alphabet - {TAU}}
        assert any(x.deferred for x in lazy) == any(
            len(ks) > 1 and rels[ks[0]].get(a, g.bdd.false) != g.bdd.false
            for a, ks in owners.items())
        merged = cluster(g.bdd, g.vars, lazy, 10**9)
        assert {id(x) for x in merged if x.deferred} == {id(x) for x in lazy if x.deferred}
        care = g.reachable()
        within = [x.within(care, g.to_next(care)) for x in lazy]  # not built by this
        built = [x.rel for x in lazy]  # built now
        assert not any(x.deferred for x in lazy)
        # a deferred action's relation may turn out empty: its group is kept (an eager
        # empty group is dropped), with the empty relation
        kept = [i for i, r in enumerate(built) if r != g.bdd.false]
        assert [(lazy[i].owners, lazy[i].controllable, lazy[i].actions) for i in kept] == \
            [(y.owners, y.controllable, y.actions) for y in eager]
        for i, y in zip(kept, eager, strict=True):
            assert built[i] == y.rel
            assert within[i] == y.rel & care & g.to_next(care)


@pytest.mark.parametrize("defer", [partition.DEFER_NODES, 0])
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_restrict_keeps_the_game_on_the_reachable_states(defer, prob):
    """``SymbolicGame.restrict(reach)``: a partitioned group restricted to the projection of
    ``reach`` on its owners (and a framed one to ``reach``) has the same moves from every
    reachable state, and the fixpoint the same winning region and iteration counts.  The
    groups are kept partitioned (``CLUSTER_MAX_NODES = 0``) and every restriction is kept,
    so the projection is exercised even where it would not shrink the relation."""
    for spec in (prepare(prob), recode_leaves(prepare(prob))):
        with patch.object(symbolic_game, "CLUSTER_MAX_NODES", 0), \
                patch.object(symbolic_game, "KEEP_SMALLER_RELATION", False), \
                patch.object(partition, "DEFER_NODES", defer):
            g = SymbolicGame(spec)
            reach = g.reachable()
            goals = [gj | g.failures for gj in (g.guarantees or [g.live])]
            care = reach & g.live
            before = [_relation(g, g.groups, c) & reach for c in (True, False)]
            plain = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=care,
                                cpre_lost=g.cpre_lost, cpre_gained=g.cpre_gained)
            g.restrict(reach)
            assert [_relation(g, g.groups, c) & reach for c in (True, False)] == before
            fast = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=care,
                               cpre_lost=g.cpre_lost, cpre_gained=g.cpre_gained)
            assert fast.winning & care == plain.winning & care
            assert fast.iterations == plain.iterations
