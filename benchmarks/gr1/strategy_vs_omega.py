"""Strategy extraction, ours vs omega, on identical slugsin instances (issue 12).

For each instance the spec is generated (``generators.py``), then solved in a fresh
subprocess, one process at a time (the machine is shared; two CPU-bound jobs distort each
other), by

* ours: ``python -m iterplan_compiler.cli solve FILE --json`` (strategy included), and
* omega 0.4.0: ``omega_anchor.py FILE --strategy`` in a separate venv (``--omega-python``;
  omega is *not* a dependency: ``python -m venv --system-site-packages /tmp/omega-venv &&
  /tmp/omega-venv/bin/pip install omega dd``), which builds the same BDDs with our reader.

Printed per instance: winning-set CPU s, strategy-extraction CPU s, strategy BDD nodes
(ours: ``⋁_j (goal = j) ∧ S_j`` with a binary goal counter; omega: its transducer
``aut.action['impl']``, goal counter included) and the verdict, plus the load average
before and after the run.  CPU seconds (``time.process_time``) are the robust figure on a
loaded machine.

    python benchmarks/gr1/strategy_vs_omega.py                       # the default instances
    python benchmarks/gr1/strategy_vs_omega.py genbuf:17 lift:40 --no-omega
    python benchmarks/gr1/strategy_vs_omega.py genbuf:17 --ours-args "--strategy-reordering off"
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(HERE))

from generators import FAMILIES, VERDICTS  # noqa: E402

DEFAULT_INSTANCES = ["genbuf:17", "genbuf:38", "lift:40", "amba_jcss12:4", "amba_fm15:5"]
DEFAULT_OMEGA = "/tmp/omega-venv/bin/python"


@dataclass
class Row:
    """One tool's result on one instance."""

    tool: str
    status: str
    realizable: bool | None = None
    winning_cpu_s: float | None = None
    strategy_cpu_s: float | None = None
    strategy_nodes: int | None = None


def _run_json(cmd: list[str], limit: float) -> tuple[str, dict[str, Any]]:
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=limit, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return f"timeout>{limit:g}s", {}
    try:
        return "ok", json.loads(proc.stdout.strip().splitlines()[-1])
    except (json.JSONDecodeError, IndexError):
        sys.stderr.write(proc.stderr[-2000:])
        return f"error(rc={proc.returncode})", {}


def run_ours(path: Path, limit: float, extra: list[str]) -> Row:
    cmd = [sys.executable, "-m", "iterplan_compiler.cli", "solve", str(path), "--json", *extra]
    status, d = _run_json(cmd, limit)
    if status != "ok":
        return Row("ours", status)
    return Row("ours", status, d["realizable"], d["winning_cpu_s"], d["strategy_cpu_s"],
               d.get("strategy_nodes"))


def run_omega(path: Path, limit: float, python: str) -> Row:
    cmd = [python, str(HERE / "omega_anchor.py"), str(path), "--strategy"]
    status, d = _run_json(cmd, limit)
    if status != "ok" or "error" in d:
        return Row("omega", status if status != "ok" else "error")
    return Row("omega", status, d["realizable"], d["winning_cpu_s"], d.get("strategy_cpu_s"),
               d.get("strategy_nodes"))


def _fmt(v: float | int | None, unit: str = "") -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.2f}{unit}"
    return f"{v / 1000:.1f} k" if v >= 1000 else str(v)


def _verdict(r: Row, expected: bool) -> str:
    if r.realizable is None:
        return r.status
    ok = "ok" if r.realizable == expected else "WRONG"
    return f"{'real.' if r.realizable else 'unreal.'} ({ok})"


def table(results: list[tuple[str, bool, Row, Row | None]]) -> str:
    lines = ["| instance | winning CPU s ours / omega | strategy CPU s ours / omega | "
             "strategy nodes ours / omega | verdict ours / omega |",
             "|---|---|---|---|---|"]
    for name, expected, ours, om in results:
        o = om or Row("omega", "not run")
        lines.append(
            f"| {name} | {_fmt(ours.winning_cpu_s)} / {_fmt(o.winning_cpu_s)} | "
            f"{_fmt(ours.strategy_cpu_s)} / {_fmt(o.strategy_cpu_s)} | "
            f"{_fmt(ours.strategy_nodes)} / {_fmt(o.strategy_nodes)} | "
            f"{_verdict(ours, expected)} / {_verdict(o, expected)} |")
    return "\n".join(lines)


def parse_instance(text: str) -> tuple[str, int]:
    fam, _, n = text.partition(":")
    if fam not in FAMILIES or not n.isdigit():
        raise argparse.ArgumentTypeError(f"expected FAMILY:N with FAMILY in {sorted(FAMILIES)}")
    return fam, int(n)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("instances", nargs="*", type=parse_instance,
                    default=[parse_instance(s) for s in DEFAULT_INSTANCES],
                    help=f"FAMILY:N (default: {' '.join(DEFAULT_INSTANCES)})")
    ap.add_argument("--omega-python", default=DEFAULT_OMEGA,
                    help=f"python of a venv with omega installed (default {DEFAULT_OMEGA})")
    ap.add_argument("--no-omega", action="store_true", help="run ours only")
    ap.add_argument("--ours-args", default="", help="extra arguments for iterc solve")
    ap.add_argument("--limit", type=float, default=600.0, help="seconds per run")
    args = ap.parse_args(argv)
    run_omega_too = not args.no_omega and Path(args.omega_python).exists()
    load0 = os.getloadavg()
    results: list[tuple[str, bool, Row, Row | None]] = []
    with tempfile.TemporaryDirectory(prefix="gr1-strat-") as tmp:
        for fam, n in args.instances:
            path = Path(tmp) / f"{fam}_{n}.slugsin"
            path.write_text(FAMILIES[fam](n), encoding="utf-8")
            ours = run_ours(path, args.limit, args.ours_args.split())
            om = run_omega(path, args.limit, args.omega_python) if run_omega_too else None
            results.append((f"{fam} n={n}", VERDICTS[fam], ours, om))
            print(table(results[-1:]).splitlines()[-1], flush=True)
    load1 = os.getloadavg()
    print()
    print(table(results))
    print(f"\nload average (1/5/15 min) before {load0[0]:.1f}/{load0[1]:.1f}/{load0[2]:.1f}, "
          f"after {load1[0]:.1f}/{load1[1]:.1f}/{load1[2]:.1f}")
    wrong = any(r.realizable is not None and r.realizable != exp
                for _, exp, ours, om in results for r in (ours, om) if r is not None)
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
