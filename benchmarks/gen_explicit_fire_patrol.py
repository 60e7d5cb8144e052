"""Write the explicit-location Fire Patrol spec for a given N (the state explosion that the
iterator avoids).

    python benchmarks/gen_explicit_fire_patrol.py 6 > /tmp/fp6.lts
    python benchmarks/gen_explicit_fire_patrol.py 6 -o /tmp/fp6.lts
"""

from __future__ import annotations

import argparse
import sys

from iterplan_compiler.experiments.catalog import explicit_fire_patrol


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", type=int, help="number of named patrol locations (N >= 1)")
    ap.add_argument("-o", "--output", help="file to write (default: stdout)")
    args = ap.parse_args(argv)
    if args.n < 1:
        ap.error("N must be at least 1")
    text = explicit_fire_patrol(args.n)
    if args.output:
        with open(args.output, "w") as fh:
            fh.write(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
