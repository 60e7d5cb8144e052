"""CPU seconds to the GR(1) verdict under different CUDD manager settings (A/B, interleaved).

    python benchmarks/cudd_settings.py FILE [FILE ...] --setting NAME=JSON [--setting ...]
        [--pairs 3] [--timeout 200]

A setting is a JSON object with any of ``memory_estimate`` (bytes), ``initial_cache_size``
(entries) — the two ``dd.cudd.BDD`` constructor arguments — and ``configure`` (a dict passed
to ``BDD.configure`` after the manager's own: ``min_hit``, ``loose_up_to``,
``garbage_collection``, ``max_cache_hard``, ``max_memory``) and ``env`` (environment variables
of the child, e.g. ``GLIBC_TUNABLES``); ``{}`` is the tree's own
``new_manager``, ``"default"`` (the string) plain ``dd.cudd.BDD()``.  Each run is a fresh
process of this tree (``--one``) that stops at the verdict (``verdict: ...`` of
``synthesis.game``, before the controller enumeration) and reports its CPU seconds then, the
CPU of reachability and of the fixpoint, its peak RSS, and CUDD's counters (cache lookups,
hits, insertions, final cache and unique-table size, garbage collections and their time,
read through the manager's C API with ``ctypes``).  Runs go round-robin over the settings
(A B C A B C ...), so a load change on this shared machine hits every setting alike; the
table shows medians over the rounds and each setting's ratio to the first one.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # measure the tree this script is in


def _cudd_lib() -> Any:
    import dd.cudd

    lib = ctypes.CDLL(dd.cudd.__file__)
    for name, res in (("Cudd_ReadGarbageCollections", ctypes.c_int),
                      ("Cudd_ReadGarbageCollectionTime", ctypes.c_long),
                      ("Cudd_ReadSlots", ctypes.c_uint), ("Cudd_ReadCacheSlots", ctypes.c_uint)):
        getattr(lib, name).argtypes = [ctypes.c_void_p]
        getattr(lib, name).restype = res
    return lib


def _counters(bdd: Any) -> dict[str, Any]:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = bdd.statistics()
    out = {k: s[k] for k in ("cache_size", "cache_lookups", "cache_hits", "cache_insertions",
                             "cache_collisions", "unique_size", "peak_live_nodes",
                             "peak_nodes", "mem")}
    from iterplan_compiler.symbolic.backoff import manager_pointer

    lib = _cudd_lib()
    p = manager_pointer(bdd)  # the checked read of the package (dd 0.6.0 only)
    if p is not None:
        out["gc"] = lib.Cudd_ReadGarbageCollections(p)
        out["gc_s"] = lib.Cudd_ReadGarbageCollectionTime(p) / 1000
    return out


def run_one(path: str, composite: str, setting: Any) -> dict[str, Any]:
    from benchmarks.syntech15_bench import load_problem
    from iterplan_compiler.symbolic import bdd as bddmod
    from iterplan_compiler.synthesis import driver, game, symbolic_game

    managers: list[Any] = []
    own = bddmod.new_manager

    def new_manager(*, backend: str | None = None, reordering: bool = False) -> Any:
        if setting == "default":
            import dd.cudd

            m = dd.cudd.BDD()
            m.configure(reordering=reordering)
        elif setting:
            import dd.cudd

            kw = {k: setting[k] for k in ("memory_estimate", "initial_cache_size")
                  if k in setting}
            m = dd.cudd.BDD(**kw)
            m.configure(reordering=reordering, **setting.get("configure", {}))
        else:
            m = own(backend=backend, reordering=reordering)
        managers.append(m)
        return m

    symbolic_game.new_manager = new_manager  # type: ignore[assignment]
    cpu = {"reach": 0.0, "fixpoint": 0.0}

    def timed(phase: str, fn: Any) -> Any:
        def wrapper(*a: Any, **kw: Any) -> Any:
            t = time.process_time()
            try:
                return fn(*a, **kw)
            finally:
                cpu[phase] += time.process_time() - t
        return wrapper

    cls = symbolic_game.SymbolicGame
    cls.reachable = timed("reach", cls.reachable)  # type: ignore[method-assign]
    cls.restrict = timed("reach", cls.restrict)  # type: ignore[method-assign]
    game.gr1_winning = timed("fixpoint", game.gr1_winning)
    problem, why = load_problem(path, composite)
    if problem is None:
        return {"verdict": "error", "why": why}

    def progress(msg: str) -> None:
        if msg.startswith("verdict:"):
            res = {"verdict": msg.split()[1], "cpu": time.process_time(), **cpu,
                   "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                   **_counters(managers[-1])}
            print(json.dumps(res), flush=True)
            os._exit(0)

    result = driver.synthesize(problem, explain=False, progress=progress)
    return {"verdict": "realizable" if result.realizable else "unrealizable", "no_verdict": 1}


def measure(path: str, composite: str, setting: Any, timeout: float) -> dict[str, Any]:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        p for p in (os.environ.get("PYTHONPATH"), str(ROOT)) if p))
    if isinstance(setting, dict):
        env.update(setting.get("env", {}))
    t = time.perf_counter()
    try:
        proc = subprocess.run([sys.executable, __file__, "--one", path, "--composite", composite,
                               "--setting-json", json.dumps(setting)],
                              stdout=subprocess.PIPE, text=True, timeout=timeout, env=env,
                              check=False)
    except subprocess.TimeoutExpired:
        return {"verdict": "timeout", "wall": time.perf_counter() - t}
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    res = json.loads(lines[-1]) if lines else {"verdict": "crash"}
    res["wall"] = time.perf_counter() - t
    res["load"] = os.getloadavg()[0]
    return res


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="*")
    ap.add_argument("--setting", action="append", default=[], help="NAME=JSON")
    ap.add_argument("--pairs", type=int, default=3, help="rounds over all settings")
    ap.add_argument("--timeout", type=float, default=200.0)
    ap.add_argument("--composite", default="Control")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    ap.add_argument("--setting-json", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(run_one(args.one, args.composite, json.loads(args.setting_json))))
        return 0
    settings = [(s.split("=", 1)[0], json.loads(s.split("=", 1)[1])) for s in args.setting]
    if not settings:
        settings = [("tree", {})]
    for path in args.files:
        runs: dict[str, list[dict[str, Any]]] = {name: [] for name, _ in settings}
        for rnd in range(args.pairs):
            order = settings if rnd % 2 == 0 else settings[::-1]
            for name, setting in order:
                r = measure(path, args.composite, setting, args.timeout)
                runs[name].append(r)
                print(f"# {Path(path).name} round {rnd} {name}: {json.dumps(r)}", flush=True)
        base = None
        print(f"\n{Path(path).name}\n| setting | CPU to verdict (median; runs) | ratio | reach | "
              "fixpoint | hit rate | insertions (M) | GC (n / s) | cache slots | RSS MB |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        for name, _ in settings:
            rs = [r for r in runs[name] if "cpu" in r]
            if not rs:
                print(f"| {name} | {runs[name][0].get('verdict')} |")
                continue
            med = statistics.median(r["cpu"] for r in rs)
            base = base or med
            last = rs[-1]
            hit = last["cache_hits"] / max(1.0, last["cache_lookups"])
            print(f"| {name} | {med:.1f} ({', '.join(format(r['cpu'], '.1f') for r in rs)}) | "
                  f"{med / base:.2f} | {statistics.median(r['reach'] for r in rs):.1f} | "
                  f"{statistics.median(r['fixpoint'] for r in rs):.1f} | {hit:.0%} | "
                  f"{last['cache_insertions'] / 1e6:.1f} | {last.get('gc', '-')} / "
                  f"{last.get('gc_s', '-')} | {last['cache_size']} | "
                  f"{max(r['rss_mb'] for r in rs):.0f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
