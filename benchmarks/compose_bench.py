"""Throughput of explicit parallel composition (``iterplan_compiler.ir.compose``).

Prints, for products of growing size, the number of product states and transitions and the
composition rate in states per second.  Two families:

* ``ring``: n philosophers-style cyclic processes sharing a label with each neighbour
  (synchronisation-heavy);
* ``free``: n independent 4-state cycles (pure interleaving, 4**n states).

Run: ``python benchmarks/compose_bench.py [--max-states N]``.
"""

from __future__ import annotations

import argparse
import time

from iterplan_compiler.ir.compose import compose
from iterplan_compiler.ir.lts import LTS, make_lts
from iterplan_compiler.ir.minimise import minimise


def cycle(name: str, labels: list[str]) -> LTS:
    n = len(labels)
    return make_lts(name, n, [(i, a, (i + 1) % n) for i, a in enumerate(labels)])


def ring(n: int) -> list[LTS]:
    """Component i: get.i -> work.i -> put.i+1 ... sharing put/get with neighbours."""
    comps = []
    for i in range(n):
        comps.append(cycle(f"P{i}", [f"take.{i}", f"work.{i}", f"give.{(i + 1) % n}",
                                     f"rest.{i}"]))
        # a token process per edge: give.i must precede take.i
        comps.append(make_lts(f"T{i}", 2, [(0, f"take.{i}", 1), (1, f"give.{i}", 0)]))
    return comps


def free(n: int) -> list[LTS]:
    return [cycle(f"F{i}", [f"a.{i}", f"b.{i}", f"c.{i}", f"d.{i}"]) for i in range(n)]


def bench(label: str, comps: list[LTS]) -> int:
    t0 = time.perf_counter()
    r = compose(comps, label)
    dt = time.perf_counter() - t0
    print(f"{label:10s} comps={len(comps):3d} states={r.num_states:9d} "
          f"transitions={r.num_transitions:9d} time={dt:7.2f}s "
          f"rate={r.num_states / dt:10.0f} states/s")
    return r.num_states


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--max-states", type=int, default=1_100_000)
    args = ap.parse_args()
    for n in range(2, 12):
        if 4 ** n > args.max_states:
            break
        bench(f"free{n}", free(n))
    for n in range(2, 14):
        if bench(f"ring{n}", ring(n)) * 3 > args.max_states:
            break
    # minimisation throughput on the largest free product that fits comfortably
    r = compose(free(7), "free7")
    t0 = time.perf_counter()
    m = minimise(r)
    print(f"minimise   states={r.num_states:9d} -> {m.num_states} in "
          f"{time.perf_counter() - t0:.2f}s")


if __name__ == "__main__":
    main()
