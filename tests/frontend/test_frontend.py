"""Unit tests of the FSP front-end: parsing, expressions, processes, composites, formulas."""

from __future__ import annotations

from fractions import Fraction

import pytest

from iterplan_compiler.diagnostics import has_errors
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.frontend.parse import parse_text
from iterplan_compiler.ir import formulas as F
from iterplan_compiler.ir.lts import ERROR, TAU
from iterplan_compiler.pipeline import load_model as load


def build(text: str, name: str):
    model, diags = load("<t>", text)
    assert model is not None and not has_errors(diags), [d.message for d in diags]
    lts, ds = model.build_lts(name)
    assert lts is not None, [d.message for d in ds]
    return lts


def edges(lts):
    return {(s, a, t) for s, a, t in lts.transitions}


def test_octal_hex_and_real_division():
    model, diags = load("<t>", "const A = 010\nconst B = 0x10\nconst C = 7/2\nconst D = 7\\2\n")
    assert not diags
    assert model.constants == {"A": 8, "B": 16, "C": 3.5, "D": 3}


def test_real_division_in_labels():
    lts = build("P = (a[7/2] -> P).", "P")
    assert lts.alphabet == {"a.3.5"}


def test_prefix_chain_and_choice():
    lts = build("P = (a -> b -> P | c -> STOP).", "P")
    assert lts.num_states == 3 and lts.alphabet == {"a", "b", "c"}


def test_indexed_locals_guards_and_bindings():
    text = ("const N = 2\nrange R = 0..N\n"
            "C = C[0], C[i:R] = (when (i < N) inc -> C[i+1] | when (i > 0) dec -> C[i-1]).")
    lts = build(text, "C")
    assert lts.num_states == 3 and lts.num_transitions == 4


def test_label_sets_ranges_and_difference():
    text = "set All = {a, b, c}\nP = (All\\{b} -> P | go[1..2] -> P | {x, y}.z -> P)."
    lts = build(text, "P")
    assert lts.alphabet == {"a", "c", "go.1", "go.2", "x.z", "y.z"}


def test_undefined_local_is_error_with_warning():
    model, diags = load("<t>", "P = (a -> Q).")
    assert [d.code for d in diags] == []
    lts, ds = model.build_lts("P")
    assert [d.code for d in ds] == ["W0301"]
    assert (0, "a", ERROR) in edges(lts)


def test_alphabet_extension_relabel_hide():
    lts = build("P = (a -> b -> P) + {c} / {x/a} \\ {b}.", "P")
    assert lts.alphabet == {"x", "c"}
    assert any(a == TAU for _, a, _ in lts.transitions)


def test_process_hide_of_alias_body():
    lts = build("P = Q \\ {a}, Q = (a -> b -> Q).", "P")
    assert lts.alphabet == {"b"}


def test_property_completion():
    lts = build("property P = (a -> b -> P).", "P")
    assert (0, "b", ERROR) in edges(lts) and (1, "a", ERROR) in edges(lts)


def test_property_composite_matches_semantics_doc():
    lts = build("LOWER = (a -> b -> LOWER).\nproperty ||PL = LOWER.", "PL")
    assert lts.num_states == 2 and lts.num_transitions == 4


def test_composition_prefix_and_sharing():
    text = "P = (a -> P).\nQ = (b -> Q).\n||C = ({x, y}:P || s::Q)."
    lts = build(text, "C")
    assert lts.alphabet == {"x.a", "y.a", "s.b"}


def test_forall_and_parameters():
    text = "range R = 1..3\nP(I=0) = (go[I] -> P).\n||C = (forall [i:R] P(i))."
    lts = build(text, "C")
    assert lts.alphabet == {"go.1", "go.2", "go.3"} and lts.num_states == 1


def test_priority_high():
    text = "P = (a -> P | b -> P).\n||C = (P) << {a}."
    lts = build(text, "C")
    assert {a for _, a, _ in lts.transitions} == {"a"}


def test_sequential_composition_loop():
    text = "A = (a -> END).\nB = (b -> END).\nP = A; B; P."
    lts = build(text, "P")
    assert lts.num_states == 2 and lts.alphabet == {"a", "b"}


def test_if_then_else_and_minimal():
    text = "const K = 1\nP = if K > 0 then (a -> P) else (b -> P).\nminimal ||M = (P) \\ {a}."
    assert build(text, "P").alphabet == {"a"}
    assert build(text, "M").num_states == 1


def test_fluents_indexed_and_initially():
    text = "range R = 0..1\nfluent F[i:R] = <on[i], off[i]> initially (i == 0)"
    model, diags = load("<t>", text)
    assert not diags
    assert model.fluents["F.0"] == F.Fluent("F.0", frozenset({"on.0"}), frozenset({"off.0"}), True)
    assert model.fluents["F.1"].initially is False


def test_formula_precedence_and_assert_inlining():
    text = ("fluent A = <a, b>\nfluent B = <b, a>\n"
            "assert G = (A && B || []<>A -> B)\nassert H = (G W A)")
    model, diags = load("<t>", text)
    assert not diags
    g = model.formulas["G"].formula
    # && binds tighter than ->, which binds tighter than ||; unary ops bind tightest
    assert g == F.Or(F.And(F.FluentProp("A"), F.FluentProp("B")),
                     F.Implies(F.Always(F.Eventually(F.FluentProp("A"))), F.FluentProp("B")))
    assert model.formulas["H"].formula == F.WeakUntil(g, F.FluentProp("A"))


def test_formula_binary_at_top_level_is_syntax_error():
    _, diags = load("<t>", "fluent A = <a, b>\nassert G = A && A")
    assert [d.code for d in diags] == ["E0001"]


def test_exists_and_action_propositions():
    text = ("range R = 1..2\nfluent F[i:R] = <on[i], off[i]>\n"
            "assert E = exists [i:R] (F[i] && X go[i])")
    model, diags = load("<t>", text)
    assert not diags
    f = model.formulas["E"].formula
    assert isinstance(f, F.Or)
    assert f.left == F.And(F.FluentProp("F.1"), F.Next(F.ActionProp(frozenset({"go.1"}))))


def test_controller_spec_and_synthesis_problem():
    text = ("set C = {c}\nE = (c -> u -> E).\nfluent U = <u, c>\nassert GU = U\n"
            "controllerSpec G = {\n safety = {}\n assumption = {}\n liveness = {GU}\n"
            " controllable = {C}\n nonblocking\n}\ncontroller ||Ctl = (E)~{G}.")
    model, diags = load("<t>", text)
    assert not diags
    spec = model.controller_specs["G"]
    assert spec.liveness == ("GU",) and spec.controllable == {"c"} and spec.nonblocking
    problem, ds = model.synthesis_problem("Ctl")
    assert problem is not None and not ds
    assert problem.guarantees == (F.FluentProp("U"),)
    assert [f.name for f in problem.fluents] == ["U"]
    assert model.controllable("Ctl") == {"c"}


def test_syntax_tree_spans_and_equality():
    a, _ = parse_text("P = (a -> P).", "x")
    b, _ = parse_text("\n\n  P = (a -> P).", "y")
    assert a.decls == b.decls
    assert isinstance(a.decls[0], S.ProcessDecl) and a.decls[0].span.line == 1


def test_all_syntax_errors_reported():
    _, diags = parse_text("P = (a -> ).\nQ = (b -> Q).\nR = (-> R).\nS = (c -> S).", "x")
    assert [d.span.line for d in diags] == [1, 3]


def test_include_relative(tmp_path):
    (tmp_path / "lib.lts").write_text("L = (x -> L).\n")
    main = tmp_path / "main.lts"
    main.write_text('include "lib.lts"\n||C = (L).\n')
    model, diags = load(str(main))
    assert not diags and "L" in model.processes


def test_include_cycle(tmp_path):
    (tmp_path / "a.lts").write_text('include "b.lts"\n')
    (tmp_path / "b.lts").write_text('include "a.lts"\n')
    _, diags = load(str(tmp_path / "a.lts"))
    assert "E0802" in {d.code for d in diags}


@pytest.mark.parametrize("text", ["P = (a -> P", "||C = (", "const = 3", "P = (a -> P).)",
                                  "\x00"])
def test_garbage_never_crashes(text):
    _, diags = load("<t>", text)
    assert has_errors(diags)


def test_num_literal_value():
    spec, _ = parse_text("const X = 0.25", "x")
    assert spec.decls[0].value == S.Num(Fraction(1, 4))
