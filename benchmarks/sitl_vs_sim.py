"""Mission time on ArduPlane SITL vs the built-in simulator with the same vehicle parameters.

    python benchmarks/sitl_vs_sim.py                     # 5 examples x 2 aircraft, ~2.5 min wall
    python benchmarks/sitl_vs_sim.py --repeat 5 --csv sitl_vs_sim.csv   # medians, ~13 min
    python benchmarks/sitl_vs_sim.py --examples cover,find_nemo --aircraft stock --jobs 1

For every example and aircraft it flies ``iterc run`` on real ArduPlane SITL (``--vehicle
mavlink``) and on the built-in simulator with ``--param`` set to the same parameter files
(``SimParams.from_arduplane``), both with the runtime's MAVLink default path follower
("carrot"), and prints SITL vs sim mission time (``duration_s`` of summary.json), the ratio
sim/SITL, and distance and misses of both.  The simulator is calibrated (``SITL_*`` constants in
runtime/sim.py) so that the two agree within 10 %; see docs/sitl-calibration.md.  Exit status 0
when every row does.

Both take off from the map's home at its arrival heading (SITL is started with ``--home``
there).  ``--repeat N`` flies N launch points a few metres apart on both and compares medians:
single flights are knife-edge (a few metres of cross-track error decide whether a cell is
missed or needs an extra circle), on SITL as on the simulator.

Aircraft: ``stock`` is SITL's plane.parm (AIRSPEED_CRUISE 22, WP_LOITER_RAD 80); ``slow`` is
plane.parm + AIRSPEED_CRUISE 17, WP_LOITER_RAD 60; ``tight`` is slow + NAVL1_PERIOD 8 (the
runtime then plans 23.4 m turns instead of 43.9 m; the experiments' ``--vehicle sitl-tight``).

The SITL kit is $ITERPLAN_SITL_DIR or ../shared/sitl beside the repository.  SITL binds 0.0.0.0,
so its part runs inside a private network namespace: unless this process already is in one (only
loopback), the script re-runs its SITL part under ``in-netns`` itself (needs root).  The
simulator part runs outside.  ``--sim-only`` skips SITL (and compares nothing).
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import csv
import json
import os
import queue
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# The SITL kit plumbing is the SITL test suite's (one place for finding and starting SITL).
from tests.sitl.harness import isolated, sitl_dir  # noqa: E402
from tests.sitl.scenario import start_sitl  # noqa: E402

EXAMPLES = {
    # name: extra `iterc run` arguments that make the mission end
    "fire_patrol": [],
    "cover": [],
    "find_nemo": [],
    "ordered_patrol": ["--until", "visited.p.0:3"],
    # The issue's `--until restart` includes the landing, which the simulator does not model
    # like ArduPlane (SITL flies the runtime's landing mission: approach point 600 m out, glide
    # to home, ~65 s from `land` at 17 m/s; the simulator sinks at home, ~45 s); so both end
    # at the controller's `land` command: the flight part of the mission.
    "search_and_map": ["--until", "land"],
}
#: aircraft name -> parameter lines added after plane.parm
AIRCRAFT = {
    "stock": {},
    "slow": {"AIRSPEED_CRUISE": 17, "WP_LOITER_RAD": 60},
    # slow with a shorter L1 period: tighter path following, so the runtime plans tighter
    # turns (runtime.vehicle.planning_bank_deg; the experiments' `sitl-tight` vehicle)
    "tight": {"AIRSPEED_CRUISE": 17, "WP_LOITER_RAD": 60, "NAVL1_PERIOD": 8},
}
TOLERANCE = 0.10


def iterc(*args: str, timeout: float | None = None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "iterplan_compiler", *args], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=timeout)


#: Launch points (metres east, north of the map's home) of the flights of one row: SITL flies
#: a given start almost identically every time, so repeats start a few metres apart, on both.
LAUNCH_OFFSETS = [(0, 0), (5, 0), (-5, 0), (0, 5), (0, -5), (5, 5), (-5, -5), (5, -5), (-5, 5)]


def map_variant(work: Path, name: str, k: int) -> Path:
    return work / "maps" / (f"{name}.json" if k == 0 else f"{name}@{k}.json")


def launch_point(name: str, k: int = 0) -> tuple[str, str]:
    """(lat,lon of the k-th launch point, start-sitl ``--home``): the map's home shifted by
    ``LAUNCH_OFFSETS[k]``, at the map's arrival heading, where the simulator takes off too.
    (SITL's default home is CMAC, the maps' SW corner, heading 353: a different first leg, and
    with it a different visiting order, would be compared.)"""
    return map_launch(ROOT / "examples" / f"{name}.json", *LAUNCH_OFFSETS[k])


def map_launch(path: Path, dx: float = 0.0, dy: float = 0.0) -> tuple[str, str]:
    """:func:`launch_point` of the map file ``path``, ``dx``/``dy`` metres east/north of its
    home."""
    from iterplan_compiler.runtime.grid import math_to_compass
    from iterplan_compiler.runtime.mapfile import load_map

    grid = load_map(path)
    lat, lon = grid.to_latlon(grid.home[0] + dx, grid.home[1] + dy)
    heading = math_to_compass(grid.arrival_heading) % 360
    return f"{lat:.7f},{lon:.7f}", f"{lat:.7f},{lon:.7f},{HOME_AMSL:g},{heading:g}"


#: SITL's default home altitude (CMAC), which the simulator's EAS2TAS assumes too.
HOME_AMSL = 584.0


def prepare(work: Path, examples: list[str], aircraft: list[str], launches: int) -> None:
    """Compile the controllers, write the aircraft parameter files and the maps (one per
    launch point, beside links to the examples' other files) into ``work``."""
    (work / "ctl").mkdir(parents=True, exist_ok=True)
    maps = work / "maps"
    maps.mkdir(exist_ok=True)
    for f in (ROOT / "examples").iterdir():
        if f.suffix not in (".py", ".lts") and not (maps / f.name).exists():
            (maps / f.name).symlink_to(f)
    for name in examples:
        data = json.loads((ROOT / "examples" / f"{name}.json").read_text())
        for k in range(1, launches):
            lat, lon = launch_point(name, k)[0].split(",")
            map_variant(work, name, k).write_text(
                json.dumps({**data, "home": [float(lat), float(lon)]}, indent=1))
    for name in examples:
        target = work / "ctl" / f"{name}.py"
        if not target.exists():
            out = iterc("compile", str(ROOT / "examples" / f"{name}.lts"), "-o", str(target))
            if out.returncode != 0:
                raise SystemExit(f"iterc compile {name} failed:\n{out.stderr}")
    for ac in aircraft:
        (work / f"{ac}.parm").write_text("".join(f"{k} {v}\n" for k, v in AIRCRAFT[ac].items()))


def param_files(work: Path, sitl: Path, ac: str) -> list[str]:
    """The files after plane.parm (start-sitl always loads plane.parm first)."""
    return [str(work / f"{ac}.parm")] if AIRCRAFT[ac] else []


def summary(out: Path, proc: subprocess.CompletedProcess, wall: float) -> dict:
    try:
        s = json.loads((out / "summary.json").read_text())
    except (OSError, ValueError):
        s = {}
    return {"rc": proc.returncode, "wall_s": round(wall, 1),
            "duration_s": s.get("duration_s"), "distance_m": s.get("distance_m"),
            "misses": s.get("misses"), "arrivals": s.get("arrivals"),
            "speed_mps": s.get("speed_mps"), "turn_radius_m": s.get("turn_radius_m"),
            "error": "" if proc.returncode == 0 else (proc.stdout + proc.stderr)[-1500:]}


# -- simulator ----------------------------------------------------------------------------------
def fly_sim(work: Path, sitl: Path, name: str, ac: str, k: int, planner: str | None) -> dict:
    out = work / "sim" / f"{name}-{ac}-{k}"
    (out / "summary.json").unlink(missing_ok=True)
    args = ["run", str(work / "ctl" / f"{name}.py"), "--map", str(map_variant(work, name, k)),
            "--no-plot", "--quiet", "--out", str(out), *EXAMPLES[name],
            "--param", str(sitl / "plane.parm")]
    for f in param_files(work, sitl, ac):
        args += ["--param", f]
    # The runtime's MAVLink default (carrot: GUIDED fly-to points), i.e. the same path follower
    # as on SITL; the simulator's own default is the course follower.
    args += ["--planner", planner or "carrot"]
    t0 = time.monotonic()
    proc = iterc(*args, timeout=600)
    return summary(out, proc, time.monotonic() - t0)


# -- SITL ---------------------------------------------------------------------------------------
def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:   # a zombie (exited, not yet reaped) is gone for our purposes
        return Path(f"/proc/{pid}/stat").read_text().split(") ")[1][0] != "Z"
    except (OSError, IndexError):
        return False


def _children(pid: int) -> list[int]:
    try:
        return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:
        return []


def _listening(port: int) -> bool:
    out = subprocess.run(["ss", "-ltnH"], capture_output=True, text=True).stdout
    return any(line.split()[3].endswith(f":{port}") for line in out.splitlines()
               if len(line.split()) > 3)


def stop(pid: int, port: int) -> None:
    """Stop the SITL started as holder ``pid`` and wait until its port is free (else the next
    start-sitl on this instance may see the old, dying SITL listening and hand it out)."""
    procs = [pid, *_children(pid)]
    for sig in (signal.SIGTERM, signal.SIGKILL):
        for p in procs:
            try:
                os.kill(p, sig)
            except ProcessLookupError:
                pass
        end = time.monotonic() + 5.0
        while time.monotonic() < end and any(_alive(p) for p in procs):
            time.sleep(0.1)
        if not any(_alive(p) for p in procs):
            break
    end = time.monotonic() + 10.0
    while time.monotonic() < end and _listening(port):
        time.sleep(0.1)


def fly_sitl(work: Path, sitl: Path, name: str, ac: str, k: int, instance: int,
             speedup: float, planner: str | None, attempts: int = 2) -> dict:
    """One SITL flight from a fresh SITL; a flight that fails before the mission started
    (SITL slow to boot: no heartbeat, not ready) is retried once."""
    tag = f"{name}-{ac}-{k}"
    wd = work / "sitl" / tag
    out = wd / "out"
    port = 5760 + 10 * instance
    for attempt in range(attempts):
        wd.mkdir(parents=True, exist_ok=True)
        (out / "summary.json").unlink(missing_ok=True)
        pid = start_sitl(sitl, instance, wd, speedup, param_files(work, sitl, ac),
                         launch_point(name, k)[1])
        try:
            args = ["run", str(work / "ctl" / f"{name}.py"),
                    "--map", str(map_variant(work, name, k)), "--no-plot", "--quiet",
                    "--out", str(out), *EXAMPLES[name], "--vehicle", "mavlink",
                    "--connect", f"tcp:127.0.0.1:{port}"]
            if planner:
                args += ["--planner", planner]
            t0 = time.monotonic()
            try:
                proc = iterc(*args, timeout=3600)
            except subprocess.TimeoutExpired as exc:
                proc = subprocess.CompletedProcess(exc.cmd, 124, "", "timed out")
            res = summary(out, proc, time.monotonic() - t0)
        finally:
            stop(pid, port)
        started = (out / "summary.json").exists()
        if res["rc"] == 0 or started:
            break
        print(f"  SITL {tag}: start-up failed ({res['error'].strip()[-200:]}); "
              f"{'retrying' if attempt + 1 < attempts else 'giving up'}",
              file=sys.stderr, flush=True)
    return res


def sitl_part(work: Path, sitl: Path, jobs_list: list[tuple[str, str, int]], n_jobs: int,
              speedup: float, planner: str | None) -> dict[str, dict]:
    """Fly the SITL jobs with up to ``n_jobs`` instances at once (must be in a namespace)."""
    instances: queue.Queue[int] = queue.Queue()
    for i in range(n_jobs):
        instances.put(i)

    def one(job: tuple[str, str, int]) -> tuple[str, dict]:
        name, ac, rep = job
        i = instances.get()
        try:
            try:
                res = fly_sitl(work, sitl, name, ac, rep, i, speedup, planner)
            except Exception as exc:  # noqa: BLE001 - one failed flight must not lose the rest
                res = {"rc": -1, "duration_s": None, "error": str(exc)}
        finally:
            instances.put(i)
        print(f"  SITL {name}/{ac}#{rep}: duration {res.get('duration_s')} s, rc {res['rc']}, "
              f"wall {res.get('wall_s')} s", file=sys.stderr, flush=True)
        return f"{name}|{ac}|{rep}", res

    with cf.ThreadPoolExecutor(n_jobs) as pool:
        return dict(pool.map(one, jobs_list))


def run_sitl(work: Path, sitl: Path, jobs_list: list[tuple[str, str, int]], n_jobs: int,
             speedup: float, planner: str | None) -> dict[str, dict]:
    if isolated():
        return sitl_part(work, sitl, jobs_list, n_jobs, speedup, planner)
    # Re-run only the SITL part of this script inside a private network namespace.
    spec = work / "sitl-jobs.json"
    result = work / "sitl-results.json"
    spec.write_text(json.dumps({"jobs": jobs_list, "n_jobs": n_jobs, "speedup": speedup,
                                "planner": planner, "sitl": str(sitl), "result": str(result)}))
    cmd = [str(sitl / "in-netns"), sys.executable, str(Path(__file__).resolve()),
           "--_sitl-part", str(spec)]
    proc = subprocess.run(cmd, cwd=ROOT)
    if proc.returncode != 0 or not result.exists():
        raise SystemExit(f"the SITL part failed (exit {proc.returncode}); is in-netns usable "
                         "(needs root)?")
    return json.loads(result.read_text())


def _sitl_part_main(spec_path: str) -> int:
    spec = json.loads(Path(spec_path).read_text())
    work = Path(spec_path).parent
    res = sitl_part(work, Path(spec["sitl"]), [tuple(j) for j in spec["jobs"]], spec["n_jobs"],
                    spec["speedup"], spec["planner"])
    Path(spec["result"]).write_text(json.dumps(res))
    return 0


# -- table --------------------------------------------------------------------------------------
def median(rows: list[dict], key: str) -> float | None:
    vals = [r[key] for r in rows if r.get("rc") == 0 and r.get(key) is not None]
    return statistics.median(vals) if vals else None


def fmt(v: float | None, spec: str = ".1f") -> str:
    return "-" if v is None else format(v, spec)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--examples", default=",".join(EXAMPLES),
                    help="comma-separated examples (default: all five)")
    ap.add_argument("--aircraft", default=",".join(AIRCRAFT),
                    help="comma-separated aircraft: stock (plane.parm), slow (+ AIRSPEED_CRUISE "
                         "17, WP_LOITER_RAD 60), tight (slow + NAVL1_PERIOD 8); default all")
    ap.add_argument("--speedup", type=float, default=10.0, help="SITL speedup (default 10)")
    ap.add_argument("--jobs", type=int, default=2, help="SITL instances in parallel (default 2)")
    ap.add_argument("--repeat", type=int, default=1,
                    help=f"flights per row on each vehicle, from launch points a few metres "
                         f"apart (up to {len(LAUNCH_OFFSETS)}); the table shows medians "
                         f"(default 1: the map's home)")
    ap.add_argument("--planner", choices=("course", "carrot"), default=None,
                    help="path follower for both (default: carrot, the runtime's MAVLink "
                         "default; the calibration is for that one)")
    ap.add_argument("--sim-only", action="store_true", help="skip SITL")
    ap.add_argument("--csv", default=None, metavar="FILE", help="also write the rows as CSV")
    ap.add_argument("--work", default=None, metavar="DIR",
                    help="keep controllers, outputs and SITL logs here (default: a temp dir)")
    ap.add_argument("--_sitl-part", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args._sitl_part:
        return _sitl_part_main(args._sitl_part)

    examples = [e for e in args.examples.split(",") if e]
    aircraft = [a for a in args.aircraft.split(",") if a]
    bad = [e for e in examples if e not in EXAMPLES] + [a for a in aircraft if a not in AIRCRAFT]
    if bad:
        ap.error(f"unknown example/aircraft: {', '.join(bad)}")
    sitl = sitl_dir()
    if sitl is None:
        print("SITL kit not found ($ITERPLAN_SITL_DIR or ../shared/sitl)", file=sys.stderr)
        return 2
    work = Path(args.work) if args.work else Path(tempfile.mkdtemp(prefix="sitl-vs-sim-"))
    work.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    if not 1 <= args.repeat <= len(LAUNCH_OFFSETS):
        ap.error(f"--repeat must be 1..{len(LAUNCH_OFFSETS)}")
    reps = range(args.repeat)
    prepare(work, examples, aircraft, args.repeat)

    sim = {(e, a, k): fly_sim(work, sitl, e, a, k, args.planner)
           for e in examples for a in aircraft for k in reps}
    # Longest flights first, so that the parallel instances finish together.
    jobs = sorted(((e, a, k) for e in examples for a in aircraft for k in reps),
                  key=lambda j: -(sim[j]["duration_s"] or 0))
    sitl_res: dict[str, dict] = {}
    if not args.sim_only:
        print(f"flying {len(jobs)} SITL missions, {args.jobs} at a time, speedup "
              f"{args.speedup:g} (work dir {work})", file=sys.stderr, flush=True)
        sitl_res = run_sitl(work, sitl, jobs, max(1, args.jobs), args.speedup, args.planner)

    rows = []
    for e in examples:
        for a in aircraft:
            runs = [sitl_res[f"{e}|{a}|{k}"] for k in reps if f"{e}|{a}|{k}" in sitl_res]
            sims = [sim[(e, a, k)] for k in reps]
            d_sitl = median(runs, "duration_s")
            d_sim = median(sims, "duration_s")
            ratio = d_sim / d_sitl if d_sim and d_sitl else None
            rows.append({
                "example": e, "aircraft": a,
                "sitl_s": d_sitl, "sim_s": d_sim, "ratio": ratio,
                "sitl_m": median(runs, "distance_m"), "sim_m": median(sims, "distance_m"),
                "sitl_misses": median(runs, "misses"), "sim_misses": median(sims, "misses"),
                "sitl_runs": ";".join(fmt(r.get("duration_s")) for r in runs),
                "sim_runs": ";".join(fmt(r.get("duration_s")) for r in sims),
                "failed": sum(1 for r in runs + sims if r.get("rc") != 0),
                "within": None if ratio is None else abs(ratio - 1) <= TOLERANCE,
            })
            for what, rs in (("SITL", runs), ("sim", sims)):
                for k, r in enumerate(rs):
                    if r.get("rc") != 0:
                        print(f"{what} {e}/{a}#{k} failed (rc {r.get('rc')}): "
                              f"{r.get('error', '')[-600:]}", file=sys.stderr)

    head = (f"{'example':<15} {'aircraft':<8} {'SITL s':>8} {'sim s':>8} {'sim/SITL':>8}  "
            f"{'SITL m':>7} {'sim m':>7}  {'SITL miss':>9} {'sim miss':>8}")
    print(head)
    print("-" * len(head))
    for r in rows:
        flag = "" if r["within"] in (None, True) else "  > 10 %"
        print(f"{r['example']:<15} {r['aircraft']:<8} {fmt(r['sitl_s']):>8} {fmt(r['sim_s']):>8} "
              f"{fmt(r['ratio'], '.3f'):>8}  {fmt(r['sitl_m'], '.0f'):>7} {fmt(r['sim_m'], '.0f'):>7}"
              f"  {fmt(r['sitl_misses'], 'g'):>9} {fmt(r['sim_misses'], 'g'):>8}{flag}")
    wall = time.monotonic() - t0
    print(f"wall time {wall:.0f} s; SITL speedup {args.speedup:g}, {args.jobs} jobs, "
          f"{args.repeat} flight(s) per row and vehicle"
          + (" (medians)" if args.repeat > 1 else ""))
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    compared = [r for r in rows if r["within"] is not None]
    if args.sim_only:
        return 0
    return 0 if compared and len(compared) == len(rows) and all(r["within"] for r in compared) \
        else 1


if __name__ == "__main__":
    sys.exit(main())
