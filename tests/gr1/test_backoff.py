"""The restart back-off of CUDD's reordering trigger (symbolic/backoff.py).

The rule is checked as a function, then through a real CUDD manager: the hook is installed,
sees explicit reorderings, and raising the trigger shows in CUDD's own ``nextDyn``.  End to
end, a game solved with the back-off (made eager so that it acts on a small instance) has
the same verdict and winning set as without it.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from iterplan_compiler.cli import main as iterc
from iterplan_compiler.gr1.game import GameOptions
from iterplan_compiler.gr1.slugsin import parse
from iterplan_compiler.gr1.solve import solve
from iterplan_compiler.symbolic import backoff
from iterplan_compiler.symbolic import bdd as bddmod

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks" / "gr1"))

import generators  # noqa: E402

needs_cudd = pytest.mark.skipif(bddmod.BACKEND != "cudd", reason="dd.cudd is not installed")


def test_rule_keeps_cudds_trigger_for_the_first_reorderings() -> None:
    for k in range(1, backoff.KEPT + 1):
        assert backoff.raised_trigger(k, last_trigger=7000, own=7000) is None
    assert backoff.raised_trigger(backoff.KEPT + 1, last_trigger=7000, own=7000) == 14000
    # CUDD's own trigger already above the doubled one: keep it
    assert backoff.raised_trigger(backoff.KEPT + 1, last_trigger=7000, own=20000) is None


def test_state_doubles_only_inside_one_product() -> None:
    s = backoff.Backoff()
    assert s.after_reordering(5000) is None  # outside any product
    s.enter()
    got = [s.after_reordering(7000) for _ in range(backoff.KEPT + 3)]
    assert got[:backoff.KEPT] == [None] * backoff.KEPT
    assert got[backoff.KEPT:] == [14000, 28000, 56000]
    s.leave()
    s.enter()  # a new product starts from CUDD's rule again
    assert s.after_reordering(7000) is None and s.repeats == 1
    s.leave()
    assert (s.seen, s.raised, s.depth) == (1 + backoff.KEPT + 3 + 1, 3, 0)


@needs_cudd
def test_installed_hook_moves_cudds_trigger() -> None:
    bdd = bddmod.new_manager(reordering=True)
    bdd.declare(*[f"x{i}" for i in range(12)])
    u = bdd.add_expr(r" /\ ".join(f"(x{i} <=> x{11 - i})" for i in range(6)))
    state = backoff.install(bdd)
    assert state is not None and backoff.manager_pointer(bdd) is not None
    bdd.reorder()
    assert (state.seen, state.raised) == (1, 0)
    # pretend the explicit sift happened inside a product that already restarted KEPT times
    state.enter()
    state.last_epoch, state.repeats = state.epoch, backoff.KEPT
    before = state.last_trigger
    bdd.reorder()
    state.leave()
    assert state.raised == 1
    assert backoff.next_trigger(bdd) == 2 * before == state.last_trigger
    assert u == bdd.add_expr(r" /\ ".join(f"(x{i} <=> x{11 - i})" for i in range(6)))


@needs_cudd
def test_product_bracket_survives_errors() -> None:
    bdd = bddmod.new_manager(reordering=True)
    bdd.declare("a", "b")
    state = backoff.install(bdd)
    assert state is not None
    a, b = bdd.var("a"), bdd.var("b")
    assert bddmod.and_exists(bdd, a, b, {"b"}, state) == a
    with pytest.raises(ValueError):                  # dd: unknown variable
        bddmod.or_forall(bdd, a, b, {"no_such_variable"}, state)
    assert (state.depth, state.epoch) == (0, 2)


def test_not_installed_where_it_cannot_be() -> None:
    assert backoff.install(object()) is None
    assert backoff.install(bddmod.new_manager(backend="autoref")) is None


@needs_cudd
def test_same_game_with_and_without_backoff(monkeypatch: pytest.MonkeyPatch) -> None:
    # KEPT = 0: every repeated reordering in a product raises the trigger, so the back-off
    # acts on this small instance (at the default it acts only on large ones)
    monkeypatch.setattr(backoff, "KEPT", 0)
    spec, diags = parse(generators.synt15(25))
    assert spec is not None, diags
    runs = {}
    for on in (True, False):
        res, _ = solve(spec, strategy=True, game_options=GameOptions(reorder_backoff=on))
        assert res is not None
        n = 2 * (len(spec.inputs) + len(spec.outputs))
        runs[on] = (res.realizable, res.game.bdd.count(res.winning, nvars=n),
                    res.stats["trigger_raises"])
    assert runs[True][:2] == runs[False][:2]
    assert runs[True][2] > 0 and runs[False][2] == 0


@needs_cudd
def test_cli_flag_switches_it_off(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                  capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(backoff, "KEPT", 0)  # so that it acts on a small instance
    p = tmp_path / "synt15_25.slugsin"
    p.write_text(generators.synt15(25))
    raises = []
    for flags in ([], ["--no-reorder-backoff"]):
        assert iterc(["solve", str(p), "--realizability-only", "--json", *flags]) == 0
        raises.append(json.loads(capsys.readouterr().out)["trigger_raises"])
    assert raises[0] > 0 and raises[1] == 0
