"""Synthesis timing: a scalable patrol-with-doors family and (when the front-end is present)
the conformance specs.  Prints phase times, game sizes and BDD sizes per variable order.

    python benchmarks/synthesis_bench.py [--max-n 7] [--explicit-max 4] [--min-n 2]
        [--conformance ../shared/conformance/mtsa [--patrol-max 5] [--limit 120]]

Family ``DoorPatrol_N``: a robot on a ring of N rooms (controllable ``go.i`` to an adjacent
room through door i, uncontrollable ``arrive.i``; controllable ``wait``, then the environment
may open doors (``open.k``) before ``resume``).  A door, once opened, stays open until the
robot passes it.  Assumptions: every door is open infinitely often; guarantees: every room is
visited infinitely often.  Realizable for every N.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from iterplan_compiler.ir.formulas import Fluent, FluentProp
from iterplan_compiler.ir.lts import make_lts
from iterplan_compiler.ir.model import SynthesisProblem
from iterplan_compiler.synthesis.driver import synthesize


def door_patrol(n: int) -> SynthesisProblem:
    """The ``DoorPatrol_N`` problem (module doc)."""
    # robot: i = in room i, n + i = moving to room i, 2n + i = waiting in room i
    trans = []
    for i in range(n):
        for j in ((i + 1) % n, (i - 1) % n):
            trans.append((i, f"go.{j}", n + j))
        trans.append((n + i, f"arrive.{i}", i))
        trans.append((i, "wait", 2 * n + i))
        trans.append((2 * n + i, "resume", i))
        for k in range(n):
            trans.append((2 * n + i, f"open.{k}", 2 * n + i))
    robot = make_lts("Robot", 3 * n, trans)
    # door k: 0 closed, 1 open; the environment opens it, passing through closes it again
    doors = [make_lts(f"Door{k}", 2, [(0, f"open.{k}", 1),
                                      (1, f"go.{k}", 0)]) for k in range(n)]
    fluents = [Fluent(f"At{i}", frozenset({f"arrive.{i}"}),
                      frozenset({f"go.{j}" for j in range(n)}), i == 0) for i in range(n)]
    fluents += [Fluent(f"Open{k}", frozenset({f"open.{k}"}), frozenset({f"go.{k}"}))
                for k in range(n)]
    ctrl = frozenset({f"go.{i}" for i in range(n)} | {"wait"})
    return SynthesisProblem(
        f"DoorPatrol_{n}", frozenset({"controller"}), (robot, *doors), (),
        tuple(FluentProp(f"Open{k}") for k in range(n)),
        tuple(FluentProp(f"At{i}") for i in range(n)), (), tuple(fluents), ctrl)


def _row(label: str, r) -> str:
    st = r.stats
    times = " ".join(f"{k[2:]}={st[k]:.3f}" for k in st if k.startswith("t_"))
    extra = f" |T|={st['trans_bdd_nodes']}" if "trans_bdd_nodes" in st else ""
    if "fixpoint_iterations" in st:
        extra += f" nuX-steps={st['fixpoint_iterations'].get('x')}"
    return (f"{label:34s} {'R' if r.realizable else 'U'} game={st.get('game_states')}"
            f" ctrl={st.get('controller_states', '-')}{extra}  {times}")


def _timed(label: str, problem: SynthesisProblem, **kw) -> None:
    """One synthesis run: wall and CPU seconds (CPU is the figure to compare on a busy box)."""
    t, c = time.perf_counter(), time.process_time()
    r = synthesize(problem, **kw)
    print(_row(label, r) + f"  total={time.perf_counter() - t:.3f}"
          f" cpu={time.process_time() - c:.3f}")


def bench_family(max_n: int, explicit_max: int, min_n: int = 2) -> None:
    print("== DoorPatrol_N (symbolic, per variable order; explicit for small N)")
    for n in range(min_n, max_n + 1):
        p = door_patrol(n)
        # the poorer orders only while they stay cheap (they are here to be compared)
        orders = ("clustered",) + (("action_first", "action_last") if n <= 6 else ()) \
            + (("blocked",) if n <= 3 else ())
        for order in orders:
            _timed(f"N={n} symbolic/{order}", p, order=order)
        if n <= explicit_max:
            _timed(f"N={n} explicit", p, solver="explicit")
        sys.stdout.flush()


def bench_conformance(root: Path, limit: float) -> None:
    try:
        from iterplan_compiler.pipeline import load_model as load
    except ImportError:
        print("(front-end not available: conformance specs skipped)")
        return
    import csv

    print(f"== conformance synthesis rows under {root}")
    with open(root / "verdicts.tsv", encoding="utf-8") as fh:
        rows = [r for r in csv.reader(fh, delimiter="\t") if len(r) > 2
                and r[1].split(" ")[0] in ("realizable", "unrealizable")]
    start = time.perf_counter()
    for rec in rows:
        if time.perf_counter() - start > limit:
            print("(time limit reached)")
            break
        try:
            model, _ = load(str(root / rec[0]))
        except Exception as exc:  # noqa: BLE001 - the front-end may be mid-change
            print(f"{rec[0]}: front-end failed: {type(exc).__name__}")
            continue
        if model is None:
            continue
        name = rec[2].split()[0] if rec[2].strip() else "C"
        problem, _ = model.synthesis_problem(name)
        if problem is None:
            continue
        r = synthesize(problem, explain=False)
        print(_row(f"{rec[0][-34:]}", r))


def bench_patrol(root: Path, ns: list[int]) -> None:
    """``Patrol_N_Locations``: the corpus' Patrol_3 benchmark with ``const Sensores = N``."""
    import re

    try:
        from iterplan_compiler.pipeline import load_model as load
    except ImportError:
        print("(front-end not available: Patrol_N skipped)")
        return
    path = root / "benchmarks" / "Patrol_3_Locations.lts"
    if not path.is_file():
        print(f"({path} not found: Patrol_N skipped)")
        return
    src = path.read_text(encoding="utf-8")
    print("== Patrol_N_Locations (front-end composes Environment into one machine)")
    for n in ns:
        text = re.sub(r"const Sensores = \d+", f"const Sensores = {n}", src)
        try:
            model, _ = load(str(path), text=text)
            problem, _ = model.synthesis_problem("Controller") if model else (None, [])
        except Exception as exc:  # noqa: BLE001 - the front-end may be mid-change
            print(f"N={n}: front-end failed: {type(exc).__name__}")
            continue
        if problem is None:
            print(f"N={n}: no synthesis problem")
            continue
        sizes = "+".join(str(c.num_states) for c in problem.plant)
        for solver in ("symbolic", "explicit"):
            _timed(f"N={n} {solver} (plant {sizes})", problem, solver=solver, explain=False)
        sys.stdout.flush()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--max-n", type=int, default=6)
    ap.add_argument("--min-n", type=int, default=2)
    ap.add_argument("--explicit-max", type=int, default=4)
    ap.add_argument("--conformance", type=Path, default=None)
    ap.add_argument("--limit", type=float, default=120.0)
    ap.add_argument("--patrol-max", type=int, default=5)
    ap.add_argument("--patrol-min", type=int, default=2)
    args = ap.parse_args()
    bench_family(args.max_n, args.explicit_max, args.min_n)
    if args.conformance:
        bench_patrol(args.conformance, list(range(args.patrol_min, args.patrol_max + 1)))
        bench_conformance(args.conformance, args.limit)


if __name__ == "__main__":
    main()
