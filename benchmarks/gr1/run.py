"""Sweep the GR(1) benchmark families with ``iterc solve`` and compare against the anchors.

Each instance is generated (``generators.py``), then solved in a fresh subprocess
(``python -m iterplan_compiler.cli solve FILE --json``) with a per-instance time limit; a
family's sweep stops after the first instance that exceeds the limit.  Runs are strictly
sequential (two CPU-bound jobs on this 2-vCPU machine distort each other by 40–100 %).

Outputs (in ``--out``, default ``/tmp/gr1-bench``): ``results.csv``, ``time_vs_n.png`` and
``summary.md`` (largest n within the limit per family, and our times at the anchor n values
next to the numbers measured for omega/slugs/gr1c in ``shared/docs/gr1-anchors.md``).

    python benchmarks/gr1/run.py                   # realizability sweep, 60 s limit
    python benchmarks/gr1/run.py --synthesis       # also build strategies
    python benchmarks/gr1/run.py --quick           # small n only (a smoke run, ~1 min)
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(HERE))

from generators import FAMILIES, VERDICTS  # noqa: E402

SCHEDULES: dict[str, list[int]] = {
    "arbiter": [2, 5, 10, 15, 20, 25, 30, 35, 40, 50, 60, 70, 80, 100, 120],
    "lift": [2, 5, 10, 15, 20, 25, 30, 35, 40, 50, 60, 70, 80, 100, 120],
    "lift_gr1c": [2, 5, 10, 20, 30, 40, 50, 60, 70, 80, 100],
    "genbuf": [2, 5, 8, 11, 14, 17, 20, 23, 26, 29, 32, 35, 38, 41, 44, 50, 60, 70, 80, 100],
    "amba_jcss12": [2, 3, 4, 5, 6, 7, 8, 9, 10],
    "amba_fm15": [2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 18, 20, 25, 30, 35, 40],
    "synt15": [2, 4, 8, 13, 20, 30, 40, 50, 60],
    "arbiter_immediate": [2, 10, 40],
    "amba_nohready": [2, 4, 8],
    "genbuf_noreceiver": [2, 10, 40],
}
QUICK: dict[str, list[int]] = {
    "arbiter": [2, 5, 10],
    "lift": [2, 5, 10],
    "lift_gr1c": [2, 5, 10],
    "genbuf": [2, 5, 8],
    "amba_jcss12": [2, 3],
    "amba_fm15": [2, 3, 4],
    "synt15": [2, 4, 8],
    "arbiter_immediate": [2, 5],
    "amba_nohready": [2, 3],
    "genbuf_noreceiver": [2, 5],
}

# Anchor numbers from shared/docs/gr1-anchors.md §5 (realizability, wall seconds, this
# machine).  Their instances are the published slugsin files; ours are re-encodings of the
# same specifications (see generators.py), so compare growth, not single digits.
ANCHORS: dict[tuple[str, int], dict[str, float]] = {
    ("synt15", 8): {"omega": 4.439, "slugs": 6.06, "gr1c": 0.84},
    ("synt15", 13): {"omega": 7.9, "slugs": 51.21, "gr1c": 1.85},
    ("synt15", 20): {"omega": 4.904, "gr1c": 1.81},
    ("synt15", 40): {"omega": 24.916, "gr1c": 4.46},
    ("synt15", 60): {"gr1c": 42.11},
    ("amba_jcss12", 4): {"gr1c": 7.52, "omega": 10.471, "slugs": 61.75},
    ("amba_jcss12", 6): {"gr1c": 50.93, "omega": 41.89},
    ("genbuf", 44): {"omega": 12.58, "gr1c": 39.49},
    ("genbuf", 29): {"omega": 4.496, "slugs": 15.27, "gr1c": 9.57},
    ("arbiter", 40): {"gr1c": 1.92, "slugs": 5.61, "omega": 16.646},
    # gr1c's lift generator (the anchors' instances); n=50/60 gr1c numbers from issue #12
    ("lift_gr1c", 20): {"gr1c": 0.1, "slugs": 0.92, "omega": 0.497},
    ("lift_gr1c", 40): {"gr1c": 0.92, "slugs": 10.49, "omega": 4.166},
    ("lift_gr1c", 50): {"gr1c": 1.6},
    ("lift_gr1c", 60): {"gr1c": 3.6},
}
ANCHOR_FAMILY_NAMES = {"amba_jcss12": "jcss12"}

FIELDS = ["family", "n", "expected", "realizable", "status", "wall_s", "build_s", "winning_s",
          "strategy_s", "total_cpu_s", "winning_cpu_s", "strategy_cpu_s", "peak_rss_mb", "peak_live_nodes", "reordering_s", "winning_nodes",
          "strategy_nodes", "variables"]


def run_one(family: str, n: int, workdir: Path, limit: float, synthesis: bool,
            extra: list[str]) -> dict:
    path = workdir / f"{family}_{n}.slugsin"
    path.write_text(FAMILIES[family](n), encoding="utf-8")
    cmd = [sys.executable, "-m", "iterplan_compiler.cli", "solve", str(path), "--json", *extra]
    if not synthesis:
        cmd.append("--realizability-only")
    row: dict = {"family": family, "n": n, "expected": VERDICTS[family]}
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=limit, cwd=ROOT)
    except subprocess.TimeoutExpired:
        row.update(status="timeout", wall_s=round(time.perf_counter() - t0, 3))
        return row
    row["wall_s"] = round(time.perf_counter() - t0, 3)
    try:
        data = json.loads(proc.stdout.strip().splitlines()[-1])
    except (json.JSONDecodeError, IndexError):
        row.update(status=f"error(rc={proc.returncode})")
        sys.stderr.write(proc.stderr[-2000:])
        return row
    row.update(
        realizable=data["realizable"],
        status="ok" if data["realizable"] == VERDICTS[family] else "WRONG",
        build_s=round(data["build_s"], 3),
        winning_s=round(data["winning_s"], 3),
        strategy_s=round(data["strategy_s"], 3),
        total_cpu_s=round(data["total_cpu_s"], 3),
        winning_cpu_s=round(data["winning_cpu_s"], 3),
        strategy_cpu_s=round(data["strategy_cpu_s"], 3),
        peak_rss_mb=round(data["peak_rss_mb"], 1),
        peak_live_nodes=data.get("peak_live_nodes"),
        reordering_s=data.get("reordering_s"),
        winning_nodes=data.get("winning_nodes"),
        strategy_nodes=data.get("strategy_nodes"),
        variables=data.get("variables"),
    )
    return row


def plot(rows: list[dict], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for fam in dict.fromkeys(r["family"] for r in rows):
        pts = [(r["n"], r["wall_s"]) for r in rows if r["family"] == fam and r["status"] == "ok"]
        if pts:
            ax.plot(*zip(*pts, strict=True), marker="o", label=fam)
    ax.set_xlabel("n (family parameter)")
    ax.set_ylabel("wall time [s] (incl. Python start-up)")
    ax.set_yscale("log")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("iterc solve: GR(1) benchmark families")
    fig.tight_layout()
    fig.savefig(out, dpi=120, metadata={"Software": None})
    plt.close(fig)


def summary(rows: list[dict], limit: float) -> str:
    lines = [f"## Largest n solved within {limit:g} s", "",
             "| family | largest n | wall s there | verdicts |", "|---|---|---|---|"]
    for fam in dict.fromkeys(r["family"] for r in rows):
        ok = [r for r in rows if r["family"] == fam and r["status"] == "ok"
              and r["wall_s"] <= limit]
        wrong = [r for r in rows if r["family"] == fam and r["status"] == "WRONG"]
        best = max(ok, key=lambda r: r["n"]) if ok else None
        lines.append(f"| {fam} | {best['n'] if best else '-'} | "
                     f"{best['wall_s'] if best else '-'} | "
                     f"{'all correct' if not wrong else f'{len(wrong)} WRONG'} |")
    lines += ["", "## At the anchor points (realizability wall seconds)", "",
              "| instance | ours: wall / winning set / winning-set CPU s | omega | slugs | gr1c |",
              "|---|---|---|---|---|"]
    for (fam, n), anc in ANCHORS.items():
        r = next((r for r in rows if r["family"] == fam and r["n"] == n), None)
        if r is None:
            continue
        ours = (f"{r['wall_s']} / {r.get('winning_s', '-')} / {r.get('winning_cpu_s', '-')}"
                if r["status"] == "ok"
                else r["status"])
        name = f"{ANCHOR_FAMILY_NAMES.get(fam, fam)} n={n}"
        lines.append(f"| {name} | {ours} | {anc.get('omega', '')} | {anc.get('slugs', '')} | "
                     f"{anc.get('gr1c', '')} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--families", nargs="*", default=list(SCHEDULES),
                    choices=sorted(SCHEDULES), help="families to run (default: all)")
    ap.add_argument("--limit", type=float, default=60.0, help="seconds per instance")
    ap.add_argument("--max-n", type=int, default=None, help="skip n above this")
    ap.add_argument("--quick", action="store_true", help="small n only")
    ap.add_argument("--synthesis", action="store_true", help="also construct strategies")
    ap.add_argument("--out", default="/tmp/gr1-bench", help="output directory")
    ap.add_argument("--solver-args", default="", help="extra arguments for iterc solve")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows: list[dict] = []
    extra = args.solver_args.split()
    with tempfile.TemporaryDirectory(prefix="gr1-bench-") as tmp:
        for fam in args.families:
            sched = (QUICK if args.quick else SCHEDULES)[fam]
            for n in sched:
                if args.max_n is not None and n > args.max_n:
                    break
                row = run_one(fam, n, Path(tmp), args.limit, args.synthesis, extra)
                rows.append(row)
                print(f"{fam:18s} n={n:<4d} {row['status']:8s} wall {row['wall_s']:8.2f} s"
                      f"  win {row.get('winning_s', '-')} (cpu {row.get('winning_cpu_s', '-')})"
                      f"  strat {row.get('strategy_s', '-')}"
                      f"  rss {row.get('peak_rss_mb', '-')} MB", flush=True)
                if row["status"] != "ok" or row["wall_s"] > args.limit:
                    break
    with open(out / "results.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    plot(rows, out / "time_vs_n.png")
    text = summary(rows, args.limit)
    (out / "summary.md").write_text(text, encoding="utf-8")
    print()
    print(text)
    wrong = [r for r in rows if r["status"] == "WRONG"]
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
