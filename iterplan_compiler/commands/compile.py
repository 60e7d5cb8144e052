"""``iterc compile SPEC [-c COMPOSITE] [-o OUT] [--emit py|dot|fsp|json]``.

Runs the whole pipeline (front-end, synthesis, back-end) and writes the controller of one
``controller`` composite: a Python module by default, or the intermediate controller as DOT,
FSP or JSON.  Without ``-o`` the text goes to standard output.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from iterplan_compiler import pipeline
from iterplan_compiler.backends.output import EMIT_KINDS, EmitKind
from iterplan_compiler.diagnostics import render
from iterplan_compiler.outputs import OutputError, atomic_write_text, refuse_overwrite_input
from iterplan_compiler.synthesis.driver import SOLVERS, Solver

HELP = "compile a spec into a Python controller module"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("spec", metavar="SPEC", help="the .lts specification file")
    parser.add_argument("-c", "--composite", metavar="NAME",
                        help="controller composite to compile (default: the last one in SPEC)")
    parser.add_argument("-o", "--output", metavar="FILE",
                        help="write here instead of standard output")
    parser.add_argument("--emit", choices=EMIT_KINDS, default=None,
                        help="what to write: py (default), dot, fsp or json; "
                             "inferred from the -o suffix when omitted")
    parser.add_argument("--solver", choices=SOLVERS, default=Solver.SYMBOLIC.value,
                        help="GR(1) solver (default: symbolic)")


_SUFFIX_KIND = {".py": "py", ".dot": "dot", ".gv": "dot", ".lts": "fsp", ".fsp": "fsp",
                ".json": "json"}


def run(args: argparse.Namespace) -> int:
    """Compile; print diagnostics to stderr; return 0, 1 (errors/unrealizable) or 2 (usage)."""
    kind = args.emit
    if kind is None:
        kind = _SUFFIX_KIND.get(Path(args.output).suffix.lower(), "py") if args.output else "py"
    try:
        refuse_overwrite_input(args.output, [args.spec])
    except OutputError as exc:
        print(f"iterc compile: {exc.message}", file=sys.stderr)
        return 1
    if args.output and not Path(args.output).parent.is_dir():
        # Checked before synthesis, which may take a while, only to fail at the very end.
        print(f"iterc compile: cannot write {args.output}: no such directory "
              f"'{Path(args.output).parent}'", file=sys.stderr)
        return 1
    out = pipeline.compile_spec(args.spec, composite=args.composite, emit_kind=EmitKind(kind),
                                solver=Solver(args.solver))
    if out.diagnostics:
        print(render(out.diagnostics, out.sources), file=sys.stderr)
    if out.text is None:
        return 1
    if args.output:
        try:
            # an included file is known only now
            refuse_overwrite_input(args.output, list(out.sources))
            atomic_write_text(args.output, out.text)
        except OutputError as exc:
            print(f"iterc compile: {exc.message}", file=sys.stderr)
            return 1
        except OSError as exc:
            print(f"iterc compile: cannot write {args.output}: {exc.strerror}", file=sys.stderr)
            return 1
        n = out.controller.num_states if out.controller is not None else 0
        print(f"{args.output}: controller for '{out.composite}' ({n} states)", file=sys.stderr)
    else:
        sys.stdout.write(out.text)
    return 0
