"""A property composed with a system: ERROR is reachable iff model checking finds a violation."""

from fltl_helpers import ACTIONS, FLUENTS, safety_formulas, total_lts
from hypothesis import HealthCheck, given, settings

from iterplan_compiler.fltl.check import model_check
from iterplan_compiler.fltl.safety import safety_lts
from iterplan_compiler.ir.compose import compose
from iterplan_compiler.ir.formulas import NamedFormula


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(total_lts(), safety_formulas)
def test_error_reachability_agrees_with_model_checking(lts, formula):
    # Extending Σφ to every system action makes the property see every position, as model
    # checking does; the system never deadlocks, so finite and infinite semantics agree.
    named = NamedFormula("P", "ltl_property", formula, frozenset(ACTIONS))
    prop, diags = safety_lts(named, FLUENTS, constraint=False)
    assert prop is not None, diags
    product = compose([lts, prop], "SYS")
    assert product.has_error == (not model_check(lts, formula, FLUENTS).holds)
