"""Macro steps (synthesis/macro.py): the compressed game gives the full game's winning
region — on random games with the Clock/Turns turn structure of the SYNTECH15 specs, on a
small FSP spec of that shape — and it is not applied where its conditions fail."""

from __future__ import annotations

from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from synthesis_helpers import F, assert_same_as_full_game, fl, problem
from test_agreement import lts_strategy

from iterplan_compiler.ir.formulas import And, Not
from iterplan_compiler.ir.lts import make_lts
from iterplan_compiler.ir.minimise import bisimilar
from iterplan_compiler.synthesis.driver import synthesize
from iterplan_compiler.synthesis.encode import prepare
from iterplan_compiler.synthesis.fixpoint import gr1_winning
from iterplan_compiler.synthesis.macro import chain_states, modified_vars, solve_macro
from iterplan_compiler.synthesis.options import MacroSteps
from iterplan_compiler.synthesis.recode import recode_leaves
from iterplan_compiler.synthesis.symbolic_game import SymbolicGame

UNC = ["u", "v"]
CTRL = ["a", "b", "c"]


def _clock():
    """Env_turn (0): uncontrolled moves, then ``tock``; Sys_turn (1): controlled, then ``tick``."""
    trans = [(0, x, 0) for x in UNC] + [(0, "tock", 1)]
    trans += [(1, x, 1) for x in CTRL] + [(1, "tick", 0)]
    return make_lts("Clock", 2, trans, frozenset([*UNC, *CTRL, "tick", "tock"]))


def _turns(n, ctrl=tuple(CTRL)):
    """``Turns(n)``: at most ``n`` controlled actions per turn (state ``n - i`` = ``i`` left)."""
    trans = [(n - i, x, n - i + 1) for i in range(1, n + 1) for x in ctrl]
    trans += [(s, "tick", 0) for s in range(n + 1)]
    return make_lts("Turns", n + 1, trans, frozenset([*ctrl, "tick"]))


@st.composite
def _env_machine(draw):
    """A machine of the environment alone (``u v``, enabled everywhere, so it blocks
    nothing): no controllable move changes its state."""
    n = draw(st.integers(2, 3))
    trans = [(s, a, draw(st.integers(0, n - 1))) for s in range(n) for a in UNC]
    return make_lts("E", n, trans, frozenset(UNC))


@st.composite
def turn_problems(draw, env_only=False):
    """A random plant over ``a b c u v`` under the turn structure; goals mostly ``tick && …``,
    assumptions ``tock && …`` or ``Tock`` (true throughout a system turn).  ``env_only``:
    also an environment machine and fluent (variables no chain move modifies)."""
    plant = [_clock(), _turns(draw(st.integers(1, 3))), draw(lts_strategy("P"))]
    if env_only:
        plant.append(draw(_env_machine()))
    safety = (draw(lts_strategy("S", 2, error_ok=True)),) if draw(st.booleans()) else ()
    every = [*UNC, *CTRL, "tick", "tock"]
    fluents = [fl("Tk", {"tick"}, set(every) - {"tick"}), fl("Tc", {"tock"}, set(every) - {"tock"}),
               fl("Tock", {"tock"}, {"tick"})]
    for i in range(draw(st.integers(1, 2))):
        init = draw(st.sets(st.sampled_from(CTRL + UNC), min_size=1, max_size=2))
        term = draw(st.sets(st.sampled_from([a for a in CTRL + UNC if a not in init]),
                            max_size=2))
        fluents.append(fl(f"F{i}", init, term, draw(st.booleans())))
    if env_only:
        fluents.append(fl("Fu", {"u"}, {"v"}, draw(st.booleans())))
    lits = st.sampled_from([F(f.name) for f in fluents[3:]] + [Not(F(f.name)) for f in fluents[3:]])
    goal = st.one_of(lits.map(lambda p: And(F("Tk"), p)), lits)
    assumption = st.one_of(lits.map(lambda p: And(F("Tc"), p)), st.just(F("Tock")), lits)
    return problem(tuple(plant), controllable={*CTRL, "tick"}, fluents=fluents,
                   guarantees=tuple(draw(st.lists(goal, max_size=2))),
                   assumptions=tuple(draw(st.lists(assumption, max_size=2))), safety=safety)


def _both(prob, min_share=0.0):
    """Per encoding of ``prob``: the game, its live reachable states, the full game's
    fixpoint, and the macro one (None: not applied) with its stats."""
    for spec in (prepare(prob), recode_leaves(prepare(prob))):
        g = SymbolicGame(spec)
        reach = g.reachable() & g.live
        goals = [gj | g.failures for gj in (g.guarantees or [g.live])]
        full = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach)
        stats: dict = {}
        fp = solve_macro(g, reach, g.assumptions, goals, say=lambda _m: None, stats=stats,
                         min_share=min_share)
        yield g, reach, full, fp, stats


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(turn_problems())
def test_macro_keeps_the_winning_region(prob):
    for g, reach, full, fp, stats in _both(prob):
        if fp is None:  # only when there is no chain state at all (e.g. the plant blocks
            # every controlled move): Turns bounds every chain, so otherwise it applies
            assert stats.get("macro_chain_states") == 0, stats
            continue
        if fp.complete:
            assert fp.winning & reach == full.winning & reach
        else:  # stopped early: the initial state is lost in both
            assert g.init & full.winning == g.bdd.false


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(turn_problems(env_only=True))
def test_macro_copies_only_modified_variables(prob):
    """``M`` keeps a copy of the variables chain moves modify only (``modified_vars``); the
    environment machine's and ``Fu``'s are left out, and the winning region is the same."""
    for g, reach, full, fp, stats in _both(prob):
        assert len(modified_vars(g)) < len(g.cur_vars)
        if fp is None:  # E may block ``tock``: then no system turn is reached
            assert stats["macro"] == "off: few chain states", stats
        elif fp.complete:
            assert fp.winning & reach == full.winning & reach
        else:
            assert g.init & full.winning == g.bdd.false


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(turn_problems())
def test_macro_keeps_verdict_and_controller(prob):
    assert_same_as_full_game(prob, MacroSteps.CHAINS)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(turn_problems())
def test_chains_satisfy_the_conditions(prob):
    """Every proposition is false on C or absorbed (C ⊆ P, every entry into C satisfies P)."""
    spec = prepare(prob)
    g = SymbolicGame(spec)
    reach = g.reachable() & g.live
    props = [*g.assumptions, *[gj | g.failures for gj in g.guarantees]]
    C = chain_states(g, reach, props)
    assert C <= g.ctrl_owned & reach
    entries = reach & ~C & g.pre_any(C)
    for P in props:
        assert C & P == g.bdd.false or (C <= P and entries <= P)


def test_a_controllable_cycle_blocks_the_transform():
    """Without ``Turns`` the controller can stay inside its turn forever: condition (a)
    fails and the full game is solved."""
    every = [*UNC, *CTRL, "tick", "tock"]
    prob = problem((_clock(),), controllable={*CTRL, "tick"},
                   fluents=[fl("Tk", {"tick"}, set(every) - {"tick"})],
                   guarantees=(F("Tk"),))
    for _g, _reach, _full, fp, stats in _both(prob):
        assert fp is None
        assert stats["macro"].startswith("off: controllable cycle")


def test_a_bad_entry_leaves_the_chain():
    """``Tock`` (absorbed: true on the system turn) is false on the environment state that
    enters the turn, so the turn's first state is no chain state: it must stay visible, or
    the compressed play would never see ``Tock`` and the assumption would hold vacuously.
    Here the controller loses (the goal never holds, the environment must ``tock``)."""
    clock = make_lts("Clock", 2, [(0, "tock", 1), (1, "a", 1), (1, "tick", 0)],
                     frozenset(["a", "tick", "tock"]))
    prob = problem((clock, _turns(2, ("a",))), controllable={"a", "tick"},
                   fluents=[fl("Tock", {"tock"}, {"tick"})],
                   assumptions=(F("Tock"),), guarantees=(And(F("Tock"), Not(F("Tock"))),))
    for g, reach, full, fp, _stats in _both(prob):
        C = chain_states(g, reach, [*g.assumptions, *g.guarantees])
        assert C != g.bdd.false and C & g.post(g.init) == g.bdd.false
        assert g.init & full.winning == g.bdd.false
        assert fp is not None and g.init & fp.winning == g.bdd.false
    assert not synthesize(prob, explain=False).realizable


TURNS_FSP = Path(__file__).resolve().parents[1] / "data" / "macro_turns.fsp"


def test_turn_structured_spec():
    """A small spec in the SYNTECH15 shape: the transform applies (Turns bounds the chains)
    and gives the same verdict and a bisimilar controller, director and permissive; without
    ``Turns`` (``LooseControl``) it does not apply."""
    from iterplan_compiler.pipeline import load_model

    model, _diags = load_model(str(TURNS_FSP))[:2]
    for name in ("Control", "Permissive"):
        prob, _ = model.synthesis_problem(name)
        on = synthesize(prob, macro=MacroSteps.CHAINS, explain=False)
        off = synthesize(prob, macro=MacroSteps.OFF, explain=False)
        assert on.stats["macro"] == "on"
        assert on.realizable and off.realizable
        assert bisimilar(on.controller, off.controller)
    prob, _ = model.synthesis_problem("LooseControl")
    on = synthesize(prob, macro=MacroSteps.CHAINS, explain=False)
    assert str(on.stats["macro"]).startswith("off")


def test_synth_command_reports_and_switches_macro_steps(capsys):
    """``iterc synth --macro chains`` says when the macro steps were used (by default the
    turn steps of test_turns.py take this spec) and ``--macro off`` solves the full game
    (same verdict, no macro line)."""
    from iterplan_compiler.cli import main

    assert main(["synth", str(TURNS_FSP), "Control", "--macro", "chains"]) == 0
    out = capsys.readouterr().out
    assert "macro steps:" in out and "chain states compressed" in out
    assert main(["synth", str(TURNS_FSP), "Control", "--macro", "off"]) == 0
    out = capsys.readouterr().out
    assert "realizable" in out and "macro steps:" not in out
