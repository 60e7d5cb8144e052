"""``iterc check SPEC --safety/--progress COMPOSITE`` end to end (exit codes, LTSA text,
diagnostics at the composite)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from iterplan_compiler import cli

REPO = Path(__file__).resolve().parents[2]

SPEC = """\
P = (a -> b -> P | a -> c -> STOP).
Q = (a -> b -> Q | c -> Q).
||DEAD = (P || Q).
property SAFE = (a -> b -> SAFE).
R = (a -> b -> R | a -> a -> R).
||BAD = (R || SAFE).
fluent F = <a, b>
ltl_property NOTWICE = [](F -> !a)
||BADLTL = (R || NOTWICE).
S = (a -> b -> S).
||GOOD = (S || SAFE).
progress PB = {b}
progress IFC = if {x} then {y}
progress IX[i:0..1] = {d[i]}
D = (d[0] -> D | go -> E), E = (d[1] -> E).
||STUCK = (D).
T = (d[0] -> d[1] -> b -> T).
||FINE = (T).
"""

DIAG = re.compile(r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): error\[(?P<code>E\d+)\]: "
                  r"(?P<msg>.*)$", re.M)


@pytest.fixture
def spec(tmp_path):
    p = tmp_path / "ltsa.lts"
    p.write_text(SPEC)
    return p


def run(capsys, *argv):
    capsys.readouterr()
    code = cli.main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def line_of(text: str) -> int:
    return next(i for i, line in enumerate(SPEC.splitlines(), 1) if text in line)


def test_deadlock(spec, capsys):
    code, out, err = run(capsys, "check", spec, "--safety", "DEAD")
    assert code == 1
    assert "Trace to DEADLOCK:\n\ta\n" in out
    (d,) = DIAG.finditer(err)
    assert d["code"] == "E1301" and d["file"] == str(spec)
    assert int(d["line"]) == line_of("||DEAD") and int(d["col"]) >= 1
    assert "Trace to DEADLOCK: a" in d["msg"]


def test_property_violation_names_the_property(spec, capsys):
    code, out, err = run(capsys, "check", spec, "--safety", "BAD")
    assert code == 1
    assert "Trace to property violation in SAFE:\n\ta\n\ta\n" in out
    (d,) = DIAG.finditer(err)
    assert d["code"] == "E1302" and int(d["line"]) == line_of("||BAD")
    assert "note: SAFE is declared here" in err
    assert f"{spec}:{line_of('property SAFE')}:" in err


def test_ltl_property_violation(spec, capsys):
    code, out, err = run(capsys, "check", spec, "--safety", "BADLTL")
    assert code == 1
    # F holds from the first a on, and that a is itself an a: the first a violates it
    assert "Trace to property violation in NOTWICE:\n\ta\n" in out
    assert "error[E1302]" in err


def test_safe_composite_passes(spec, capsys):
    code, out, err = run(capsys, "check", spec, "--safety", "GOOD")
    assert code == 0, err
    assert "No deadlocks/errors" in out
    assert "ltsa.lts: ok" in out


def test_progress_violations(spec, capsys):
    code, out, err = run(capsys, "check", spec, "--progress", "STUCK")
    assert code == 1
    assert ("Progress violation: PB\nTrace to terminal set of states:\n\tgo\n"
            "Cycle in terminal set:\n\td.1\nActions in terminal set:\n\t{d.1}\n") in out
    assert "Progress violation: IX[0]" in out
    assert "IX[1]" not in out and "IFC" not in out  # d.1 occurs; the if-set never does
    codes = [(m["code"], int(m["line"])) for m in DIAG.finditer(err)]
    assert codes == [("E1303", line_of("||STUCK"))] * 2
    assert "note: progress PB is declared here" in err


def test_progress_holds(spec, capsys):
    code, out, err = run(capsys, "check", spec, "--progress", "FINE")
    assert code == 0, err
    assert "No progress violations detected." in out


def test_default_progress_without_declarations(tmp_path, capsys):
    p = tmp_path / "noprog.lts"
    p.write_text("P = (start -> L), L = (work -> L).\n||SYS = (P).\n"
                 "C = (a -> b -> C).\n||CYC = (C).\n")
    code, out, err = run(capsys, "check", p, "--progress", "SYS")
    assert code == 1
    assert "Progress violation for actions:\n\t{start}\n" in out
    assert "Trace to terminal set of states:\n\tstart\n" in out
    assert "error[E1303]" in err
    code, out, _ = run(capsys, "check", p, "--progress", "CYC")
    assert code == 0 and "No progress violations detected." in out


def test_both_checks_and_unknown_name(spec, capsys):
    code, out, err = run(capsys, "check", spec, "--safety", "GOOD", "--progress", "FINE")
    assert code == 0, err
    code, out, err = run(capsys, "check", spec, "--safety", "NOPE")
    assert code == 1
    assert f"{spec}: error[E0104]: no process or composite named 'NOPE'" in err


def test_progress_is_no_longer_ignored(spec, capsys):
    code, out, err = run(capsys, "check", spec)
    assert code == 0
    assert "W0151" not in err


def test_bundled_example_is_deadlock_free(capsys):
    code, out, err = run(capsys, "check", REPO / "examples" / "search_and_map.lts",
                         "--safety", "SearchAndMapSystem", "--progress", "SearchAndMapSystem")
    assert code == 0, err
    assert "No deadlocks/errors" in out and "No progress violations detected." in out


def test_explicit_error_in_a_process_is_named(tmp_path, capsys):
    p = tmp_path / "err.lts"
    p.write_text("P = (a -> ERROR | b -> P).\n||S = (P).\n")
    code, out, err = run(capsys, "check", p, "--safety", "S")
    assert code == 1
    assert "Trace to property violation in P:\n\ta\n" in out
    assert f"{p}:2:3: error[E1302]" in err


@pytest.mark.parametrize("text", ["P = (a -> .\n", "||S = (P || Q).\n"])
def test_bad_input_is_a_diagnostic(tmp_path, capsys, text):
    p = tmp_path / "bad.lts"
    p.write_text(text)
    for option in ("--safety", "--progress"):
        code, out, err = run(capsys, "check", p, option, "S")
        assert code == 1
        assert "error[" in err and "Traceback" not in err


def test_progress_declarations_print_back(spec, capsys):
    code, out, _ = run(capsys, "check", spec, "--print")
    assert code == 0
    assert "progress PB = {b}\n" in out
    assert "progress IFC = if {x} then {y}\n" in out
    assert "progress IX[i:0..1] = {d[i]}\n" in out


# A single-lane bridge (the classic progress example, written afresh): cars of one colour
# may share the bridge, entering and leaving in order; under congestion (exits at low priority)
# the colour on the bridge can keep it for ever.
BRIDGE = """\
const N = 3
range ID = 1..N
CAR = (enter -> exit -> CAR).
INORDER = C[1], C[i:ID] = ([i].enter -> C[i % N + 1]).
OUTORDER = C[1], C[i:ID] = ([i].exit -> C[i % N + 1]).
||CONVOY = ([ID]:CAR || INORDER || OUTORDER).
BRIDGE = B[0][0],
B[nr:0..N][nb:0..N] = (when nb == 0 red[ID].enter -> B[nr + 1][nb]
                     | red[ID].exit -> B[nr - 1][nb]
                     | when nr == 0 blue[ID].enter -> B[nr][nb + 1]
                     | blue[ID].exit -> B[nr][nb - 1]).
||FREE = (red:CONVOY || blue:CONVOY || BRIDGE).
||CONGESTED = FREE >> {red[ID].exit, blue[ID].exit}.
progress BLUECROSS = {blue[ID].enter}
progress REDCROSS = {red[ID].enter}
"""


def test_congested_bridge_starves_a_colour(tmp_path, capsys):
    p = tmp_path / "bridge.lts"
    p.write_text(BRIDGE)
    code, out, err = run(capsys, "check", p, "--safety", "FREE", "--progress", "FREE")
    assert code == 0, err
    assert "No deadlocks/errors" in out and "No progress violations detected." in out
    code, out, err = run(capsys, "check", p, "--progress", "CONGESTED")
    assert code == 1
    assert "Progress violation: BLUECROSS\nTrace to terminal set of states:\n\tred.1.enter\n" in out
    assert "Progress violation: REDCROSS\nTrace to terminal set of states:\n\tblue.1.enter\n" in out
    assert ("Actions in terminal set:\n\t{red.1.enter, red.1.exit, red.2.enter, red.2.exit, "
            "red.3.enter, red.3.exit}\n") in out
    assert [m["code"] for m in DIAG.finditer(err)] == ["E1303", "E1303"]
