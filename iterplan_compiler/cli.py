"""The ``iterc`` command line: argument parsing and dispatch only, no compiler logic.

Each sub-command lives in ``iterplan_compiler/commands/<name>.py`` and provides

* ``HELP: str`` — one line for ``iterc --help``;
* ``add_arguments(parser: argparse.ArgumentParser) -> None``;
* ``run(args: argparse.Namespace) -> int`` — the exit code.

Command modules are imported lazily so ``iterc run`` does not pay for lark/dd start-up.

Exit codes (documented in the README): 0 success, 1 the input has errors (diagnostics were
printed) or a check failed (unrealizable, property violated), 2 bad command-line usage,
3 internal error (a compiler bug: please report it).
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys
import traceback
from collections.abc import Sequence

from iterplan_compiler import __version__, limits

# name -> (module, one-line help).  The help is duplicated here so `iterc --help` need not
# import every command module.
COMMANDS: dict[str, str] = {
    "check": "parse and elaborate a spec; report diagnostics",
    "lts": "compose a process or composite and print it",
    "verify": "model-check an FLTL assert on a composite",
    "synth": "synthesise a controller (GR(1)) and report sizes and times",
    "compile": "compile a spec into a Python controller module",
    "dot": "export a process, composite or controller as Graphviz",
    "solve": "GR(1) realizability/strategy for a slugsin file",
    "run": "run a generated controller on the simulator or a MAVLink vehicle",
    "view": "show a finished run (iterc run --out folder) in the mission view, with a time slider",
    "demo": "compile the bundled Fire Patrol example and fly it in the simulator",
    "conformance": "run the MTSA conformance corpus and print a report",
    "experiment": "reproduce the paper's Fig. 3 experiments",
    "animate": "animate a process or composite: pick actions, undo, save the trace",
}

#: commands that compile specs and so take the resource-limit flags (limits.py)
LIMITED_COMMANDS = frozenset({"check", "lts", "verify", "synth", "compile", "dot"})

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2
EXIT_INTERNAL = 3


def _load(name: str):
    return importlib.import_module(f"iterplan_compiler.commands.{name}")


def _available(name: str) -> bool:
    """True if the command's module ships in this build (checked without importing it)."""
    return importlib.util.find_spec(f"iterplan_compiler.commands.{name}") is not None


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """Build the argument parser; with ``only``, import just that command's module."""
    parser = argparse.ArgumentParser(
        prog="iterc",
        description="iterplan: compile iterator-based FSP task specs into controllers and fly them.",
    )
    parser.add_argument("--version", action="version", version=f"iterc {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, help_text in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        if only == name:
            _load(name).add_arguments(p)
            if name in LIMITED_COMMANDS:
                limits.add_arguments(p)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``iterc``; returns the process exit code."""
    args_list = list(sys.argv[1:] if argv is None else argv)
    command = next((a for a in args_list if not a.startswith("-")), None)
    if command not in COMMANDS:
        command = None
    elif not _available(command):
        print(f"iterc: the '{command}' command is not part of this build", file=sys.stderr)
        return EXIT_USAGE
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
        return int(_load(args.command).run(args))
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
