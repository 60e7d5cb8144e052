"""Controller + iterator loop rate: a full Fire Patrol pass over N locations.

Run: ``python benchmarks/loop_bench.py [--locations 700000]``.  The hand-written Fire Patrol
controller (tests/runtime/fire_patrol.py) iterates once over every location through the
standard bindings (has.next -> y.next, is.next.inP -> yes/no.next.inP, remove.next, ...) with the
built-in simulator and the distance sorter; a sparse patrol set makes a few go.next legs happen.
Prints locations/s and controller steps/s for (a) the bare Controller + Iterator loop and (b) the
full executor (bindings, logging, time accounting), plus the simulated mission overhead caused by
the compute time when it is charged to the simulated clock.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from iterplan_compiler.runtime.controller import Controller  # noqa: E402
from iterplan_compiler.runtime.executor import Executor, RunConfig  # noqa: E402
from iterplan_compiler.runtime.grid import GridMap  # noqa: E402
from iterplan_compiler.runtime.iterator import Iterator  # noqa: E402
from iterplan_compiler.runtime.sim import SimParams, SimVehicle  # noqa: E402
from iterplan_compiler.runtime.sorter import Pose, make_sorter  # noqa: E402
from tests.runtime.fire_patrol import TABLE  # noqa: E402


def bare_loop(n: int) -> tuple[float, int]:
    """Controller.step + Iterator ops only (no patrol cells: one pass, no flying)."""
    side = int(math.ceil(math.sqrt(n)))
    ids = np.arange(n)
    it = Iterator(ids, (ids % side) * 50.0, (ids // side) * 50.0,
                  make_sorter("distance", radius=47.0, arrival_heading=math.pi / 2),
                  Pose(0, 0, math.pi / 2))
    c = Controller(TABLE)
    step = c.step
    steps = 0
    t = time.perf_counter()
    while True:
        step("has.next")
        if not it.has_next():
            step("n.next")
            steps += 2
            break
        step("y.next")
        step("is.next.inP")
        step("no.next.inP")
        step("remove.next")
        it.remove_next()
        steps += 5
    return time.perf_counter() - t, steps


def full_executor(n: int, ideal: bool) -> tuple[float, dict]:
    side = int(math.ceil(math.sqrt(n)))
    g = GridMap.from_size(side, int(math.ceil(n / side)))
    g.cells = g.cells[:n]
    rng = np.random.default_rng(0)
    # Five patrol cells within ~1 km of home, so legs are short and iteration dominates.
    block = (np.arange(20)[:, None] * g.cols + np.arange(20)[None, :]).ravel()
    g.set_sensor("inP", rng.choice(block[block < n], 5, replace=False))
    g.set_sensor("fire", g.sensors["inP"][:2])
    g.home = g.centre(int(g.cells[0]))
    v = SimVehicle(SimParams(), home=g.home)
    cfg = RunConfig(ideal_compute=ideal, log_limit=0, track_every=5.0, max_time=1e9)
    t = time.perf_counter()
    r = Executor(TABLE, g, v, config=cfg).run()
    wall = time.perf_counter() - t
    assert r.ok, r.reason
    return wall, r.summary


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--locations", type=int, default=700_000)
    args = ap.parse_args()
    n = args.locations
    wall, steps = bare_loop(n)
    print(f"bare Controller+Iterator pass over {n:,} locations: {wall:.2f} s, "
          f"{n / wall:,.0f} locations/s, {steps / wall:,.0f} steps/s")
    for ideal in (True, False):
        wall, s = full_executor(n, ideal)
        print(f"executor pass ({'ideal compute' if ideal else 'compute charged'}): "
              f"{wall:.2f} s wall, {n / wall:,.0f} locations/s, {s['steps'] / wall:,.0f} steps/s;"
              f" mission {s['duration_s']:.0f} s for {s['arrivals']} patrol cells, overhead "
              f"{s['overhead_pct']} %, compute {s['compute_s']:.2f} s, {s['resorts']} re-sorts")


if __name__ == "__main__":
    main()
