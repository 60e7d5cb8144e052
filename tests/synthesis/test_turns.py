"""Turn steps (synthesis/turns.py): the game on the turn starts gives the full game's verdict
and winning region — on random games in the SYNTECH15 shape (Clock, Turns, one machine per
variable, monitors that judge at ``tick``/``tock``), on a small FSP spec of that shape and on
GyroLTL_390 — and it is not applied where one of its conditions fails."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from synthesis_helpers import F, assert_same_as_full_game, fl, problem
from test_macro import _turns as macro_turns

from iterplan_compiler.ir.formulas import And, Not
from iterplan_compiler.ir.lts import ERROR, make_lts
from iterplan_compiler.ir.minimise import bisimilar
from iterplan_compiler.synthesis.driver import synthesize
from iterplan_compiler.synthesis.encode import prepare
from iterplan_compiler.synthesis.fixpoint import gr1_winning
from iterplan_compiler.synthesis.options import MacroSteps
from iterplan_compiler.synthesis.recode import recode_leaves
from iterplan_compiler.synthesis.symbolic_game import SymbolicGame
from iterplan_compiler.synthesis.turns import find_turns, solve_turns

#: variables: name -> its setter actions (value i set by the i-th)
ENV_VARS = {"e": ("e0", "e1"), "d": ("d0", "d1")}
SYS_VARS = {"x": ("x0", "x1", "x2"), "y": ("y0", "y1")}
UNC = [a for acts in ENV_VARS.values() for a in acts]
CTRL = [a for acts in SYS_VARS.values() for a in acts]
EVERY = [*UNC, *CTRL, "tick", "tock"]


def _clock(unc=tuple(UNC), ctrl=tuple(CTRL)):
    trans = [(0, a, 0) for a in unc] + [(0, "tock", 1)]
    trans += [(1, a, 1) for a in ctrl] + [(1, "tick", 0)]
    return make_lts("Clock", 2, trans, frozenset([*unc, *ctrl, "tick", "tock"]))


def _turns(n):
    return macro_turns(n, tuple(CTRL))


def _variable(name, setters):
    """One machine per variable: ``setters[i]`` sets value ``i`` from anywhere."""
    n = len(setters)
    return make_lts(name, n, [(s, a, i) for s in range(n) for i, a in enumerate(setters)],
                    frozenset(setters))


@st.composite
def _monitor(draw, var, judge):
    """Tracks ``var`` and a residual of 2 states, and moves only on ``judge`` (``tick``:
    a property, to ERROR where it fails; ``tock``: an environment constraint, blocked where
    it fails) — the shape of the translated ``[](tick -> …)`` properties."""
    setters = {**ENV_VARS, **SYS_VARS}[var]
    n = len(setters)

    def code(v, r):
        return 2 * v + r

    trans = [(code(v, r), a, code(i, r)) for v in range(n) for r in range(2)
             for i, a in enumerate(setters)]
    for v, r in itertools.product(range(n), range(2)):
        to = draw(st.integers(-1, 1))  # -1: fails here
        if to >= 0:
            trans.append((code(v, r), judge, code(v, to)))
        elif judge == "tick":
            trans.append((code(v, r), judge, ERROR))
    return make_lts(f"M_{var}_{judge}", 2 * n, trans, frozenset([*setters, judge]))


@st.composite
def _hazard(draw):
    """A property over the environment's moves alone: tracks ``e`` and fails (ERROR) on
    some ``d`` moves for some values of ``e`` — an environment move inside its turn that
    loses the game for the controller."""
    trans = [(v, a, i) for v in range(2) for i, a in enumerate(ENV_VARS["e"])]
    for v, a in itertools.product(range(2), ENV_VARS["d"]):
        trans.append((v, a, ERROR if draw(st.integers(0, 3)) == 0 else v))
    return make_lts("Hazard", 2, trans, frozenset([*ENV_VARS["e"], *ENV_VARS["d"]]))


def _value(var, i):
    """The fluent ``var == i``."""
    setters = {**ENV_VARS, **SYS_VARS}[var]
    return fl(f"{var}{i}", {setters[i]}, set(setters) - {setters[i]}, i == 0)


@st.composite
def turn_problems(draw, budget=None):
    plant = [_clock(), _turns(budget or draw(st.integers(2, 4)))]
    plant += [_variable(v, acts) for v, acts in {**ENV_VARS, **SYS_VARS}.items()]
    safety = []
    for var in draw(st.lists(st.sampled_from(sorted(SYS_VARS)), max_size=2, unique=True)):
        safety.append(draw(_monitor(var, "tick")))
    for var in draw(st.lists(st.sampled_from(sorted(ENV_VARS)), max_size=1)):
        plant.append(draw(_monitor(var, "tock")))
    if draw(st.booleans()):
        safety.append(draw(_hazard()))
    marks = [fl("Tk", {"tick"}, set(EVERY) - {"tick"}), fl("Tc", {"tock"}, set(EVERY) - {"tock"}),
             fl("Tock", {"tock"}, {"tick"})]
    values = [_value(v, i) for v, acts in {**ENV_VARS, **SYS_VARS}.items()
              for i in range(len(acts))]
    env_lits = st.sampled_from([F(f.name) for f in values if f.name[0] in ENV_VARS])
    lits = st.sampled_from([F(f.name) for f in values] + [Not(F(f.name)) for f in values])
    goals = st.lists(lits.map(lambda p: And(F("Tk"), p)), max_size=2)
    assumptions = st.lists(st.one_of(env_lits.map(lambda p: And(F("Tc"), p)),
                                     st.just(F("Tock"))), min_size=1, max_size=2)
    return problem(tuple(plant), controllable={*CTRL, "tick"}, fluents=[*marks, *values],
                   guarantees=tuple(draw(goals)), assumptions=tuple(draw(assumptions)),
                   safety=tuple(safety))


def _games(prob):
    for spec in (prepare(prob), recode_leaves(prepare(prob))):
        g = SymbolicGame(spec)
        goals = [gj | g.failures for gj in (g.guarantees or [g.live])]
        stats: dict = {}
        sol = solve_turns(g, g.assumptions, goals, say=lambda _m: None, stats=stats)
        reach = g.reachable() & g.live
        full = gr1_winning(g.bdd, g.cpre, g.assumptions, goals, care=reach)
        yield g, reach, full, sol, stats


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(turn_problems())
def test_turns_keep_the_verdict_and_the_winning_region(prob):
    for g, reach, full, sol, stats in _games(prob):
        if sol is None:  # only a budget below the number of system variables, or no
            # assumption (an endless environment turn would not lose)
            assert stats["turns"].startswith(("off: no turn budget",
                                              "off: an environment that never")), stats
            continue
        assert sol.realizable == (g.init & full.winning != g.bdd.false)
        B = sol.game.boundary
        assert B <= reach and g.init <= B
        if sol.fixpoint.complete:
            assert sol.fixpoint.winning & B == full.winning & B
        assert sol.reachable() & g.live == reach
        assert sol.full_winning(reach, exact=True) == full.winning & reach


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(turn_problems(budget=3))
def test_turns_keep_the_controller(prob):
    assert_same_as_full_game(prob, MacroSteps.AUTO)


def _base(**kw):
    every = [*UNC, *CTRL, "tick", "tock"]
    plant = kw.pop("plant", [_clock(), _turns(3)] + [_variable(v, a) for v, a in
                                                      {**ENV_VARS, **SYS_VARS}.items()])
    return problem(tuple(plant), controllable={*CTRL, "tick"},
                   fluents=[fl("Tk", {"tick"}, set(every) - {"tick"}),
                            fl("Tock", {"tock"}, {"tick"}), _value("x", 1)],
                   guarantees=(And(F("Tk"), F("x1")),), assumptions=(F("Tock"),), **kw)


def _reason(prob):
    g = SymbolicGame(prepare(prob))
    out = find_turns(g)
    return out if isinstance(out, str) else None


def test_applies_to_the_plain_shape():
    assert _reason(_base()) is None


def test_order_dependent_moves_block_it():
    """A machine that remembers whether ``x1`` came before ``y1`` in the turn: the two do
    not commute, so their groups are merged, and then ``x1 ; y1`` is not ``y1`` alone —
    the turn's end states are not those of one canonical order."""
    order = make_lts("Order", 3, [(0, "x1", 1), (0, "y1", 2), (1, "y1", 1), (2, "x1", 2),
                                  (1, "tick", 0), (2, "tick", 0), (0, "tick", 0)],
                     frozenset(["x1", "y1", "tick"]))
    prob = _base(safety=(order,))
    assert _reason(prob) == "Order: x1 then y1 is not y1 alone"
    assert synthesize(prob, explain=False).stats["turns"].startswith("off")


def test_a_move_that_counts_blocks_it():
    """``x1 ; x1`` differs from ``x1`` (a machine counts them): not "last wins"."""
    count = make_lts("Count", 3, [(0, "x1", 1), (1, "x1", 2), (2, "x1", 2),
                                  *((s, "tick", 0) for s in range(3))],
                     frozenset(["x1", "tick"]))
    assert "is not x1 alone" in _reason(_base(safety=(count,)))


def test_no_budget_blocks_it():
    """Without ``Turns`` a system turn may go on for ever."""
    plant = [_clock()] + [_variable(v, a) for v, a in {**ENV_VARS, **SYS_VARS}.items()]
    assert _reason(_base(plant=plant)).startswith("no turn budget")
    # a budget too small for one move per system variable does not count either
    plant = [_clock(), _turns(1)] + [_variable(v, a) for v, a in
                                     {**ENV_VARS, **SYS_VARS}.items()]
    assert _reason(_base(plant=plant)).startswith("no turn budget")


def test_no_turn_component_blocks_it():
    prob = problem((_variable("x", SYS_VARS["x"]), _variable("e", ENV_VARS["e"])),
                   controllable=set(SYS_VARS["x"]))
    assert _reason(prob) == "no turn component"


def test_a_proposition_inside_a_turn_blocks_it():
    """A goal on a variable's value without ``tick &&`` holds inside turns too: the
    compressed play would not see it there."""
    prob = _base()
    prob = problem(prob.plant, controllable=set(prob.controllable), fluents=prob.fluents,
                   guarantees=(F("x1"),), assumptions=prob.assumptions)
    out = synthesize(prob, explain=False)
    assert out.stats["turns"] == "off: a GR(1) proposition holds on part of a turn only"
    assert out.realizable


DATA = Path(__file__).resolve().parents[1] / "data"
SYNTECH = Path(__file__).resolve().parents[3] / "shared" / "benchmarks" / "syntech15"


def test_turn_structured_spec_and_the_switch(capsys):
    """The small SYNTECH15-shaped spec: turn steps apply, same verdict and bisimilar
    controllers (director and permissive) as the full game; ``iterc synth`` says so, and
    ``--macro chains`` / ``off`` do not use them."""
    from iterplan_compiler.cli import main
    from iterplan_compiler.pipeline import load_model

    model = load_model(str(DATA / "macro_turns.fsp"))[0]
    for name in ("Control", "Permissive"):
        prob, _ = model.synthesis_problem(name)
        on = synthesize(prob, explain=False)
        off = synthesize(prob, macro=MacroSteps.OFF, explain=False)
        assert on.stats["turns"] == "on"
        assert on.realizable and off.realizable
        assert bisimilar(on.controller, off.controller)
    assert main(["synth", str(DATA / "macro_turns.fsp"), "Control"]) == 0
    assert "turn steps: solved on 8 turn starts" in capsys.readouterr().out
    for flag in ("chains", "off"):
        assert main(["synth", str(DATA / "macro_turns.fsp"), "Control", "--macro", flag]) == 0
        assert "turn steps" not in capsys.readouterr().out


@pytest.mark.skipif(not SYNTECH.is_dir(), reason="../shared/benchmarks/syntech15 not present")
def test_syntech15_gyro_390():
    """A real SYNTECH15 translation: turn steps apply; same controller as without."""
    from iterplan_compiler.pipeline import load_model

    prob, _ = load_model(str(SYNTECH / "GyroLTL_390_GyroAspect.fsp"))[0] \
        .synthesis_problem("Control")
    on = synthesize(prob, explain=False)
    off = synthesize(prob, macro=MacroSteps.CHAINS, explain=False)
    assert on.stats["turns"] == "on" and on.realizable and off.realizable
    assert bisimilar(on.controller, off.controller)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(turn_problems(budget=3))
def test_turns_keep_the_explanation(prob):
    """An unrealizable game explained (counts and the environment's play) from the full
    winning region the turn game rebuilds: the same text as from the full game."""
    on = synthesize(prob, explain=True)
    off = synthesize(prob, macro=MacroSteps.OFF, explain=True)
    assert on.realizable == off.realizable
    assert on.explanation == off.explanation


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(turn_problems())
def test_turn_game_verdict_only_builds_no_deferred_relation(prob):
    """With every multi-owner action deferred (``partition.DEFER_NODES = 0``) the turn game
    still gives the full game's verdict, and a verdict-only solve never builds the system
    exit's deferred relation (the exit is imaged through its clusters): so on
    GyroLTLVar2_701 the 5.5 M-node ``tick`` is not built before its verdict."""
    from unittest.mock import patch

    from iterplan_compiler.synthesis import partition
    from iterplan_compiler.synthesis.game import solve_symbolic
    from iterplan_compiler.synthesis.symbolic_game import SymbolicGame as Game

    spec = prepare(prob)
    want = synthesize(prob, explain=False, macro=MacroSteps.OFF).realizable
    stats: dict = {}
    with patch.object(partition, "DEFER_NODES", 0), \
            patch.object(Game, "reachable", side_effect=AssertionError("full BFS")):
        try:
            ok, ctrl, _ = solve_symbolic(spec, stats, lambda _m: None, explain=False,
                                         name="C", verdict_only=True)
        except AssertionError:  # the conditions failed: the full game's BFS was asked for
            assert stats.get("turns", "").startswith("off"), stats
            return
    assert stats["turns"] == "on" and ctrl is None and ok == want
    with patch.object(partition, "DEFER_NODES", 0), \
            patch.object(partition.Group, "rel", property(_no_build, _set_rel)):
        ok, ctrl, _ = solve_symbolic(spec, {}, lambda _m: None, explain=False, name="C",
                                     verdict_only=True)
        assert ok == want and ctrl is None


def _no_build(grp):
    """``Group.rel`` that refuses to build the system exit's (``tick``) deferred relation
    (the chain and environment groups' relations the turn game reads, so they are built)."""
    if grp.factors and "tick" in grp.actions:
        raise AssertionError("the exit's deferred relation was built before the verdict")
    if grp.factors:
        grp.built, grp.factors = grp.within(), ()
    return grp.built


def _set_rel(grp, value):
    grp.built, grp.factors = value, ()


@pytest.mark.skipif(not SYNTECH.is_dir(), reason="../shared/benchmarks/syntech15 not present")
def test_syntech15_declaration_order_keeps_verdict_and_controller(tmp_path):
    """``benchmarks/syntech15_permute.py`` variants (the ``||Env`` operands, the action sets
    and the variable blocks shuffled: FSP gives their order no meaning) are solved to the
    original's verdict and a bisimilar controller; the script changed every file."""
    import subprocess
    import sys

    from iterplan_compiler.pipeline import load_model

    script = Path(__file__).resolve().parents[2] / "benchmarks" / "syntech15_permute.py"
    subprocess.run([sys.executable, str(script), str(tmp_path), "--from", str(SYNTECH),
                    "--seeds", "1", "2"], check=True, capture_output=True)
    for rel in ("GyroLTL_390_GyroAspect.fsp",
                "unrealizable/GyroUnrealizable_Var1_710_GyroAspect_unrealizable.fsp"):
        original = SYNTECH / rel
        runs = []
        for path in (original, *(tmp_path / Path(rel).parent / f"{original.stem}_p{s}.fsp"
                                 for s in (1, 2))):
            assert path == original or path.read_text() != original.read_text()
            prob, _ = load_model(str(path))[0].synthesis_problem("Control")
            runs.append(synthesize(prob, explain=False))
        assert len({r.realizable for r in runs}) == 1
        assert runs[0].realizable == (not rel.startswith("unrealizable"))
        if runs[0].realizable:
            assert all(bisimilar(runs[0].controller, r.controller) for r in runs[1:])


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(turn_problems(budget=3))
def test_learned_order_keeps_verdict_and_controller(prob):
    """The variable order learned from the turn starts (synthesis/learn_order.py; with
    ``LEARN_NODES = 0`` after the first turn) gives the declared order's verdict and a
    bisimilar controller; without learning nothing is learned."""
    from iterplan_compiler.synthesis import turns

    runs = {}
    for at in (None, 0):
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(turns, "LEARN_NODES", at)
            runs[at] = synthesize(prob, explain=False)
    plain, learned = runs[None], runs[0]
    assert "order_learned_at" not in plain.stats
    assert plain.realizable == learned.realizable
    if plain.realizable:
        assert bisimilar(plain.controller, learned.controller)


def test_learned_order_is_the_rebuilt_games_order(monkeypatch, capsys):
    """On the small SYNTECH15-shaped spec, learning from the first turn rebuilds the game
    with its variables in the sifted order (each current variable right before its primed
    copy), says so, and solves it to the same controller."""
    from iterplan_compiler.cli import main
    from iterplan_compiler.pipeline import load_model
    from iterplan_compiler.synthesis import game, turns
    from iterplan_compiler.synthesis.learn_order import sifted_order

    prob, _ = load_model(str(DATA / "macro_turns.fsp"))[0].synthesis_problem("Control")
    plain = synthesize(prob, explain=False)
    built: list[SymbolicGame] = []
    encode = game._encode
    monkeypatch.setattr(game, "_encode", lambda *a, **k: built.append(encode(*a, **k))
                        or built[-1])
    sifted: list[tuple[str, ...] | None] = []
    monkeypatch.setattr(turns, "sifted_order",
                        lambda *a: sifted.append(sifted_order(*a)) or sifted[-1])
    monkeypatch.setattr(turns, "LEARN_NODES", 0)
    learned = synthesize(prob, explain=False)
    assert learned.stats["order_learned_at"] > 0 and len(built) == 2 and len(sifted) == 1
    first, second = built
    names = tuple(n for n in sorted(second.bdd.vars, key=second.bdd.level_of_var)
                  if n in second.cur_vars)
    assert names == sifted[0] and sorted(names) == sorted(first.cur_vars)
    for n in names:
        assert second.bdd.level_of_var(n + "'") == second.bdd.level_of_var(n) + 1
    assert bisimilar(plain.controller, learned.controller)
    assert main(["synth", str(DATA / "macro_turns.fsp"), "Control"]) == 0
    assert "variable order learned from them" in capsys.readouterr().out


def test_declared_order_can_be_given():
    """``SymbolicGame(names=...)`` declares exactly that order; a list that is not a
    permutation of the game's own variables is refused."""
    prob, _ = _syntech_free_problem()
    spec = prepare(prob)
    g = SymbolicGame(spec)
    names = tuple(reversed(sorted(g.cur_vars, key=g.bdd.level_of_var)))
    h = SymbolicGame(spec, names=names)
    assert tuple(sorted(h.cur_vars, key=h.bdd.level_of_var)) == names
    with pytest.raises(ValueError):
        SymbolicGame(spec, names=names[1:])


def test_sifted_order_needs_cudd():
    import dd.autoref

    from iterplan_compiler.synthesis.learn_order import sifted_order

    b = dd.autoref.BDD()
    b.declare("x", "x'")
    assert sifted_order(b, b.var("x"), {"x"}) is None


def _syntech_free_problem():
    from iterplan_compiler.pipeline import load_model

    return load_model(str(DATA / "macro_turns.fsp"))[0].synthesis_problem("Control")
