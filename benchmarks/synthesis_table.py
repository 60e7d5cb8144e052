"""Print the synthesis-time table: iterator-based examples (constant in the number of
locations) vs the explicit-location Fire Patrol and the Ordered Patrol for growing N.

    python benchmarks/synthesis_table.py                 # N = 1..8, 60 s budget per synthesis
    python benchmarks/synthesis_table.py --max-n 4 --budget 10
(also: iterc experiment synthesis-table)
"""

from __future__ import annotations

import argparse
import sys

from iterplan_compiler.experiments.synthesis_table import format_table, table


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-n", type=int, default=8)
    ap.add_argument("--budget", type=float, default=60.0, help="seconds per synthesis")
    args = ap.parse_args(argv)
    rows = table(list(range(1, args.max_n + 1)), budget_s=args.budget)
    print(format_table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
