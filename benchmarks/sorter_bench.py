"""Sorter throughput: ns per location of the vectorised Dubins (CSC) kernel.

Run: ``python benchmarks/sorter_bench.py`` (pin to one core with ``taskset -c 0`` to compare with
the paper's single-board figure: 40,000 locations in 2.9 s on a Raspberry Pi 3B+).  Prints, for
40 k, 700 k and 10 M locations on a 50 m grid: the kernel alone with a fixed arrival heading, with
"parallel" arrival (either direction, the runtime default), and a full Iterator re-sort (kernel +
first-block partial sort), best of several runs.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from iterplan_compiler.runtime.iterator import Iterator
from iterplan_compiler.runtime.sorter import DistanceSorter, Pose, dubins_lengths


def grid(n: int, cell: float = 50.0):
    side = int(math.ceil(math.sqrt(n)))
    ids = np.arange(n)
    return ((ids % side) + 0.5) * cell, ((ids // side) + 0.5) * cell


def best_of(fn, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def bench_size(n: int, radius: float) -> None:
    xs, ys = grid(n)
    xs32, ys32 = xs.astype(np.float32), ys.astype(np.float32)
    start = Pose(float(xs.mean()) + 10, float(ys.mean()) - 20, 0.3)
    reps = 7 if n <= 1_000_000 else 2
    dubins_lengths(start, xs32[:1000], ys32[:1000], math.pi / 2, radius)  # warm up
    it = Iterator(np.arange(n), xs32, ys32, DistanceSorter(radius, math.pi / 2, parallel=False),
                  start)
    rows = [
        ("kernel, fixed heading", lambda: dubins_lengths(
            start, xs32, ys32, math.pi / 2, radius, parallel=False)),
        ("kernel, parallel", lambda: dubins_lengths(
            start, xs32, ys32, math.pi / 2, radius, parallel=True)),
        ("iterator resort, fixed", lambda: (it.resort(start), it.peek_order(1))),
    ]
    for name, fn in rows:
        t = best_of(fn, reps)
        print(f"{n:>11,} {name:<22} {t * 1e3:>8.1f} ms {t / n * 1e9:>12.1f}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="40000,700000,10000000")
    ap.add_argument("--radius", type=float, default=33.0)
    args = ap.parse_args()
    print(f"{'locations':>11} {'variant':<22} {'time':>10} {'ns/location':>12}")
    for n in (int(s) for s in args.sizes.split(",")):
        bench_size(n, args.radius)


if __name__ == "__main__":
    main()
