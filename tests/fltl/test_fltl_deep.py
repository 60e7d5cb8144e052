"""Formulas nested far beyond Python's recursion limit are reported as E0606, not raised (found
by the CLI QA: generated specs can nest ~1000 deep)."""

from iterplan_compiler.fltl.check import check_assert
from iterplan_compiler.fltl.safety import safety_lts
from iterplan_compiler.ir.formulas import Always, And, Fluent, FluentProp, NamedFormula, Not
from iterplan_compiler.ir.lts import make_lts

FLUENTS = {"F": Fluent("F", frozenset({"a"}), frozenset({"b"}))}
SYS = make_lts("A", 2, [(0, "a", 1), (1, "b", 0)])


def _nested(depth: int, conj: bool):
    f = FluentProp("F")
    for _ in range(depth):
        f = And(FluentProp("F"), f) if conj else Not(f)
    return f


def test_moderate_nesting_still_works():
    lts, diags = safety_lts(NamedFormula("P", "ltl_property", Always(_nested(200, True))),
                            FLUENTS, constraint=False)
    assert lts is not None and diags == []
    result, diags = check_assert(SYS, NamedFormula("Q", "assert", _nested(200, False)), FLUENTS)
    # 200 negations = F, which holds at the first position (after the initiating action a).
    assert result is not None and diags == [] and result.holds is True


def test_too_deep_is_a_diagnostic():
    deep = NamedFormula("P", "ltl_property", Always(_nested(5000, True)))
    lts, diags = safety_lts(deep, FLUENTS, constraint=False)
    assert lts is None and [d.code for d in diags] == ["E0606"]
    assert "nested too deeply" in diags[0].message
    result, diags = check_assert(SYS, NamedFormula("Q", "assert", _nested(5000, False)), FLUENTS)
    assert result is None and [d.code for d in diags] == ["E0606"]
