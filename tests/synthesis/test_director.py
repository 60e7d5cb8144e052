"""The GR(1) director of ``heuristic`` composites (symbolic_strategy, StrategyKind.DIRECTOR):
a sub-strategy of MTSA's controller with one controllable move per state, winning (checked
on the closed system with the explicit oracle), the same from both solvers, deterministic."""

from __future__ import annotations

import argparse
from dataclasses import replace

from hypothesis import HealthCheck, given, settings
from synthesis_helpers import F, fl, problem
from test_agreement import _check_controlled, _check_goal_on_every_run, problems

from iterplan_compiler.ir.lts import make_lts
from iterplan_compiler.ir.minimise import bisimilar
from iterplan_compiler.synthesis.driver import StrategyKind, _minimise, strategy_kind, synthesize
from iterplan_compiler.synthesis.encode import prepare
from iterplan_compiler.synthesis.explicit import build_game, solve_ranks
from iterplan_compiler.synthesis.fixpoint import gr1_winning
from iterplan_compiler.synthesis.game import SymbolicGame, solve_symbolic
from iterplan_compiler.synthesis.strategy import extract_controller
from iterplan_compiler.synthesis.symbolic_strategy import enumerate_strategy, rank_layers

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])


def _solved(prob):
    """The symbolic game of ``prob`` and its winning region (None: the initial state loses)."""
    g = SymbolicGame(prepare(prob))
    reach = g.reachable()
    g.restrict(reach)
    goals = [gj | g.failures for gj in (g.guarantees or [g.live])]
    W = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach & g.live).winning & reach
    return g, (W if (g.init & W) != g.bdd.false else None)


def _moves(e):
    out: dict = {}
    for k, label, k2 in e.trans:
        out.setdefault(e.order[k], set()).add((label, e.order[k2]))
    return out


@SETTINGS
@given(problems())
def test_director_is_a_sub_strategy_with_one_controllable_move(prob):
    """Every director state is a state of MTSA's controller and every director move one of
    its moves from that state; every uncontrollable move is kept; a state keeps at most one
    controllable move, exactly one where the game has no uncontrollable move."""
    g, W = _solved(prob)
    if W is None:
        return
    director = _moves(enumerate_strategy(g, W, StrategyKind.DIRECTOR))
    permissive = _moves(enumerate_strategy(g, W, StrategyKind.PERMISSIVE))
    ctrl = g.spec.controllable
    for key, moves in director.items():
        assert moves <= permissive[key], key
        assert {m for m in permissive[key] if m[0] not in ctrl} <= moves
        n_ctrl = sum(1 for a, _ in moves if a in ctrl)
        assert n_ctrl <= 1, key
        if key[0] is not None and all(a in ctrl for a, _ in permissive[key]):
            assert n_ctrl == 1, key  # controller-owned: its one move
    assert len(director) <= len(permissive)


@SETTINGS
@given(problems())
def test_director_wins_and_both_solvers_agree(prob):
    """Both solvers' directors (solved as for ``heuristic``, without the DCS preconditions,
    which most random problems fail) are bisimilar; the director never blocks an
    uncontrollable action, never deadlocks or reaches ERROR, and every run satisfies the
    GR(1) goal (the closed system solved by the explicit oracle)."""
    spec = prepare(prob)
    ok, sym, _ = solve_symbolic(spec, {}, lambda _m: None, explain=False, name="C",
                                kind=StrategyKind.DIRECTOR)
    game = build_game(spec)
    ranks = solve_ranks(game)
    assert ok == ranks.winning(game.initial)
    if not ok:
        return
    exp = extract_controller(game, ranks, "C", spec.alphabet, kind=StrategyKind.DIRECTOR)
    director = _minimise(sym)
    assert bisimilar(director, _minimise(exp))
    _check_controlled(prob, director)
    _check_goal_on_every_run(prob, director)


@SETTINGS
@given(problems())
def test_frontier_rank_layers_are_the_plain_ones(prob):
    """rank_layers with the fixpoint's frontier step gives the same layers as without."""
    g, W = _solved(prob)
    if W is None:
        return
    A = g.assumptions or [g.live]
    for gj in g.guarantees or [g.live]:
        goal = gj | g.failures
        assert rank_layers(g, W, goal, A, ratio=1000) == rank_layers(g, W, goal, A, ratio=0)


def _choice_plant():
    """From the goal state 0 (``Done``) the controller may ``go`` (one step from the goal
    again) or take a ``detour`` (two steps); the environment answers ``arrive``.  MTSA's
    controller keeps both (from a goal state any winning move is allowed); the director
    only ``go``, the least rank — not the first label."""
    return make_lts("P", 3, [(0, "go", 2), (0, "detour", 1), (1, "step", 2), (2, "arrive", 0)],
                    {"go", "detour", "step", "arrive"})


def _choice_problem(keywords):
    return problem(_choice_plant(), controllable={"go", "detour", "step"},
                   fluents=[fl("Done", {"arrive"}, {"go", "detour"}, initially=True)],
                   guarantees=(F("Done"),), keywords=keywords)


def test_director_takes_the_least_rank_move():
    full = synthesize(_choice_problem(("controller",)))
    director = synthesize(_choice_problem(("heuristic",)))
    assert full.stats.strategy is StrategyKind.PERMISSIVE
    assert director.stats.strategy is StrategyKind.DIRECTOR
    assert {a for _, a, _ in full.controller.transitions} == {"go", "detour", "step", "arrive"}
    assert {a for _, a, _ in director.controller.transitions} == {"go", "arrive"}
    assert director.controller.num_states < full.controller.num_states


def test_director_output_is_deterministic():
    runs = [synthesize(_choice_problem(("heuristic",))) for _ in range(2)]
    a, b = (r.controller for r in runs)
    assert a.transitions == b.transitions and a.num_states == b.num_states


def test_strategy_kind_by_keywords():
    def kind(**kw):
        prob = _choice_problem(kw.pop("keywords"))
        prob = replace(prob, **kw)
        return strategy_kind(prob, prepare(prob))

    assert kind(keywords=("controller",)) is StrategyKind.PERMISSIVE
    assert kind(keywords=("heuristic",)) is StrategyKind.DIRECTOR
    assert kind(keywords=("heuristic",), permissive=True) is StrategyKind.PERMISSIVE
    assert kind(keywords=("monolithicDirector",)) is StrategyKind.PERMISSIVE
    # heuristic + marking + nonblocking: the non-blocking director, as before
    assert kind(keywords=("heuristic",), marking=frozenset({"arrive"}), guarantees=(),
                nonblocking=True) is StrategyKind.DIRECTOR


SPEC = """
set Ctrl = {go, detour, step}
P = (go -> Q | detour -> step -> Q), Q = (arrive -> P).
fluent Done = <arrive, {go, detour}> initially 1
assert DONE = Done
controllerSpec G = { liveness = {DONE} controllable = Ctrl }
heuristic ||C = (P)~{G}.
"""


def test_cli_says_director(tmp_path, capsys):
    from iterplan_compiler.commands import synth

    spec = tmp_path / "spec.lts"
    spec.write_text(SPEC, encoding="utf-8")
    parser = argparse.ArgumentParser()
    synth.add_arguments(parser)
    assert synth.run(parser.parse_args([str(spec), "C"])) == 0
    out = capsys.readouterr().out
    assert "controller (director): " in out, out


def test_director_is_not_refused_by_the_controller_bound():
    """--max-states is checked up front against |winning region| x |goals| for MTSA's
    controller; the director, far smaller, is only held to the cap while it is enumerated."""
    import pytest

    from iterplan_compiler import limits

    previous = limits.set_limits(max_states=2)
    try:
        with pytest.raises(limits.LimitReached):
            synthesize(_choice_problem(("controller",)))
        director = synthesize(_choice_problem(("heuristic",)))
    finally:
        limits.set_limits(previous)
    assert director.realizable and director.controller.num_states <= 2
