"""``iterc lts SPEC [NAME] [--stats] [--fsp]`` — build a process or composite and print it.

Without NAME the last composite (else the last process) is built; ``DEFAULT`` composes every
process and safety formula (MTSA's fallback).  Nothing is synthesised: a ``controller``
composite is built as the plant its game is played on (body ∥ safety machines), with a note
saying so (``iterc synth`` / ``iterc compile`` solve it).  Default output: states,
transitions (``src -label-> dst``, ERROR as ``E``) and the alphabet; ``--stats`` prints only
the sizes; ``--fsp`` prints the machine back as FSP (``Q0 = (...)`` style).
"""

from __future__ import annotations

import argparse
import sys

from iterplan_compiler import pipeline
from iterplan_compiler.diagnostics import render
from iterplan_compiler.ir.fsp_print import lts_to_fsp

HELP = "compose a process or composite and print it"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("spec", help="FSP specification file (.lts)")
    parser.add_argument("name", nargs="?", help="process or composite (default: the last composite)")
    parser.add_argument("--stats", action="store_true", help="print sizes only")
    parser.add_argument("--fsp", action="store_true", help="print as FSP")


def run(args: argparse.Namespace) -> int:
    elab = pipeline.load(args.spec)
    if not elab.ok or elab.model is None:
        print(render([d for d in elab.diagnostics if d.is_error], elab.sources), file=sys.stderr)
        return 1
    model = elab.model
    name = args.name or model.default_name()
    # E0104 as `iterc dot SPEC NAME` (the same mistake gets the same code in both commands)
    unknown = pipeline.unknown_name(elab, name)
    if unknown is not None or name is None:
        print(render([unknown] if unknown else []), file=sys.stderr)
        return 1
    # nothing is solved here: a controller composite is shown as the plant of its game
    built = pipeline.build(elab, name, pipeline.BuildMode.PLANT)
    lts = built.lts
    errs = [d for d in built.diagnostics if d.is_error]
    if errs or lts is None:
        print(render(errs, elab.sources), file=sys.stderr)
        return 1
    if model.is_synthesis_composite(name):
        print(f"note: {name} is a controller composite; this is the plant its game is played "
              "on (iterc lts does not synthesise: use iterc synth or iterc compile)",
              file=sys.stderr)
    elif used := model.synthesis_components(name):
        print(f"note: {name} uses controller composite(s) {', '.join(used)}, built here as "
              "the plant of their game (iterc lts does not synthesise)", file=sys.stderr)
    alphabet = " ".join(sorted(lts.alphabet))
    if args.stats:
        print(f"{name}: states {lts.num_states} transitions {lts.num_transitions} "
              f"alphabet {len(lts.alphabet)}")
        return 0
    if args.fsp:
        print(lts_to_fsp(lts))
        return 0
    print(f"{name}: states {lts.num_states} transitions {lts.num_transitions}")
    print(f"alphabet: {{{alphabet}}}")
    for s, a, t in lts.transitions:
        print(f"  {s} -{a}-> {'E' if t < 0 else t}")
    return 0
