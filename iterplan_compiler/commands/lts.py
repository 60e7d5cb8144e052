"""``iterc lts SPEC [NAME] [--stats] [--fsp]`` — build a process or composite and print it.

Without NAME the last composite (else the last process) is built; ``DEFAULT`` composes every
process and safety formula (MTSA's fallback).  Default output: states,
transitions (``src -label-> dst``, ERROR as ``E``) and the alphabet; ``--stats`` prints only
the sizes; ``--fsp`` prints the machine back as FSP (``Q0 = (...)`` style).
"""

from __future__ import annotations

import argparse
import sys

from iterplan_compiler.diagnostics import Span, error, has_errors, render

HELP = "compose a process or composite and print it"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("spec", help="FSP specification file (.lts)")
    parser.add_argument("name", nargs="?", help="process or composite (default: the last composite)")
    parser.add_argument("--stats", action="store_true", help="print sizes only")
    parser.add_argument("--fsp", action="store_true", help="print as FSP")


def run(args: argparse.Namespace) -> int:
    import difflib

    from iterplan_compiler.frontend import load_with_sources

    model, diags, sources = load_with_sources(args.spec)
    if model is None or has_errors(diags):
        print(render([d for d in diags if d.is_error], sources), file=sys.stderr)
        return 1
    whole_file = Span(args.spec, 0, 0)
    name = args.name or model.default_name()
    # E0104 as `iterc dot SPEC NAME` (the same mistake gets the same code in both commands)
    if name is None:
        print(render([error("E0104", "the spec defines no process or composite to build",
                            whole_file)]), file=sys.stderr)
        return 1
    if name not in model.names() and name != "DEFAULT":  # DEFAULT: MTSA's all-processes
        close = difflib.get_close_matches(name, model.names(), n=1)
        hint = (f"did you mean '{close[0]}'?" if close
                else "defined: " + (", ".join(model.names()) or "none"))
        print(render([error("E0104", f"no process or composite named '{name}'; {hint}",
                            whole_file)]), file=sys.stderr)
        return 1
    lts, ds = model.build_lts(name)
    errs = [d for d in ds if d.is_error]
    if errs or lts is None:
        print(render(errs, model.sources), file=sys.stderr)
        return 1
    alphabet = " ".join(sorted(lts.alphabet))
    if args.stats:
        print(f"{name}: states {lts.num_states} transitions {lts.num_transitions} "
              f"alphabet {len(lts.alphabet)}")
        return 0
    if args.fsp:
        from iterplan_compiler.ir.fsp_print import lts_to_fsp

        print(lts_to_fsp(lts))
        return 0
    print(f"{name}: states {lts.num_states} transitions {lts.num_transitions}")
    print(f"alphabet: {{{alphabet}}}")
    for s, a, t in lts.transitions:
        print(f"  {s} -{a}-> {'E' if t < 0 else t}")
    return 0
