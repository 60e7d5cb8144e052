"""Known verdicts of the benchmark families, strategies simulated, and ``iterc solve``."""

from __future__ import annotations

import json
import random
import sys
from pathlib import Path

import pytest

from iterplan_compiler.cli import main as iterc
from iterplan_compiler.gr1.slugsin import parse
from iterplan_compiler.gr1.solve import SolverOptions, solve
from iterplan_compiler.oracle.gr1_explicit import check_strategy, evaluate, solve_explicit

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks" / "gr1"))

import generators  # noqa: E402

SMALL = [
    ("arbiter", 2), ("arbiter", 4), ("lift", 2), ("lift", 4), ("genbuf", 2), ("genbuf", 3),
    ("amba_jcss12", 2), ("amba_fm15", 2), ("synt15", 2), ("synt15", 3), ("synt15", 5),
    ("arbiter_immediate", 2), ("arbiter_immediate", 3), ("amba_nohready", 2),
    ("genbuf_noreceiver", 2),
]


@pytest.mark.parametrize("family, n", SMALL)
def test_known_verdicts(family, n):
    spec, diags = parse(generators.FAMILIES[family](n), f"{family}_{n}")
    assert spec is not None, diags
    res, _ = solve(spec, strategy=False)
    assert res.realizable == generators.VERDICTS[family]
    # early unrealizability detection must not change verdicts
    res2, _ = solve(spec, strategy=False,
                    solver_options=SolverOptions(early_unrealizable=False, feedback=False))
    assert res2.realizable == res.realizable


@pytest.mark.parametrize("family, n", [("arbiter", 2), ("lift", 2), ("arbiter_immediate", 2)])
def test_small_families_against_explicit_oracle(family, n):
    spec, _ = parse(generators.FAMILIES[family](n))
    expected, _ = solve_explicit(spec)
    assert expected == generators.VERDICTS[family]
    res, _ = solve(spec)
    assert res.realizable == expected
    if expected:
        assert check_strategy(spec, res.strategy) == []


def _simulate(spec, strategy, steps: int, seed: int) -> dict[int, int]:
    """Random legal environment moves; checks ρs on every step; returns goal visit counts."""
    rng = random.Random(seed)
    env_tr = [ln.expr for ln in spec.lines("ENV_TRANS")]
    sys_tr = [ln.expr for ln in spec.lines("SYS_TRANS")]
    env_init = [ln.expr for ln in spec.lines("ENV_INIT")]
    sys_init = [ln.expr for ln in spec.lines("SYS_INIT")]

    def legal_inputs(cur):
        while True:  # rejection sampling; every family here has legal moves
            nxt = {v: rng.random() < 0.5 for v in spec.inputs}
            if all(evaluate(e, cur, nxt) for e in env_tr):
                return nxt

    x0 = legal_inputs({}) if not env_init else None
    while x0 is None or not all(evaluate(e, x0, {}) for e in env_init):
        x0 = {v: rng.random() < 0.5 for v in spec.inputs}
    y0 = strategy.initial(x0)
    state = {**x0, **y0}
    assert all(evaluate(e, state, {}) for e in sys_init)
    goal = 0
    advanced: dict[int, int] = {}
    for _ in range(steps):
        xn = legal_inputs(state)
        res = strategy.step(state, goal, xn)
        assert res is not None, "strategy has no move for a legal input"
        yn, g2 = res
        nxt = {**xn, **yn}
        assert all(evaluate(e, state, nxt) for e in sys_tr), "strategy violated SYS_TRANS"
        if g2 != goal:
            advanced[goal] = advanced.get(goal, 0) + 1
        goal, state = g2, nxt
    return advanced


@pytest.mark.parametrize("family, n", [("arbiter", 3), ("lift", 3), ("genbuf", 2),
                                       ("amba_jcss12", 2), ("synt15", 2)])
def test_strategy_simulation(family, n):
    spec, _ = parse(generators.FAMILIES[family](n))
    res, _ = solve(spec)
    assert res.realizable and res.strategy is not None
    advanced = _simulate(spec, res.strategy, steps=300, seed=n)
    # random environments are fair with probability 1, so the goal counter keeps cycling
    assert len(advanced) == len(spec.lines("SYS_LIVENESS"))


@pytest.mark.parametrize("dropped", ["[ENV_LIVENESS]\nready\n", "! pc_withdraw_lock\n\n[SYS_LIVENESS]"])
def test_synt15_needs_both_assumptions(dropped):
    # without GF ready no access starts (G1) and the master never changes (G6); without A1's
    # progress label a locked INCR burst never ends (G2): both make synt15 unrealizable
    text = generators.synt15(2)
    assert text.count(dropped) == 1
    kept = dropped.replace("ready\n", "").replace("! pc_withdraw_lock\n", "")
    spec, _ = parse(text.replace(dropped, kept))
    res, _ = solve(spec, strategy=False)
    assert not res.realizable


def test_primed_liveness_uses_transition_based_fixpoint():
    # the goal "g rises" (! g & g') is transition-level; realizable by toggling g
    text = "[INPUT]\nx\n[OUTPUT]\ng\n[SYS_LIVENESS]\n& ! g g'\n"
    spec, _ = parse(text)
    res, _ = solve(spec)
    assert res.game.live_primed
    assert res.realizable
    assert check_strategy(spec, res.strategy) == []
    # ... and unrealizable when g may never change
    spec2, _ = parse(text + "[SYS_TRANS]\n! ^ g g'\n")
    res2, _ = solve(spec2)
    assert not res2.realizable


def test_game_diagnostics():
    spec, _ = parse("[INPUT]\nx\n[OUTPUT]\ny\n[ENV_TRANS]\ny'\n[SYS_INIT]\ny'\n", "g.slugsin")
    res, diags = solve(spec)
    assert res is None
    assert {d.code for d in diags} == {"G201", "G202"}
    assert all(d.span.file == "g.slugsin" and d.span.line > 0 for d in diags)


def test_cli_solve_progress(tmp_path, capsys):
    """``-v``: phases, Z iterations, the verdict and each goal's strategy on stderr; ``-q``
    (and stderr not a terminal, as here) nothing; the report on stdout either way."""
    p = tmp_path / "arb.slugsin"
    p.write_text(generators.arbiter(3))
    assert iterc(["solve", str(p), "-v"]) == 0
    cap = capsys.readouterr()
    lines = cap.err.splitlines()
    assert lines[0].endswith("building the game (3 inputs, 3 outputs)"), cap.err
    assert any("gr1: Z-iteration 1" in line for line in lines)
    assert any(line.endswith("verdict: realizable") for line in lines)
    assert any("strategy: goal 3/3" in line for line in lines)
    assert all(line.startswith("[") and " s] " in line for line in lines)
    assert "REALIZABLE" in cap.out
    for quiet in (["-q"], []):
        assert iterc(["solve", str(p), *quiet]) == 0
        assert capsys.readouterr().err == ""


def test_cli_solve(tmp_path, capsys):
    p = tmp_path / "arb.slugsin"
    p.write_text(generators.arbiter(3))
    assert iterc(["solve", str(p)]) == 0
    out = capsys.readouterr().out
    assert "REALIZABLE" in out and "winning set" in out and "strategy" in out
    assert iterc(["solve", str(p), "--realizability-only", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["realizable"] is True and "strategy_nodes" not in data
    q = tmp_path / "imm.slugsin"
    q.write_text(generators.arbiter_immediate(2))
    assert iterc(["solve", str(q)]) == 1
    assert "UNREALIZABLE" in capsys.readouterr().out
    bad = tmp_path / "bad.slugsin"
    bad.write_text("[INPUT]\na\n[SYS_TRANS]\n& a\n")
    assert iterc(["solve", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "bad.slugsin:4:4: error[G103]" in err
    assert iterc(["solve", str(tmp_path / "missing.slugsin")]) == 1
    assert "G100" in capsys.readouterr().err
