"""Run omega's GR(1) solver on a slugsin file (optional like-for-like anchor for run.py).

omega (tulip-control) is *not* a dependency of iterplan; install it in a separate venv
(``python -m venv --system-site-packages V && V/bin/pip install omega==0.4.0``) and pass
``--omega-python V/bin/python`` to ``run.py``.  This script builds the game BDDs with our own
slugsin reader and formula builder into omega's ``temporal.Automaton`` (so both solvers see
identical formulas and the same initial variable order), then times
``omega.games.gr1.solve_streett_game`` (+ ``make_streett_transducer`` with ``--strategy``)
with slugs semantics: ``moore=False, plus_one=False, qinit='\\A \\E'``.  Prints one JSON line.
Liveness lines with primed variables are rejected (omega supports state predicates only).
"""

from __future__ import annotations

import argparse
import json
import resource
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("spec")
    ap.add_argument("--strategy", action="store_true")
    args = ap.parse_args(argv)
    from omega.games import gr1
    from omega.symbolic import temporal as trl

    from iterplan_compiler.gr1 import slugsin
    from iterplan_compiler.gr1.game import _build_expr

    t0 = time.perf_counter()
    spec, diags, _ = slugsin.load(args.spec)
    if spec is None:
        print(json.dumps({"error": [d.message for d in diags]}))
        return 2
    aut = trl.Automaton()
    aut.declare_variables(**{v: "bool" for v in spec.inputs + spec.outputs})
    aut.varlist = {"env": list(spec.inputs), "sys": list(spec.outputs)}
    aut.prime_varlists()
    bdd = aut.bdd
    memo: dict = {}

    def conj(sec: str):
        u = bdd.true
        for line in spec.lines(sec):
            u &= _build_expr(bdd, line.expr, memo)
        return u

    def each(sec: str):
        return [_build_expr(bdd, line.expr, memo) for line in spec.lines(sec)] or [bdd.true]

    aut.init["env"] = conj("ENV_INIT")
    aut.init["sys"] = conj("SYS_INIT")
    aut.action["env"] = conj("ENV_TRANS")
    aut.action["sys"] = conj("SYS_TRANS")
    aut.win["<>[]"] = [~a for a in each("ENV_LIVENESS")]
    aut.win["[]<>"] = each("SYS_LIVENESS")
    aut.moore = False
    aut.plus_one = False
    aut.qinit = r"\A \E"
    t1 = time.perf_counter()
    c1 = time.process_time()
    z, yij, xijk = gr1.solve_streett_game(aut)
    realizable = gr1.is_realizable(z, aut)
    t2 = time.perf_counter()
    c2 = time.process_time()
    nodes = None
    if args.strategy and realizable:
        gr1.make_streett_transducer(z, yij, xijk, aut)
        nodes = len(aut.action["impl"])
    t3 = time.perf_counter()
    c3 = time.process_time()
    out = {
        "realizable": bool(realizable),
        "build_s": t1 - t0,
        "winning_s": t2 - t1,
        "winning_cpu_s": c2 - c1,
        "strategy_s": t3 - t2,
        "strategy_cpu_s": c3 - c2,
        "total_s": t3 - t0,
        "strategy_nodes": nodes,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
    }
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
