"""Solve the *published* SYNT'15 AMBA instances with ``iterc solve`` (optional benchmark).

The files are not shipped with iterplan: they are the compiled slugsin instances of the
``johnyf/gr1experiments`` repository (Filippidis & Murray, SYNT'15),
``examples/synt15/slugsin/synt15_<n>.txt`` with ``n`` = number of masters.  Put any of them
in a directory (keep the names) and run

    python benchmarks/gr1/published.py DIR                  # realizability, 3 runs each
    python benchmarks/gr1/published.py DIR --runs 1 --strategy --limit 120

Every ``synt15_<n>.txt`` (or ``.slugsin``) in DIR is solved in a fresh subprocess
(``python -m iterplan_compiler.cli solve FILE --json``), one at a time, under ``nice``;
the table gives n, verdict, the median CPU seconds of the whole run, CUDD's reordering
seconds, the number of reorderings and the peak live BDD nodes, next to the anchor numbers
of ``shared/docs/gr1-anchors.md`` (gr1c / omega / slugs wall seconds on the same files).
``--solver-args`` passes options through (e.g. ``--solver-args=--no-sift-after-build``).
Our own re-encoding of the same specification is the ``synt15`` family of
``generators.py`` (docs/gr1.md, "synt15").
"""

from __future__ import annotations

import argparse
import json
import re
import shlex
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
NAME = re.compile(r"synt15_(\d+)\.(txt|slugsin)$")
#: anchors on the published files (wall s), shared/docs/gr1-anchors.md §5 and issue 12
ANCHORS: dict[int, dict[str, float]] = {
    8: {"gr1c": 0.84, "omega": 4.439, "slugs": 6.06},
    13: {"gr1c": 1.85, "omega": 7.9, "slugs": 51.21},
    20: {"gr1c": 1.81, "omega": 4.904},
    40: {"gr1c": 4.46, "omega": 24.916},
    50: {"gr1c": 6.4},
    60: {"gr1c": 42.11},
}


def instances(directory: Path) -> list[tuple[int, Path]]:
    """``(n, path)`` of every published instance file in ``directory``, by ``n``."""
    found = [(int(m.group(1)), p) for p in directory.iterdir()
             if (m := NAME.fullmatch(p.name))]
    return sorted(found)


def solve_once(path: Path, limit: float, strategy: bool, extra: list[str]) -> dict:
    """One ``iterc solve --json`` run; ``{"status": "timeout"}`` past ``limit`` seconds."""
    cmd = ["nice", sys.executable, "-m", "iterplan_compiler.cli", "solve", str(path),
           "--format", "slugsin", "--json", *extra]
    if not strategy:
        cmd.append("--realizability-only")
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=limit, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return {"status": "timeout"}
    try:
        data = json.loads(proc.stdout.strip().splitlines()[-1])
    except (json.JSONDecodeError, IndexError):
        return {"status": f"error(rc={proc.returncode}): {proc.stderr.strip()[-300:]}"}
    data["status"] = "ok"
    return data


def row(n: int, runs: list[dict]) -> str:
    """One markdown table row (medians over the finished runs)."""
    ok = [r for r in runs if r["status"] == "ok"]
    anc = ANCHORS.get(n, {})
    anchors = " / ".join(f"{k} {v:g}" for k, v in anc.items()) or "-"
    if not ok:
        return f"| {n} | {runs[0]['status']} | - | - | - | - | - | {anchors} |"
    verdict = "REALIZABLE" if ok[0]["realizable"] else "UNREALIZABLE"
    if len({r["realizable"] for r in ok}) > 1:
        verdict = "INCONSISTENT"

    def med(key: str, digits: int = 2) -> str:
        vals = [float(r[key]) for r in ok if r.get(key) is not None]
        return f"{statistics.median(vals):.{digits}f}" if vals else "-"

    cpu = [float(r["total_cpu_s"]) for r in ok]
    spread = f" ({min(cpu):.2f}–{max(cpu):.2f})" if len(cpu) > 1 else ""
    return (f"| {n} | {verdict} | {med('total_cpu_s')}{spread} | {med('reordering_s')} | "
            f"{med('reorderings', 0)} | {med('trigger_raises', 0)} | {med('peak_live_nodes', 0)} | "
            f"{anchors} |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("directory", type=Path, help="directory holding synt15_<n>.txt files")
    ap.add_argument("--runs", type=int, default=3, help="runs per instance (median)")
    ap.add_argument("--limit", type=float, default=300.0, help="seconds per run")
    ap.add_argument("--strategy", action="store_true", help="also build the strategy")
    ap.add_argument("--solver-args", default="", help="extra arguments for iterc solve")
    args = ap.parse_args(argv)
    found = instances(args.directory)
    if not found:
        print(f"no synt15_<n>.txt in {args.directory}", file=sys.stderr)
        return 2
    extra = shlex.split(args.solver_args)
    print("| n | verdict | CPU s (median, range) | reordering s | reorderings | "
          "triggers backed off | peak live nodes | anchors (wall s) |")
    print("|---|---|---|---|---|---|---|---|")
    for n, path in found:
        runs = []
        for _ in range(args.runs):
            runs.append(solve_once(path, args.limit, args.strategy, extra))
            if runs[-1]["status"] != "ok":
                break  # a timeout or error repeats; do not wait for it again
        print(row(n, runs), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
