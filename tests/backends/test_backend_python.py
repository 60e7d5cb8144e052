"""The Python back-end: generated controller modules, as text and as running code."""

from __future__ import annotations

import subprocess
import sys

import pytest
from backends_helpers import (
    FIRE_PATROL_CONTROLLABLE,
    TOGGLE_CONTROLLABLE,
    check_golden,
    fire_patrol,
    load_module,
    toggle,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from iterplan_compiler import __version__
from iterplan_compiler.backends.python import BackendError, class_name, emit_module
from iterplan_compiler.diagnostics import Span
from iterplan_compiler.ir.lts import make_lts
from iterplan_compiler.runtime.controller import Controller, ControllerTable, RefusedEvent

HASH = "0" * 63 + "1"


def fire_text() -> str:
    return emit_module(
        fire_patrol(), controllable=FIRE_PATROL_CONTROLLABLE, name="FirePatrol",
        source_name="/somewhere/private/fire_patrol.lts", spec_hash=HASH,
        origins={"controller composite FirePatrol": Span("/abs/fire_patrol.lts", 42, 3),
                 "controllerSpec Goal": Span("/abs/fire_patrol.lts", 30, 1)},
    )


def toggle_text() -> str:
    return emit_module(toggle(), controllable=TOGGLE_CONTROLLABLE, name="toggle-ctl",
                       source_name="toggle.lts", spec_hash=HASH, origins=None)


@pytest.fixture
def fire(tmp_path):
    return load_module(fire_text(), tmp_path, "fire_patrol_ctl")


def test_golden_modules():
    check_golden(fire_text(), "fire_patrol_controller.py")
    check_golden(toggle_text(), "toggle_controller.py")


def test_header_is_deterministic_and_path_free():
    text = fire_text()
    assert text == fire_text()
    assert "/abs" not in text and "/somewhere" not in text
    assert f"iterc {__version__}" in text
    assert HASH in text
    assert "# controller composite FirePatrol: fire_patrol.lts:42:3" in text
    assert "# controllerSpec Goal: fire_patrol.lts:30:1" in text


def test_module_contract(fire):
    c = fire.make_controller()
    assert isinstance(c, Controller) and isinstance(c, fire.CONTROLLER_CLASS)
    assert fire.CONTROLLER_CLASS.__name__ == "FirePatrolController"
    assert isinstance(fire.TABLE, ControllerTable)
    assert fire.CONTROLLABLE == FIRE_PATROL_CONTROLLABLE
    assert fire.UNCONTROLLABLE == fire_patrol().alphabet - FIRE_PATROL_CONTROLLABLE
    assert fire.SPEC_FILE == "fire_patrol.lts" and fire.SPEC_SHA256 == HASH
    assert fire.NAME == "FirePatrol" and fire.STATE_NAMES is None
    assert set(c.transitions) == set(fire_patrol().transitions)
    assert list(c.states) == list(range(12))
    assert fire.RefusedEvent is RefusedEvent


def test_scripted_sequence_and_refusal(fire):
    c = fire.make_controller()
    script = ["has.next", "y.next", "is.next.inP", "yes.next.inP", "go.next", "arrived",
              "is.fire", "yes.fire", "take.photo", "remove.next", "has.next", "n.next", "reset"]
    states = [c.step(e) for e in script]
    assert states == [1, 2, 3, 4, 5, 6, 7, 8, 10, 0, 1, 11, 0]
    assert c.enabled() == {"has.next"}
    with pytest.raises(RefusedEvent) as info:
        c.step("go.next")  # must ask the iterator first
    assert info.value.state == 0 and info.value.event == "go.next"
    assert "go.next" in str(info.value) and "has.next" in str(info.value)
    assert c.state == 0  # a refused event leaves the state unchanged


def test_run_feeds_binding_answers_back(fire):
    c = fire.make_controller()
    answers = iter(["y.next", "y.next", "n.next"])
    patrol = iter(["yes.next.inP", "no.next.inP"])
    calls: list[str] = []

    def record(label, answer=None):
        def call():
            calls.append(label)
            return answer() if callable(answer) else answer
        return call

    bindings = {
        "has.next": record("has.next", lambda: next(answers)),
        "is.next.inP": record("is.next.inP", lambda: next(patrol)),
        "go.next": record("go.next", "arrived"),
        "is.fire": record("is.fire", ["yes.fire"]),
        "take.photo": record("take.photo"),
        "remove.next": record("remove.next"),
        "reset": record("reset"),
    }
    report = c.run(bindings, max_steps=18)
    assert report["steps"] == 18
    assert calls == ["has.next", "is.next.inP", "go.next", "is.fire", "take.photo",
                     "remove.next", "has.next", "is.next.inP", "remove.next", "has.next",
                     "reset"]
    assert report["trace"][:10] == [
        "has.next", "y.next", "is.next.inP", "yes.next.inP", "go.next", "arrived", "is.fire",
        "yes.fire", "take.photo", "remove.next"]
    assert c.state == 0


def test_run_checks_bindings_before_the_first_step(fire):
    c = fire.make_controller()
    with pytest.raises(ValueError, match="no binding for controllable action"):
        c.run({"has.next": lambda: "y.next"})
    assert c.state == 0
    full = {a: (lambda: None) for a in fire.CONTROLLABLE}
    full["has.next"] = lambda: "arrived"  # an answer the controller does not allow now
    with pytest.raises(RefusedEvent, match="arrived"):
        c.run(full, max_steps=5)


def test_run_with_events_source_and_stop(tmp_path):
    mod = load_module(toggle_text(), tmp_path, "toggle_ctl")
    assert mod.CONTROLLER_CLASS.__name__ == "ToggleCtlController"
    assert mod.STATE_NAMES == ("Idle", "Busy", "Done")
    assert "unused.ev" in mod.UNCONTROLLABLE
    c = mod.make_controller()
    env = iter(["ack", "fail"])
    report = c.run({"on": lambda: None, "stop": lambda: None}, events=lambda: next(env, None),
                   choose=lambda opts: "on")
    # on, ack, on, fail -> Done (no moves): the run ends there by itself.
    assert report["trace"] == ["on", "ack", "on", "fail"] and c.state == 2
    c.reset()
    report = c.run({"on": lambda: None, "stop": lambda: None}, choose=lambda opts: "stop")
    assert report["steps"] == 1 and c.state == 2


def test_generated_module_imports_only_runtime(tmp_path):
    path = tmp_path / "fire_ctl.py"
    path.write_text(fire_text(), encoding="utf-8")
    code = (
        "import sys; sys.path.insert(0, sys.argv[1])\n"
        "import fire_ctl\n"
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('lark', 'dd', 'pydot')\n"
        "             or m.startswith('iterplan_compiler.') and not\n"
        "             m.startswith('iterplan_compiler.runtime'))\n"
        "assert not bad, bad\n"
        "print(fire_ctl.make_controller().step('has.next'))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True,
                          text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "1"


@pytest.mark.parametrize("transitions, why", [
    ([(0, "a", 1), (0, "a", 0)], "nondeterministic"),
    ([(0, "a", -1)], "ERROR"),
    ([(0, "tau", 1)], "tau"),
])
def test_rejects_non_controllers(transitions, why):
    lts = make_lts("Bad", 2, transitions)
    with pytest.raises(BackendError, match=why):
        emit_module(lts, controllable=frozenset(), name="Bad", source_name="b.lts",
                    spec_hash=HASH, origins=None)


@pytest.mark.parametrize("name, expected", [
    ("C", "CController"), ("fire_patrol", "FirePatrolController"), ("2x", "C2xController"),
    ("", "SpecController"), ("a.b-c", "ABCController"),
])
def test_class_name(name, expected):
    assert class_name(name) == expected
    assert expected.isidentifier()


_labels = st.sampled_from(["a", "b.c", "x[1]", "it's", 'q"x', "#w#_c", "-1", "é.ü"])


@st.composite
def deterministic_lts(draw):
    n = draw(st.integers(1, 6))
    rows = draw(st.lists(st.dictionaries(_labels, st.integers(0, n - 1), max_size=4),
                         min_size=n, max_size=n))
    trans = [(s, a, t) for s, row in enumerate(rows) for a, t in row.items()]
    extra = draw(st.sets(_labels, max_size=2))
    return make_lts(draw(st.sampled_from(["C", "Ctl", "x y"])), n, trans, extra)


@settings(max_examples=40, deadline=None)
@given(lts=deterministic_lts(), ctrl=st.sets(_labels, max_size=4), data=st.data())
def test_table_equals_lts_for_random_controllers(tmp_path_factory, lts, ctrl, data):
    text = emit_module(lts, controllable=frozenset(ctrl), name=lts.name, source_name="r.lts",
                       spec_hash=HASH, origins=None)
    mod = load_module(text, tmp_path_factory.mktemp("gen"), "random_ctl")
    assert set(mod.TRANSITIONS) == set(lts.transitions)
    assert mod.TABLE.num_states == lts.num_states and mod.TABLE.initial == lts.initial
    assert mod.CONTROLLABLE | mod.UNCONTROLLABLE == lts.alphabet
    assert mod.CONTROLLABLE == lts.alphabet & ctrl
    # A random walk of the module agrees with the LTS step by step.
    c = mod.make_controller()
    out = lts.out_edges()
    s = lts.initial
    for _ in range(10):
        moves = sorted(out[s])
        if not moves:
            break
        a, t = data.draw(st.sampled_from(moves))
        assert c.enabled() == {b for b, _ in moves}
        s = c.step(a)
        assert s == t


@settings(max_examples=30, deadline=None)
@given(lts=deterministic_lts(), data=st.data())
def test_canonical_numbering_ignores_synthesis_numbering(lts, data):
    """Renumbering the controller's states does not change the emitted module."""
    from iterplan_compiler.backends.output import canonical_controller

    perm = data.draw(st.permutations(range(lts.num_states)))
    shuffled = make_lts(lts.name, lts.num_states,
                        [(perm[s], a, perm[t]) for s, a, t in lts.transitions],
                        lts.alphabet, perm[lts.initial])

    def emit(m):
        return emit_module(canonical_controller(m), controllable=frozenset({"a"}), name="C",
                           source_name="c.lts", spec_hash=HASH, origins=None)

    assert emit(shuffled) == emit(lts)
