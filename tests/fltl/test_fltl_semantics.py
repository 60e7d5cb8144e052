"""The direct FLTL evaluator (the oracle) on hand-computed traces."""

from fltl_helpers import FLUENTS, act, fl

from iterplan_compiler.fltl.semantics import (
    Lasso,
    UnknownFluentError,
    evaluate,
    fluent_trajectory,
    formula_alphabet,
)
from iterplan_compiler.ir.formulas import (
    Always,
    And,
    Eventually,
    FluentProp,
    Implies,
    Next,
    Not,
    Until,
    WeakUntil,
)

F = FluentProp("F")  # <a, b>
G = FluentProp("G")  # <c, a> initially true


def test_fluent_values_follow_initiating_and_terminating_sets():
    traj = fluent_trajectory(("c", "a", "c", "b", "a"), FLUENTS, ["F", "G"])
    assert [v["F"] for v in traj] == [False, True, True, False, True]
    assert [v["G"] for v in traj] == [True, False, True, True, False]


def test_initial_value_is_never_observed_before_the_first_action():
    # G is initially true, but ``a`` terminates it: position 1 (after ``a``) sees false.
    assert not evaluate(G, Lasso(("a",), ("b",)), FLUENTS)
    # An action outside G's sets keeps the initial value.
    assert evaluate(G, Lasso(("b",), ("b",)), FLUENTS)


def test_action_proposition_is_the_last_action():
    f = And(act("p"), Not(act("q")))  # ConstraintTest: "the first action is p"
    assert evaluate(f, Lasso(("p",), ("q",)), {})
    assert not evaluate(f, Lasso(("q",), ("p",)), {})
    assert evaluate(act("p", "q"), Lasso((), ("q",)), {})


def test_liveness_on_lassos():
    inf_a = Always(Eventually(act("a")))
    assert evaluate(inf_a, Lasso(("b",), ("a", "b")), {})
    assert not evaluate(inf_a, Lasso(("a",), ("b",)), {})
    # Fluent set in the prefix, never touched by the cycle: stays true.
    assert evaluate(Always(F), Lasso(("a",), ("c",)), FLUENTS)
    stable = Eventually(Always(F))
    assert not evaluate(stable, Lasso((), ("a", "c", "b")), FLUENTS)
    assert evaluate(Always(Eventually(F)), Lasso((), ("a", "c", "b")), FLUENTS)


def test_next_wraps_around_the_cycle():
    f = Always(Implies(act("b"), Next(act("a"))))
    assert evaluate(f, Lasso(("c",), ("a", "b")), {})
    assert not evaluate(f, Lasso(("c",), ("b", "b")), {})


def test_strong_and_weak_until():
    trace = Lasso((), ("a",))  # b never happens
    assert not evaluate(Until(act("a"), act("b")), trace, {})
    assert evaluate(WeakUntil(act("a"), act("b")), trace, {})
    assert evaluate(Until(act("a"), act("b")), Lasso(("a", "a", "b"), ("c",)), {})
    assert not evaluate(WeakUntil(act("a"), act("b")), Lasso(("a", "c", "b"), ("c",)), {})


def test_good_prefix_semantics_of_finite_traces():
    f = Always(Implies(act("p"), Next(act("q"))))
    assert evaluate(f, ("p",), {})  # q may still come
    assert evaluate(f, ("p", "q", "q"), {})
    assert not evaluate(f, ("p", "p"), {})  # every continuation violates
    # A liveness formula has no bad prefix over an alphabet that can fulfil it.
    assert evaluate(Eventually(act("p")), ("q", "q"), {}, alphabet={"p", "q"})
    # ... but over an alphabet that cannot, the empty trace is already bad.
    assert not evaluate(Eventually(act("p")), (), {}, alphabet={"q"})


def test_alphabet_and_unknown_fluents():
    f = And(F, act("x"))
    assert formula_alphabet(f, FLUENTS, {"y"}) == {"a", "b", "x", "y"}
    try:
        formula_alphabet(FluentProp("Nope"), FLUENTS)
    except UnknownFluentError as exc:
        assert exc.name == "Nope"
    else:
        raise AssertionError("unknown fluent accepted")


def test_initiating_wins_for_malformed_fluent():
    both = {"H": fl("H", {"a"}, {"a"})}
    assert evaluate(FluentProp("H"), Lasso(("a",), ("a",)), both)
