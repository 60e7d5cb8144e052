"""Fast skip: a Fire Patrol pass over N locations with and without it.

Run: ``python benchmarks/fast_skip_bench.py [--locations 700000] [--repeats 3]``.  Five patrol
cells near home, so almost every location is a skip cycle (has.next, y.next, is.next.inP,
no.next.inP, remove.next).  Compute time is charged to the simulated clock (as in the paper:
the aircraft flies on while the plan iterates), so the mission is longer than the same mission
with ``ideal_compute``; the difference is the iteration overhead.  Prints, median of the
repeats: wall time of the pass, mission duration, and the overhead over the ideal-compute
mission, without and with ``fast_skip``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks.loop_bench import patrol_grid  # noqa: E402
from iterplan_compiler.runtime.executor import Executor, RunConfig  # noqa: E402
from iterplan_compiler.runtime.grid import GridMap  # noqa: E402
from iterplan_compiler.runtime.sim import SimParams, SimVehicle  # noqa: E402
from tests.runtime.fire_patrol import TABLE  # noqa: E402


def mission(g: GridMap, *, fast: bool, ideal: bool) -> tuple[float, float, int]:
    v = SimVehicle(SimParams(), home=g.home)
    cfg = RunConfig(ideal_compute=ideal, fast_skip=fast, log_limit=0, track_every=5.0,
                    max_time=1e9)
    t = time.perf_counter()
    r = Executor(TABLE, g, v, config=cfg).run()
    assert r.ok, r.reason
    return time.perf_counter() - t, r.summary["duration_s"], r.counts["skipped"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--locations", type=int, default=700_000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    g = patrol_grid(args.locations)
    _, ideal_t, _ = mission(g, fast=False, ideal=True)
    print(f"{args.locations:,} locations; ideal-compute mission {ideal_t:.1f} s")
    for fast in (False, True):
        runs = [mission(g, fast=fast, ideal=False) for _ in range(args.repeats)]
        wall = statistics.median(r[0] for r in runs)
        dur = statistics.median(r[1] for r in runs)
        print(f"fast_skip={str(fast):<5}  pass wall {wall:7.2f} s   mission {dur:8.1f} s   "
              f"iteration overhead {100 * (dur - ideal_t) / ideal_t:6.1f} %   "
              f"skipped {runs[0][2]:,}")


if __name__ == "__main__":
    main()
