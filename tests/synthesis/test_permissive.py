"""The spec flag ``permissive`` (MTSA semantics §3.6, §3.11).

A permissive controller also keeps the controllable moves to winning but not rank-improving
successors, relabelled ``#w#_<action>``; deleting those transitions gives back the ordinary
controller.  The hand-written spec mirrors the shape of MTSA's PermissiveControllerTests: from
the initial state ``work`` reaches the goal at once, while ``detour`` is winning (the
environment's ``beep`` brings the robot back) but not better.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from synthesis_helpers import F, fl, problem

from iterplan_compiler.ir.formulas import Not
from iterplan_compiler.ir.lts import LTS, make_lts, reachable
from iterplan_compiler.ir.minimise import bisimilar
from iterplan_compiler.pipeline import load_model as load
from iterplan_compiler.synthesis.driver import synthesize
from iterplan_compiler.synthesis.strategy import PERMISSIVE_PREFIX

SOLVERS = ["symbolic", "explicit"]

SPEC = """
set Ctrl = {work, detour, crash}
set All = {Ctrl, beep}

Robot = (work -> Done | detour -> beep -> Robot | crash -> ERROR),
Done = (work -> Done).

fluent Worked = <work, All\\{work}>
fluent Beeped = <beep, All\\{beep}>

assert Beep = Beeped
assert Work = Worked

controllerSpec Loose = {
    permissive
    assumption = {Beep}
    liveness = {Work}
    controllable = {Ctrl}
}

controllerSpec Strict = {
    assumption = {Beep}
    liveness = {Work}
    controllable = {Ctrl}
}

controller ||Perm = Robot~{Loose}.
controller ||Plain = Robot~{Strict}.
"""


def _problem(name: str):
    model, diags = load("permissive.lts", text=SPEC)
    assert model is not None, diags
    prob, diags = model.synthesis_problem(name)
    assert prob is not None, diags
    return prob


def _initial_labels(lts: LTS) -> set[str]:
    return {a for s, a, _ in lts.transitions if s == lts.initial}


def _strip(lts: LTS) -> LTS:
    """The controller without its ``#w#_`` moves (and the states only they reach)."""
    keep = [(s, a, t) for s, a, t in lts.transitions if not a.startswith(PERMISSIVE_PREFIX)]
    alpha = {a for a in lts.alphabet if not a.startswith(PERMISSIVE_PREFIX)}
    return reachable(make_lts(lts.name, lts.num_states, keep, alpha, lts.initial))


def test_front_end_passes_the_flag():
    assert _problem("Perm").permissive
    assert not _problem("Plain").permissive


@pytest.mark.parametrize("solver", SOLVERS)
def test_winning_not_better_move_is_kept_as_w(solver):
    perm = synthesize(_problem("Perm"), solver=solver)
    plain = synthesize(_problem("Plain"), solver=solver)
    assert perm.realizable and plain.realizable
    # the non-permissive controller only keeps the rank-improving move
    assert _initial_labels(plain.controller) == {"work"}
    assert not any(a.startswith(PERMISSIVE_PREFIX) for a in plain.controller.alphabet)
    # the permissive one also offers the winning detour, tagged; never the losing crash
    assert _initial_labels(perm.controller) == {"work", "#w#_detour"}
    assert "#w#_crash" not in perm.controller.alphabet
    # uncontrollable moves are never tagged; after the detour the beep is still allowed
    assert "beep" in {a for _, a, _ in perm.controller.transitions}
    assert "#w#_beep" not in perm.controller.alphabet
    # the tagged label survives re-composition with the plant (it is a controller-only move)
    assert perm.composition is not None
    assert "#w#_detour" in {a for _, a, _ in perm.composition.transitions}


@pytest.mark.parametrize("solver", SOLVERS)
def test_stripping_w_moves_gives_the_plain_controller(solver):
    perm = synthesize(_problem("Perm"), solver=solver)
    plain = synthesize(_problem("Plain"), solver=solver)
    assert bisimilar(_strip(perm.controller), plain.controller)
    # and the tagged moves are what makes them differ
    assert not bisimilar(perm.controller, plain.controller, same_alphabet=False)


# --- property: on random small problems the flag only adds #w#_ moves ---------------------

ACTIONS = ["a", "b", "c", "u"]


@st.composite
def _plants(draw):
    n = draw(st.integers(1, 4))
    alpha = sorted(draw(st.sets(st.sampled_from(ACTIONS), min_size=1, max_size=4)))
    trans = draw(st.lists(st.tuples(st.integers(0, n - 1), st.sampled_from(alpha),
                                    st.integers(-1, n - 1)), max_size=3 * n))
    det = {(s, a): t for s, a, t in trans}  # deterministic plant (§3.2 step 5)
    return make_lts("P", n, [(s, a, t) for (s, a), t in det.items()], alpha)


@st.composite
def _problems(draw):
    plant = draw(_plants())
    fluents = []
    for i in range(draw(st.integers(1, 2))):
        init = draw(st.sets(st.sampled_from(ACTIONS), min_size=1, max_size=2))
        term = draw(st.sets(st.sampled_from([a for a in ACTIONS if a not in init]),
                            max_size=2))
        fluents.append(fl(f"F{i}", init, term, draw(st.booleans())))
    props = st.sampled_from([F(f.name) for f in fluents] + [Not(F(f.name)) for f in fluents])
    return problem(plant, controllable=draw(st.sets(st.sampled_from(ACTIONS))),
                   fluents=fluents, guarantees=tuple(draw(st.lists(props, max_size=2))),
                   assumptions=tuple(draw(st.lists(props, max_size=2))))


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_problems(), st.sampled_from(SOLVERS))
def test_permissive_only_adds_tagged_controllable_moves(prob, solver):
    from dataclasses import replace

    plain = synthesize(prob, solver=solver, explain=False)
    perm = synthesize(replace(prob, permissive=True), solver=solver, explain=False)
    assert perm.realizable == plain.realizable
    if not plain.realizable:
        return
    for _, a, _ in perm.controller.transitions:
        if a.startswith(PERMISSIVE_PREFIX):
            assert a[len(PERMISSIVE_PREFIX):] in prob.controllable
    assert bisimilar(_strip(perm.controller), plain.controller)
