"""Controller + iterator loop rate: a full Fire Patrol pass over N locations.

Run: ``python benchmarks/loop_bench.py [--locations 700000]``.  The hand-written Fire Patrol
controller (tests/runtime/fire_patrol.py) iterates once over every location through the
standard bindings (has.next -> y.next, is.next.inP -> yes/no.next.inP, remove.next, ...) with the
built-in simulator and the distance sorter; a sparse patrol set makes a few go.next legs happen.
Prints locations/s and controller steps/s for (a) the bare Controller + Iterator loop and (b) the
full executor (bindings, logging, time accounting), plus the simulated mission overhead caused by
the compute time when it is charged to the simulated clock.

``--view`` (needs ``pip install 'iterplan[view]'``) compares the executor's loop rate without and
with the live view attached (observer hook + server thread + a WebSocket client in another
process, as a browser would be): the iteration-bound pass above and a tick-bound mission (the
8x8 Fire Patrol example, many passes, where the observer is called on every physical tick).
Runs alternate (ABBA), ``--repeat`` times each; the medians and the best runs of process CPU
time (the server thread included; robust on a shared machine) and of wall time are compared.
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
from iterplan_compiler.runtime.sorter import Pose  # noqa: E402
from iterplan_compiler.runtime.sorters import make_sorter  # noqa: E402
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


def patrol_grid(n: int) -> GridMap:
    """N locations with five patrol cells within ~1 km of home (two of them on fire), so legs
    are short and iteration dominates (also used by fast_skip_bench.py)."""
    side = int(math.ceil(math.sqrt(n)))
    g = GridMap.from_size(side, int(math.ceil(n / side)))
    g.cells = g.cells[:n]
    rng = np.random.default_rng(0)
    block = (np.arange(20)[:, None] * g.cols + np.arange(20)[None, :]).ravel()
    g.set_sensor("inP", rng.choice(block[block < n], 5, replace=False))
    g.set_sensor("fire", g.sensors["inP"][:2])
    g.home = g.centre(int(g.cells[0]))
    return g


def full_executor(n: int, ideal: bool, observe=None) -> tuple[float, dict]:
    g = patrol_grid(n)
    v = SimVehicle(SimParams(), home=g.home)
    cfg = RunConfig(ideal_compute=ideal, log_limit=0, track_every=5.0, max_time=1e9,
                    observe=observe)
    t, c = time.perf_counter(), time.process_time()
    r = Executor(TABLE, g, v, config=cfg).run()
    wall = time.perf_counter() - t
    assert r.ok, r.reason
    r.summary["cpu_s"] = time.process_time() - c
    return wall, r.summary


def tick_bound(passes: int, observe=None) -> tuple[float, dict]:
    """The 8x8 Fire Patrol example for ``passes`` passes: mostly physical ticks."""
    from iterplan_compiler.runtime.mapfile import load_map

    g = load_map(Path(__file__).resolve().parents[1] / "examples" / "fire_patrol.json")
    v = SimVehicle(SimParams(), home=g.home, heading=g.arrival_heading)
    cfg = RunConfig(ideal_compute=True, passes=passes, max_time=1e9, observe=observe)
    t, c = time.perf_counter(), time.process_time()
    r = Executor(TABLE, g, v, config=cfg).run()
    wall = time.perf_counter() - t
    assert r.ok, r.reason
    r.summary["cpu_s"] = time.process_time() - c
    return wall, r.summary


CLIENT = """
import asyncio, sys, aiohttp
async def main():
    n = 0
    async with aiohttp.ClientSession() as s:
        async with s.ws_connect(sys.argv[1]) as ws:
            print("connected", flush=True)
            async for m in ws:
                n += 1
                if '"final"' in m.data:
                    break
    print(n, flush=True)
asyncio.run(main())
"""


def with_view(grid_of, run):
    """Run ``run(observe)`` with a live view attached and a WebSocket client in another process;
    returns (wall, summary, snapshots, seconds spent in snapshots, messages the client got)."""
    import subprocess

    from iterplan_compiler.view.live import LiveView

    view = LiveView(grid_of(), "127.0.0.1:0")
    client = subprocess.Popen([sys.executable, "-c", CLIENT, view.url + "ws"],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert client.stdout.readline().strip() == "connected"
        wall, s = run(view.observe)
        got = int(client.stdout.readline() or 0)
    finally:
        client.wait(30)
        client.stdout.close()
        view.close()
    return wall, s, view.observe.snapshots, (view.observe.seconds, view.server.cpu_s), got


def view_comparison(n: int, passes: int, repeat: int, only: str = "") -> None:
    import statistics

    from iterplan_compiler.runtime.mapfile import load_map

    def big_grid():
        side = int(math.ceil(math.sqrt(n)))
        g = GridMap.from_size(side, int(math.ceil(n / side)))
        g.cells = g.cells[:n]
        return g

    cases = [
        (f"iteration-bound pass, {n:,} locations", big_grid,
         lambda obs: full_executor(n, True, obs), "steps"),
        (f"tick-bound Fire Patrol 8x8, {passes} passes", lambda: load_map(
            Path(__file__).resolve().parents[1] / "examples" / "fire_patrol.json"),
         lambda obs: tick_bound(passes, obs), "ticks"),
    ]
    for title, grid_of, run, unit in cases:
        if only and only not in title:
            continue
        rows: dict[str, list[float]] = {"wall": [], "cpu": [], "wall_v": [], "cpu_v": []}
        extra = []
        for i in range(repeat):
            for viewed in ((False, True) if i % 2 == 0 else (True, False)):   # ABBA order
                if viewed:
                    w2, s2, snaps, secs, got = with_view(grid_of, run)
                    rows["wall_v"].append(w2)
                    rows["cpu_v"].append(s2["cpu_s"])
                    extra.append((snaps, secs, got))
                else:
                    w, s = run(None)
                    rows["wall"].append(w)
                    rows["cpu"].append(s["cpu_s"])
            assert s2["steps"] == s["steps"] and s2["duration_s"] == s["duration_s"]
        med = {k: statistics.median(v) for k, v in rows.items()}
        best = {k: min(v) for k, v in rows.items()}
        work = s["steps"] if unit == "steps" else s["duration_s"] / 0.25
        snaps, secs, got = extra[len(extra) // 2]
        print(f"{title} ({work:,.0f} {unit}), median of {repeat}:")
        for kind in ("cpu", "wall"):
            a, b = med[kind], med[kind + "_v"]
            a1, b1 = best[kind], best[kind + "_v"]
            # Paired: each viewed run against the plain run next to it (ABBA), so slow drifts
            # of the machine's load cancel; the median of those ratios.
            paired = statistics.median(v / p for p, v in zip(rows[kind], rows[kind + "_v"],
                                                            strict=True)) - 1
            print(f"  {kind:>4}: without view {a:.2f} s ({work / a:,.0f} {unit}/s), with view "
                  f"{b:.2f} s ({work / b:,.0f} {unit}/s): slow-down {(b - a) / a * 100:+.1f} %"
                  f" (paired {paired * 100:+.1f} %; best runs: {a1:.2f} / {b1:.2f} s, {(b1 - a1) / a1 * 100:+.1f} %)"
                  f"  [without {' '.join(f'{x:.2f}' for x in rows[kind])}; with "
                  f"{' '.join(f'{x:.2f}' for x in rows[kind + '_v'])}]")
        obs_s, srv_s = secs
        print(f"  per viewed run: {snaps} snapshots, {got} messages to the page; CPU "
              f"{obs_s * 1000:.0f} ms in the observer and {srv_s * 1000:.0f} ms in the server "
              f"thread = {(obs_s + srv_s) / med['cpu'] * 100:.1f} % of a run")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--locations", type=int, default=700_000)
    ap.add_argument("--view", action="store_true",
                    help="compare the loop rate without and with the live view attached")
    ap.add_argument("--repeat", type=int, default=5, help="runs of each kind with --view")
    ap.add_argument("--passes", type=int, default=60,
                    help="passes of the tick-bound mission with --view")
    ap.add_argument("--only", choices=("iteration", "tick"), default="",
                    help="with --view: only the iteration-bound or the tick-bound comparison")
    args = ap.parse_args()
    n = args.locations
    if args.view:
        view_comparison(n, args.passes, args.repeat, args.only)
        return
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
