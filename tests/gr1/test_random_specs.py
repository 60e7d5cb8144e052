"""Symbolic solver vs the brute-force explicit oracle on tiny random slugsin specs."""

from __future__ import annotations

import itertools
import os

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from iterplan_compiler.diagnostics import NO_SPAN
from iterplan_compiler.gr1.game import GameOptions, GameOrder
from iterplan_compiler.gr1.slugsin import Expr, Line, SlugsSpec, parse, write
from iterplan_compiler.gr1.solve import SolverOptions, solve
from iterplan_compiler.oracle.gr1_explicit import check_strategy, explicit_game, solve_explicit


def exprs(atoms: list[tuple[str, bool]], depth: int = 3):
    leaves = st.sampled_from([Expr("var", name=n, primed=p) for n, p in atoms]
                             + [Expr("const", value=True), Expr("const", value=False)])
    if depth == 0:
        return leaves

    def extend(children):
        return st.one_of(
            children.map(lambda a: Expr("not", args=(a,))),
            st.tuples(st.sampled_from(["and", "or", "xor"]), children, children).map(
                lambda t: Expr(t[0], args=(t[1], t[2]))),
        )

    return st.recursive(leaves, extend, max_leaves=6)


@st.composite
def specs(draw, allow_primed_live: bool = True):
    nx = draw(st.integers(1, 2))
    ny = draw(st.integers(1, 2))
    xs = [f"x{k}" for k in range(nx)]
    ys = [f"y{k}" for k in range(ny)]
    cur_x = [(v, False) for v in xs]
    cur = cur_x + [(v, False) for v in ys]
    nxt_x = [(v, True) for v in xs]
    allv = cur + nxt_x + [(v, True) for v in ys]

    def lines(atoms, lo, hi):
        return tuple(Line(e, NO_SPAN) for e in draw(st.lists(exprs(atoms), min_size=lo,
                                                             max_size=hi)))

    live_atoms = allv if allow_primed_live and draw(st.booleans()) else cur
    sections = {
        "ENV_INIT": lines(cur_x, 0, 1),
        "SYS_INIT": lines(cur, 0, 1),
        "ENV_TRANS": lines(cur + nxt_x, 0, 2),
        "SYS_TRANS": lines(allv, 0, 2),
        "ENV_LIVENESS": lines(live_atoms, 0, 2),
        "SYS_LIVENESS": lines(live_atoms, 0, 2),
    }
    spec = SlugsSpec(tuple(xs), tuple(ys), sections)
    # round-trip through the printer and the parser, so the reader is exercised too
    parsed, diags = parse(write(spec))
    assert parsed is not None, diags
    return parsed


CONFIGS = [
    (GameOptions(), SolverOptions()),
    (GameOptions(partition=False, order=GameOrder.BLOCKED), SolverOptions(feedback=False, recycle=False,
                                                                   early_unrealizable=False)),
    (GameOptions(group_pairs=True, cluster_nodes=1), SolverOptions(recycle=False)),
    # the MTSA defaults of the one engine (recycling, chained μY) on slugs games
    # (chained μY applies only without iterates: that config runs realizability-only)
    (GameOptions(reordering=False, order=GameOrder.SPEC), SolverOptions(recycle=True, chained=True,
                                                                early_unrealizable=False)),
    (GameOptions(order=GameOrder.SPEC), SolverOptions(recycle=True, feedback=False)),
]


def _z_states(res, spec):
    game = explicit_game(spec)
    bdd = res.game.bdd
    out = set()
    for s in game.states:
        if bdd.let(dict(zip(game.names, s, strict=True)), res.winning) == bdd.true:
            out.add(s)
    return out


@settings(max_examples=int(os.environ.get("GR1_EXAMPLES", "60")), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(specs(), st.sampled_from(range(len(CONFIGS))))
def test_symbolic_matches_explicit(spec, cfg):
    gopt, sopt = CONFIGS[cfg]
    expected_real, expected_z = solve_explicit(spec)
    res, diags = solve(spec, strategy=not sopt.chained, game_options=gopt, solver_options=sopt)
    assert res is not None, diags
    assert res.realizable == expected_real
    if not res.stats["early_stop"]:
        assert _z_states(res, spec) == expected_z
    if res.realizable and res.strategy is not None:
        assert check_strategy(spec, res.strategy) == []


def test_check_strategy_detects_a_bad_strategy():
    """The exhaustive checker must be able to fail: a strategy that never grants."""
    text = "[INPUT]\nr\n[OUTPUT]\ng\n[ENV_TRANS]\n| ! & r ! g r'\n[SYS_LIVENESS]\n| ! r g\n"
    spec, _ = parse(text)
    res, _ = solve(spec)
    assert res.realizable

    class Never:
        def initial(self, inputs):
            return {"g": False}

        def step(self, state, goal, nxt):
            return {"g": False}, goal

    assert check_strategy(spec, Never()) != []
    assert check_strategy(spec, res.strategy) == []


def test_all_small_assignments_enumerated():
    spec, _ = parse("[INPUT]\na\nb\n[OUTPUT]\nc\n")
    game = explicit_game(spec)
    assert sorted(game.states) == sorted(itertools.product((False, True), repeat=3))
