"""Markdown tables of `iterc experiment` summaries next to the paper's numbers.

    python benchmarks/results_table.py docs/results

Reads ``<dir>/*/fig3*_summary.csv`` (one sub-directory per sweep) and prints, per experiment,
mean +- 3 SEM of the overhead (and the kinematic floor's share, "physics") per size and sorter.
"""

from __future__ import annotations

import csv
import math
import sys
from collections import defaultdict
from pathlib import Path

PAPER = {
    "fig3b": "at most 88 % over ideal at 700,000 locations (3 sorters alike)",
    "fig3c": "distance ~60 %, near constant in N",
    "fig3d": "near-constant duration as the universe grows; sorter matters",
}


def fmt(mean: str, err: str) -> str:
    m, e = float(mean or "nan"), float(err or "nan")
    return "" if math.isnan(m) else f"{m:.1f} ± {e:.1f}"


def table(path: Path) -> str:
    rows = list(csv.DictReader(path.open()))
    exp = rows[0]["experiment"]
    xkey = "count" if exp == "fig3c" else "universe"
    sorters = sorted({r["sorter"] for r in rows})
    by = defaultdict(dict)
    for r in rows:
        by[int(r[xkey])][r["sorter"]] = r
    # sweeps measured after a warm-up loop also report the first loop (fig3b --warmup), and
    # newer fig3b sweeps the launch leg (s from the start to the first visit of p.0)
    extras = [(key, title) for key, title in (("first_loop", "first loop % (distance)"),
                                              ("launch", "launch s (distance)"))
              if any(r.get(f"{key}_pct" if key == "first_loop" else f"{key}_s")
                     not in (None, "", "nan") for r in rows)]
    head = f"| {xkey} | n | " + " | ".join(f"{s} overhead %" for s in sorters) + \
        "".join(f" | {title}" for _, title in extras) + \
        " | physics floor % (distance) | ideal s |"
    out = [f"**{exp}** ({path.parent.name}; paper: {PAPER.get(exp, '')})", "", head,
           "|" + "---|" * (len(sorters) + 4 + len(extras))]
    for x in sorted(by):
        cells = [fmt(by[x][s]["overhead_pct"], by[x][s]["overhead_err3"]) if s in by[x] else ""
                 for s in sorters]
        any_row = next(iter(by[x].values()))
        ref = by[x].get("distance", any_row)
        extra = "".join(
            f" | {fmt(ref.get('first_loop_pct', ''), ref.get('first_loop_err3', ''))}"
            if key == "first_loop" else
            f" | {fmt(ref.get('launch_s', ''), ref.get('launch_err3', ''))}"
            for key, _ in extras)
        out.append(f"| {x:,} | {any_row['n']} | " + " | ".join(cells) + extra +
                   f" | {fmt(ref.get('physics_pct', ''), ref.get('physics_err3', ''))} | "
                   f"{float(any_row['ideal']):.1f} |")
    return "\n".join(out)


def main(argv: list[str]) -> int:
    base = Path(argv[0] if argv else "docs/results")
    for p in sorted(base.glob("*/fig3*_summary.csv")):
        print(table(p))
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
