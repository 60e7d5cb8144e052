"""Print how many controller steps per second a generated controller module sustains.

Usage::

    python benchmarks/controller_steps.py                 # hand-made Fire Patrol controller
    python benchmarks/controller_steps.py OUT.py          # a module written by `iterc compile`
    python benchmarks/controller_steps.py --states 5000   # a large random deterministic controller

A step is ``controller.step(label)`` on an enabled label (the hot path of ``run()``); the walk
follows a pre-computed random path so the timing excludes choosing the label.  The target is a
step well under one microsecond.
"""

from __future__ import annotations

import argparse
import importlib.util
import random
import sys
import tempfile
import time
from pathlib import Path
from types import ModuleType

from iterplan_compiler.backends.python import emit_module
from iterplan_compiler.ir.lts import LTS, make_lts


def fire_patrol() -> LTS:
    """The hand-made Fire-Patrol-like controller also used by the back-end tests."""
    t = [(0, "has.next", 1), (1, "y.next", 2), (1, "n.next", 11), (2, "is.next.inP", 3),
         (3, "yes.next.inP", 4), (3, "no.next.inP", 10), (4, "go.next", 5), (5, "arrived", 6),
         (6, "is.fire", 7), (7, "yes.fire", 8), (7, "no.fire", 10), (8, "take.photo", 10),
         (10, "remove.next", 0), (11, "reset", 0)]
    return make_lts("FirePatrol", 12, t)


def random_controller(states: int, labels: int, seed: int) -> LTS:
    """A strongly connected-ish deterministic LTS: every state has 1-4 moves, one to s+1."""
    rng = random.Random(seed)
    alphabet = [f"ev.{i}" for i in range(labels)]
    trans = []
    for s in range(states):
        picks = rng.sample(alphabet, k=min(labels, rng.randint(1, 4)))
        trans.append((s, picks[0], (s + 1) % states))
        trans += [(s, a, rng.randrange(states)) for a in picks[1:]]
    return make_lts("Random", states, trans)


def load(path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(path.stem, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def measure(module: ModuleType, steps: int, seed: int) -> tuple[float, int]:
    """Return (seconds, steps) for a random walk of ``steps`` events."""
    ctrl = module.make_controller()
    delta = module.TABLE.delta
    rng = random.Random(seed)
    path = []
    s = module.TABLE.initial
    for _ in range(steps):
        row = delta[s]
        if not row:
            break
        a = rng.choice(sorted(row))
        path.append(a)
        s = row[a]
    step = ctrl.step
    t0 = time.perf_counter()
    for a in path:
        step(a)
    return time.perf_counter() - t0, len(path)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("module", nargs="?", help="a generated controller module (.py)")
    ap.add_argument("--states", type=int, help="benchmark a random controller of this size")
    ap.add_argument("--steps", type=int, default=1_000_000)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)

    if args.module:
        path = Path(args.module)
    else:
        lts = (random_controller(args.states, 64, args.seed) if args.states else fire_patrol())
        ctrl = frozenset(sorted(lts.alphabet)[::2]) if args.states else frozenset(
            {"has.next", "remove.next", "reset", "is.next.inP", "go.next", "is.fire",
             "take.photo"})
        t0 = time.perf_counter()
        text = emit_module(lts, controllable=ctrl, name=lts.name, source_name="bench.lts",
                           spec_hash="0" * 64, origins=None)
        t_emit = time.perf_counter() - t0
        tmp = Path(tempfile.mkdtemp(prefix="iterplan-bench-"))
        path = tmp / "bench_controller.py"
        path.write_text(text, encoding="utf-8")
        print(f"emitted {lts.name}: {lts.num_states} states, {lts.num_transitions} transitions, "
              f"{len(text) / 1024:.0f} KiB in {t_emit * 1e3:.1f} ms")
    t0 = time.perf_counter()
    module = load(path)
    print(f"import: {(time.perf_counter() - t0) * 1e3:.1f} ms")
    best = None
    for rep in range(3):
        secs, n = measure(module, args.steps, args.seed + rep)
        best = secs / n if best is None else min(best, secs / n)
    assert best is not None
    print(f"python {sys.version.split()[0]}: {1 / best:,.0f} steps/s  "
          f"({best * 1e9:.0f} ns/step, best of 3 x {args.steps:,} steps)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
