"""``iterc solve SPEC.slugsin`` — GR(1) realizability and strategy for the slugs input formats.

Exit codes: 0 realizable, 1 unrealizable or input errors, 2 usage.
"""

from __future__ import annotations

import argparse
import json
import sys

from iterplan_compiler.commands import talk
from iterplan_compiler.gr1.game import GameOrder
from iterplan_compiler.gr1.slugsin import SpecFormat
from iterplan_compiler.gr1.strategy import StrategyOptions, StrategyReordering

HELP = "GR(1) realizability/strategy for a slugsin (or structuredslugs) file"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("spec", help="specification file (slugsin, or structuredslugs)")
    parser.add_argument("--format", choices=[f.value for f in SpecFormat],
                        default=SpecFormat.AUTO.value,
                        help="input format (default: by extension, .structuredslugs or slugsin)")
    parser.add_argument("--realizability-only", action="store_true",
                        help="decide realizability only: keep no iterates, build no strategy")
    parser.add_argument("--order", choices=[o.value for o in GameOrder],
                        default=GameOrder.INTERLEAVED.value,
                        help="initial BDD variable order (default: x next to x')")
    parser.add_argument("--group-pairs", action="store_true",
                        help="reorder each variable together with its primed copy")
    parser.add_argument("--no-reorder", action="store_true",
                        help="switch CUDD dynamic reordering off")
    parser.add_argument("--no-sift-after-build", action="store_true",
                        help="no explicit sifting pass between building the relations and "
                        "the fixpoint (dynamic reordering only)")
    parser.add_argument("--no-reorder-backoff", action="store_true",
                        help="CUDD's own reordering trigger everywhere (by default the trigger "
                        "backs off inside a relational product that keeps restarting)")
    parser.add_argument("--max-growth", type=float, default=None,
                        help="CUDD sifting max growth (default: dd's 1.2)")
    parser.add_argument("--monolithic", action="store_true",
                        help="one transition BDD per player instead of clustered parts")
    parser.add_argument("--cluster-nodes", type=int, default=5000,
                        help="node bound for clustering transition conjuncts (default 5000)")
    parser.add_argument("--recycle", action="store_true",
                        help="fixpoint recycling (start each νX from its previous value; keeps "
                        "every X set alive, which measured slower on arbiter/lift)")
    parser.add_argument("--no-feedback", action="store_true",
                        help="classic Z passes (no per-goal Z update / early fixpoint)")
    parser.add_argument("--no-early-unrealizable", action="store_true",
                        help="do not stop as soon as the initial states are lost")
    parser.add_argument("--chained", action="store_true",
                        help="Gauss-Seidel μY (realizability-only runs; see synthesis/fixpoint.py)")
    parser.add_argument("--strategy-reordering", choices=[m.value for m in StrategyReordering],
                        default=StrategyOptions().reordering.value,
                        help="CUDD reordering while the strategy is built: dynamic (default: "
                        "CUDD's automatic sifting), guarded (dynamic off, an explicit sift "
                        "when the manager doubled), off")
    parser.add_argument("--no-strategy-final-sift", action="store_true",
                        help="no sifting pass once the strategy relations exist")
    parser.add_argument("--no-strategy-restrict", action="store_true",
                        help="keep S_j ∧ Win instead of simplifying S_j by restrict to the "
                        "care set Win ∧ ρe")
    parser.add_argument("--json", action="store_true", help="print statistics as JSON")
    talk.add_flags(parser)


def run(args: argparse.Namespace) -> int:
    from iterplan_compiler.diagnostics import render
    from iterplan_compiler.gr1 import slugsin
    from iterplan_compiler.gr1.game import GameOptions
    from iterplan_compiler.gr1.solve import SolverOptions, solve

    if SpecFormat(args.format).resolve(args.spec) is SpecFormat.STRUCTUREDSLUGS:
        # Infix formulas and bounded integers, translated to the slugsin IR (gr1/structured.py).
        from iterplan_compiler.gr1 import structured

        spec, diags, text = structured.load(args.spec)
    else:
        spec, diags, text = slugsin.load(args.spec)
    sources = {args.spec: text} if text is not None else {}
    if diags:
        print(render(diags, sources), file=sys.stderr)
    if spec is None:
        return 1
    gopt = GameOptions(
        order=GameOrder(args.order),
        group_pairs=args.group_pairs,
        reordering=not args.no_reorder,
        sift_after_build=not args.no_sift_after_build,
        max_growth=args.max_growth,
        partition=not args.monolithic,
        cluster_nodes=args.cluster_nodes,
        reorder_backoff=not args.no_reorder_backoff,
    )
    sopt = SolverOptions(
        feedback=not args.no_feedback,
        early_unrealizable=not args.no_early_unrealizable,
        recycle=args.recycle,
        chained=args.chained,
    )
    stopt = StrategyOptions(reordering=StrategyReordering(args.strategy_reordering),
                            final_sift=not args.no_strategy_final_sift,
                            restrict=not args.no_strategy_restrict)
    res, diags = solve(spec, strategy=not args.realizability_only, game_options=gopt,
                       solver_options=sopt, strategy_options=stopt,
                       progress=talk.progress(args))
    if diags:
        print(render(diags, sources), file=sys.stderr)
    if res is None:
        return 1
    st = res.stats
    if args.json:
        out = {"realizable": res.realizable, **st}
        print(json.dumps(out, sort_keys=True, default=str))
    else:
        print("REALIZABLE" if res.realizable else "UNREALIZABLE")
        print(f"variables        {len(spec.inputs)} inputs, {len(spec.outputs)} outputs")
        print(f"build            {st['build_s']:.3f} s  (ρe {st['env_trans_nodes']} nodes in "
              f"{st['env_clusters']} parts, ρs {st['sys_trans_nodes']} nodes in "
              f"{st['sys_clusters']} parts)")
        it = st["iterations"]
        print(f"winning set      {st['winning_s']:.3f} s  ({st['winning_nodes']} nodes; "
              f"{it.get('z', 0)} Z / {it.get('y', 0)} Y / {it.get('x', 0)} X iterations"
              f"{'; stopped early' if st['early_stop'] else ''})")
        if res.strategy is not None:
            print(f"strategy         {st['strategy_s']:.3f} s  ({st['strategy_nodes']} nodes, "
                  f"{res.strategy.goals} goals)")
        print(f"total            {st['total_s']:.3f} s")
        if st.get("peak_live_nodes") is not None:
            print(f"BDD              peak {st['peak_live_nodes']} live nodes, "
                  f"{st['reorderings']} reorderings, {st['reordering_s']:.3f} s reordering"
                  + (f", {st['trigger_raises']} triggers backed off" if st["trigger_raises"]
                     else ""))
        print(f"peak memory      {st['peak_rss_mb']:.1f} MB")
    return 0 if res.realizable else 1
