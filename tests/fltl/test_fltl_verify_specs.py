"""FLTL through the real front-end: MTSA's ConstraintTest shapes and ``iterc verify``."""

import pytest

from iterplan_compiler import cli
from iterplan_compiler.ir.minimise import bisimilar
from iterplan_compiler.pipeline import load_model as load

CONSTRAINT_TEST = """\
constraint C1 = [] (p -> X q)
A1 = (p -> q -> A1 | q -> A1).
constraint C2 = (p && !q)
A2 = (p -> B2), B2 = ({p,q} -> B2).
fluent FA = <a, c>
fluent FB = <b, c>
constraint C3 = [](FA -> X FB)
A3 = Q0, Q0 = (c -> Q0 | a -> Q1 | b -> Q2), Q1 = (b -> Q3),
     Q2 = (c -> Q0 | b -> Q2 | a -> Q3), Q3 = ({a,b} -> Q3).
ltl_property P1 = [] (p -> X q)
property PA1 = (p -> q -> PA1 | q -> PA1).
ltl_property Live = []<>p + {r}
"""

MUTEX = """\
const N = 2
range U = 1..N
USER = (enter -> exit -> USER).
LOCK = (acquire -> release -> LOCK).
||SYS = (u[i:U]:USER || LOCK)/{u[i:U].enter/acquire, u[i:U].exit/release}.
ONCE = (u[1].enter -> u[1].exit -> STOP) + {u[2].enter}.
||HALT = (SYS || ONCE).
fluent CRIT[i:U] = <u[i].enter, u[i].exit>
assert MUTEX = [](!(CRIT[1] && CRIT[2]))
assert LIVE1 = []<>CRIT[1]
assert SOME_ENTERS = exists[i:U] <>CRIT[i]
assert RESPONSE = forall[i:U] [](u[i].enter -> X u[i].exit)
assert NEVER2 = [](!u[2].enter)
assert NO_EXIT = [](!u[1].exit)
"""


@pytest.fixture
def model(tmp_path):
    def build(text):
        path = tmp_path / "spec.lts"
        path.write_text(text)
        m, diags = load(str(path))
        assert m is not None, diags
        return m, str(path)
    return build


@pytest.mark.parametrize("constraint, expected", [("C1", "A1"), ("C2", "A2"), ("C3", "A3")])
def test_constraint_test_through_the_front_end(model, constraint, expected):
    m, _ = model(CONSTRAINT_TEST)
    got, d1 = m.build_lts(constraint)
    want, d2 = m.build_lts(expected)
    assert d1 == [] and d2 == []
    assert bisimilar(got, want)
    assert got.num_states == want.num_states


def test_ltl_property_equals_property_process(model):
    m, _ = model(CONSTRAINT_TEST)
    got, _ = m.build_lts("P1")
    want, _ = m.build_lts("PA1")
    assert got.has_error and bisimilar(got, want)


def test_non_safety_ltl_property_points_at_its_declaration(model):
    m, _ = model(CONSTRAINT_TEST)
    lts, diags = m.build_lts("Live")
    assert lts is None
    codes = [(d.code, d.span.line) for d in diags]
    assert ("E0605", 12) in codes


def test_verify_command(model, capsys):
    _, path = model(MUTEX)
    assert cli.main(["verify", path, "--assert", "MUTEX", "--assert", "RESPONSE",
                     "--assert", "SOME_ENTERS", "--on", "SYS"]) == 0
    out = capsys.readouterr().out
    assert out.count("No LTL Property violations detected") == 3
    # Fair choice lets both users in infinitely often; an unfair scheduler may starve user 1.
    assert cli.main(["verify", path, "--assert", "LIVE1", "--on", "SYS"]) == 0
    capsys.readouterr()
    assert cli.main(["verify", path, "--assert", "LIVE1", "--on", "SYS", "--unfair"]) == 1
    out = capsys.readouterr().out
    assert "Violation of LTL property LIVE1" in out and "Cycle in terminal set:" in out
    assert "u.2.enter" in out.split("Cycle in terminal set:")[1]


def test_verify_deadlocking_composite(model, capsys):
    _, path = model(MUTEX)
    # HALT: user 1 enters and exits once, then everything deadlocks (user 2 never may enter).
    # The finite run is no counterexample to a liveness assert ...
    assert cli.main(["verify", path, "--assert", "LIVE1", "--assert", "NEVER2",
                     "--on", "HALT"]) == 0
    out = capsys.readouterr().out
    assert out.count("No LTL Property violations detected") == 2
    assert "1 reachable deadlock/END state(s)" in out
    # ... but a safety violation on the way to the deadlock is reported, without a cycle.
    assert cli.main(["verify", path, "--assert", "NO_EXIT", "--on", "HALT"]) == 1
    out = capsys.readouterr().out
    assert "u.1.enter\n    u.1.exit\n  (every continuation violates the property)" in out


def test_verify_unknown_assert_and_composite(model, capsys):
    _, path = model(MUTEX)
    assert cli.main(["verify", path, "--assert", "MUTEXX", "--on", "SYS"]) == 1
    err = capsys.readouterr().err
    assert "E0607" in err and "did you mean 'MUTEX'" in err
    assert cli.main(["verify", path, "--assert", "MUTEX", "--on", "NOPE"]) == 1
    assert "error" in capsys.readouterr().err
