"""``iterc synth SPEC [COMPOSITE] [--solver symbolic|explicit] [--explain]``.

Prints the verdict (realizable / unrealizable), game and controller sizes and the time of each
phase.  Exit codes: 0 realizable, 1 unrealizable or errors in SPEC, 2 usage.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

HELP = "synthesise a controller for a controller composite and report"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("spec", metavar="SPEC", help="the .lts specification file")
    parser.add_argument("composite", metavar="COMPOSITE", nargs="?",
                        help="the controller composite (default: the last one in SPEC)")
    parser.add_argument("--solver", choices=("symbolic", "explicit"), default="symbolic",
                        help="symbolic BDD solver (default) or MTSA's explicit rank solver")
    parser.add_argument("--explain", action="store_true",
                        help="for an unrealizable spec, print losing states and a "
                             "counter-strategy trace")
    parser.add_argument("--order",
                        choices=("clustered", "action_first", "action_last", "blocked"),
                        default="clustered", help="BDD variable order (symbolic solver)")


def _pick_composite(model) -> str | None:
    specs = getattr(model, "synthesis_composites", None)
    if callable(specs):
        names = list(specs())
        return names[-1] if names else None
    for name in reversed(list(model.names())):
        problem, diags = model.synthesis_problem(name)
        if problem is not None:
            return name
    return None


def run(args: argparse.Namespace) -> int:
    """Run synthesis and print the report; return the exit code."""
    from iterplan_compiler.diagnostics import has_errors, render

    path = Path(args.spec)
    if not path.is_file():
        print(f"iterc synth: no such file: {args.spec}", file=sys.stderr)
        return 2
    try:
        from iterplan_compiler.frontend import load
    except ImportError as exc:
        print(f"iterc synth: the front-end is not available ({exc})", file=sys.stderr)
        return 3
    from iterplan_compiler.synthesis.driver import synthesize

    model, diags = load(str(path))
    if diags:
        print(render(diags), file=sys.stderr)
    if model is None or has_errors(diags):
        return 1
    name = args.composite or _pick_composite(model)
    if name is None:
        print("iterc synth: SPEC has no controller composite", file=sys.stderr)
        return 2
    problem, pdiags = model.synthesis_problem(name)
    if pdiags:
        print(render(pdiags), file=sys.stderr)
    if problem is None or has_errors(pdiags):
        return 1
    result = synthesize(problem, solver=args.solver, explain=args.explain, order=args.order)
    if result.diagnostics:
        print(render(list(result.diagnostics)), file=sys.stderr)
        return 1
    print(format_report(name, result))
    if not result.realizable and args.explain and result.explanation:
        print(result.explanation)
    return 0 if result.realizable else 1


def format_report(name: str, result) -> str:
    """The human-readable report printed by ``iterc synth``."""
    st = result.stats
    lines = [f"{name}: {'realizable' if result.realizable else 'UNREALIZABLE'}"
             f" ({st.get('solver')} solver, {st.get('mode')} semantics)"]
    lines.append(f"  game: {st.get('game_states', '?')} states"
                 + (f", winning {st['winning_states']}" if "winning_states" in st else "")
                 + (f", |T| = {st['trans_bdd_nodes']} BDD nodes over {st['bdd_vars']} vars"
                    if "trans_bdd_nodes" in st else ""))
    if result.realizable:
        lines.append(f"  controller: {st.get('controller_states')} states, "
                     f"{st.get('controller_transitions')} transitions; controlled system "
                     f"{st.get('composition_states')} states")
    phases = [k for k in st if k.startswith("t_")]
    lines.append("  time: " + ", ".join(f"{k[2:]} {st[k]:.3f}s" for k in phases))
    for w in st.get("warnings", ()):
        lines.append(f"  warning: {w}")
    return "\n".join(lines)
