"""Property test: symbolic and explicit solvers agree (winning sets, verdicts, controllers)."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from synthesis_helpers import F, fl, problem

from iterplan_compiler.ir.formulas import Not
from iterplan_compiler.ir.lts import ERROR, make_lts
from iterplan_compiler.ir.minimise import bisimilar
from iterplan_compiler.synthesis.driver import synthesize
from iterplan_compiler.synthesis.encode import prepare
from iterplan_compiler.synthesis.explicit import build_game, winning_region
from iterplan_compiler.synthesis.fixpoint import gr1_winning
from iterplan_compiler.synthesis.game import SymbolicGame

ACTIONS = ["a", "b", "c", "u", "v"]


@st.composite
def lts_strategy(draw, name, max_states=4, error_ok=False):
    n = draw(st.integers(1, max_states))
    alpha = draw(st.sets(st.sampled_from(ACTIONS), min_size=1, max_size=4))
    targets = st.integers(-1 if error_ok else 0, n - 1)
    trans = draw(st.lists(st.tuples(st.integers(0, n - 1), st.sampled_from(sorted(alpha)),
                                    targets), max_size=3 * n))
    # MTSA's normal case is a deterministic plant (§3.2 step 5): keep one target per (s, a)
    det = {(s, a): t for s, a, t in trans}
    return make_lts(name, n, [(s, a, t) for (s, a), t in det.items()], alpha)


@st.composite
def problems(draw):
    plant = [draw(lts_strategy("P"))]
    if draw(st.booleans()):
        plant.append(draw(lts_strategy("Q", 3)))
    safety = (draw(lts_strategy("S", 2, error_ok=True)),) if draw(st.booleans()) else ()
    fluents = []
    for i in range(draw(st.integers(1, 3))):
        init = draw(st.sets(st.sampled_from(ACTIONS), min_size=1, max_size=2))
        term = draw(st.sets(st.sampled_from([a for a in ACTIONS if a not in init]),
                            max_size=2))
        fluents.append(fl(f"F{i}", init, term, draw(st.booleans())))
    props = st.sampled_from([F(f.name) for f in fluents] + [Not(F(f.name)) for f in fluents])
    guarantees = tuple(draw(st.lists(props, max_size=2)))
    assumptions = tuple(draw(st.lists(props, max_size=2)))
    ctrl = draw(st.sets(st.sampled_from(ACTIONS)))
    return problem(tuple(plant), controllable=ctrl, fluents=fluents, guarantees=guarantees,
                   assumptions=assumptions, safety=safety)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_symbolic_and_explicit_agree(prob):
    spec = prepare(prob)
    game = build_game(spec)
    win_explicit = winning_region(game)
    g = SymbolicGame(spec)
    reach = g.reachable()
    goals = [gj | g.failures for gj in g.guarantees]
    fp = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach)
    # the chained (Gauss–Seidel) μY and the layered (Jacobi) one reach the same fixpoint
    layered = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach, keep_iterates=True)
    assert layered.winning == fp.winning
    W = fp.winning & reach
    for s, tup in enumerate(game.tuples):
        if tup is None:
            assert s not in win_explicit
            continue
        sym = (g.state_cube(tup) & W) != g.bdd.false
        assert sym == (s in win_explicit), (s, tup)
    r_sym = synthesize(prob, solver="symbolic")
    r_exp = synthesize(prob, solver="explicit")
    assert r_sym.realizable == r_exp.realizable == (game.initial in win_explicit)
    if r_sym.realizable:
        assert bisimilar(r_sym.controller, r_exp.controller)
        _check_controlled(prob, r_exp.controller)
        _check_goal_on_every_run(prob, r_sym.controller)


def _check_goal_on_every_run(prob, controller):
    """Every run of controller ∥ plant satisfies the GR(1) goal, however the remaining
    choices are resolved: with *no* controllable action every state belongs to the
    environment, so the spec is "realizable" iff all runs are safe, deadlock-free and
    (∧ GF A) → (∧ GF G)."""
    from dataclasses import replace

    closed = replace(prob, plant=(controller, *prob.plant), controllable=frozenset())
    assert synthesize(closed, solver="explicit").realizable


def _check_controlled(prob, controller):
    """The controlled plant never reaches ERROR, never deadlocks, never blocks uncontrollables."""
    from iterplan_compiler.synthesis.explicit import explore_product

    comps = [controller, *prob.plant, *prob.safety]
    tuples, edges, _ = explore_product(comps)
    plant_only = list(prob.plant) + list(prob.safety)
    _, _, _ = explore_product(plant_only)
    for k, out in enumerate(edges):
        assert out, "controlled system deadlocks"
        assert all(t != ERROR for _, t in out), "controlled system reaches ERROR"
        # legality: every uncontrollable action the plant enables is enabled in the product
        plant_state = tuples[k][1:]
        enabled = _enabled(plant_only, plant_state)
        got = {a for a, _ in out}
        for a in enabled - prob.controllable:
            assert a in got, f"controller blocks uncontrollable {a}"


def _enabled(components, state):
    owners: dict[str, list[int]] = {}
    for k, c in enumerate(components):
        for a in c.alphabet:
            owners.setdefault(a, []).append(k)
    out = set()
    for a, ks in owners.items():
        if all(any(s == state[k] and x == a for s, x, _ in components[k].transitions)
               for k in ks):
            out.add(a)
    return out


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems(), st.sets(st.sampled_from(ACTIONS), min_size=1, max_size=2))
def test_nonblocking_solvers_agree(prob, marking):
    from dataclasses import replace

    nb = replace(prob, keywords=frozenset({"heuristic"}), marking=frozenset(marking),
                 nonblocking=True, guarantees=(), assumptions=())
    r_sym = synthesize(nb, solver="symbolic")
    r_exp = synthesize(nb, solver="explicit")
    assert r_sym.stats["mode"] == "nonblocking"
    assert r_sym.realizable == r_exp.realizable
    if r_sym.realizable:
        assert r_sym.stats["winning_states"] == r_exp.stats["winning_states"]
        _check_controlled(nb, r_exp.controller)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_explanations_never_fail(prob):
    from iterplan_compiler.synthesis.explain import explain_losing

    spec = prepare(prob)
    game = build_game(spec)
    win = winning_region(game)
    if game.initial not in win:
        text = explain_losing(spec, game, win)  # must not raise
        assert text.startswith("unrealizable")


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_symbolic_rank_layers_are_mtsa_ranks(prob):
    """The symbolic rank layers (symbolic_strategy.rank_layers) give exactly the least rank
    function of the explicit solver on every winning reachable state, for every guarantee."""
    from iterplan_compiler.synthesis.explicit import solve_ranks
    from iterplan_compiler.synthesis.symbolic_strategy import _Oracle, rank_layers

    spec = prepare(prob)
    game = build_game(spec)
    ranks = solve_ranks(game)
    g = SymbolicGame(spec)
    reach = g.reachable()
    goals = [gj | g.failures for gj in (g.guarantees or [g.live])]
    W = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach & g.live).winning & reach
    A = g.assumptions or [g.live]
    layers = [rank_layers(g, W, gj, A) for gj in goals] if W != g.bdd.false else []
    orc = _Oracle(g, W, layers)
    for s, tup in enumerate(game.tuples):
        if tup is None or not ranks.winning(s):
            continue
        for j in range(len(goals)):
            assert orc.rank(j, tup) == ranks.rank[j][s], (s, j)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_realizability_only_gives_the_same_verdict(prob):
    """``synthesize(..., realizability_only=True)`` (``iterc synth --realizability-only``)
    stops at the verdict: the full run's verdict, no controller, both solvers."""
    for solver in ("symbolic", "explicit"):
        full = synthesize(prob, solver=solver, explain=False)
        quick = synthesize(prob, solver=solver, explain=False, realizability_only=True)
        assert quick.realizable == full.realizable
        assert quick.controller is None and quick.composition is None
