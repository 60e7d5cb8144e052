"""Strategy extraction controls (reordering mode, final sift, restrict) and the checker."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import pytest

from iterplan_compiler.cli import main as iterc
from iterplan_compiler.gr1.slugsin import parse
from iterplan_compiler.gr1.solve import solve
from iterplan_compiler.gr1.strategy import Strategy, StrategyOptions, StrategyReordering
from iterplan_compiler.oracle.gr1_explicit import check_strategy

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks" / "gr1"))

import generators  # noqa: E402

OPTIONS = [
    StrategyOptions(),
    StrategyOptions(reordering=StrategyReordering.GUARDED),
    StrategyOptions(reordering=StrategyReordering.OFF, final_sift=False),
    StrategyOptions(restrict=False),
    StrategyOptions(reordering=StrategyReordering.DYNAMIC, final_sift=False, restrict=False),
]


@pytest.mark.parametrize("options", OPTIONS, ids=lambda o: f"{o.reordering.value}-"
                         f"{'sift' if o.final_sift else 'nosift'}-"
                         f"{'restrict' if o.restrict else 'norestrict'}")
@pytest.mark.parametrize("family, n", [("arbiter", 3), ("lift", 3), ("genbuf", 3),
                                       ("amba_jcss12", 2), ("amba_fm15", 2)])
def test_strategy_is_winning_safe_under_every_option(family, n, options):
    spec, _ = parse(generators.FAMILIES[family](n))
    res, _ = solve(spec, strategy_options=options)
    assert res is not None and res.realizable and res.strategy is not None
    assert res.strategy.violations() == []
    assert res.stats["strategy_nodes"] > 0


@pytest.mark.parametrize("restrict", [True, False])
@pytest.mark.parametrize("family, n", [("arbiter", 2), ("lift", 2)])
def test_restricted_strategy_passes_the_exhaustive_check(family, n, restrict):
    spec, _ = parse(generators.FAMILIES[family](n))
    res, _ = solve(spec, strategy_options=StrategyOptions(restrict=restrict))
    assert check_strategy(spec, res.strategy) == []


def test_violations_detects_unsafe_and_missing_moves():
    spec, _ = parse(generators.arbiter(2))
    res, _ = solve(spec)
    s = res.strategy
    g = res.game
    bdd = g.bdd
    # every move allowed (also illegal ones and ones that leave Win) → unsafe
    loose = Strategy(g, s.winning, [bdd.true] * s.goals)
    assert any("violates" in p for p in loose.violations())
    # no move at all → stuck
    empty = Strategy(g, s.winning, [bdd.false] * s.goals)
    assert any("no move" in p for p in empty.violations())
    assert s.violations() == []


def test_goal_counter_is_on_top_of_the_order():
    spec, _ = parse(generators.genbuf(3))
    res, _ = solve(spec)
    bdd = res.game.bdd
    assert bdd.level_of_var("_goal@0") == 0
    # counting again gives the same number (no reordering moves the counter)
    assert res.strategy.node_count() == res.stats["strategy_nodes"]


def test_no_reorder_manager_is_never_sifted():
    from iterplan_compiler.gr1.game import GameOptions

    spec, _ = parse(generators.arbiter(3))
    res, _ = solve(spec, game_options=GameOptions(reordering=False),
                   strategy_options=replace(StrategyOptions(), final_sift=True))
    assert res.stats.get("reorderings") in (0, None)
    assert res.strategy.violations() == []


def test_cli_strategy_flags(tmp_path, capsys):
    p = tmp_path / "arb.slugsin"
    p.write_text(generators.arbiter(3))
    for mode in StrategyReordering:
        assert iterc(["solve", str(p), "--strategy-reordering", mode.value,
                      "--no-strategy-final-sift", "--no-strategy-restrict"]) == 0
        assert "REALIZABLE" in capsys.readouterr().out
    with pytest.raises(SystemExit) as exc:
        iterc(["solve", str(p), "--strategy-reordering", "sometimes"])
    assert exc.value.code == 2
