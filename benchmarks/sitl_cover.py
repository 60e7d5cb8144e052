"""Fig. 3(c) Cover missions flown on ArduPlane SITL and on the built-in simulator.

The Cover sweeps (``iterc experiment fig3c``) run on the SITL-calibrated simulator; this flies
the sweep's own layouts (universe 713, ``--count`` cells, seeds 0 .. ``--seeds``-1) with
``iterc run`` on real ArduPlane SITL and on the simulator with the same parameter files, map,
launch point and runtime arguments, and prints per flight the mission time on both, their
ratio, the misses and the planned turn radius.  It checks that what the sweeps report for an
aircraft (e.g. ``tight``: NAVL1_PERIOD 8, the sweeps' ``--vehicle sitl-tight``) is what
ArduPlane flies::

    python benchmarks/sitl_cover.py --aircraft tight --count 10 --seeds 6
    python benchmarks/sitl_cover.py --aircraft slow --sorters tour --seeds 3

Sorter arguments are the sweep's: ``tour`` with grid arrival headings and the planned heading
(``missions.arrival_for`` for up to 25 cells), ``distance`` the paper's.  Both start from the
map's home at the map's arrival heading (SITL's ``--home``), not the sweep's random launch
heading, so the missions differ from the sweep's by their first leg.  The whole script re-runs
itself under ``in-netns`` (SITL binds 0.0.0.0) unless it already is in a loopback-only
namespace.  Exit status 0 when every pair is within 10 %.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import json
import os
import queue
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import sitl_vs_sim as svs  # noqa: E402  (the SITL plumbing and the aircraft)

from tests.sitl.harness import isolated, sitl_dir  # noqa: E402

SORTER_ARGS = {
    "tour": ["--sorter", "tour", "--headings", "grid", "--heading-choice", "lookahead"],
    "distance": ["--sorter", "distance"],
}


def write_maps(work: Path, count: int, seeds: range) -> dict[int, Path]:
    from iterplan_compiler.experiments.sweeps import Experiment, case_map_data, sweep

    cases = sweep(Experiment.FIG3C, seeds=max(seeds) + 1, counts=(count,))
    maps = {}
    for case in cases:
        if case.seed in seeds and case.seed not in maps:
            path = work / "maps" / f"fig3c-{count}-{case.seed}.json"
            path.write_text(json.dumps(case_map_data(case), indent=1))
            maps[case.seed] = path
    return maps


def fly(work: Path, sitl: Path, ac: str, m: Path, sorter: str, where: str,
        instances: queue.Queue[int], speedup: float) -> dict:
    out = work / where / f"{m.stem}-{sorter}"
    args = ["run", str(work / "ctl" / "cover.py"), "--map", str(m), "--no-plot", "--quiet",
            "--out", str(out), *SORTER_ARGS[sorter]]
    t0 = time.monotonic()
    if where == "sim":
        params = [str(sitl / "plane.parm"), *svs.param_files(work, sitl, ac)]
        args += [x for p in params for x in ("--param", p)] + ["--planner", "carrot"]
        return svs.summary(out, svs.iterc(*args, timeout=600), time.monotonic() - t0)
    i = instances.get()
    try:
        port = 5760 + 10 * i
        wd = work / "sitl-work" / out.name
        wd.mkdir(parents=True, exist_ok=True)
        pid = svs.start_sitl(sitl, i, wd, speedup, svs.param_files(work, sitl, ac),
                              svs.map_launch(m)[1])
        try:
            proc = svs.iterc(*args, "--vehicle", "mavlink", "--connect",
                             f"tcp:127.0.0.1:{port}", timeout=3600)
        finally:
            svs.stop(pid, port)
    finally:
        instances.put(i)
    return svs.summary(out, proc, time.monotonic() - t0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--aircraft", default="tight", choices=sorted(svs.AIRCRAFT),
                    help="parameter set (benchmarks/sitl_vs_sim.py AIRCRAFT; default tight)")
    ap.add_argument("--count", type=int, default=10, help="cells to cover (default 10)")
    ap.add_argument("--seeds", type=int, default=6, help="layouts: seeds 0..N-1 (default 6)")
    ap.add_argument("--sorters", default="tour,distance", help="comma-separated (tour,distance)")
    ap.add_argument("--speedup", type=float, default=10.0, help="SITL speedup (default 10)")
    ap.add_argument("--jobs", type=int, default=2, help="SITL instances at once (default 2)")
    ap.add_argument("--work", default=None, metavar="DIR", help="keep outputs here")
    args = ap.parse_args(argv)
    sorters = [s for s in args.sorters.split(",") if s]
    if any(s not in SORTER_ARGS for s in sorters) or args.seeds < 1 or args.count < 1:
        ap.error("sorters are tour and distance; --seeds and --count at least 1")
    sitl = sitl_dir()
    if sitl is None:
        print("SITL kit not found ($ITERPLAN_SITL_DIR or ../shared/sitl)", file=sys.stderr)
        return 2
    if not isolated():          # SITL and its clients only inside a loopback-only namespace
        argv_all = [sys.executable, str(Path(__file__).resolve()), *(argv or sys.argv[1:])]
        os.execv(str(sitl / "in-netns"), [str(sitl / "in-netns"), *argv_all])
    work = Path(args.work) if args.work else Path(tempfile.mkdtemp(prefix="sitl-cover-"))
    work.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    svs.prepare(work, ["cover"], [args.aircraft], 1)
    maps = write_maps(work, args.count, range(args.seeds))
    instances: queue.Queue[int] = queue.Queue()
    for i in range(max(1, args.jobs)):
        instances.put(i)
    jobs = [(s, so, w) for w in ("sitl", "sim") for s in maps for so in sorters]
    with cf.ThreadPoolExecutor(max(1, args.jobs)) as pool:
        flown = pool.map(lambda j: fly(work, sitl, args.aircraft, maps[j[0]], j[1], j[2],
                                       instances, args.speedup), jobs)
        res = dict(zip(jobs, flown, strict=True))
    return report(res, maps, sorters, args, time.monotonic() - t0)


def report(res: dict, maps: dict, sorters: list[str], args, wall: float) -> int:
    print(f"fig3c layouts, universe 713, {args.count} cells, aircraft {args.aircraft}")
    print(f"{'seed':>4} {'sorter':<8} {'SITL s':>7} {'sim s':>7} {'sim/SITL':>8} "
          f"{'SITL miss':>9} {'sim miss':>8} {'radius m':>8}")
    ratios, bad = [], 0
    for s in maps:
        for so in sorters:
            a, b = res[(s, so, "sitl")], res[(s, so, "sim")]
            ok = a["rc"] == 0 and b["rc"] == 0 and a["duration_s"] and b["duration_s"]
            ratio = b["duration_s"] / a["duration_s"] if ok else None
            if ratio is not None:
                ratios.append(ratio)
            bad += ratio is None or abs(ratio - 1) > svs.TOLERANCE
            print(f"{s:>4} {so:<8} {svs.fmt(a['duration_s']):>7} {svs.fmt(b['duration_s']):>7} "
                  f"{svs.fmt(ratio, '.3f'):>8} {svs.fmt(a['misses'], 'g'):>9} "
                  f"{svs.fmt(b['misses'], 'g'):>8} {svs.fmt(a['turn_radius_m']):>8}")
            for what, r in (("SITL", a), ("sim", b)):
                if r["rc"] != 0:
                    print(f"  {what} failed (rc {r['rc']}): {r['error'][-400:]}")
    if ratios:
        print(f"sim/SITL median {statistics.median(ratios):.3f}, range {min(ratios):.3f}-"
              f"{max(ratios):.3f}; {bad} pair(s) failed or off by more than 10 %")
    print(f"wall time {wall:.0f} s; SITL speedup {args.speedup:g}, {args.jobs} jobs")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
