"""Package-level smoke tests: the CLI answers, the runtime stays light."""

import subprocess
import sys

from iterplan_compiler import __version__
from iterplan_compiler.cli import main


def test_version(capsys):
    try:
        main(["--version"])
    except SystemExit as exc:
        assert exc.code == 0
    assert __version__ in capsys.readouterr().out


def test_no_command_prints_help(capsys):
    assert main([]) == 2
    assert "usage: iterc" in capsys.readouterr().out


def test_runtime_imports_without_lark_or_dd():
    code = (
        "import sys, importlib, pkgutil\n"
        "import iterplan_compiler.runtime as r\n"
        "for m in pkgutil.iter_modules(r.__path__):\n"
        "    importlib.import_module('iterplan_compiler.runtime.' + m.name)\n"
        "bad = [m for m in ('lark', 'dd') if m in sys.modules]\n"
        "assert not bad, bad\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_recursion_error_escaping_a_command_is_an_internal_error(monkeypatch, capsys):
    """Deep *input* nesting is diagnostic E0005 where it happens (the front-end's boundaries,
    see tests/cli/test_cli_bad_inputs.py::test_deeply_nested_input); a RecursionError that
    reaches cli.main is a recursive path of ours: a bug (exit 3), not the user's fault."""
    from iterplan_compiler import cli
    from iterplan_compiler.commands import check

    def deep(_args):
        raise RecursionError("maximum recursion depth exceeded")

    monkeypatch.setattr(check, "run", deep)
    assert cli.main(["check", "x.lts"]) == cli.EXIT_INTERNAL
    err = capsys.readouterr().err
    assert "internal error" in err and "RecursionError" in err
