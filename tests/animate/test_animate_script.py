"""``iterc animate --script``: the screen text, undo, save, errors, controllable marks."""

from __future__ import annotations

from pathlib import Path

import pytest

from iterplan_compiler import cli
from iterplan_compiler.ir.animator import AnimationError, Animator
from iterplan_compiler.ir.formulas import Fluent
from iterplan_compiler.ir.lts import ERROR, make_lts

REPO = Path(__file__).resolve().parents[2]
COVER = REPO / "examples" / "cover.lts"

SPEC = """\
P = (a -> b -> P | a -> c -> STOP).
Q = (a -> b -> Q | c -> Q).
||SYS = (P || Q).
fluent Busy = <a, b>
property SAFE = (a -> b -> SAFE).
R = (a -> b -> R | a -> a -> R).
||BAD = (R || SAFE).
H = (x -> tau_hidden -> y -> H) \\ {tau_hidden}.
ST = (go -> STOP).
"""


def run(capsys, *argv):
    capsys.readouterr()
    code = cli.main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture
def spec(tmp_path):
    p = tmp_path / "anim.lts"
    p.write_text(SPEC)
    return p


def script(tmp_path, *lines):
    p = tmp_path / "script.txt"
    p.write_text("\n".join(lines) + "\n")
    return p


def test_screen_fire_by_number_and_name_undo_save(spec, tmp_path, capsys):
    saved = tmp_path / "trace.txt"
    s = script(tmp_path, "# comment", "1", "b", "undo", "b", "a", f"save {saved}", "quit")
    code, out, err = run(capsys, "animate", spec, "SYS", "--script", s)
    assert code == 0, err
    screens = out.split("== SYS")
    assert screens[1].startswith(" (3 states) ==\ntrace (0): (empty)\nstate: 0\n"
                                 "fluents: Busy=false\nenabled actions:\n  1  a\n> 1\n")
    # after `a` P may have chosen its c-branch, which Q blocks: two states, one a deadlock
    assert ("trace (1): a\nstates: {1, 2}\nstatus: possibly DEADLOCK (state 2 has no action)"
            "\nfluents: Busy=true\nenabled actions:\n  1  b\n> b\n") in out
    assert "> undo\nundone\n== SYS (3 states) ==\ntrace (1): a\n" in out
    assert "trace (3): a b a\n" in out
    assert f"saved 3 actions to {saved}" in out
    assert saved.read_text() == "a\nb\na\n"
    # a saved trace replays as a script
    code, out2, _ = run(capsys, "animate", spec, "SYS", "--script", saved)
    assert code == 0 and out2.rstrip().endswith("  1  b")
    assert "trace (3): a b a\n" in out2


def test_deadlock_is_shown(spec, tmp_path, capsys):
    code, out, err = run(capsys, "animate", spec, "ST", "--script", script(tmp_path, "go"))
    assert code == 0, err
    assert "trace (1): go\nstate: 1\nstatus: DEADLOCK (no action enabled)\n" in out


def test_error_state_is_shown(spec, tmp_path, capsys):
    code, out, err = run(capsys, "animate", spec, "BAD", "--script", script(tmp_path, "a", "a"))
    assert code == 0, err
    assert "states: {ERROR}\nstatus: ERROR reached (a property is violated)" in out
    assert out.rstrip().endswith("enabled actions: none")


def test_tau_is_taken_silently(spec, tmp_path, capsys):
    code, out, err = run(capsys, "animate", spec, "H", "--script", script(tmp_path, "x"))
    assert code == 0, err
    assert "trace (1): x\nstates: {1, 2}\n" in out
    assert "  1  y\n" in out and "tau" not in out.split("> x")[1]


@pytest.mark.parametrize("bad, message", [
    ("9", "no action number 9: choose 1..1"),
    ("b", "'b' is not enabled here"),
    ("nosuch", "'nosuch' is not an action of SYS"),
    ("undo", "nothing to undo: the trace is empty"),
    ("save", "save needs one file name: save PATH"),
    ("frob x", "unknown command 'frob x'"),
])
def test_bad_commands_are_located_errors(spec, tmp_path, capsys, bad, message):
    s = script(tmp_path, "", bad)
    code, out, err = run(capsys, "animate", spec, "SYS", "--script", s)
    assert code == 1
    assert f"{s}:2:1: error[E1311]: {message}" in err


def test_bad_names(spec, tmp_path, capsys):
    s = script(tmp_path, "quit")
    code, _, err = run(capsys, "animate", spec, "SIS", "--script", s)
    assert code == 1 and "error[E0104]: no process or composite named 'SIS'; did you mean 'SYS'?" in err
    code, _, err = run(capsys, "animate", spec, "SYS", "--spec", "G", "--script", s)
    assert code == 1 and "error[E1312]: no controllerSpec named 'G'" in err
    code, _, err = run(capsys, "animate", spec, "--script", tmp_path / "missing.txt")
    assert code == 1 and "error[E0800]" in err


def test_controller_marks_controllable_actions(tmp_path, capsys):
    s = script(tmp_path, "takeoff", "takeoff.ended", "has.next")
    code, out, err = run(capsys, "animate", COVER, "Cover", "--script", s)
    assert code == 0, err
    assert "enabled actions (* = controllable, from Cover's controllerSpec):\n" \
           "  1  takeoff *\n" in out
    assert "  1  takeoff.ended\n" in out  # uncontrollable: no mark
    assert "fluents: Arrived=false HasNext=true" in out
    # the plant (no spec of its own) takes the spec's only controllable set
    code, out, err = run(capsys, "animate", COVER, "Environment", "--script", s)
    assert code == 0, err
    assert "(* = controllable, from controllerSpec CoverSpec)" in out


def test_stdin_without_terminal_is_a_script(spec, capsys, monkeypatch):
    import io

    monkeypatch.setattr("sys.stdin", io.StringIO("a\nb\n"))
    code, out, err = run(capsys, "animate", spec, "SYS")
    assert code == 0, err
    assert "trace (2): a b\n" in out


def test_animator_directly():
    lts = make_lts("M", 2, [(0, "go", 1), (1, "back", 0), (1, "boom", ERROR)])
    an = Animator(lts, frozenset({"go"}),
                  {"Out": Fluent("Out", frozenset({"go"}), frozenset({"back"}))})
    assert an.enabled() == ["go"]
    an.fire("go")
    assert an.fluent_values() == {"Out": True}
    assert an.enabled() == ["back", "boom"]
    with pytest.raises(AnimationError):
        an.fire("go")
    an.fire("2")
    assert an.states == frozenset({ERROR}) and an.enabled() == []
    assert an.undo() and an.undo() and not an.undo()
    assert an.trace_text() == ""
