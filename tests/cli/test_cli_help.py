"""`iterc --help`, every sub-command's `--help`, and usage errors (exit 2, never a traceback)."""

from __future__ import annotations

import pytest
from cli_helpers import assert_no_crash, run_cli

from iterplan_compiler import cli


@pytest.mark.parametrize("command", sorted(cli.COMMANDS))
def test_every_command_has_help(command, capsys):
    res = run_cli(capsys, command, "--help")
    assert res.code == 0, res.err
    assert res.out.startswith(f"usage: iterc {command}"), res.out[:200]
    # The one-line description from cli.COMMANDS is shown, and at least one option besides -h.
    assert cli.COMMANDS[command].help in " ".join(res.out.split())
    assert res.out.count("--") >= 2 or command in ("demo",), res.out


def test_top_level_help_lists_every_command(capsys):
    res = run_cli(capsys, "--help")
    assert res.code == 0
    for command in cli.COMMANDS:
        assert command in res.out


def test_no_command_is_usage(capsys):
    res = run_cli(capsys)
    assert res.code == cli.EXIT_USAGE
    assert "usage: iterc" in res.out + res.err


def test_version(capsys):
    res = run_cli(capsys, "--version")
    assert res.code == 0 and res.out.startswith("iterc ")


@pytest.mark.parametrize("argv", [
    ["frobnicate"],                                    # unknown command
    ["check"],                                         # missing SPEC
    ["check", "x.lts", "--no-such-option"],            # unknown option
    ["compile", "x.lts", "--emit", "cobol"],           # bad choice
    ["verify", "x.lts", "--assert", "A"],              # missing --on
    ["verify", "x.lts", "--on", "S"],                  # missing --assert
    ["synth", "x.lts", "--solver", "magic"],
    ["dot", "x.lts", "--solver"],                      # option without its value
    ["run"],                                           # missing CONTROLLER.py and --map
    ["experiment", "no-such-experiment"],
    ["conformance", "x", "--jobs", "many"],            # not an int
])
def test_usage_errors_exit_2(argv, capsys):
    res = run_cli(capsys, *argv)
    assert_no_crash(res)
    assert res.code == cli.EXIT_USAGE, (res.code, res.err)
    assert "usage: iterc" in res.err and "error:" in res.err
