"""Conformance check of one ``verdicts.tsv`` synthesis row (used by ``iterc conformance``).

``check_row(model, row) -> (ok, detail)`` where ``ok`` is True (pass), False (fail) or None
(the row needs a feature we do not support).  It never raises.  Checks, as §4.2 describes:

* the verdict (``realizable``/``unrealizable`` in ``row.expected``);
* realizable rows: if the model has ``ExpectedC``, the composition must be strongly bisimilar
  to it (BisimilarFSP); if it has an ``assert Check`` (or ``TESTGOAL``/``CheckWith``/
  ``CheckWithout``) and a ``Sys``-like composite, the assertion must hold on it.
"""

from __future__ import annotations

from typing import Protocol

from iterplan_compiler.diagnostics import has_errors
from iterplan_compiler.fltl.check import model_check
from iterplan_compiler.ir.alphabet_ops import property_complete
from iterplan_compiler.ir.minimise import bisimilar, deterministic
from iterplan_compiler.ir.model import Model
from iterplan_compiler.synthesis.driver import Solver, SynthesisResult, synthesize


class Row(Protocol):
    """What a check needs of a ``verdicts.tsv`` row (``conformance.Row``)."""

    @property
    def composite_name(self) -> str: ...

    @property
    def expected(self) -> str: ...

    @property
    def checks(self) -> str: ...


def check_row(model: Model, row: Row, *, solver: Solver | str = Solver.SYMBOLIC
              ) -> tuple[bool | None, str]:
    """Check one row against ``model`` (a front-end ``Model``); see the module doc."""
    try:
        return _check(model, row, solver)
    except Exception as exc:  # noqa: BLE001 - a conformance row must never crash the run
        return False, f"internal error: {type(exc).__name__}: {exc}"


def _check(model: Model, row: Row, solver: Solver | str) -> tuple[bool | None, str]:
    name = row.composite_name
    problem, diags = model.synthesis_problem(name)
    if problem is None or has_errors(diags):
        msgs = "; ".join(d.message for d in diags)[:200]
        return None, f"no synthesis problem for {name}: {msgs}"
    result = synthesize(problem, solver=solver, explain=False)
    want = not row.expected.startswith("unrealizable")
    verdict = "realizable" if result.realizable else "unrealizable"
    game = result.stats.game_states
    sizes = f"game {game if game is not None else '?'} states"
    if result.realizable != want:
        return False, f"{verdict} (expected {row.expected}); {sizes}"
    if not result.realizable:
        return True, f"{verdict}; {sizes}"
    detail = [verdict, sizes, f"controller {result.stats.controller_states} states"]
    names = set(model.names())
    if "ExpectedC" in names and "ExpectedC" in row.checks:
        # only BisimilarFSP asserts ExpectedC; the NonBlocking files' directors are not checked
        expected, d2 = model.build_lts("ExpectedC")
        if expected is None:
            return None, "cannot build ExpectedC"
        ours = result.composition
        if ours is None:
            return False, "realizable but no composition was built"
        if "property" in problem.keywords:
            # §2.6: `property` is applied after synthesis (determinise, complete to ERROR)
            ours = property_complete(deterministic(ours))
        if not bisimilar(ours, expected, same_alphabet=False):
            return False, "; ".join(detail + [
                f"not bisimilar to ExpectedC ({ours.num_states} vs "
                f"{expected.num_states} states)"])
        detail.append("bisimilar to ExpectedC")
    ok, msg = _check_assertion(model, names, result)
    if msg:
        detail.append(msg)
    return ok, "; ".join(detail)


def _check_assertion(model: Model, names: set[str], result: SynthesisResult
                     ) -> tuple[bool, str]:
    formulas = model.formulas
    for fname, sysname in (("Check", "Sys"), ("TESTGOAL", None), ("CheckWith", "SysWith"),
                           ("CheckWithout", "SysWithout")):
        if fname not in formulas:
            continue
        system = result.composition
        if system is None:
            return False, f"assert {fname}: no composition to check"
        if sysname and sysname in names:
            built, _ = model.build_lts(sysname)
            if built is not None:
                system = built
        res = model_check(system, formulas[fname].formula, model.fluents)
        if not res.holds:
            return False, f"assert {fname} violated"
        return True, f"assert {fname} holds"
    return True, ""
