"""``iterc synth SPEC [COMPOSITE] [--solver symbolic|explicit] [--explain]
[--realizability-only] [-v|-q]``.

Prints the verdict (realizable / unrealizable), game and controller sizes and the time of each
phase; the solver's progress (phases, fixpoint iterations, the verdict as soon as it is known)
goes to stderr with the elapsed seconds when stderr is a terminal or with ``-v``.  Exit codes:
0 realizable, 1 unrealizable or errors in SPEC, 2 usage.
"""

from __future__ import annotations

import argparse
import sys

from iterplan_compiler import pipeline
from iterplan_compiler.commands import talk
from iterplan_compiler.diagnostics import Diagnostic, render
from iterplan_compiler.synthesis.driver import (
    MacroSteps,
    Solver,
    StrategyKind,
    SynthesisResult,
    VariableOrder,
)

HELP = "synthesise a controller for a controller composite and report"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("spec", metavar="SPEC", help="the .lts specification file")
    parser.add_argument("composite", metavar="COMPOSITE", nargs="?",
                        help="the controller composite (default: the last one in SPEC)")
    parser.add_argument("--solver", choices=[s.value for s in Solver],
                        default=Solver.SYMBOLIC.value,
                        help="symbolic BDD solver (default) or MTSA's explicit rank solver")
    parser.add_argument("--explain", action="store_true",
                        help="for an unrealizable spec, print the environment's winning play "
                             "(actions and fluent values: the step that breaks a safety "
                             "property, or the loop that keeps a guarantee false)")
    parser.add_argument("--order",
                        choices=[o.value for o in VariableOrder],
                        default=VariableOrder.CLUSTERED.value,
                        help="BDD variable order (symbolic solver)")
    parser.add_argument("--macro", choices=[m.value for m in MacroSteps],
                        default=MacroSteps.AUTO.value,
                        help="solve a turn-based game (the SYNTECH15 translations' "
                             "Clock/Turns) one whole turn at a time, else compress "
                             "controller-only chains into macro steps, where that is sound "
                             "(auto, default); only the latter (chains); or solve the full "
                             "game (off); symbolic solver, docs/synthesis.md")
    parser.add_argument("--realizability-only", action="store_true",
                        help="stop at the verdict: build no controller (SYNTECH15's large "
                             "games decide in seconds, their controllers take minutes)")
    talk.add_flags(parser)


def run(args: argparse.Namespace) -> int:
    """Run synthesis and print the report; return the exit code.

    Every problem with the input (unreadable SPEC, syntax/elaboration errors, no controller
    composite, unknown COMPOSITE, a goal synthesis cannot pose as a game) is a diagnostic
    rendered with its source line, and exit code 1.
    """
    elab = pipeline.load(args.spec)
    if elab.diagnostics:
        print(render(elab.diagnostics, elab.sources), file=sys.stderr)
    if not elab.ok:
        return 1
    name = pipeline.pick_composite(elab, args.composite)
    if isinstance(name, Diagnostic):
        print(render([name]), file=sys.stderr)
        return 1
    posed = pipeline.pose(elab, name)
    if posed.diagnostics:
        print(render(posed.diagnostics, elab.sources), file=sys.stderr)
    options = pipeline.SynthesisOptions(Solver(args.solver), explain=args.explain,
                                        order=VariableOrder(args.order),
                                        macro=MacroSteps(args.macro),
                                        progress=talk.progress(args),
                                        realizability_only=args.realizability_only)
    synth = pipeline.synthesise(posed, options)
    result = synth.result
    if result is None:
        return 1
    print(format_report(name, result))
    if result.diagnostics:
        print(render(list(result.diagnostics), elab.sources), file=sys.stderr)
    if not result.realizable and args.explain and result.explanation:
        print(result.explanation)
    return 0 if result.realizable else 1


def format_report(name: str, result: SynthesisResult) -> str:
    """The human-readable report printed by ``iterc synth``."""
    st = result.stats
    how = f"{st.solver} solver" + (f", {st.mode} semantics" if st.mode is not None else "")
    lines = [f"{name}: {'realizable' if result.realizable else 'UNREALIZABLE'} ({how})"]
    if st.game_states is not None:
        lines.append(f"  game: {st.game_states} states"
                     + (f", winning {st.winning_states}" if st.winning_states is not None
                        else "")
                     + (f", |T| = {st.trans_bdd_nodes} BDD nodes over {st.bdd_vars} vars"
                        if st.trans_bdd_nodes is not None else ""))
    if st.get("turns") == "on":
        lines.append(f"  turn steps: solved on {st.get('turn_starts')} turn starts "
                     f"({st.get('turn_start_nodes')} BDD nodes), one whole turn per move"
                     + ("; variable order learned from them"
                        if st.get("order_learned_at") is not None else ""))
    if st.get("macro") == "on":
        lines.append(f"  macro steps: {st.get('macro_chain_states')} controller-only chain "
                     f"states compressed, {st.get('macro_v_states')} others, exit relation "
                     f"{st.get('macro_exit_nodes')} BDD nodes")
    if result.realizable and result.controller is None:
        lines.append("  controller: not built (--realizability-only)")
    elif result.realizable:
        what = "controller (director)" if st.strategy is StrategyKind.DIRECTOR else "controller"
        lines.append(f"  {what}: {st.controller_states} states, "
                     f"{st.controller_transitions} transitions; controlled system "
                     f"{st.composition_states} states")
    if st.times:
        lines.append("  time: " + ", ".join(f"{k} {v:.3f}s" for k, v in st.times))
    for w in st.warnings:
        lines.append(f"  warning: {w}")
    return "\n".join(lines)
