"""MTSA §3.7/§3.8 for ``controller`` composites: a nondeterministic (or tau) plant product is
controlled-determinised (action ``-1``, uncontrollable) before synthesis; an unrealizable
composite is error E0901, or -- with ``build_lts(name, unrealizable=Unrealizable.PLANT)`` -- MTSA's
composition, the plant renamed ``C_#NC#``."""

from __future__ import annotations

from iterplan_compiler.diagnostics import has_errors
from iterplan_compiler.frontend.operators import CONTROL_ACTION, eliminate_tau
from iterplan_compiler.ir.alphabet_ops import is_deterministic
from iterplan_compiler.ir.lts import ERROR, TAU, make_lts
from iterplan_compiler.ir.model import Unrealizable
from iterplan_compiler.pipeline import load_model as load

# MTSA's Alphabet/lts_alphabet_hiding_compose.lts: M offers c3 twice (nondeterministic)
HIDING_COMPOSE = """\
set Alph = {c1, a, g1, g2}
set Controllable = {c1, g1, g2}
fluent A = <a, Alph\\{a}>
fluent G1 = <g1, Alph\\{g1}>
fluent G2 = <g2, Alph\\{g2}>
assert GG1 = G1
assert GG2 = G2
assert As = A
controller ||C = M~{G1}.
controllerSpec G1 = {
    safety = {}
    assumption = {As}
    liveness = {GG1, GG2}
    controllable = {Controllable}
}
M = (c3->MC3 | c1->MA | c2->A | c3->W),
W = (w->W),
A = (a->A),
MC3 = (l->MC3 | c3->a->MC3),
MA = (a->MM),
MM = ({g1,g2}->MA).
"""

# After `u` the plant is in P1 or P2; both only offer the controllable `c`, so the controller
# takes the turn through `-1` and plays `c` (enabled in both): realizable.
NONDET_REALIZABLE = """\
P = (u -> P1 | u -> P2),
P1 = (c -> P),
P2 = (c -> P).
fluent C = <c, u>
assert SeeC = C
controllerSpec G = { liveness = {SeeC} controllable = {c} }
controller ||K = (P)~{G}.
"""

DET_UNREALIZABLE = """\
P = (a -> b -> P | c -> d -> P).
set All = {a, b, c, d}
fluent B = <b, All\\{b}>
assert SeeB = B
controllerSpec G = { liveness = {SeeB} controllable = {b, d} }
controller ||C = (P)~{G}.
"""


def _model(text: str):
    model, diags = load("t.lts", text)
    assert model is not None and not has_errors(diags), [d.message for d in diags]
    return model


def test_unrealizable_nondeterministic_plant_is_an_error_by_default():
    lts, diags = _model(HIDING_COMPOSE).build_lts("C")
    assert lts is None
    assert [d.code for d in diags if d.is_error] == ["E0901"]


def test_unrealizable_plant_mode_gives_mtsa_composition():
    lts, diags = _model(HIDING_COMPOSE).build_lts("C", unrealizable=Unrealizable.PLANT)
    assert lts is not None and not has_errors(diags)
    assert [d.code for d in diags] == ["W0902"]
    assert lts.name == "C_#NC#"
    # MTSA's expected alphabet for this row (verdicts.tsv): [c3 a -1 w g1 g2 l c1 c2]
    assert set(lts.alphabet) == {"c3", "a", CONTROL_ACTION, "w", "g1", "g2", "l", "c1", "c2"}
    assert is_deterministic(lts)


def test_unrealizable_deterministic_plant_mode_is_the_plant_product():
    model = _model(DET_UNREALIZABLE)
    lts, diags = model.build_lts("C", unrealizable=Unrealizable.PLANT)
    assert lts is not None and lts.name == "C_#NC#"
    assert CONTROL_ACTION not in lts.alphabet
    plant, _ = model.build_lts("P")
    assert lts.num_states == plant.num_states and lts.num_transitions == plant.num_transitions


def test_plant_mode_does_not_change_realizable_or_plain_composites():
    model = _model(NONDET_REALIZABLE + "||Plain = (P).\n")
    for name in ("K", "Plain"):
        a, da = model.build_lts(name)
        b, db = model.build_lts(name, unrealizable=Unrealizable.PLANT)
        assert a is not None and a is b and da == db


def test_nondeterministic_plant_is_controlled_determinised_before_synthesis():
    model = _model(NONDET_REALIZABLE)
    lts, diags = model.build_lts("K")
    assert lts is not None and not has_errors(diags), [d.message for d in diags]
    assert CONTROL_ACTION in lts.alphabet  # the controller was built on the determinised plant
    assert is_deterministic(lts)
    # `iterc synth`/`compile` solve the same (determinised) problem as build_lts
    problem, _ = model.synthesis_problem("K")
    assert problem is not None and len(problem.plant) == 1 and problem.safety == ()
    assert CONTROL_ACTION in problem.plant[0].alphabet
    assert CONTROL_ACTION not in problem.controllable


def test_deterministic_plant_problem_keeps_its_components():
    problem, _ = _model(DET_UNREALIZABLE + "Q = (b -> Q).\ncontroller ||D = (P || Q)~{G}.\n"
                        ).synthesis_problem("D")
    assert problem is not None and [m.name for m in problem.plant] == ["P", "Q"]


def test_nonblocking_spec_skips_controlled_determinisation():
    text = NONDET_REALIZABLE.replace("controllable = {c} }", "controllable = {c} nonblocking }")
    lts, diags = _model(text).build_lts("K")
    assert lts is None or CONTROL_ACTION not in lts.alphabet


def test_eliminate_tau_keeps_weak_moves():
    # 0 -tau-> 1 -a-> 2 -tau-> 3(END);  2 -b-> ERROR
    lts = make_lts("T", 4, [(0, TAU, 1), (1, "a", 2), (2, TAU, 3), (2, "b", ERROR)],
                   {"a", "b"}, 0, [3])
    out = eliminate_tau(lts)
    assert TAU not in out.alphabet
    assert set(out.transitions) == {(0, "a", 2), (0, "a", 3), (1, "a", 2), (1, "a", 3),
                                    (2, "b", ERROR)}
    assert set(out.end_states) == {2, 3}


def test_hidden_plant_action_goes_through_controlled_determinisation():
    text = """\
P = (u -> h -> Q), Q = (c -> P).
fluent C = <c, u>
assert SeeC = C
controllerSpec G = { liveness = {SeeC} controllable = {c} }
||Hidden = (P)\\{h}.
controller ||K = (Hidden)~{G}.
"""
    lts, diags = _model(text).build_lts("K")
    assert lts is not None and not has_errors(diags), [d.message for d in diags]
    assert TAU not in lts.alphabet and "h" not in lts.alphabet
    assert CONTROL_ACTION in lts.alphabet


COMPAT = """\
P = (a -> P | b -> P).
fluent A = <a, b>
assert As = A
controllerSpec G = { assumption = {As} controllable = {CTRL} }
checkCompatibility ||Comp = (P)~{G}.
"""


def test_check_compatibility_composite_compatible():
    model = _model(COMPAT.replace("CTRL", "b"))
    lts, diags = model.build_lts("Comp")
    assert lts is not None and diags == []
    assert lts.num_states == 1 and set(lts.alphabet) == {"a", "b"}  # the plant product


def test_check_compatibility_composite_not_compatible_warns():
    # the controller can play b forever, so it can force a violation of the assumption
    model = _model(COMPAT.replace("CTRL", "a, b"))
    lts, diags = model.build_lts("Comp")
    assert lts is not None
    assert [(d.code, d.is_error) for d in diags] == [("W0903", False)]
    assert "NOT compatible" in diags[0].message


def test_permissive_flag_reaches_the_synthesis_problem():
    model = _model(NONDET_REALIZABLE.replace("controllable = {c} }",
                                             "controllable = {c} permissive }"))
    problem, _ = model.synthesis_problem("K")
    assert problem is not None and problem.permissive
    problem, _ = _model(NONDET_REALIZABLE).synthesis_problem("K")
    assert problem is not None and not problem.permissive
