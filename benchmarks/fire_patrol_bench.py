"""Explicit Fire Patrol: the largest N synthesised within a time limit.

    python benchmarks/fire_patrol_bench.py [--limit 60] [--start 4] [--step 1] [--cpu]

For N = start, start+step, ... the spec of ``gen_explicit_fire_patrol.py`` is synthesised in
a fresh process (``iterc synth``-equivalent: load, elaborate, solve, extract, minimise,
re-compose); the first N over the limit stops the sweep.  Prints one line per N (wall time,
game and controller states) and then the largest N within the limit.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _one(n: int) -> dict:
    import warnings

    warnings.simplefilter("ignore")
    from iterplan_compiler import limits
    from iterplan_compiler.experiments.catalog import explicit_fire_patrol
    from iterplan_compiler.pipeline import load_model as load
    from iterplan_compiler.synthesis.driver import synthesize

    # the game and the controller grow as 2^N: the default --max-states (300 000) would stop
    # the sweep at N = 11 on a limit, not on time
    limits.set_limits(max_states=100_000_000, max_memory_mb=16_000)
    t0 = time.perf_counter()
    with tempfile.NamedTemporaryFile("w", suffix=".lts", delete=False) as fh:
        fh.write(explicit_fire_patrol(n))
    model, _diags = load(fh.name)
    problem, _ = model.synthesis_problem("ExplicitFirePatrol")
    t1 = time.perf_counter()
    r = synthesize(problem, explain=False)
    st = r.stats
    return {"realizable": r.realizable, "game_states": st.get("game_states"),
            "controller_states": st.get("controller_states"), "t_front": t1 - t0,
            "t_solve": st.get("t_solve"), "t_extract": st.get("t_extract")}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--limit", type=float, default=60.0)
    ap.add_argument("--start", type=int, default=4)
    ap.add_argument("--step", type=int, default=1)
    ap.add_argument("--cpu", action="store_true",
                    help="apply the limit to CPU time (RLIMIT_CPU of the child) instead of "
                         "wall time: on a shared, loaded machine wall time measures the load")
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(_one(args.one)))
        return 0
    best = None
    n = args.start
    cpu_before = 0.0
    while True:
        t = time.perf_counter()
        try:
            out = subprocess.run([sys.executable, __file__, "--one", str(n)], text=True,
                                 capture_output=True,
                                 timeout=args.limit * (20 if args.cpu else 1),
                                 preexec_fn=_cpu_limit(args.limit) if args.cpu else None).stdout
            res = json.loads(out.strip().splitlines()[-1])
        except (subprocess.TimeoutExpired, IndexError):  # IndexError: killed by RLIMIT_CPU
            print(f"N={n}: over {args.limit:g} s{' CPU' if args.cpu else ''}")
            break
        dt = time.perf_counter() - t
        ru = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = ru.ru_utime + ru.ru_stime - cpu_before
        cpu_before += cpu
        print(f"N={n}: {dt:.1f} s wall, {cpu:.1f} s CPU, game {res['game_states']} states, "
              f"controller {res['controller_states']} states (front-end {res['t_front']:.1f} s, "
              f"solve {res['t_solve']:.1f} s, extract {res['t_extract']:.1f} s)", flush=True)
        if not res["realizable"] or (cpu if args.cpu else dt) > args.limit:
            break
        best = n
        n += args.step
    print(f"largest N within {args.limit:g} s{' CPU' if args.cpu else ''}: {best}")
    return 0


def _cpu_limit(seconds: float):  # noqa: ANN202 - a preexec_fn
    def apply() -> None:
        s = max(1, int(seconds + 0.999))
        resource.setrlimit(resource.RLIMIT_CPU, (s, s + 1))
    return apply


if __name__ == "__main__":
    sys.exit(main())
