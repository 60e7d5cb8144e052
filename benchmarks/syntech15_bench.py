"""SYNTECH15 benchmark: per-file verdict, time, peak BDD nodes and peak memory.

    python benchmarks/syntech15_bench.py [FOLDER] [--timeout 60] [--composite Control]

FOLDER defaults to ../shared/benchmarks/syntech15 (relative to the repository).  Files at the
top of FOLDER are expected realizable, files under ``unrealizable/`` unrealizable.  Each file
runs in its own process (``--one FILE``), so the reported peak RSS is that file's alone and a
time-out kills only that run.  Time is wall-clock of the whole process (load, elaboration,
synthesis, controller extraction and minimisation) and its CPU time (user + system; on a
shared, loaded machine the wall time can be 2× the CPU time).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

DEFAULT = Path(__file__).resolve().parents[2] / "shared" / "benchmarks" / "syntech15"


def run_one(path: str, composite: str) -> dict:
    """Synthesise ``composite`` of ``path`` in this process; the result as a dict."""
    import warnings

    warnings.simplefilter("ignore")
    from iterplan_compiler import limits
    from iterplan_compiler.diagnostics import has_errors
    from iterplan_compiler.pipeline import load_model_with_sources as load_with_sources
    from iterplan_compiler.synthesis.driver import synthesize

    # the translated specs exceed the interactive defaults (GyroLTLVar2_701's G5 has 13
    # temporal subformulas, over --max-temporal-ops 10): a benchmark measures the engine,
    # the time-out is the limit
    limits.set_limits(max_temporal_ops=24, max_states=50_000_000, max_memory_mb=16_000)
    model, diags, _ = load_with_sources(path)
    if model is None or has_errors(diags):
        return {"verdict": "error"}
    problem, pdiags = model.synthesis_problem(composite)
    if problem is None or has_errors(pdiags):
        return {"verdict": "error", "why": [str(d) for d in pdiags][:2]}
    result = synthesize(problem, explain=False)
    st = result.stats
    return {"verdict": "realizable" if result.realizable else "unrealizable",
            "game_states": st.get("game_states"), "peak_bdd_nodes": st.get("peak_bdd_nodes"),
            "controller_states": st.get("controller_states")}


def measure(path: Path, composite: str, timeout: float) -> dict:
    t = time.perf_counter()
    proc = subprocess.Popen([sys.executable, __file__, "--one", str(path), "--composite",
                             composite], stdout=subprocess.PIPE, text=True)
    try:
        out, _ = proc.communicate(timeout=timeout)
        res = json.loads(out.strip().splitlines()[-1]) if out.strip() else {"verdict": "crash"}
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        res = {"verdict": f"timeout (>{timeout:g}s)"}
    res["seconds"] = time.perf_counter() - t
    # ru_maxrss of the children so far is a running max; each run is measured in isolation
    # by the caller printing it right after the run (monotone, so report it only if it grew)
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    res["peak_rss_mb"] = ru.ru_maxrss / 1024
    res["cpu"] = ru.ru_utime + ru.ru_stime
    return res


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default=str(DEFAULT))
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--composite", default="Control")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(run_one(args.one, args.composite)))
        return 0
    folder = Path(args.folder)
    files = [(p, "realizable") for p in sorted(folder.glob("*.fsp"))]
    files += [(p, "unrealizable") for p in sorted((folder / "unrealizable").glob("*.fsp"))]
    print("| file | expected | verdict | wall (s) | CPU (s) | peak BDD nodes | peak RSS (MB) |")
    print("|---|---|---|---|---|---|---|")
    ok = 0
    for path, expected in files:
        # a fresh interpreter per file; RUSAGE_CHILDREN is a max over finished children, so
        # run each measurement through its own intermediate process to isolate it
        res = _isolated(path, args.composite, args.timeout)
        good = res["verdict"] == expected
        ok += good
        print(f"| {path.name} | {expected} | {res['verdict']}{'' if good else ' ✗'} | "
              f"{res['seconds']:.1f} | {res['cpu']:.1f} | {res.get('peak_bdd_nodes') or '-'} | "
              f"{res['peak_rss_mb']:.0f} |", flush=True)
    print(f"\n{ok}/{len(files)} files give the expected verdict within {args.timeout:g} s")
    return 0 if ok == len(files) else 1


def _isolated(path: Path, composite: str, timeout: float) -> dict:
    """:func:`measure` in a forked child, so its RUSAGE_CHILDREN covers this file only."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - child
        os.close(r)
        res = measure(path, composite, timeout)
        os.write(w, json.dumps(res).encode())
        os._exit(0)
    os.close(w)
    data = b""
    while chunk := os.read(r, 65536):
        data += chunk
    os.close(r)
    os.waitpid(pid, 0)
    return json.loads(data.decode())


if __name__ == "__main__":
    sys.exit(main())
