"""SYNTECH15 benchmark: per-file verdict, time, peak BDD nodes and peak memory.

    python benchmarks/syntech15_bench.py [FOLDER] [--timeout 60] [--composite Control]

FOLDER defaults to ../shared/benchmarks/syntech15 (relative to the repository).  Files at the
top of FOLDER are expected realizable, files under ``unrealizable/`` unrealizable.  Each file
runs in its own process (``--one FILE``), so the reported peak RSS is that file's alone and a
time-out kills only that run.  Time is wall-clock of the whole process (load, elaboration,
synthesis, controller extraction and minimisation) and its CPU time (user + system; on a
shared, loaded machine the wall time can be 2× the CPU time).  "verdict at" is when the GR(1)
fixpoint decided (``verdict: ... at N s`` of :mod:`synthesis.game`), before the explicit
controller enumeration: wall seconds since the process started / its CPU seconds then; a run
that times out during the enumeration still reports it, and is counted as "verdict within
the limit" (issue 12's target) but not as complete.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import selectors
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

DEFAULT = Path(__file__).resolve().parents[2] / "shared" / "benchmarks" / "syntech15"
_STARTED = time.perf_counter()


def load_problem(path: str, composite: str) -> tuple[Any, list[str]]:
    """The synthesis problem ``composite`` of ``path`` from this checkout, with the
    interactive limits lifted, or ``(None, why)``.  Also used by ``synth_phases.py``."""
    import warnings

    warnings.simplefilter("ignore")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # measure this checkout
    from iterplan_compiler import limits
    from iterplan_compiler.diagnostics import has_errors
    from iterplan_compiler.pipeline import load_model_with_sources as load_with_sources

    # the translated specs exceed the interactive defaults (GyroLTLVar2_701's G5 has 13
    # temporal subformulas, over --max-temporal-ops 10): a benchmark measures the engine,
    # the time-out is the limit
    limits.set_limits(max_temporal_ops=24, max_states=50_000_000, max_memory_mb=16_000)
    model, diags, _ = load_with_sources(path)
    if model is None or has_errors(diags):
        return None, [str(d) for d in diags][:2]
    problem, pdiags = model.synthesis_problem(composite)
    if problem is None or has_errors(pdiags):
        return None, [str(d) for d in pdiags][:2]
    return problem, []


def run_one(path: str, composite: str) -> dict:
    """Synthesise ``composite`` of ``path`` in this process; the result as a dict."""
    problem, why = load_problem(path, composite)
    if problem is None:
        return {"verdict": "error", "why": why}
    from iterplan_compiler.synthesis.driver import synthesize

    def progress(msg: str) -> None:
        if msg.startswith("verdict:"):  # the fixpoint decided: tell the parent at once
            print(json.dumps({"early": msg.split()[1],
                              "verdict_wall": time.perf_counter() - _STARTED,
                              "verdict_cpu": time.process_time()}), flush=True)

    result = synthesize(problem, explain=False, progress=progress)
    st = result.stats
    return {"verdict": "realizable" if result.realizable else "unrealizable",
            "game_states": st.get("game_states"), "peak_bdd_nodes": st.get("peak_bdd_nodes"),
            "controller_states": st.get("controller_states")}


def measure(path: Path, composite: str, timeout: float) -> dict:
    t = time.perf_counter()
    proc = subprocess.Popen([sys.executable, __file__, "--one", str(path), "--composite",
                             composite], stdout=subprocess.PIPE, text=True)
    lines = _read_lines(proc, t + timeout)
    res: dict = {}
    for line in lines:  # the early verdict line, then the result
        res.update(json.loads(line))
    if proc.poll() is None:
        proc.kill()
        proc.wait()
        res["verdict"] = f"timeout (>{timeout:g}s)"
    elif "verdict" not in res:
        res["verdict"] = "crash"
    res["seconds"] = time.perf_counter() - t
    # ru_maxrss of the children so far is a running max; each run is measured in isolation
    # by the caller printing it right after the run (monotone, so report it only if it grew)
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    res["peak_rss_mb"] = ru.ru_maxrss / 1024
    res["cpu"] = ru.ru_utime + ru.ru_stime
    return res


def _read_lines(proc: subprocess.Popen, deadline: float) -> list[str]:
    """The child's stdout lines until it closes stdout or ``deadline`` passes."""
    assert proc.stdout is not None
    sel = selectors.DefaultSelector()
    sel.register(proc.stdout, selectors.EVENT_READ)
    out: list[str] = []
    while (left := deadline - time.perf_counter()) > 0:
        if not sel.select(timeout=left):
            continue
        line = proc.stdout.readline()
        if not line:
            proc.wait(timeout=max(0.1, deadline - time.perf_counter()))
            break
        if line.startswith("{"):
            out.append(line)
    sel.close()
    return out


def _verdict_at(res: dict) -> str:
    if "verdict_wall" not in res:
        return "-"
    return f"{res['verdict_wall']:.1f} / {res['verdict_cpu']:.1f}"


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
    print("| file | expected | verdict | verdict at (wall / CPU s) | wall (s) | CPU (s) | "
          "peak BDD nodes | peak RSS (MB) |")
    print("|---|---|---|---|---|---|---|---|")
    ok = decided = 0
    for path, expected in files:
        # a fresh interpreter per file; RUSAGE_CHILDREN is a max over finished children, so
        # run each measurement through its own intermediate process to isolate it
        res = _isolated(path, args.composite, args.timeout)
        good = res["verdict"] == expected
        ok += good
        decided += res.get("early") == expected
        print(f"| {path.name} | {expected} | {res['verdict']}{'' if good else ' ✗'} | "
              f"{_verdict_at(res)} | {res['seconds']:.1f} | {res['cpu']:.1f} | "
              f"{res.get('peak_bdd_nodes') or '-'} | {res['peak_rss_mb']:.0f} |", flush=True)
    print(f"\n{decided}/{len(files)} files reach the expected verdict within "
          f"{args.timeout:g} s; {ok}/{len(files)} also finish the controller")
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
