"""``iterc synth`` on small specs written to a temporary folder."""

from __future__ import annotations

import argparse

import pytest

SPEC = """
Plant = (u -> (c -> Plant | d -> Plant)).
fluent C = <c, {u, d}>
fluent D = <d, {u, c}>
assert GC = C
assert GD = D
controllerSpec Goal = {
    liveness = {GC, GD}
    controllable = {c, d}
}
controller ||Ctrl = Plant~{Goal}.
"""


def _run(tmp_path, text, *extra):
    pytest.importorskip("iterplan_compiler.frontend")
    from iterplan_compiler.commands import synth

    spec = tmp_path / "spec.lts"
    spec.write_text(text, encoding="utf-8")
    parser = argparse.ArgumentParser()
    synth.add_arguments(parser)
    return synth.run(parser.parse_args([str(spec), *extra]))


def test_realizable(tmp_path, capsys):
    assert _run(tmp_path, SPEC, "Ctrl") == 0
    out = capsys.readouterr().out
    assert "Ctrl: realizable" in out and "controller:" in out and "time:" in out


def test_realizability_only_and_progress(tmp_path, capsys):
    """``--realizability-only`` stops at the verdict (no controller, exit code as usual);
    ``-v`` prints the solver's progress with elapsed seconds on stderr, ``-q`` nothing."""
    assert _run(tmp_path, SPEC, "Ctrl", "--realizability-only", "-v") == 0
    cap = capsys.readouterr()
    assert "Ctrl: realizable" in cap.out and "controller: not built" in cap.out
    assert "states," not in cap.out.split("controller:")[1]
    lines = cap.err.splitlines()
    assert any(" s] verdict: realizable at " in line for line in lines), cap.err
    assert all(line.startswith("[") for line in lines), cap.err
    text = SPEC.replace("controllable = {c, d}", "controllable = {c}")
    assert _run(tmp_path, text, "Ctrl", "--realizability-only", "-q") == 1
    cap = capsys.readouterr()
    assert "UNREALIZABLE" in cap.out and "verdict:" not in cap.err


def test_unrealizable_explained(tmp_path, capsys):
    # d is now uncontrollable: after u the environment always chooses it, so C never holds
    text = SPEC.replace("controllable = {c, d}", "controllable = {c}")
    assert _run(tmp_path, text, "Ctrl", "--explain", "--solver", "explicit") == 1
    out = capsys.readouterr().out
    assert "UNREALIZABLE" in out and "keeps guarantee" in out and "false forever" in out


def test_missing_file_is_a_diagnostic(tmp_path, capsys):
    # commands/synth.py: an unreadable SPEC is an input problem (diagnostic, exit code 1)
    from iterplan_compiler.commands import synth

    parser = argparse.ArgumentParser()
    synth.add_arguments(parser)
    assert synth.run(parser.parse_args([str(tmp_path / "nope.lts")])) == 1
    captured = capsys.readouterr()
    assert "nope.lts" in captured.out + captured.err
