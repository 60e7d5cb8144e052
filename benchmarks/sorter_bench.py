"""Sorter throughput: ns per location of the vectorised Dubins (CSC) kernel.

Run: ``python benchmarks/sorter_bench.py`` (pin to one core with ``taskset -c 0`` to compare with
the paper's single-board figure: 40,000 locations in 2.9 s on a Raspberry Pi 3B+; the issue's
target is 700 k in < 30 ms and 10 M in < 0.3 s on one core).  Prints, for 40 k, 700 k and 10 M
locations on a 50 m grid: the kernel alone with a fixed arrival heading, with "parallel" arrival
(either direction, the runtime default), and a full Iterator re-sort (kernel + first-block
partial sort), best of several runs; the runtime's per-next-location choice (re-sort from the
arrival pose, parallel arrival, take the first) with and without lower-bound pruning; then the no-full-sort paths: ``Sorter.best`` (kernel +
argmin) and ``select_smallest`` (the 4096 best, in order) against the ``argpartition`` that the
Iterator uses today.  ``time`` is wall clock, ``cpu`` process time (less sensitive to other jobs
on the machine); the load average is printed before and after, because on a shared 2-core VM
wall-clock figures move by 2x with the load.

``--chunks 8192,32768`` sweeps the kernel's chunk size instead (700 k, fixed and parallel).
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from iterplan_compiler.runtime.iterator import Iterator
from iterplan_compiler.runtime.sorter import (
    DistanceSorter,
    Pose,
    dubins_lengths,
    select_smallest,
)


def grid(n: int, cell: float = 50.0):
    side = int(math.ceil(math.sqrt(n)))
    ids = np.arange(n)
    return ((ids % side) + 0.5) * cell, ((ids // side) + 0.5) * cell


def best_of(fn, repeats: int) -> tuple[float, float]:
    """(best wall seconds, best CPU seconds) over ``repeats`` runs."""
    wall = cpu = float("inf")
    for _ in range(repeats):
        t, c = time.perf_counter(), time.process_time()
        fn()
        wall = min(wall, time.perf_counter() - t)
        cpu = min(cpu, time.process_time() - c)
    return wall, cpu


def row(n: int, name: str, wall: float, cpu: float) -> None:
    print(f"{n:>11,} {name:<22} {wall * 1e3:>8.1f} ms {wall / n * 1e9:>12.1f} "
          f"{cpu * 1e3:>9.1f} ms", flush=True)


def bench_size(n: int, radius: float) -> None:
    xs, ys = grid(n)
    xs32, ys32 = xs.astype(np.float32), ys.astype(np.float32)
    ids = np.arange(n)
    start = Pose(float(xs.mean()) + 10, float(ys.mean()) - 20, 0.3)
    reps = 7 if n <= 1_000_000 else 3
    dubins_lengths(start, xs32[:1000], ys32[:1000], math.pi / 2, radius)  # warm up
    it = Iterator(ids, xs32, ys32, DistanceSorter(radius, math.pi / 2, parallel=False), start,
                  prune_min=n + 1)
    par = DistanceSorter(radius, math.pi / 2, parallel=True)
    # What the runtime does per next-location choice: re-sort R from the arrival pose and take
    # the first location; with lower-bound pruning (the default for large R) and without.
    pruned = Iterator(ids, xs32, ys32, par, start)
    unpruned = Iterator(ids, xs32, ys32, par, start, prune_min=n + 1)
    keys = par.keys(xs32, ys32, ids, start)
    rows = [
        ("kernel, fixed heading", lambda: dubins_lengths(
            start, xs32, ys32, math.pi / 2, radius, parallel=False)),
        ("kernel, parallel", lambda: dubins_lengths(
            start, xs32, ys32, math.pi / 2, radius, parallel=True)),
        ("iterator resort, fixed", lambda: (it.resort(start), it.peek_order(1))),
        ("next choice, unpruned", lambda: (unpruned.resort(start), unpruned.peek_order(1))),
        ("next choice, pruned", lambda: (pruned.resort(start), pruned.peek_order(1))),
        ("best(), parallel", lambda: par.best(xs32, ys32, ids, start)),
        ("argpartition 4096", lambda: np.argpartition(keys, min(4095, n - 1))),
        ("select_smallest 4096", lambda: select_smallest(keys, 4096)),
    ]
    for name, fn in rows:
        row(n, name, *best_of(fn, reps))


def sweep_chunks(chunks: list[int], radius: float, n: int = 700_000) -> None:
    xs, ys = grid(n)
    xs32, ys32 = xs.astype(np.float32), ys.astype(np.float32)
    start = Pose(float(xs.mean()) + 10, float(ys.mean()) - 20, 0.3)
    for parallel in (False, True):
        for ch in chunks:
            wall, cpu = best_of(lambda ch=ch, par=parallel: dubins_lengths(
                start, xs32, ys32, math.pi / 2, radius, parallel=par, chunk=ch), 7)
            row(n, f"chunk {ch} {'par' if parallel else 'fixed'}", wall, cpu)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="40000,700000,10000000")
    ap.add_argument("--radius", type=float, default=33.0)
    ap.add_argument("--chunks", default="", help="sweep these chunk sizes instead (700 k)")
    args = ap.parse_args()
    load = os.getloadavg()
    print(f"# load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} CPUs; "
          f"affinity {sorted(os.sched_getaffinity(0))}")
    print(f"{'locations':>11} {'variant':<22} {'time':>10} {'ns/location':>12} {'cpu':>12}")
    if args.chunks:
        sweep_chunks([int(c) for c in args.chunks.split(",")], args.radius)
    else:
        for n in (int(s) for s in args.sizes.split(",")):
            bench_size(n, args.radius)
    load = os.getloadavg()
    print(f"# load average after: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")


if __name__ == "__main__":
    main()
