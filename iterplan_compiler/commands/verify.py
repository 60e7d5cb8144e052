"""``iterc verify SPEC --assert NAME [--assert NAME ...] --on COMPOSITE``.

Model-checks FLTL ``assert`` formulas on a process or composite of SPEC (what MTSA's tests do
with ``assert Check`` on ``||Sys``; mtsa-semantics §2.9) and prints, for each, either
``No LTL Property violations detected`` or the violation and a counterexample trace (prefix,
then the cycle repeated forever).  Like LTSA, only fair runs count unless ``--unfair`` is
given.  Semantics, including fairness and deadlocks: ``docs/fltl.md``.

Exit codes: 0 every assert holds, 1 a violation or input errors, 2 usage.
"""

from __future__ import annotations

import argparse
import difflib
import sys
from pathlib import Path

from iterplan_compiler import limits, pipeline
from iterplan_compiler.diagnostics import Diagnostic, Span, error, has_errors, render
from iterplan_compiler.fltl.check import check_assert
from iterplan_compiler.fltl.semantics import subformulas
from iterplan_compiler.ir.formulas import Always, Eventually, Next, Until, WeakUntil

HELP = "model-check an FLTL assert on a composite"

E_NO_SUCH_ASSERT = "E0607"
E_NO_SUCH_TARGET = "E0608"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("spec", metavar="SPEC", help="the .lts specification file")
    parser.add_argument("--assert", dest="asserts", metavar="NAME", action="append",
                        required=True, help="assert to check (repeatable)")
    parser.add_argument("--on", dest="target", metavar="COMPOSITE", required=True,
                        help="process or composite to check the asserts on")
    parser.add_argument("--unfair", action="store_true",
                        help="check every infinite run, not only the fair ones (default: "
                             "fair choice, as LTSA/MTSA)")
    # --max-states (composition and the model-checking product) is one of the shared
    # resource-limit flags of limits.py, added by cli.py


def _missing(name: str, known, spec: str, *, what: str = "assert",
             code: str = E_NO_SUCH_ASSERT) -> Diagnostic:
    hint = difflib.get_close_matches(name, sorted(known), n=1)
    extra = f" (did you mean '{hint[0]}'?)" if hint else ""
    # Line 0 = "the file as a whole": renders as `SPEC: error[E0607]: ...`.
    return error(code, f"no {what} named '{name}' in {Path(spec).name}{extra}",
                 Span(spec, 0, 0))


def _is_state_formula(formula) -> bool:
    """True iff ``formula`` has no temporal operator (X, [], <>, U, W)."""

    temporal = (Next, Always, Eventually, Until, WeakUntil)
    return not any(isinstance(f, temporal) for f in subformulas(formula))


def run(args: argparse.Namespace) -> int:
    """Check; diagnostics to stderr, verdicts and traces to stdout."""
    # A missing or unreadable SPEC is an input error the front-end reports (E0800, exit 1),
    # the same as for `iterc check`/`iterc lts`.
    elab = pipeline.load(args.spec)
    model, diags, sources = elab.model, list(elab.diagnostics), elab.sources
    named = []
    if model is not None:
        for name in args.asserts:
            nf = model.formulas.get(name)
            if nf is None:
                diags.append(_missing(name, model.formulas, args.spec))
            else:
                named.append(nf)
    if model is not None and args.target not in set(model.names()):
        # Checked here (not left to build_lts) so the message names SPEC and suggests a name.
        diags.append(_missing(args.target, model.names(), args.spec,
                              what="process or composite", code=E_NO_SUCH_TARGET))
    lts = None
    if model is not None and not has_errors(diags):
        built = pipeline.build(elab, args.target, pipeline.BuildMode.SOLVE)
        lts = built.lts
        diags.extend(built.diagnostics)
    if has_errors(diags) or lts is None or model is None:
        if diags:
            print(render(diags, sources), file=sys.stderr)
        return 1
    if diags:
        print(render(diags, sources), file=sys.stderr)

    failed = False
    for nf in named:
        result, cdiags = check_assert(lts, nf, model.fluents, fair=not args.unfair,
                                      max_states=limits.current().max_states)
        if cdiags:
            print(render(cdiags, sources), file=sys.stderr)
        if result is None:
            failed = True
            continue
        if result.holds:
            print(f"assert {nf.name} on {args.target}: No LTL Property violations detected.")
        else:
            failed = True
            print(f"assert {nf.name} on {args.target}: Violation of LTL property {nf.name}")
            print(f"Trace to property violation in {args.target}:")
            if result.counterexample is not None:
                print(result.counterexample.render())
            if _is_state_formula(nf.formula):
                # A frequent surprise: `assert G = (F)` means []<>F only as a controllerSpec
                # liveness goal; checked on its own it is a condition on the first position.
                print(f"  note: {nf.name} has no temporal operator, so it is checked at the "
                      "first position only (as a controllerSpec liveness goal it means "
                      f"[]<>{nf.name})")
        if result.error_reachable:
            print(f"  note: {args.target} can reach ERROR (a safety property is violated); "
                  "runs end there")
        if result.deadlocks:
            print(f"  note: {args.target} has {result.deadlocks} reachable deadlock/END "
                  "state(s); finite runs are checked only for safety violations")
    return 1 if failed else 0
