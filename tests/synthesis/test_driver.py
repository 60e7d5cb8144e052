"""End-to-end driver behaviour on hand-made problems (MTSA semantics §3)."""

from __future__ import annotations

import pytest
from synthesis_helpers import F, fl, problem

from iterplan_compiler.ir.formulas import Next
from iterplan_compiler.ir.lts import ERROR, make_lts
from iterplan_compiler.synthesis.driver import synthesize

SOLVERS = ["symbolic", "explicit"]

# a robot that can go left/right between two rooms; the environment may raise an alarm in
# room 1, after which the controller must go back to room 0 ('l') or the system breaks.
ROOMS = make_lts("Rooms", 2, [(0, "r", 1), (1, "l", 0), (1, "alarm", 1)])
IN0 = fl("In0", {"l"}, {"r"}, True)
IN1 = fl("In1", {"r"}, {"l"})


@pytest.mark.parametrize("solver", SOLVERS)
def test_patrol_two_rooms_realizable(solver):
    p = problem(ROOMS, controllable={"l", "r"}, fluents=[IN0, IN1],
                guarantees=(F("In0"), F("In1")), assumptions=())
    r = synthesize(p, solver=solver)
    # room 1 is env-owned (alarm enabled): the environment can loop on alarm forever
    assert not r.realizable
    assert "guarantee #1" in r.explanation
    # with the assumption that alarms stop infinitely often (Quiet = <{r, l}, alarm>) the
    # environment's alarm loop violates the assumption, so the controller wins
    quiet = fl("Quiet", {"r", "l"}, {"alarm"})
    p2 = problem(ROOMS, controllable={"l", "r"}, fluents=[IN0, IN1, quiet],
                 guarantees=(F("In0"), F("In1")), assumptions=(F("Quiet"),))
    r2 = synthesize(p2, solver=solver)
    assert r2.realizable
    assert "alarm" in {a for _, a, _ in r2.controller.transitions}  # never blocked


@pytest.mark.parametrize("solver", SOLVERS)
def test_two_guarantees_alternate(solver):
    plant = make_lts("P", 3, [(0, "a", 1), (0, "b", 2), (1, "back", 0), (2, "back", 0)])
    fa, fb = fl("A", {"a"}, {"b"}), fl("B", {"b"}, {"a"})
    r = synthesize(problem(plant, controllable={"a", "b"}, fluents=[fa, fb],
                           guarantees=(F("A"), F("B"))), solver=solver)
    assert r.realizable
    # the controller must alternate a and b: both labels occur
    labels = {a for _, a, _ in r.controller.transitions}
    assert {"a", "b", "back"} <= labels
    assert r.composition is not None and r.composition.name == "C"


@pytest.mark.parametrize("solver", SOLVERS)
def test_safety_error_is_avoided_and_explained(solver):
    plant = make_lts("P", 2, [(0, "go", 1), (0, "wait", 0), (1, "u", 0)])
    # property: never 'go' (every go is an error)
    prop = make_lts("NoGo", 1, [(0, "go", ERROR)])
    ok = synthesize(problem(plant, controllable={"go", "wait"}, safety=(prop,)), solver=solver)
    assert ok.realizable
    assert all(a != "go" for _, a, _ in ok.controller.transitions)
    # without 'wait' the controller's only move is 'go' (an error)
    plant2 = make_lts("P", 2, [(0, "go", 1), (1, "u", 0)])
    bad = synthesize(problem(plant2, controllable={"go"}, safety=(prop,)), solver=solver)
    assert not bad.realizable
    assert "dead end" in bad.explanation and "ERROR" in bad.explanation


@pytest.mark.parametrize("solver", SOLVERS)
def test_failures_count_as_guarantees(solver):
    plant = make_lts("P", 2, [(0, "u", 1), (1, "fail", 1), (1, "ok", 0)])
    g = fl("G", {"ok"}, {"u"})
    fail = fl("Failed", {"fail"}, {"ok", "u"})
    base = dict(controllable={"ok"}, fluents=[g, fail], guarantees=(F("G"),))
    assert not synthesize(problem(plant, **base), solver=solver).realizable
    assert synthesize(problem(plant, **base, failures=(F("Failed"),)), solver=solver).realizable


def test_temporal_goal_is_a_diagnostic():
    plant = make_lts("P", 1, [(0, "a", 0)])
    r = synthesize(problem(plant, controllable={"a"}, fluents=[fl("A", {"a"}, set())],
                           guarantees=(Next(F("A")),)))
    assert not r.realizable and r.diagnostics and r.diagnostics[0].code == "S002"


@pytest.mark.parametrize("solver", SOLVERS)
def test_nonblocking_marking(solver):
    # u12/u21 environment loop that can exit towards the marked action m (NonBlocking test1)
    plant = make_lts("P", 3, [(0, "u12", 1), (1, "u21", 0), (1, "c", 2), (2, "m", 0)])
    p = problem(plant, controllable={"c", "m"}, keywords=("heuristic",), marking={"m"},
                nonblocking=True)
    assert synthesize(p, solver=solver).realizable
    p_missing = problem(plant, controllable={"c", "m"}, keywords=("heuristic",),
                        marking={"zzz"}, nonblocking=True)
    assert not synthesize(p_missing, solver=solver).realizable


def test_variable_orders_agree():
    plant = make_lts("P", 3, [(0, "a", 1), (0, "b", 2), (1, "back", 0), (2, "back", 0)])
    fa, fb = fl("A", {"a"}, {"b"}), fl("B", {"b"}, {"a"})
    p = problem(plant, controllable={"a", "b"}, fluents=[fa, fb], guarantees=(F("A"), F("B")))
    sizes = {synthesize(p, order=o).stats["controller_states"]
             for o in ("action_first", "action_last", "blocked")}
    assert len(sizes) == 1
