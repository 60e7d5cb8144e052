"""Whole-process ``iterc compile`` time of the paper's tasks (issue #12: < 0.5 s each).

For every example in ``examples/`` it runs ``python -m iterplan_compiler.cli compile`` as a
fresh process ``--runs`` times and prints the median wall and CPU (user + system of the child)
time, warm (the per-user caches filled: Lark tables, compiled safety LTSs) and cold (an empty
cache folder each run), plus the import cost of ``iterplan_compiler.pipeline``.

    python benchmarks/compile_time.py [--runs 5]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TASKS = ["fire_patrol", "cover", "find_nemo", "ordered_patrol", "search_and_map"]


def _run(args: list[str], env: dict[str, str]) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(args, env=env, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    out = Path(tempfile.mkdtemp(prefix="iterplan-compile-time-"))
    warm_cache = tempfile.mkdtemp(prefix="iterplan-cache-")
    imp = [_run([sys.executable, "-c", "import iterplan_compiler.pipeline"],
                {**os.environ, "XDG_CACHE_HOME": warm_cache}) for _ in range(args.runs)]
    print(f"import iterplan_compiler.pipeline: wall {statistics.median(w for w, _ in imp):.3f} s,"
          f" CPU {statistics.median(c for _, c in imp):.3f} s (median of {args.runs})")
    print(f"{'task':16} {'warm wall':>10} {'warm CPU':>9} {'cold wall':>10} {'cold CPU':>9}")
    for task in TASKS:
        cmd = [sys.executable, "-m", "iterplan_compiler.cli", "compile",
               str(ROOT / "examples" / f"{task}.lts"), "-o", str(out / f"{task}.py")]
        _run(cmd, {**os.environ, "XDG_CACHE_HOME": warm_cache})   # fill the warm cache
        warm = [_run(cmd, {**os.environ, "XDG_CACHE_HOME": warm_cache})
                for _ in range(args.runs)]
        cold = [_run(cmd, {**os.environ, "XDG_CACHE_HOME": tempfile.mkdtemp()})
                for _ in range(args.runs)]
        med = [statistics.median(x) for x in ([w for w, _ in warm], [c for _, c in warm],
                                               [w for w, _ in cold], [c for _, c in cold])]
        print(f"{task:16} {med[0]:9.3f}s {med[1]:8.3f}s {med[2]:9.3f}s {med[3]:8.3f}s")
    print(f"load average: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores "
          "(wall time is noisy on a loaded machine; CPU time is the steadier figure)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
