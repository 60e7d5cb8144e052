"""The ``iterc`` command line: argument parsing and dispatch only, no compiler logic.

Each sub-command lives in ``iterplan_compiler/commands/<name>.py`` and provides

* ``HELP: str`` — one line for ``iterc --help``;
* ``add_arguments(parser: argparse.ArgumentParser) -> None``;
* ``run(args: argparse.Namespace) -> int`` — the exit code.

:data:`COMMANDS` is the static command table; a command's module is imported (by an ordinary
import in its loader) only when that command runs, so ``iterc run`` does not pay for lark/dd
start-up.

Exit codes (documented in the README): 0 success, 1 the input has errors (diagnostics were
printed) or a check failed (unrealizable, property violated), 2 bad command-line usage,
3 internal error (a compiler bug: please report it).
"""

from __future__ import annotations

import argparse
import sys
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

from iterplan_compiler import __version__, limits


class CommandModule(Protocol):
    """What a module of ``iterplan_compiler/commands/`` provides."""

    HELP: str

    def add_arguments(self, parser: argparse.ArgumentParser) -> None: ...

    def run(self, args: argparse.Namespace) -> int: ...


@dataclass(frozen=True)
class Command:
    """One sub-command: its ``--help`` line and how to import its module.

    The loaders are ordinary imports, run only for the command given, so ``iterc run`` does
    not pay for lark/dd start-up and ``iterc --help`` imports no command module."""

    help: str
    load: Callable[[], CommandModule]


def _check() -> CommandModule:
    from iterplan_compiler.commands import check
    return check


def _lts() -> CommandModule:
    from iterplan_compiler.commands import lts
    return lts


def _verify() -> CommandModule:
    from iterplan_compiler.commands import verify
    return verify


def _synth() -> CommandModule:
    from iterplan_compiler.commands import synth
    return synth


def _compile() -> CommandModule:
    from iterplan_compiler.commands import compile as compile_command
    return compile_command


def _dot() -> CommandModule:
    from iterplan_compiler.commands import dot
    return dot


def _solve() -> CommandModule:
    from iterplan_compiler.commands import solve
    return solve


def _run_command() -> CommandModule:
    from iterplan_compiler.commands import run
    return run


def _view() -> CommandModule:
    from iterplan_compiler.commands import view
    return view


def _demo() -> CommandModule:
    from iterplan_compiler.commands import demo
    return demo


def _conformance() -> CommandModule:
    from iterplan_compiler.commands import conformance
    return conformance


def _experiment() -> CommandModule:
    from iterplan_compiler.commands import experiment
    return experiment


def _animate() -> CommandModule:
    from iterplan_compiler.commands import animate
    return animate


COMMANDS: dict[str, Command] = {
    "check": Command("parse and elaborate a spec; report diagnostics", _check),
    "lts": Command("compose a process or composite and print it", _lts),
    "verify": Command("model-check an FLTL assert on a composite", _verify),
    "synth": Command("synthesise a controller (GR(1)) and report sizes and times", _synth),
    "compile": Command("compile a spec into a Python controller module", _compile),
    "dot": Command("export a process, composite or controller as Graphviz", _dot),
    "solve": Command("GR(1) realizability/strategy for a slugsin file", _solve),
    "run": Command("run a generated controller on the simulator or a MAVLink vehicle",
                   _run_command),
    "view": Command("show a finished run (iterc run --out folder) in the mission view, with a "
                    "time slider", _view),
    "demo": Command("compile the bundled Fire Patrol example and fly it in the simulator",
                    _demo),
    "conformance": Command("run the MTSA conformance corpus and print a report", _conformance),
    "experiment": Command("reproduce the paper's Fig. 3 experiments", _experiment),
    "animate": Command("animate a process or composite: pick actions, undo, save the trace",
                       _animate),
}

#: commands that compile specs and so take the resource-limit flags (limits.py)
LIMITED_COMMANDS = frozenset({"check", "lts", "verify", "synth", "compile", "dot"})

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2
EXIT_INTERNAL = 3


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """Build the argument parser; with ``only``, import just that command's module."""
    parser = argparse.ArgumentParser(
        prog="iterc",
        description="iterplan: compile iterator-based FSP task specs into controllers and fly them.",
    )
    parser.add_argument("--version", action="version", version=f"iterc {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, command in COMMANDS.items():
        p = sub.add_parser(name, help=command.help, description=command.help)
        if only == name:
            command.load().add_arguments(p)
            if name in LIMITED_COMMANDS:
                limits.add_arguments(p)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``iterc``; returns the process exit code."""
    args_list = list(sys.argv[1:] if argv is None else argv)
    command = next((a for a in args_list if not a.startswith("-")), None)
    if command not in COMMANDS:
        command = None
    parser = build_parser(only=command)
    args = parser.parse_args(args_list)
    if args.command is None:
        parser.print_help()
        return EXIT_USAGE
    previous = limits.set_limits()  # restored on return: in-process callers (tests) share it
    limits.apply(args)
    if argv is None and args.command in LIMITED_COMMANDS:
        # the real command line (not an in-process caller such as a test): enforce the
        # memory and time limits even inside a long BDD operation
        limits.start_watchdog(exit_code=EXIT_FAIL, label=f"iterc {args.command}")
    try:
        return _run(args)
    finally:
        limits.stop_watchdog()
        limits.set_limits(previous)


def _run(args: argparse.Namespace) -> int:
    try:
        return int(COMMANDS[args.command].load().run(args))
    except KeyboardInterrupt:
        print("iterc: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return EXIT_OK
    except limits.LimitReached as e:
        # a resource limit reached outside a stage that turns it into a located diagnostic
        print(f"iterc: error[{e.code}]: {e.message}", file=sys.stderr)
        return EXIT_FAIL
    except RecursionError:
        # The front-end turns deep nesting of the *input* into diagnostic E0005 where it
        # happens (frontend.load, build_lts, FLTL); a RecursionError that reaches this point
        # comes from a recursive path of ours that the input did not ask for: a bug.
        print("iterc: internal error (this is a bug in iterc, please report it): unbounded "
              "recursion (RecursionError) outside the front-end's nesting checks",
              file=sys.stderr)
        traceback.print_exc(limit=-8)
        return EXIT_INTERNAL
    except Exception:  # a compiler bug: never show a bare traceback as if it were the user's fault
        print("iterc: internal error (this is a bug in iterc, please report it):",
              file=sys.stderr)
        traceback.print_exc()
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
