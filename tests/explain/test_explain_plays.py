"""``iterc synth --explain`` as a play (synthesis/explain.py): golden plays on three
unrealizable variants of Fire Patrol, the same text from both solvers, the same counts."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from iterplan_compiler import cli
from iterplan_compiler.pipeline import load_model as load
from iterplan_compiler.synthesis.driver import synthesize

REPO = Path(__file__).resolve().parents[2]
VARIANTS = REPO / "tests" / "data" / "fire_patrol_variants"
GOLDEN = REPO / "tests" / "data" / "golden"
NAMES = ["safety_violation", "liveness_loss", "missing_assumption"]


def explanation(capsys, spec: Path, solver: str) -> str:
    capsys.readouterr()
    code = cli.main(["synth", str(spec), "--explain", "--solver", solver])
    out = capsys.readouterr().out
    assert code == 1
    assert out.startswith("FirePatrol: UNREALIZABLE")
    return out[out.index("unrealizable:"):]


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("solver", ["symbolic", "explicit"])
def test_play_matches_golden(capsys, name, solver):
    got = explanation(capsys, VARIANTS / f"{name}.lts", solver)
    golden = GOLDEN / f"explain_{name}.txt"
    if os.environ.get("ITERPLAN_UPDATE_GOLDEN"):
        golden.write_text(got, encoding="utf-8")
    assert got == golden.read_text(encoding="utf-8")


def test_safety_play_names_the_property_and_the_breaking_step(capsys):
    text = explanation(capsys, VARIANTS / "safety_violation.lts", "symbolic")
    assert "forces a violation of safety property NeverEmpty" in text
    last = [line for line in text.splitlines() if line.strip()[:1].isdigit()][-1]
    assert "environment  n.next" in last and "violates safety property NeverEmpty" in last


def test_liveness_play_is_a_lasso_with_assumption_visits(capsys):
    text = explanation(capsys, VARIANTS / "liveness_loss.lts", "symbolic")
    assert "keeps guarantee FireFound false forever" in text
    assert "then, forever:" in text
    assert "assumption GotLocation holds in the loop after step(s)" in text
    assert "FireFound never holds" in text


def test_no_assumption_talk_without_assumptions(capsys):
    text = explanation(capsys, VARIANTS / "missing_assumption.lts", "explicit")
    assert "keeps guarantee GotLocation false forever" in text
    assert "the spec has no assumptions" in text
    assert "assumption-satisfying" not in text and "assumption GotLocation" not in text


@pytest.mark.parametrize("name", NAMES)
def test_plays_speak_actions_and_fluents_not_state_numbers(capsys, name):
    text = explanation(capsys, VARIANTS / f"{name}.lts", "symbolic")
    assert "Iterator=" not in text and "Flight=" not in text  # no component states
    assert "controller   takeoff (its only move)" in text
    assert "HasNext=true" in text


@pytest.mark.parametrize("name", NAMES)
def test_both_solvers_count_the_same_losing_states(name):
    model, _ = load(str(VARIANTS / f"{name}.lts"))
    problem, _ = model.synthesis_problem("FirePatrol")
    heads = {(solver, explain): synthesize(problem, solver=solver, explain=explain)
             .explanation.splitlines()[0]
             for solver in ("symbolic", "explicit") for explain in (False, True)}
    counted = {h for h in heads.values() if "(" in h}
    assert len(counted) == 1, heads
    # the symbolic solver stops early without --explain: it then gives no count, never a wrong one
    assert heads[("symbolic", False)] in counted | {"unrealizable: the initial state is losing"}


def test_early_stopped_fixpoint_is_recomputed_for_the_explanation():
    # missing_assumption: the early-stopped νZ keeps 96 states the exact region loses
    model, _ = load(str(VARIANTS / "missing_assumption.lts"))
    problem, _ = model.synthesis_problem("FirePatrol")
    res = synthesize(problem, solver="symbolic", explain=True)
    assert "(146 of 146 reachable game states are losing" in res.explanation


CORPUS = REPO.parent.parent / "shared" / "conformance" / "mtsa"
if not (CORPUS / "verdicts.tsv").is_file():
    CORPUS = Path("/work/shared/conformance/mtsa")


def _unrealizable_games():
    from iterplan_compiler import conformance as conf

    specs = [(VARIANTS / f"{n}.lts", "FirePatrol") for n in NAMES]
    if (CORPUS / "verdicts.tsv").is_file():
        specs += [(CORPUS / r.file, r.composites[0]) for r in conf.read_rows(CORPUS)
                  if r.kind == "unrealizable"]
    return specs


@pytest.mark.parametrize("path,name", _unrealizable_games(),
                         ids=lambda x: x.name if isinstance(x, Path) else x)
def test_every_play_is_a_real_play(path, name):
    """Each step is an edge of the game taken by its owner; a liveness play ends in a loop
    that keeps its guarantee false and visits every assumption, or in a dead end."""
    from iterplan_compiler.synthesis import explain as E
    from iterplan_compiler.synthesis import explicit as X
    from iterplan_compiler.synthesis.encode import prepare

    model, _ = load(str(path))
    problem, _ = model.synthesis_problem(name)
    spec = prepare(problem)
    game = X.build_game(spec)
    ranks = X.solve_ranks(game)
    win = frozenset(s for s in range(game.num_states) if ranks.winning(s))
    assert game.initial not in win
    n = game.num_states
    dead = {s for s in range(n) if not game.edges[s]} | {
        s for s in range(n)
        if not game.env[s] and not any(a in game.controllable for a, _ in game.edges[s])}
    text = E.explain_losing(spec, game, win)
    assert "switching" not in text  # every corpus game gets a play
    if E._safety_play(spec, game, dead) is not None:
        return
    avoid = frozenset(dead)
    rank, layers = E._layers(game, set(range(n)) - win - dead, avoid)
    steps, cut, kept = E._Play(game, rank, layers, avoid).run(game.initial)
    s = game.initial
    for st in steps:
        assert st.state == s and (st.action, st.target) in game.edges[s]
        assert st.by_controller == (st.action in game.controllable)
        assert st.by_controller or game.env[s]
        s = st.target
    if steps and steps[-1].target in dead:
        return
    loop = steps[cut:]
    assert loop and loop[-1].target == loop[0].state
    avoided = game.guarantees[kept[cut]] | game.failures
    assert not any(st.state in avoided for st in loop)
    for a in game.assumptions:
        assert any(st.state in a for st in loop)
