"""``iterc check SPEC`` — parse and elaborate a spec, report diagnostics.

With ``--build`` every process, composite and safety formula *declared in SPEC itself* is also
built (composed, synthesised when a synthesis keyword asks for it), which finds errors that only
show when a machine is built; declarations of included files are built only when SPEC's own
machines use them (a library fragment may need sets that only the including file declares).
With ``--print`` the parsed file is printed back as canonical FSP on stdout (the printer of
``frontend/printer.py``; parsing the output gives the same syntax tree), and with
``--legality NAME`` MTSA's legality check is run on composite NAME (machine 0 is the
controller, machine 1 the plant).
``--safety NAME`` and ``--progress NAME`` run LTSA's deadlock/ERROR and progress checks on NAME
(``commands/ltsa_checks.py``, ``docs/ltsa.md``).
Exit code 0 if there are no errors (warnings are printed) and the legality check (if asked)
passes, 1 otherwise (also when a ``--safety``/``--progress`` check finds a violation).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from iterplan_compiler import pipeline
from iterplan_compiler.commands.ltsa_checks import run_checks
from iterplan_compiler.commands.semantic_checks import (
    include_set_dependencies,
    labels_against_plants,
)
from iterplan_compiler.diagnostics import has_errors, render
from iterplan_compiler.frontend.parse import parse_text
from iterplan_compiler.frontend.printer import print_spec

HELP = "parse and elaborate a spec; report diagnostics"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("spec", help="FSP specification file (.lts)")
    parser.add_argument("--build", action="store_true",
                        help="also build every process and composite declared in SPEC "
                        "(and what they use from included files)")
    parser.add_argument("-q", "--quiet", action="store_true", help="do not print warnings")
    parser.add_argument("--print", dest="print_fsp", action="store_true",
                        help="print the file back as canonical FSP (includes not expanded)")
    parser.add_argument("--legality", metavar="COMPOSITE",
                        help="check that machine 0 of COMPOSITE never blocks an uncontrollable "
                        "action of machine 1 (MTSA's LegalityAnalyser)")
    # LTSA's analyses (commands/ltsa_checks.py, docs/ltsa.md)
    parser.add_argument("--safety", metavar="COMPOSITE", action="append",
                        help="report a reachable deadlock or ERROR state of COMPOSITE with the "
                        "shortest trace to it (repeatable)")
    parser.add_argument("--progress", metavar="COMPOSITE", action="append",
                        help="check the spec's progress properties on COMPOSITE (fair choice; "
                        "without any, every action in every terminal set) (repeatable)")


def run(args: argparse.Namespace) -> int:
    if getattr(args, "print_fsp", False):
        return _print(args.spec)
    elab = pipeline.load(args.spec)
    model, diags, sources = elab.model, list(elab.diagnostics), elab.sources
    if model is not None and elab.ok:
        diags += labels_against_plants(model) + include_set_dependencies(model)
    if model is not None and args.build:
        for name in model.own_names():
            built = pipeline.build(elab, name, pipeline.BuildMode.SOLVE)
            diags += [d for d in built.diagnostics if d not in diags]
    shown = [d for d in diags if d.is_error or not args.quiet]
    if shown:
        print(render(shown, model.sources if model is not None else sources),
              file=sys.stderr)
    if has_errors(diags):
        n = sum(1 for d in diags if d.is_error)
        print(f"{args.spec}: {n} error(s)", file=sys.stderr)
        return 1
    assert model is not None
    if getattr(args, "legality", None):
        legal, detail = model.legality(args.legality)
        print(f"{args.legality}: {detail}")
        if not legal:
            return 1
    if getattr(args, "safety", None) or getattr(args, "progress", None):
        if run_checks(args, model):
            return 1
    print(f"{args.spec}: ok ({len(model.processes)} processes, {len(model.composites)} "
          f"composites, {len(model.fluents)} fluents, {len(model.formulas)} formulas, "
          f"{len(model.controller_specs)} controller specs)")
    return 0


def _print(path: str) -> int:
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as e:
        print(f"{path}: cannot read: {e.strerror or e}", file=sys.stderr)
        return 1
    spec, diags = parse_text(text, path)
    if has_errors(diags):
        print(render(diags, {path: text}), file=sys.stderr)
        return 1
    sys.stdout.write(print_spec(spec))
    return 0
