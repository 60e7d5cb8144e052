"""``iterc check`` / ``iterc lts`` / ``iterc synth`` on bad input: coded diagnostics about the
file (with source line and caret where there is a location) and exit code 1, never a bare
message or the usage exit code 2.  Also the static name checks of ``frontend.load``."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from iterplan_compiler import cli
from iterplan_compiler.pipeline import load_model as load

DIAG = re.compile(r"^(?P<file>[^\s:][^:]*?)(?::(?P<line>\d+):(?P<col>\d+))?: "
                  r"error\[(?P<code>[A-Z]\d+)\]: (?P<msg>.*)$", re.M)

PATROL = """\
P = (a -> b -> P | c -> P).
set All = {a, b, c}
fluent B = <b, All\\{b}>
assert SeeB = B
controllerSpec Goal = { liveness = {SeeB} controllable = {b, c} }
controller ||C = (P)~{Goal}.
"""


def _run(capsys: pytest.CaptureFixture[str], *argv: str | Path) -> tuple[int, str, str]:
    capsys.readouterr()
    code = cli.main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def _errors(err: str) -> list[dict[str, str]]:
    return [m.groupdict() for m in DIAG.finditer(err)]


def _write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


# ---------------------------------------------------------------- static checks of load()
def test_load_reports_undefined_component_at_the_reference(tmp_path):
    p = _write(tmp_path, "c.lts", "A = (a -> A).\n||S = (A || Missing).\n")
    model, diags = load(str(p))
    errs = [(d.code, d.span.line, d.span.column) for d in diags if d.is_error]
    assert errs == [("E0102", 2, 13)]
    assert model is not None  # elaboration errors still give a model


def test_load_reports_undefined_spec_on_plain_composite(tmp_path):
    p = _write(tmp_path, "c.lts", "A = (a -> A).\n||S = (A)~{Nope}.\n")
    _, diags = load(str(p))
    errs = [(d.code, d.span.line) for d in diags if d.is_error]
    assert errs == [("E0701", 2)]
    assert "Nope" in diags[0].message


def test_load_accepts_components_of_every_kind(tmp_path):
    # processes, composites (declared later), ltl_property and DEFAULT are all components
    text = ("A = (a -> A).\nfluent F = <a, b>\nltl_property Safe = [](F -> !b)\n"
            "||T = (S || Safe).\n||S = (A || B).\nB = (b -> B).\n")
    _, diags = load(str(_write(tmp_path, "ok.lts", text)))
    assert [d for d in diags if d.is_error] == []


def test_check_without_build_rejects_undefined_component(tmp_path, capsys):
    p = _write(tmp_path, "c.lts", "A = (a -> A).\n||S = (A || Missing).\n")
    code, _, err = _run(capsys, "check", p)
    assert code == 1
    [e] = _errors(err)
    assert (e["file"], e["line"], e["col"], e["code"]) == (str(p), "2", "13", "E0102")
    assert "^~~~~~~" in err  # caret under `Missing`


# ---------------------------------------------------------------- iterc lts
def test_lts_unknown_name_is_a_coded_error(tmp_path, capsys):
    p = _write(tmp_path, "p.lts", PATROL)
    code, _, err = _run(capsys, "lts", p, "Cc")
    assert code == 1
    [e] = _errors(err)
    assert (e["file"], e["code"]) == (str(p), "E0104") and "'Cc'" in e["msg"]
    code, _, err = _run(capsys, "lts", p, "PP")
    assert "did you mean 'P'" in err


def test_lts_empty_file_is_a_coded_error(tmp_path, capsys):
    p = _write(tmp_path, "empty.lts", "")
    code, _, err = _run(capsys, "lts", p)
    assert code == 1
    assert [e["code"] for e in _errors(err)] == ["E0104"]


# ---------------------------------------------------------------- iterc synth
@pytest.mark.parametrize("kind", ["missing", "directory"])
def test_synth_unreadable_spec(kind, tmp_path, capsys):
    p = tmp_path / "spec.lts"
    if kind == "directory":
        p.mkdir()
    code, _, err = _run(capsys, "synth", p)
    assert code == 1
    assert [(e["file"], e["code"]) for e in _errors(err)] == [(str(p), "E0800")]


def test_synth_without_controller_composite(tmp_path, capsys):
    p = _write(tmp_path, "plain.lts", "A = (a -> A).\n||S = (A).\n")
    code, _, err = _run(capsys, "synth", p)
    assert code == 1
    assert [(e["file"], e["code"]) for e in _errors(err)] == [(str(p), "E0904")]


def test_synth_unknown_composite(tmp_path, capsys):
    p = _write(tmp_path, "p.lts", PATROL)
    code, _, err = _run(capsys, "synth", p, "D")
    assert code == 1
    assert [(e["file"], e["code"]) for e in _errors(err)] == [(str(p), "E0904")]


def test_synth_syntax_error_shows_source_and_caret(tmp_path, capsys):
    p = _write(tmp_path, "syn.lts", "A = (a -> B),\nB = (b -> A\n")
    code, _, err = _run(capsys, "synth", p)
    assert code == 1
    assert _errors(err)[0]["line"] == "2"
    assert "    B = (b -> A" in err and "^" in err


def test_synth_shows_why_a_goal_cannot_be_posed(tmp_path, capsys):
    text = PATROL.replace("assert SeeB = B", "assert SeeB = []<>B")
    p = _write(tmp_path, "temporal.lts", text)
    code, out, err = _run(capsys, "synth", p)
    assert code == 1
    assert "C: UNREALIZABLE" in out
    [e] = _errors(err)
    assert e["code"] == "E0907" and e["line"] == "6"  # goal not propositional
    assert "controller ||C" in err  # the composite's source line


def test_synth_realizable_report(tmp_path, capsys):
    p = _write(tmp_path, "p.lts", PATROL)
    code, out, _ = _run(capsys, "synth", p)
    assert code == 0 and out.startswith("C: realizable")


# ---------------------------------------------------------------- iterc check --build
LIBRARY = """\
// a library fragment that needs a set only its includer declares
Sensors = (sense[s:MySensors] -> Sensors).
Helper = (h -> Helper).
"""


def test_check_build_builds_own_declarations_only(tmp_path, capsys):
    _write(tmp_path, "lib.lts", LIBRARY)
    main = _write(tmp_path, "main.lts", 'include "lib.lts"\nA = (a -> A).\n||S = (A || Helper).\n')
    model, _ = load(str(main))
    assert model is not None and model.own_names() == ("A", "S")
    assert model.origins["Sensors"] == str(tmp_path / "lib.lts")
    code, out, err = _run(capsys, "check", "--build", main)
    assert code == 0, err  # Sensors (unused, MySensors undeclared) is not built
    assert "ok" in out


def test_check_build_still_builds_what_own_machines_use(tmp_path, capsys):
    _write(tmp_path, "lib.lts", LIBRARY)
    main = _write(tmp_path, "main.lts", 'include "lib.lts"\n||S = (Sensors || Helper).\n')
    code, _, err = _run(capsys, "check", "--build", main)
    assert code == 1
    [e] = _errors(err)
    assert e["code"] == "E0201" and e["file"].endswith("lib.lts") and "MySensors" in e["msg"]


def test_controller_composite_is_synthesised_once(tmp_path, monkeypatch):
    from iterplan_compiler.synthesis import driver

    calls: list[str] = []
    real = driver.synthesize

    def counting(problem, **kw):
        calls.append(problem.name)
        return real(problem, **kw)

    monkeypatch.setattr(driver, "synthesize", counting)
    p = _write(tmp_path, "p.lts", PATROL + "||Sys = (C || P).\n")
    model, diags = load(str(p))
    assert model is not None and not diags
    for name in model.own_names():
        lts, ds = model.build_lts(name)
        assert lts is not None, ds
    assert calls == ["C"]


# ---------------------------------------------------------------- deep nesting
def test_long_action_sequence_builds_without_recursion(tmp_path):
    text = "A = (" + " -> ".join(f"a{i}" for i in range(3000)) + " -> A).\n"
    model, diags = load(str(_write(tmp_path, "long.lts", text)))
    assert model is not None and not diags
    lts, ds = model.build_lts("A")
    assert lts is not None and not ds
    assert lts.num_states == 3000 and lts.num_transitions == 3000
    # state i is reached by a_{i-1}: the numbering follows the sequence
    assert (0, "a0", 1) in lts.transitions and (2999, "a2999", 0) in lts.transitions


@pytest.mark.parametrize("formula", ["!" * 3000 + "F", "(F && " * 800 + "F" + ")" * 800],
                         ids=["not", "and"])
def test_absurdly_nested_formula_is_a_diagnostic(formula, tmp_path, capsys):
    p = _write(tmp_path, "deep.lts", f"fluent F = <a, b>\nA = (a -> b -> A).\nassert P = {formula}\n")
    code, _, err = _run(capsys, "check", "--build", p)
    assert code == 1
    assert [(e["file"], e["code"]) for e in _errors(err)] == [(str(p), "E0005")]
