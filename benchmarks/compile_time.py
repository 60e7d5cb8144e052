"""Whole-process ``iterc compile`` time of the paper's tasks (issue #12: < 0.5 s each).

For every example in ``examples/`` it runs ``python -m iterplan_compiler.cli compile`` as a
fresh process ``--runs`` times and prints the median wall and CPU (user + system of the child)
time, warm (the per-user caches filled: Lark tables, compiled safety LTSs) and cold (an empty
cache folder each run), plus the import cost of ``iterplan_compiler.pipeline``.

Python's own bytecode cache is not one of iterc's caches: by default the children inherit the
environment's setting (with ``PYTHONDONTWRITEBYTECODE=1`` every process compiles every module
from source, ~0.1 s that no installed copy pays); ``--bytecode`` gives them a private,
pre-filled one (``PYTHONPYCACHEPREFIX``), as a pip-installed package has, for warm and cold.

    python benchmarks/compile_time.py [--runs 5] [--bytecode]
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
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
    ap.add_argument("--bytecode", action="store_true",
                    help="children use a private, pre-filled bytecode cache (an installed "
                         "package's .pyc files) instead of the environment's setting")
    args = ap.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="iterplan-compile-time-"))
    try:
        return _measure(args, scratch)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _scratch(scratch: Path) -> str:
    return tempfile.mkdtemp(dir=scratch)


def _measure(args: argparse.Namespace, scratch: Path) -> int:
    out = Path(_scratch(scratch))
    warm_cache = _scratch(scratch)
    base = dict(os.environ)
    if args.bytecode:
        base.pop("PYTHONDONTWRITEBYTECODE", None)
        base["PYTHONPYCACHEPREFIX"] = _scratch(scratch)
    print("bytecode: " + ("private pre-filled cache (--bytecode)" if args.bytecode else
                          "off (PYTHONDONTWRITEBYTECODE): every module compiled from source"
                          if base.get("PYTHONDONTWRITEBYTECODE") else "environment default"))
    imp_cmd = [sys.executable, "-c", "import iterplan_compiler.pipeline"]
    _run(imp_cmd, {**base, "XDG_CACHE_HOME": warm_cache})   # fill the bytecode cache, if any
    imp = [_run(imp_cmd, {**base, "XDG_CACHE_HOME": warm_cache}) for _ in range(args.runs)]
    print(f"import iterplan_compiler.pipeline: wall {statistics.median(w for w, _ in imp):.3f} s,"
          f" CPU {statistics.median(c for _, c in imp):.3f} s (median of {args.runs})")
    print(f"{'task':16} {'warm wall':>10} {'warm CPU':>9} {'cold wall':>10} {'cold CPU':>9}")
    for task in TASKS:
        cmd = [sys.executable, "-m", "iterplan_compiler.cli", "compile",
               str(ROOT / "examples" / f"{task}.lts"), "-o", str(out / f"{task}.py")]
        _run(cmd, {**base, "XDG_CACHE_HOME": warm_cache})   # fill the warm cache
        warm = [_run(cmd, {**base, "XDG_CACHE_HOME": warm_cache})
                for _ in range(args.runs)]
        if args.bytecode:   # the cold path imports modules the warm one does not (Lark)
            _run(cmd, {**base, "XDG_CACHE_HOME": _scratch(scratch)})
        cold = [_run(cmd, {**base, "XDG_CACHE_HOME": _scratch(scratch)})
                for _ in range(args.runs)]
        med = [statistics.median(x) for x in ([w for w, _ in warm], [c for _, c in warm],
                                               [w for w, _ in cold], [c for _, c in cold])]
        print(f"{task:16} {med[0]:9.3f}s {med[1]:8.3f}s {med[2]:9.3f}s {med[3]:8.3f}s")
    print(f"load average: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores "
          "(wall time is noisy on a loaded machine; CPU time is the steadier figure)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
