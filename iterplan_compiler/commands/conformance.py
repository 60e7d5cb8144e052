"""``iterc conformance DIR``: run the MTSA conformance corpus and print a report."""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

HELP = "run the MTSA conformance corpus and print a report"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("corpus", type=Path,
                        help="the corpus folder holding verdicts.tsv (../shared/conformance/mtsa)")
    parser.add_argument("-j", "--jobs", type=int, default=os.cpu_count() or 1,
                        help="rows checked in parallel (default: number of cores)")
    parser.add_argument("--timeout", type=float, default=30.0,
                        help="seconds per row before it counts as a time-out (default 30)")
    parser.add_argument("--budget", type=float, default=None,
                        help="wall seconds for the whole run; rows not started by then count "
                             "as time-outs (rows that passed in --baseline run first)")
    parser.add_argument("-k", "--filter", default="",
                        help="only rows whose file path contains this text")
    parser.add_argument("--baseline", type=Path, default=None,
                        help="exit 1 if a row listed as 'pass' in this TSV no longer passes")
    parser.add_argument("--write-baseline", type=Path, default=None,
                        help="write the statuses of this run as a new baseline")
    parser.add_argument("-v", "--verbose", action="store_true",
                        help="also print the detail of checks that pass")


def run(args: argparse.Namespace) -> int:
    from iterplan_compiler import conformance as conf
    from iterplan_compiler.conformance_checks import Status

    root: Path = args.corpus
    if not (root / "verdicts.tsv").is_file():
        print(f"iterc conformance: {root}/verdicts.tsv not found", file=sys.stderr)
        return 2
    rows = [r for r in conf.read_rows(root) if args.filter in r.file]
    baseline = conf.read_baseline(args.baseline) if args.baseline is not None else {}
    # Rows that passed before run first, so a time budget never turns them into regressions.
    rows.sort(key=lambda r: conf.baseline_status(baseline, r.key) != "pass")
    done = 0
    start = time.perf_counter()

    def show(res: conf.RowResult) -> None:
        """Every row with every check and its status; details of the checks that do not
        pass (of all checks with -v)."""
        nonlocal done
        done += 1
        names = "; ".join(f"{c.name}: {c.status.value}" for c in res.checks) or res.detail
        print(f"[{done:>3}/{len(rows)}] {res.status:<11} {res.key} ({res.seconds:.1f} s) "
              f"{names}", flush=True)
        for check in res.checks:
            if check.detail and (args.verbose or check.status is not Status.PASS):
                print(f"      {check.status.value:<11} {check.name}: {check.detail}", flush=True)

    results = conf.run_corpus(root, rows, jobs=args.jobs, timeout=args.timeout,
                              budget=args.budget, on_result=show)
    print()
    print(f"MTSA conformance corpus: {len(results)} rows in "
          f"{time.perf_counter() - start:.1f} s wall")
    print(conf.summary_table(results))
    if args.write_baseline is not None:
        # never drop a pass: the previous baseline (the file itself, or --baseline) is kept
        keep = {**conf.read_baseline(args.write_baseline), **baseline}
        conf.write_baseline(args.write_baseline, results, keep=keep)
        print(f"baseline written to {args.write_baseline}")
    if args.baseline is not None:
        lost = conf.regressions(results, baseline)
        if lost:
            print(f"\n{len(lost)} row(s) passed in {args.baseline} and no longer pass:")
            for r in lost:
                print(f"  {r.key}: {r.status}: {r.detail}")
            return 1
        print(f"no regressions against {args.baseline}")
    return 0
