"""Reproduce the paper's Fig. 3 (b)-(d) and print the numbers next to the paper's.

    python benchmarks/experiments.py --quick            # CI sizes, a minute or two
    python benchmarks/experiments.py -j 2               # full sizes (hours: 700,000 locations,
                                                        # 30 seeds per point for fig3b)
    python benchmarks/experiments.py fig3b --seeds 3 -j 2

Same as ``iterc experiment all``; results (CSV, PNG) go to ./iterplan-experiments.
"""

from __future__ import annotations

import sys

from iterplan_compiler import cli

PAPER = {
    "fig3b": "paper: Ordered Patrol loop overhead at most 88 % over ideal at 700,000 locations",
    "fig3c": "paper: Cover with the distance sorter ~60 % overhead, near constant in N",
    "fig3d": "paper: Cover of 61 locations, near constant duration as the universe grows",
}


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    names = [a for a in args if a in ("fig3b", "fig3c", "fig3d", "synthesis-table", "all")]
    if not names:
        args = ["all", *args]
        names = ["all"]
    rc = cli.main(["experiment", *args])
    for n in (PAPER if "all" in names else names):
        if n in PAPER:
            print(PAPER[n])
    return rc


if __name__ == "__main__":
    sys.exit(main())
