"""``iterc check SPEC`` — parse and elaborate a spec, report diagnostics.

With ``--build`` every process and composite is also built (composed, synthesised when a
synthesis keyword asks for it), which finds errors that only show when a machine is built.
Exit code 0 if there are no errors (warnings are printed), 1 otherwise.
"""

from __future__ import annotations

import argparse
import sys

from iterplan_compiler.diagnostics import has_errors, render

HELP = "parse and elaborate a spec; report diagnostics"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("spec", help="FSP specification file (.lts)")
    parser.add_argument("--build", action="store_true",
                        help="also build every process and composite")
    parser.add_argument("-q", "--quiet", action="store_true", help="do not print warnings")


def run(args: argparse.Namespace) -> int:
    from iterplan_compiler.frontend import load, parse_file

    model, diags = load(args.spec)
    if model is not None and args.build:
        for name in model.names():
            _, ds = model.build_lts(name)
            diags += [d for d in ds if d not in diags]
    shown = [d for d in diags if d.is_error or not args.quiet]
    if shown:
        sources = model.sources if model is not None else parse_file(args.spec)[2]
        print(render(shown, sources), file=sys.stderr)
    if has_errors(diags):
        n = sum(1 for d in diags if d.is_error)
        print(f"{args.spec}: {n} error(s)", file=sys.stderr)
        return 1
    assert model is not None
    print(f"{args.spec}: ok ({len(model.processes)} processes, {len(model.composites)} "
          f"composites, {len(model.fluents)} fluents, {len(model.formulas)} formulas, "
          f"{len(model.controller_specs)} controller specs)")
    return 0
