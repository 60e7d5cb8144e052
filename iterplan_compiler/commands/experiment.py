"""``iterc experiment``: reproduce the paper's Fig. 3 (a)-(d) and the synthesis-time table.

    iterc experiment fig3b --quick            # small sizes (CI), 2 seeds
    iterc experiment fig3b --jobs 4           # full sizes (up to 700,000 locations, 30 seeds)
    iterc experiment fig3b --sizes 1000,700000 --seeds 3 --sorters distance,last
    iterc experiment fig3a                    # trajectories, 'last' sorter
    iterc experiment all --quick --out results/
    iterc experiment synthesis-table --max-n 6

Writes ``<out>/<exp>.csv`` (one row per simulated mission), ``<out>/<exp>_summary.csv``
(mean ± 3 SEM per point) and ``<out>/<exp>.png``; fig3a writes ``<out>/fig3a.csv`` (loop time
per universe) and ``<out>/fig3a.png``; prints the summary.  While a sweep runs, each finished
mission is appended to ``<out>/<exp>.partial.csv``; a sweep that was killed resumes from it,
and a re-run skips the runs already in ``<out>/<exp>.csv`` (``--fresh`` starts over).  Every
file is written atomically (outputs.py).  ``--jobs N`` runs on a ``dask.distributed``
LocalCluster of N workers, ``--scheduler ADDR`` on an existing Dask cluster.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import os
import sys
from pathlib import Path

from iterplan_compiler import outputs
from iterplan_compiler.commands.run import add_arrival_arguments

HELP = "reproduce the paper's Fig. 3 experiments"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from iterplan_compiler.experiments.missions import VehicleKind
    from iterplan_compiler.experiments.sweeps import Experiment

    parser.add_argument("name", choices=[e.value for e in Experiment], help="which experiment")
    parser.add_argument("--quick", action="store_true",
                        help="small sizes (seconds; what CI runs)")
    parser.add_argument("--seeds", type=int, default=None,
                        help="runs per point (default 30)")
    parser.add_argument("--sorters", default=None,
                        help="comma-separated subset of distance,last,random,tour")
    parser.add_argument("--sizes", default=None,
                        help="comma-separated sizes to run instead of the defaults: numbers of "
                             "locations (fig3b, fig3d) or of locations to cover (fig3c)")
    parser.add_argument("--jobs", "-j", type=int, default=1,
                        help="parallel processes (default 1; 0 = one per CPU)")
    parser.add_argument("--scheduler", default=None, metavar="ADDR",
                        help="run on the Dask cluster at ADDR, e.g. tcp://host:8786 (default "
                             "with --jobs > 1: a dask.distributed LocalCluster of that many "
                             "workers; pip install 'iterplan[experiments]')")
    parser.add_argument("--vehicle", choices=[k.value for k in VehicleKind],
                        default=VehicleKind.SITL.value,
                        help="simulated aircraft: sitl, the SITL-calibrated simulator at the "
                             "paper's 17 m/s cruise (default); sitl-tight, the same with "
                             "NAVL1_PERIOD 8 (tighter path following, 23 m planned turns "
                             "instead of 44 m); paper, the plain kinematic model")
    parser.add_argument("--out", "-o", default="iterplan-experiments",
                        help="output directory (default ./iterplan-experiments)")
    parser.add_argument("--max-n", type=int, default=None,
                        help="synthesis-table: largest N (default 8, quick 4)")
    parser.add_argument("--budget", type=float, default=None,
                        help="synthesis-table: seconds per synthesis (default 60, quick 10)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--fast-skip", action="store_true",
                        help="fig3b: the runtime's fast skip of the controller's skip cycles "
                             "(same controller behaviour, less iteration overhead)")
    # for every sorter; default: the paper's, and for tour on Cover its planned headings
    add_arrival_arguments(parser, paper_default=False)
    parser.add_argument("--warmup", type=int, default=0, metavar="LOOPS",
                        help="fig3b: patrol loops flown before the measured ones (default 0: "
                             "the paper's, the first loop is measured)")
    parser.add_argument("--fresh", action="store_true",
                        help="ignore the runs saved by an interrupted sweep (<exp>.partial.csv)"
                        " and start over")


def run(args: argparse.Namespace) -> int:
    from iterplan_compiler.experiments import harness, sweeps
    from iterplan_compiler.experiments.sweeps import Experiment
    from iterplan_compiler.runtime.sorter import SorterKind

    out = Path(args.out)
    names = Experiment(args.name).expand()
    sorters = None
    if args.sorters:
        given = tuple(s.strip() for s in args.sorters.split(",") if s.strip())
        bad = [s for s in given if s not in sweeps.SORTERS]
        if bad:
            print(f"iterc experiment: unknown sorter(s) {', '.join(bad)}; choose from "
                  f"{', '.join(sweeps.SORTERS)}", file=sys.stderr)
            return 2
        sorters = tuple(SorterKind(s) for s in given)
    if args.warmup < 0:
        print("iterc experiment: --warmup must be at least 0", file=sys.stderr)
        return 2
    if args.seeds is not None and args.seeds < 1:
        print("iterc experiment: --seeds must be at least 1", file=sys.stderr)
        return 2
    sizes = None
    if args.sizes:
        try:
            sizes = tuple(int(x) for x in args.sizes.split(",") if x.strip())
        except ValueError:
            print("iterc experiment: --sizes takes comma-separated integers", file=sys.stderr)
            return 2
    args.size_list = sizes
    jobs = args.jobs if args.jobs > 0 else (os.cpu_count() or 1)
    out.mkdir(parents=True, exist_ok=True)
    status = 0
    for name in names:
        if name is Experiment.SYNTHESIS_TABLE:
            status = max(status, _synthesis_table(args, out))
            continue
        if name is Experiment.FIG3A:
            status = max(status, _trajectories(args, out))
            continue
        status = max(status, _figure(name, args, out, jobs, sorters, harness, sweeps))
    return status


def _arrival(args: argparse.Namespace):
    """(ArrivalHeadings, HeadingChoice) from --headings / --heading-choice, or None (the
    per-sorter defaults of ``missions.arrival_for``)."""
    if args.headings is None and args.heading_choice is None:
        return None
    from iterplan_compiler.runtime.planner import ArrivalHeadings, HeadingChoice

    return (ArrivalHeadings(args.headings) if args.headings else ArrivalHeadings.PARALLEL,
            HeadingChoice(args.heading_choice) if args.heading_choice
            else HeadingChoice.SHORTEST)


def _figure(experiment, args, out: Path, jobs: int, sorters, harness, sweeps) -> int:
    from iterplan_compiler.experiments import missions, plots
    from iterplan_compiler.experiments.sweeps import Experiment

    name = experiment.value  # in file names and messages
    sizes = getattr(args, "size_list", None)
    cover = experiment is Experiment.FIG3C
    try:
        cases = sweeps.sweep(experiment, quick=args.quick, seeds=args.seeds, sorters=sorters,
                             universes=sizes if not cover else None,
                             counts=sizes if cover else None)
    except ValueError as exc:
        print(f"iterc experiment {name}: {exc}", file=sys.stderr)
        return 2
    problem = missions.preflight(experiment, out / "controllers")
    if problem:
        print(f"iterc experiment {name}: cannot run: {problem}", file=sys.stderr)
        return 1
    runner = missions.Runner(str(out / "controllers"), fast_skip=args.fast_skip,
                             vehicle=missions.VehicleKind(args.vehicle),
                             arrival=_arrival(args), warmup=args.warmup)
    clash = _same_options(out / f"{name}.options.json", args)
    if clash:
        print(f"iterc experiment {name}: {out} holds runs made with other options ({clash}); "
              "use another --out, or --fresh to replace them", file=sys.stderr)
        return 2
    # Each finished run is appended to <name>.partial.csv at once (one fsync-ed line), so a
    # sweep killed after hours resumes where it stopped: runs already in the file are kept.
    partial = out / f"{name}.partial.csv"
    fields = harness.CASE_FIELDS + harness.RESULT_FIELDS + ["floor", "physics_pct",
                                                           "first_loop", "warmup", "launch"]
    final = out / f"{name}.csv"
    done_rows = [] if args.fresh else _resumable_rows(partial, fields) + \
        _finished_rows(final, fields)
    ident = {tuple(str(r[f]) for f in harness.CASE_FIELDS): r for r in done_rows
             if not r.get("error")}  # failed runs are run again
    todo = [c for c in cases if tuple(str(v) for v in c.values()) not in ident]
    if done_rows:
        kept = len(cases) - len(todo)
        print(f"iterc experiment {name}: resuming: {kept} of {len(cases)} runs already done "
              f"in {partial} (--fresh to start over)", file=sys.stderr)
    if not partial.exists() or args.fresh or not _resumable_rows(partial, fields):
        outputs.atomic_write_text(partial, _csv_line(fields, {f: f for f in fields}))
        for r in done_rows:             # keep the finished runs of the final CSV
            outputs.append_line(partial, _csv_line(fields, r))
    prog = harness.Progress(len(todo), name, enabled=not args.no_progress)

    def save(row: dict) -> None:
        outputs.append_line(partial, _csv_line(fields, row))

    try:
        new_rows = harness.run_cases(todo, runner, jobs=jobs, scheduler=args.scheduler,
                                     progress=prog, on_row=save)
    except harness.ExperimentError as exc:
        print(f"iterc experiment: {exc}", file=sys.stderr)
        return 2
    by_case = dict(ident)
    for r in new_rows:
        by_case[tuple(str(r[f]) for f in harness.CASE_FIELDS)] = r
    keys = [tuple(str(v) for v in c.values()) for c in cases]
    rows = [by_case[k] for k in keys if k in by_case]
    # finished runs of other sizes/sorters/seeds stay in the CSV (a sweep grows by re-runs)
    wanted = set(keys)
    rows += [r for k, r in sorted(by_case.items()) if k not in wanted]
    outputs.atomic_write_text(out / f"{name}.csv", harness.write_csv(rows))
    partial.unlink()  # only once the complete CSV is in place
    points = harness.aggregate(rows)
    outputs.atomic_write_text(out / f"{name}_summary.csv", harness.write_summary_csv(points))
    png = plots.plot(experiment, points, out / f"{name}.png", note=f"vehicle {args.vehicle}")
    print(_summary_text(experiment, points))
    print(f"wrote {out / (name + '.csv')}, {out / (name + '_summary.csv')}, {png}")
    failed = [r for r in rows if r.get("error")]
    if failed:
        print(f"{len(failed)} of {len(rows)} runs failed; first: {failed[0]['error']}",
              file=sys.stderr)
        return 1
    return 0


def _same_options(path: Path, args: argparse.Namespace) -> str:
    """Record the options that shape a run's result (vehicle, arrival rule, fast skip, warm-up)
    in ``path``; if a previous sweep into the same directory recorded others, say which
    differ ("" if none): resuming would mix runs of different aircraft or rules."""
    now = {"vehicle": args.vehicle, "fast_skip": bool(args.fast_skip),
           "headings": args.headings, "heading_choice": args.heading_choice,
           "warmup": args.warmup}
    if path.exists() and not args.fresh:
        try:
            before = json.loads(path.read_text(encoding="utf-8"))
        except ValueError:
            before = {}
        diff = [f"{k} {before[k]!r} before, {v!r} now" for k, v in now.items()
                if k in before and before[k] != v]
        if diff:
            return "; ".join(diff)
    outputs.atomic_write_text(path, json.dumps(now, indent=1, sort_keys=True) + "\n")
    return ""


def _csv_line(fields: list[str], row: dict) -> str:
    buf = io.StringIO()
    csv.DictWriter(buf, fieldnames=fields, extrasaction="ignore",
                   lineterminator="\n").writerow({k: row.get(k, "") for k in fields})
    return buf.getvalue()


def _finished_rows(final: Path, fields: list[str]) -> list[dict]:
    """Rows of a previous complete run (``<exp>.csv``): a re-run skips them too."""
    if not final.exists():
        return []
    rows = list(csv.DictReader(io.StringIO(final.read_text(encoding="utf-8"))))
    from iterplan_compiler.experiments import harness

    # Columns added since (e.g. first_loop) may be missing: the case and its result suffice.
    needed = [f for f in fields if f in harness.CASE_FIELDS or f in harness.RESULT_FIELDS]
    if rows and not set(needed) <= set(rows[0].keys()):
        return []
    return rows


def _resumable_rows(partial: Path, fields: list[str]) -> list[dict]:
    """Rows of a previous, interrupted run of the same sweep (none if the header differs)."""
    lines = outputs.complete_lines(partial)
    if not lines:
        return []
    rows = list(csv.DictReader(io.StringIO("\n".join(lines) + "\n")))
    if not rows and lines[0].split(",") != fields:
        return []
    if rows and list(rows[0].keys()) != fields:
        return []
    return rows


def _trajectories(args, out: Path) -> int:
    from iterplan_compiler.experiments import missions, trajectories
    from iterplan_compiler.experiments.sweeps import Experiment

    problem = missions.preflight(Experiment.FIG3B, out / "controllers")
    if problem:
        print(f"iterc experiment fig3a: cannot run: {problem}", file=sys.stderr)
        return 1
    sizes = getattr(args, "size_list", None) or (
        trajectories.QUICK_SIZES if args.quick else trajectories.FULL_SIZES)
    runs = trajectories.fly_tracks(out / "controllers", sizes, seed=0)
    bad = [(u, r.reason) for u, r, _ in runs if not r.ok]
    png = trajectories.plot_tracks(runs, out / "fig3a.png")
    lines = ["universe,loop_s,ideal_s,overhead_pct"]
    for u, r, grid in runs:
        loops = missions.loop_times(r.log)
        loop = loops[0] if loops else float("nan")
        ideal = trajectories.ideal_loop(grid, r.speed)
        print(f"fig3a: {u:>9,} locations: loop {loop:8.1f} s (ideal {ideal:.1f} s)")
        lines.append(f"{u},{loop:.3f},{ideal:.3f},{100 * (loop - ideal) / ideal:.2f}")
    outputs.atomic_write_text(out / "fig3a.csv", "\n".join(lines) + "\n")
    print(f"wrote {out / 'fig3a.csv'}, {png}")
    if bad:
        print(f"iterc experiment fig3a: mission(s) ended early: {bad}", file=sys.stderr)
        return 1
    return 0


def _summary_text(experiment, points) -> str:
    from iterplan_compiler.experiments.sweeps import Experiment

    name, cover = experiment.value, experiment is Experiment.FIG3C
    unit = "overhead %" if cover else "duration s"
    lines = [f"{name}: mean ± 3 SEM ({unit}), ideal s, overhead %",
             f"{'universe':>9} {'count':>5} {'sorter':<8} {'n':>3} {'value':>18} "
             f"{'ideal':>9} {'overhead':>9} {'physics floor':>16}"]
    for p in points:
        if cover:
            val = f"{p.overhead_pct:8.1f} ± {p.overhead_err3:6.1f}"
        else:
            val = f"{p.duration:8.1f} ± {p.duration_err3:6.1f}"
        lines.append(f"{p.universe:>9} {p.count:>5} {p.sorter:<8} {p.n:>3} {val:>18} "
                     f"{p.ideal:9.1f} {p.overhead_pct:8.1f}% "
                     f"{p.physics_pct:7.1f} ± {p.physics_err3:5.1f}%")
    return "\n".join(lines)


def _synthesis_table(args, out: Path) -> int:
    from iterplan_compiler.experiments import harness
    from iterplan_compiler.experiments.synthesis_table import format_table, rows_csv, table

    max_n = args.max_n or (4 if args.quick else 8)
    budget = args.budget or (10.0 if args.quick else 60.0)
    ns = list(range(1, max_n + 1))
    prog = harness.Progress(4 + len(ns) + sum(n >= 2 for n in ns), "synthesis-table", enabled=not args.no_progress)
    rows = table(ns, budget_s=budget, progress=prog)
    outputs.atomic_write_text(out / "synthesis_table.csv", rows_csv(rows))
    print(format_table(rows))
    print(f"wrote {out / 'synthesis_table.csv'}")
    errors = [r for r in rows if r.status == "error"]
    if errors:
        print(f"iterc experiment synthesis-table: {len(errors)} spec(s) failed; first: "
              f"{errors[0].spec}: {errors[0].detail}", file=sys.stderr)
        return 1
    return 0
