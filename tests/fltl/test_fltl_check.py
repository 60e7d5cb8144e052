"""FLTL model checking: hand-written systems and agreement with the direct evaluator."""

from fltl_helpers import (
    ACTIONS,
    FLUENTS,
    act,
    fl,
    formulas,
    is_fair_cycle,
    is_run,
    lasso_runs,
    lassos,
    total_lts,
)
from hypothesis import HealthCheck, example, given, settings

from iterplan_compiler.fltl.check import Counterexample, check_assert, model_check
from iterplan_compiler.fltl.semantics import Lasso, evaluate, is_good_prefix
from iterplan_compiler.ir.formulas import (
    Always,
    And,
    Eventually,
    FluentProp,
    Implies,
    NamedFormula,
    Next,
    Not,
    Or,
    Until,
    WeakUntil,
)
from iterplan_compiler.ir.lts import ERROR, TAU, make_lts

SETTINGS = settings(max_examples=80, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

# P = (a -> b -> P | a -> c -> P)
CHOICE = make_lts("P", 3, [(0, "a", 1), (1, "b", 0), (0, "a", 2), (2, "c", 0)])


def holds(lts, f, fluents=None, *, fair=True):
    return model_check(lts, f, fluents or {}, fair=fair).holds


def test_liveness_with_cycles():
    assert holds(CHOICE, Always(Eventually(act("a"))))
    assert not holds(CHOICE, Eventually(Always(act("a"))))
    assert holds(CHOICE, Always(Eventually(Or(act("b"), act("c")))))
    # Without fairness the a-c loop starves b ...
    res = model_check(CHOICE, Always(Eventually(act("b"))), {}, fair=False)
    assert not res.holds
    cex = res.counterexample
    assert cex.cycle and "b" not in cex.cycle
    assert is_run(CHOICE, cex.prefix, cex.cycle)
    assert not evaluate(Always(Eventually(act("b"))), Lasso(cex.prefix, cex.cycle), {})
    # ... but under fair choice (LTSA's default) both a-moves are taken infinitely often.
    assert holds(CHOICE, Always(Eventually(act("b"))))


def test_fair_violation_needs_a_terminal_set():
    # P = (a -> P | go -> Q), Q = (c -> Q): every fair run leaves the a-loop for good.
    sys_ = make_lts("P", 2, [(0, "a", 0), (0, "go", 1), (1, "c", 1)])
    res = model_check(sys_, Always(Eventually(act("a"))), {})
    assert not res.holds
    assert res.counterexample == Counterexample(("go",), ("c",), ("c",))
    assert "Actions in terminal set:\n    {c}" in res.counterexample.render()
    assert holds(sys_, Eventually(Always(act("c"))))
    assert not holds(sys_, Eventually(Always(act("c"))), fair=False)


def test_mtsa_gr1test43_escape_from_an_uncontrolled_loop():
    # Blocking/ControllableFSPs/GR1Test43's controlled system: the d-e loop can be repeated
    # forever only unfairly (c and f stay enabled); MTSA expects Check = []<>S1 to hold.
    sys_ = make_lts("Sys", 6, [(0, "g", 1), (1, "a", 2), (2, "b", 3), (3, "c", 4), (3, "d", 5),
                               (4, "g", 1), (5, "e", 3), (5, "f", 4)])
    every = {"a", "b", "c", "d", "e", "f", "g"}
    fluents = {"FS1": fl("FS1", {"c", "f"}, every - {"c", "f"})}
    check = Always(Eventually(FluentProp("FS1")))
    assert holds(sys_, check, fluents)
    res = model_check(sys_, check, fluents, fair=False)
    assert not res.holds and set(res.counterexample.cycle) == {"d", "e"}


def test_safety_and_next():
    assert holds(CHOICE, Always(Implies(act("a"), Next(Or(act("b"), act("c"))))))
    assert not holds(CHOICE, Always(Implies(act("a"), Next(act("b")))))
    assert not holds(CHOICE, Always(Not(act("c"))))
    assert holds(CHOICE, act("a"))  # position 1 is after the first action
    assert not holds(CHOICE, Next(act("b")))
    assert holds(CHOICE, Until(act("a"), Or(act("b"), act("c"))))
    # "a c ..." shows c before any b:
    assert not holds(CHOICE, WeakUntil(Not(act("c")), act("b")))
    assert holds(CHOICE, WeakUntil(Not(act("c")), Or(act("b"), act("c"))))


def test_fluent_liveness_mutex():
    # Two users alternate through a lock; fluent Crit1 = <enter1, exit1>.
    sys_ = make_lts("M", 4, [(0, "enter1", 1), (1, "exit1", 2), (2, "enter2", 3),
                             (3, "exit2", 0)])
    fluents = {"C1": fl("C1", {"enter1"}, {"exit1"}), "C2": fl("C2", {"enter2"}, {"exit2"})}
    c1, c2 = FluentProp("C1"), FluentProp("C2")
    assert holds(sys_, Always(Not(And(c1, c2))), fluents)
    assert holds(sys_, Always(Eventually(c1)), fluents)
    assert holds(sys_, Always(Implies(c1, Eventually(c2))), fluents)
    assert not holds(sys_, Eventually(Always(c1)), fluents)
    # A system that may stay in user 1's critical section forever (a work loop): only an
    # unfair run does so.
    loop = make_lts("L", 4, [(0, "enter1", 1), (1, "work", 1), (1, "exit1", 2),
                             (2, "enter2", 3), (3, "exit2", 0)])
    assert holds(loop, Always(Eventually(c2)), fluents)
    res = model_check(loop, Always(Eventually(c2)), fluents, fair=False)
    assert not res.holds and res.counterexample.cycle == ("work",)
    # A lock that user 1 may keep for good once it chose to: a fair violation.
    keep = make_lts("K", 5, [(0, "enter1", 1), (1, "exit1", 2), (1, "keep", 4), (4, "work", 4),
                             (2, "enter2", 3), (3, "exit2", 0)])
    res = model_check(keep, Always(Eventually(c2)), fluents)
    assert not res.holds and res.counterexample.cycle == ("work",)
    assert res.counterexample.terminal_actions == ("work",)


def test_deadlock_is_not_a_liveness_counterexample_but_safety_is_checked():
    stop = make_lts("S", 2, [(0, "a", 1)])  # a -> STOP
    res = model_check(stop, Always(Eventually(act("b"))), {})
    assert res.holds and res.deadlocks == 1
    res = model_check(stop, Always(Not(act("a"))), {})
    assert not res.holds and res.counterexample.prefix == ("a",)
    assert res.counterexample.cycle == ()
    # "a" alone is not a bad prefix of [](a -> X b): b could still follow.
    assert holds(stop, Always(Implies(act("a"), Next(act("b")))))
    # END states are finite runs too.
    end = make_lts("E", 2, [(0, "a", 1)], end_states=[1])
    assert holds(end, Always(Eventually(act("b"))))


def test_error_moves_end_the_run():
    err = make_lts("X", 1, [(0, "a", 0), (0, "b", ERROR)])
    # The run "b" stops in ERROR; it is a finite run, and a bad prefix of [] a.
    res = model_check(err, Always(act("a")), {})
    assert not res.holds and res.counterexample == Counterexample(("b",), ())
    assert res.error_reachable and not model_check(CHOICE, act("a"), {}).error_reachable
    # ... but not a liveness counterexample.
    assert holds(err, Always(Eventually(act("a"))))


def test_tau_is_not_a_position():
    # (a -> tau -> b -> P): the hidden step does not break "a is followed by b".
    hidden = make_lts("H", 3, [(0, "a", 1), (1, TAU, 2), (2, "b", 0)])
    assert holds(hidden, Always(Implies(act("a"), Next(act("b")))))
    # A tau-divergence after a is a finite visible run: no liveness violation.
    div = make_lts("D", 2, [(0, "a", 1), (1, TAU, 1)])
    assert holds(div, Always(Eventually(act("b"))))


def test_actions_outside_the_formula_are_positions():
    sys_ = make_lts("Z", 3, [(0, "a", 1), (1, "z", 2), (2, "b", 0)])
    res = model_check(sys_, Always(Implies(act("a"), Next(act("b")))), {})
    assert not res.holds
    assert res.counterexample.prefix[:2] == ("a", "z") or "z" in res.counterexample.cycle


def test_unknown_fluent_is_a_diagnostic():
    res, diags = check_assert(CHOICE, NamedFormula("A", "assert", FluentProp("Nope")), {})
    assert res is None and [d.code for d in diags] == ["E0604"]


def _chain(lasso: Lasso):
    """A deterministic LTS whose only run is the lasso."""
    word = lasso.prefix + lasso.cycle
    n = len(word)
    trans = [(i, a, i + 1) for i, a in enumerate(word[:-1])]
    trans.append((n - 1, word[-1], len(lasso.prefix)))
    return make_lts("W", n, trans)


@SETTINGS
@given(formulas, lassos)
def test_single_run_system_agrees_with_evaluator(formula, lasso):
    res = model_check(_chain(lasso), formula, FLUENTS)
    assert res.holds == evaluate(formula, lasso, FLUENTS)
    if not res.holds:
        cex = res.counterexample
        assert cex.cycle  # the system never deadlocks
        assert not evaluate(formula, Lasso(cex.prefix, cex.cycle), FLUENTS)


@SETTINGS
@given(total_lts(), formulas)
@example(make_lts("R", 1, [(0, "a", 0), (0, "b", 0)], ACTIONS), Always(Eventually(act("a"))))
def test_random_systems_agree_with_brute_force(lts, formula):
    for fair in (False, True):
        res = model_check(lts, formula, FLUENTS, fair=fair)
        brute = [r for r in lasso_runs(lts, 6, fair=fair)
                 if not evaluate(formula, Lasso(r[0], r[1]), FLUENTS)]
        if res.holds:
            assert brute == []
            continue
        cex = res.counterexample
        assert cex.cycle and is_run(lts, cex.prefix, cex.cycle)
        assert not evaluate(formula, Lasso(cex.prefix, cex.cycle), FLUENTS)
        if fair and res.stats.get("fair_cycle", True):
            assert set(cex.terminal_actions) >= set(cex.cycle)
        if len(cex.prefix) + len(cex.cycle) <= 3:
            assert brute  # a short counterexample is within the brute-force bound


@SETTINGS
@given(total_lts(), formulas)
def test_fair_counterexamples_are_fair_on_deterministic_systems(lts, formula):
    seen = set()
    first = []
    for t in lts.transitions:  # keep one move per (state, label): a deterministic system
        if (t[0], t[1]) not in seen:
            seen.add((t[0], t[1]))
            first.append(t)
    det = make_lts("D", lts.num_states, first, lts.alphabet)
    res = model_check(det, formula, FLUENTS)
    if not res.holds and res.counterexample.cycle:
        cex = res.counterexample
        assert is_fair_cycle(det, cex.prefix, cex.cycle)
    # Fairness only removes counterexamples.
    if model_check(det, formula, FLUENTS, fair=False).holds:
        assert res.holds


@SETTINGS
@given(total_lts(max_states=3), formulas)
def test_deadlocking_systems_report_only_bad_prefixes(lts, formula):
    # Remove every move of one reachable state: it becomes a deadlock.
    dead = max(t for _, _, t in lts.transitions)
    cut = make_lts("C", lts.num_states, [t for t in lts.transitions if t[0] != dead],
                   lts.alphabet)
    res = model_check(cut, formula, FLUENTS)
    if not res.holds and not res.counterexample.cycle:
        cex = res.counterexample
        assert is_run(cut, cex.prefix, ())
        letters = {"a", "b", "c", "z"}
        assert not is_good_prefix(formula, cex.prefix, FLUENTS, letters, bound=3)
