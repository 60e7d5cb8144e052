"""Every spec-reading command on bad input: exit 1 with `file[:line:col]: error[CODE]:`
diagnostics, never a traceback or exit 3 (README "Exit codes")."""

from __future__ import annotations

import pytest
from cli_helpers import GOLDEN_SPEC, assert_input_error, assert_no_crash, run_cli

#: argv templates of the commands that read an FSP spec; {spec} is replaced by the path.
SPEC_COMMANDS = {
    "check": ["check", "{spec}"],
    "check --build": ["check", "--build", "{spec}"],
    "lts": ["lts", "{spec}"],
    "synth": ["synth", "{spec}"],
    "compile": ["compile", "{spec}"],
    "dot": ["dot", "{spec}"],
    "verify": ["verify", "{spec}", "--assert", "P", "--on", "S"],
}

def argv_for(command: str, spec) -> list[str]:
    return [str(spec) if a == "{spec}" else a for a in SPEC_COMMANDS[command]]


@pytest.fixture
def write(tmp_path):
    def _write(name: str, data: bytes | str):
        path = tmp_path / name
        path.write_bytes(data.encode("utf-8") if isinstance(data, str) else data)
        return path
    return _write


@pytest.mark.parametrize("command", SPEC_COMMANDS)
def test_missing_file(command, tmp_path, capsys):
    missing = tmp_path / "nope.lts"
    res = run_cli(capsys, *argv_for(command, missing))
    m = assert_input_error(res, missing, code="E0800")
    assert "No such file" in m["msg"]


@pytest.mark.parametrize("command", SPEC_COMMANDS)
def test_directory_instead_of_file(command, tmp_path, capsys):
    folder = tmp_path / "spec.lts"
    folder.mkdir()
    res = run_cli(capsys, *argv_for(command, folder))
    assert_input_error(res, folder, code="E0800")


@pytest.mark.parametrize("command", SPEC_COMMANDS)
def test_binary_garbage(command, write, capsys):
    # Fixed bytes (not os.urandom) so a failure reproduces; includes NUL and invalid UTF-8.
    data = bytes(range(256)) * 3 + b"\x00\xff\xfe\x80 A = (a -> A).\n\x1b[31m"
    spec = write("garbage.lts", data)
    res = run_cli(capsys, *argv_for(command, spec))
    assert_input_error(res, spec, located=True)


@pytest.mark.parametrize("command", SPEC_COMMANDS)
def test_non_utf8_bytes(command, write, capsys):
    spec = write("latin1.lts", "// caf\xe9\nA = (a -> \xe9t\xe9 -> A).\n".encode("latin-1"))
    res = run_cli(capsys, *argv_for(command, spec))
    m = assert_input_error(res, spec, located=True)
    # The comment's bad byte is harmless; the first error is on line 2, at the bad byte.
    assert (m["line"], m["col"]) == ("2", "11"), res.err


@pytest.mark.parametrize("command", SPEC_COMMANDS)
def test_syntax_error_has_line_col_and_caret(command, write, capsys):
    spec = write("syntax.lts", "A = (a -> B),\nB = (b -> A\n")
    res = run_cli(capsys, *argv_for(command, spec))
    m = assert_input_error(res, spec, located=True)
    assert m["line"] in ("2", "3")
    assert "^" in res.err  # the caret under the source line


@pytest.mark.parametrize("command", SPEC_COMMANDS)
def test_undefined_constant(command, write, capsys):
    spec = write("undef.lts", "const N = M + 1\nrange R = 0..N\nA = (a[i:R] -> A).\n")
    res = run_cli(capsys, *argv_for(command, spec))
    m = assert_input_error(res, spec, located=True)
    assert (m["line"], m["col"]) == ("1", "11") and "'M'" in m["msg"]


@pytest.mark.parametrize("command", SPEC_COMMANDS)
def test_undefined_name_in_controller_spec(command, write, capsys):
    spec = write("spec.lts", "A = (a -> A).\ncontrollerSpec G = { liveness = {Nope} "
                             "controllable = {a} }\ncontroller ||C = (A)~{G}.\n")
    res = run_cli(capsys, *argv_for(command, spec))
    m = assert_input_error(res, spec, located=True)
    assert m["line"] == "2" and "Nope" in m["msg"]


@pytest.mark.parametrize("command", ["check --build", "lts", "dot"])
def test_undefined_composite_component(command, write, capsys):
    spec = write("comp.lts", "A = (a -> A).\n||S = (A || Missing).\n")
    res = run_cli(capsys, *argv_for(command, spec))
    m = assert_input_error(res, spec, located=True)
    assert (m["line"], m["col"]) == ("2", "13") and "Missing" in m["msg"]


def test_check_without_build_finds_undefined_component(write, capsys):
    spec = write("comp.lts", "A = (a -> A).\n||S = (A || Missing).\n")
    assert_input_error(run_cli(capsys, "check", spec), spec, located=True)


@pytest.mark.parametrize("command", SPEC_COMMANDS)
def test_empty_file(command, write, capsys):
    spec = write("empty.lts", "")
    res = run_cli(capsys, *argv_for(command, spec))
    assert_no_crash(res)
    if command.startswith("check"):
        assert res.code == 0  # an empty spec is a valid (if useless) spec
    elif command == "lts":  # `SPEC: no process or composite to build`, without a code
        assert res.code == 1 and f"{spec}: " in res.err
    elif command == "synth":  # no controller composite: an input error
        assert res.code == 1 and str(spec) in res.err
    else:
        assert_input_error(res, spec)


@pytest.mark.parametrize("command", ["compile", "dot", "lts", "synth"])
def test_unknown_composite_name(command, capsys):
    argv = {"compile": ["compile", GOLDEN_SPEC, "-c", "Nope"],
            "dot": ["dot", GOLDEN_SPEC, "Nope"],
            "lts": ["lts", GOLDEN_SPEC, "Nope"],
            "synth": ["synth", GOLDEN_SPEC, "Nope"]}[command]
    res = run_cli(capsys, *argv)
    m = assert_input_error(res, GOLDEN_SPEC)
    assert "'Nope'" in m["msg"]


def test_verify_unknown_names_suggest(capsys):
    res = run_cli(capsys, "verify", GOLDEN_SPEC, "--assert", "AskForevr", "--on", "Environment")
    m = assert_input_error(res, GOLDEN_SPEC, code="E0607")
    assert "did you mean 'AskForever'" in m["msg"]
    res = run_cli(capsys, "verify", GOLDEN_SPEC, "--assert", "AskForever", "--on", "Enviroment")
    m = assert_input_error(res, GOLDEN_SPEC, code="E0608")
    assert "did you mean 'Environment'" in m["msg"]


UNREALIZABLE = """\
// the environment picks a or c; the controller must see both b and d infinitely often.
Plant = (a -> b -> Plant | c -> d -> Plant).
set All = {a, b, c, d}
fluent B = <b, All\\{b}>
fluent D = <d, All\\{d}>
assert SeeB = B
assert SeeD = D
controllerSpec Goal = {
    liveness = {SeeB, SeeD}
    controllable = {b, d}
}
controller ||C = (Plant)~{Goal}.
"""


@pytest.mark.parametrize("argv", [["synth"], ["compile"], ["dot", "--controller"], ["dot"],
                                  ["check", "--build"]])
def test_unrealizable_spec_exits_1(argv, write, capsys):
    spec = write("unreal.lts", UNREALIZABLE)
    res = run_cli(capsys, argv[0], spec, *argv[1:])
    assert_no_crash(res)
    assert res.code == 1, res.err
    assert "unrealizable" in (res.out + res.err).lower()
    if argv[0] != "synth":  # synth prints a report on stdout instead of a diagnostic
        m = assert_input_error(res, spec, located=True)
        assert m["line"] == "12"


def test_lts_builds_the_plant_without_solving(write, capsys, monkeypatch):
    """`iterc lts` never runs the GR(1) solver: a controller composite (here unrealizable)
    is shown as the plant of its game, with a note saying so."""
    from iterplan_compiler.synthesis import driver

    def no_solving(*_a, **_k):
        raise AssertionError("iterc lts ran the GR(1) solver")

    monkeypatch.setattr(driver, "synthesize", no_solving)
    spec = write("unreal.lts", UNREALIZABLE)
    res = run_cli(capsys, "lts", spec, "C")
    assert_no_crash(res)
    assert res.code == 0, res.err
    assert res.out.startswith("C: states 3 transitions 4")
    assert "note: C is a controller composite; this is the plant" in res.err
    # a composite using the controller composite is built on its plant too
    spec = write("uses.lts", UNREALIZABLE + "||Sys = (C).\n")
    res = run_cli(capsys, "lts", spec, "Sys", "--stats")
    assert res.code == 0, res.err
    assert res.out.startswith("Sys: states 3 transitions 4")
    assert "note: Sys uses controller composite(s) C, built here as the plant" in res.err


def test_output_path_unwritable(tmp_path, capsys):
    res = run_cli(capsys, "compile", GOLDEN_SPEC, "-o", tmp_path / "no" / "dir" / "x.py")
    assert_no_crash(res)
    assert res.code == 1 and "cannot write" in res.err
    res = run_cli(capsys, "dot", GOLDEN_SPEC, "-o", tmp_path / "no" / "x.svg")
    assert_no_crash(res)
    assert res.code == 1 and "no such directory" in res.err
    res = run_cli(capsys, "dot", GOLDEN_SPEC, "-o", tmp_path / "x.bmp")
    assert res.code == 2 and "use .dot" in res.err


# Deep nesting: every input must end in diagnostics (or success), never a RecursionError.
# Minimised with a bisection (QA notes): a 990-action sequence, 988 `!`, 198 nested `(F && ...)`.
DEEP_INPUTS = {
    "long-sequence": "A = (" + " -> ".join(f"a{i}" for i in range(1000)) + " -> A).\n",
    "nested-not": "fluent F = <a, b>\nA = (a -> b -> A).\nassert P = " + "!" * 1000 + "F\n",
    "nested-and": "fluent F = <a, b>\nA = (a -> b -> A).\nltl_property P = []"
                  + "(F && " * 250 + "F" + ")" * 250 + "\n",
}


@pytest.mark.parametrize("kind", sorted(DEEP_INPUTS))
def test_deeply_nested_input(kind, write, capsys):
    spec = write(f"{kind}.lts", DEEP_INPUTS[kind])
    res = run_cli(capsys, "check", "--build", spec)
    assert_no_crash(res)


def test_utf8_bom_and_crlf_are_accepted(write, capsys):
    # Notepad-style files: BOM + CRLF line ends.
    spec = write("windows.lts", b"\xef\xbb\xbfA = (a -> A).\r\nB = (b -> B).\r\n")
    res = run_cli(capsys, "check", spec)
    assert res.code == 0, res.err


def test_crlf_positions(write, capsys):
    spec = write("crlf.lts", b"A = (a -> A).\r\nB = (b -> B\r\n")
    m = assert_input_error(run_cli(capsys, "check", spec), spec, located=True)
    assert (m["line"], m["col"]) == ("2", "11")
