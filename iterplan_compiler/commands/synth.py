"""``iterc synth SPEC [COMPOSITE] [--solver symbolic|explicit] [--explain]``.

Prints the verdict (realizable / unrealizable), game and controller sizes and the time of each
phase.  Exit codes: 0 realizable, 1 unrealizable or errors in SPEC, 2 usage.
"""

from __future__ import annotations

import argparse
import sys

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


#: composite keywords that ask for a controller (``checkCompatibility`` only checks the spec)
_CONTROLLER_KEYWORDS = frozenset({"controller", "gr", "heuristic", "monolithicDirector"})


def _pick_composite(model) -> str | None:
    """The last composite of SPEC that asks for synthesis (by its keywords; cheap: nothing
    is built)."""
    for name in reversed(model.composites):
        if model.composite_keywords.get(name, frozenset()) & _CONTROLLER_KEYWORDS:
            return name
    return None


def run(args: argparse.Namespace) -> int:
    """Run synthesis and print the report; return the exit code.

    Every problem with the input (unreadable SPEC, syntax/elaboration errors, no controller
    composite, unknown COMPOSITE, a goal synthesis cannot pose as a game) is a diagnostic
    rendered with its source line, and exit code 1.
    """
    import difflib

    from iterplan_compiler.diagnostics import Span, error, has_errors, render

    try:
        from iterplan_compiler.frontend import load_with_sources
    except ImportError as exc:
        print(f"iterc synth: the front-end is not available ({exc})", file=sys.stderr)
        return 3
    from iterplan_compiler.synthesis.driver import synthesize

    model, diags, sources = load_with_sources(args.spec)
    if diags:
        print(render(diags, sources), file=sys.stderr)
    if model is None or has_errors(diags):
        return 1
    whole_file = Span(args.spec, 0, 0)
    name = args.composite
    if name is None:
        name = _pick_composite(model)
        if name is None:
            print(render([error("E0904", "no controller composite to synthesise (write "
                                "`controller ||C = (Plant)~{Spec}.`)", whole_file)]),
                  file=sys.stderr)
            return 1
    elif name not in model.composites:
        close = difflib.get_close_matches(name, model.composites, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        print(render([error("E0904", f"no composite named '{name}'{hint}", whole_file)]),
              file=sys.stderr)
        return 1
    problem, pdiags = model.synthesis_problem(name)
    if pdiags:
        print(render(pdiags, sources), file=sys.stderr)
    if problem is None or has_errors(pdiags):
        return 1
    result = synthesize(problem, solver=args.solver, explain=args.explain, order=args.order)
    print(format_report(name, result))
    if result.diagnostics:
        # why the problem could not be posed as a game (e.g. S002): shown with the verdict
        print(render(list(result.diagnostics), sources), file=sys.stderr)
    if not result.realizable and args.explain and result.explanation:
        print(result.explanation)
    return 0 if result.realizable else 1


def format_report(name: str, result) -> str:
    """The human-readable report printed by ``iterc synth``."""
    st = result.stats
    how = f"{st.get('solver')} solver" + (f", {st['mode']} semantics" if "mode" in st else "")
    lines = [f"{name}: {'realizable' if result.realizable else 'UNREALIZABLE'} ({how})"]
    if "game_states" in st:
        lines.append(f"  game: {st.get('game_states', '?')} states"
                     + (f", winning {st['winning_states']}" if "winning_states" in st else "")
                     + (f", |T| = {st['trans_bdd_nodes']} BDD nodes over {st['bdd_vars']} vars"
                        if "trans_bdd_nodes" in st else ""))
    if result.realizable:
        lines.append(f"  controller: {st.get('controller_states')} states, "
                     f"{st.get('controller_transitions')} transitions; controlled system "
                     f"{st.get('composition_states')} states")
    phases = [k for k in st if k.startswith("t_")]
    if phases:
        lines.append("  time: " + ", ".join(f"{k[2:]} {st[k]:.3f}s" for k in phases))
    for w in st.get("warnings", ()):
        lines.append(f"  warning: {w}")
    return "\n".join(lines)
