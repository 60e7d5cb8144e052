"""``ltl_property`` / ``constraint`` automata: MTSA's pinned shapes and property tests."""

from fltl_helpers import (
    FLUENTS,
    act,
    dfa_accepts_lasso,
    fl,
    formulas,
    lassos,
    project,
    run_dfa,
    safety_formulas,
    words,
)
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from iterplan_compiler.fltl.safety import not_safety_witness, safety_dfa, safety_lts
from iterplan_compiler.fltl.semantics import Lasso, evaluate, is_good_prefix
from iterplan_compiler.ir.alphabet_ops import property_complete
from iterplan_compiler.ir.formulas import (
    Always,
    And,
    Const,
    Eventually,
    FluentProp,
    Implies,
    NamedFormula,
    Next,
    Not,
    Or,
    Until,
)
from iterplan_compiler.ir.lts import ERROR, make_lts
from iterplan_compiler.ir.minimise import bisimilar, minimise

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])


def compile_(formula, fluents=None, *, constraint=False, extra=()):
    named = NamedFormula("N", "constraint" if constraint else "ltl_property", formula,
                         frozenset(extra))
    return safety_lts(named, fluents or {}, constraint=constraint)


def check_shape(formula, fluents, expected_constraint):
    """Both keywords against one expected ``constraint`` shape (ConstraintTest, §2.8)."""
    c, diags = compile_(formula, fluents, constraint=True)
    assert diags == []
    assert bisimilar(c, expected_constraint)
    assert c.num_states == expected_constraint.num_states  # minimal, like MTSA
    p, diags = compile_(formula, fluents)
    assert diags == []
    assert bisimilar(p, property_complete(expected_constraint))


def test_constraint_test_next():
    # [] (p -> X q)  ==>  A = (p -> q -> A | q -> A)
    expected = make_lts("E", 2, [(0, "p", 1), (1, "q", 0), (0, "q", 0)])
    check_shape(Always(Implies(act("p"), Next(act("q")))), {}, expected)


def test_constraint_test_first_action():
    # (p && !q)  ==>  A = (p -> B), B = ({p,q} -> B): the first action is p
    expected = make_lts("E", 2, [(0, "p", 1), (1, "p", 1), (1, "q", 1)], {"p", "q"})
    check_shape(And(act("p"), Not(act("q"))), {}, expected)


def test_constraint_test_fluents():
    # fluent A=<a,c>, B=<b,c>, [](A -> X B)
    fluents = {"A": fl("A", {"a"}, {"c"}), "B": fl("B", {"b"}, {"c"})}
    expected = make_lts("E", 4, [
        (0, "c", 0), (0, "a", 1), (0, "b", 2), (1, "b", 3),
        (2, "c", 0), (2, "b", 2), (2, "a", 3), (3, "a", 3), (3, "b", 3),
    ])
    check_shape(Always(Implies(FluentProp("A"), Next(FluentProp("B")))), fluents, expected)


def test_property_tests_lower_as_a_formula():
    # PropertyTests: property ||PL = LOWER, LOWER = (a->b->LOWER) is
    # PL = (a->P1 | b->ERROR), P1 = (b->PL | a->ERROR); the same language as an FLTL formula:
    f = And(act("a"), Always(And(Implies(act("a"), Next(act("b"))),
                                 Implies(act("b"), Next(act("a"))))))
    expected = make_lts("PL", 2, [(0, "a", 1), (0, "b", ERROR), (1, "b", 0), (1, "a", ERROR)])
    lts, diags = compile_(f)
    assert diags == [] and bisimilar(lts, expected)
    assert lts.num_states == 2 and lts.num_transitions == 4


def test_extra_alphabet_letters_are_positions():
    # With "+{r}", r is a position: it falsifies the action proposition q after p.
    lts, _ = compile_(Always(Implies(act("p"), Next(act("q")))), extra={"r"})
    assert lts.alphabet == {"p", "q", "r"}
    assert run_dfa(lts, ("p", "r")) == ERROR
    assert run_dfa(lts, ("r", "p", "q", "r")) not in (None, ERROR)


def test_non_safety_formula_is_a_diagnostic_with_a_witness():
    for f in (Eventually(act("p")), Always(Implies(act("p"), Eventually(act("q")))),
              Until(act("p"), act("q"))):
        lts, diags = compile_(f, extra={"r"})
        assert lts is None
        assert [d.code for d in diags] == ["E0605"]
        assert "safety" in diags[0].message and ")^w" in diags[0].message


def test_semantic_not_syntactic_safety():
    # <> true and (<>p || !<>p) are safety (valid) formulas although they use <>.
    lts, diags = compile_(Or(Eventually(act("p")), Not(Eventually(act("p")))), extra={"q"})
    assert diags == [] and lts.num_states == 1 and not lts.has_error


def test_unknown_fluent_and_unsatisfiable():
    lts, diags = compile_(FluentProp("Nope"))
    assert lts is None and [d.code for d in diags] == ["E0604"]
    lts, diags = compile_(Const(False), extra={"x"})
    assert [d.code for d in diags] == ["W0604"]
    assert lts.transitions == ((0, "x", ERROR),)
    c, _ = compile_(Const(False), extra={"x"}, constraint=True)
    assert c.num_states == 1 and c.num_transitions == 0


def _check_automaton(formula, lasso, word):
    lts, diags = compile_(formula, FLUENTS)
    if lts is None:
        assert [d.code for d in diags] == ["E0605"]
        return None
    assert minimise(lts).num_states == lts.num_states
    # Deterministic and complete over its alphabet (ltl_property).
    moves = {(s, a) for s, a, _ in lts.transitions}
    assert len(moves) == lts.num_transitions == lts.num_states * len(lts.alphabet)
    if not lts.alphabet:
        return lts
    # Infinite traces: accepted by the DFA (no ERROR ever) <=> satisfy the formula.
    proj = project(lasso, lts.alphabet)
    if proj is not None:
        assert dfa_accepts_lasso(lts, proj) == evaluate(formula, proj, FLUENTS)
    # Finite traces: rejected => bad prefix; accepted => a satisfying continuation exists.
    w = tuple(a for a in word if a in lts.alphabet)
    end = run_dfa(lts, w)
    stuck = end != ERROR and all(t == ERROR for s, _, t in lts.transitions if s == end)
    if stuck:  # only an unsatisfiable formula has a state without a good move
        assert end == lts.initial and [d.code for d in diags] == ["W0604"]
    if end == ERROR or stuck:
        assert not is_good_prefix(formula, w, FLUENTS, lts.alphabet, bound=3)
    else:
        u, v = _continuation(lts, end)
        assert evaluate(formula, Lasso(w + u, v), FLUENTS)
    return lts


def _continuation(lts, start):
    """Some lasso path ``u (v)^w`` of the DFA from ``start`` avoiding ERROR."""
    out = {}
    for s, a, t in lts.transitions:
        if t != ERROR:
            out.setdefault(s, []).append((a, t))
    path, seen, cur = [], {start: 0}, start
    while True:
        a, t = out[cur][0]  # every state of a good-prefix DFA has a non-ERROR move
        path.append(a)
        if t in seen:
            k = seen[t]
            return tuple(path[:k]), tuple(path[k:])
        seen[t] = len(path)
        cur = t


@SETTINGS
@given(safety_formulas, lassos, words)
def test_safety_fragment_automaton_matches_evaluator(formula, lasso, word):
    assert _check_automaton(formula, lasso, word) is not None  # the fragment is always safety


@SETTINGS
@given(formulas, lassos, words)
def test_any_formula_automaton_or_non_safety_witness(formula, lasso, word):
    lts = _check_automaton(formula, lasso, word)
    if lts is None:
        # The witness must be a real counterexample to safety: an infinite trace that the
        # good-prefix automaton never rejects, yet that violates the formula.
        named = NamedFormula("N", "ltl_property", formula)
        dfa, _, _ = safety_dfa(named, FLUENTS)
        prefix, cycle = not_safety_witness(dfa, named, FLUENTS)
        witness = Lasso(tuple(prefix), tuple(cycle))
        assert dfa_accepts_lasso(dfa, witness)
        assert not evaluate(formula, witness, FLUENTS)


@SETTINGS
@given(safety_formulas, st.booleans())
def test_constraint_is_property_without_error_moves(formula, _flag):
    p, _ = compile_(formula, FLUENTS)
    c, _ = compile_(formula, FLUENTS, constraint=True)
    assume(p is not None)
    stripped = make_lts("N", p.num_states, [t for t in p.transitions if t[2] != ERROR],
                        p.alphabet)
    assert bisimilar(c, stripped)
    assert not c.has_error
