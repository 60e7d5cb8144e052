"""Mission time on ArduPlane SITL vs the built-in simulator with the same vehicle parameters.

    python benchmarks/sitl_vs_sim.py                     # 5 examples x 2 aircraft, ~10 min wall
    python benchmarks/sitl_vs_sim.py --examples cover,find_nemo --aircraft stock --jobs 2
    python benchmarks/sitl_vs_sim.py --repeat 3 --csv sitl_vs_sim.csv   # medians of 3 SITL flights

For every example and aircraft it flies ``iterc run`` once on real ArduPlane SITL (``--vehicle
mavlink``, the runtime's default "carrot" follower there) and on the built-in simulator with
``--param`` set to the same parameter files (``SimParams.from_arduplane``), and prints SITL vs
sim mission time (``duration_s`` of summary.json), the ratio sim/SITL, and distance and misses
of both.  The simulator is calibrated (``SITL_*`` constants in runtime/sim.py) so that every row
agrees within 10 %; see docs/sitl-calibration.md.

Aircraft: ``stock`` is SITL's plane.parm (AIRSPEED_CRUISE 22, WP_LOITER_RAD 80); ``slow`` is
plane.parm + AIRSPEED_CRUISE 17, WP_LOITER_RAD 60.

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

EXAMPLES = {
    # name: extra `iterc run` arguments that make the mission end
    "fire_patrol": [],
    "cover": [],
    "find_nemo": [],
    "ordered_patrol": ["--until", "visited.p.0:3"],
    # The issue's `--until restart` includes the landing; ArduPlane SITL refuses the runtime's
    # landing mission (DO_SET_MISSION_CURRENT DENIED, a runtime problem, not a model one), so
    # both end at the controller's `land` command: the flight part of the mission.
    "search_and_map": ["--until", "land"],
}
#: aircraft name -> parameter lines added after plane.parm
AIRCRAFT = {
    "stock": {},
    "slow": {"AIRSPEED_CRUISE": 17, "WP_LOITER_RAD": 60},
}
TOLERANCE = 0.10


def sitl_dir() -> Path | None:
    env = os.environ.get("ITERPLAN_SITL_DIR")
    d = Path(env) if env else ROOT.parent / "shared" / "sitl"
    return d if (d / "arduplane").exists() and (d / "start-sitl").exists() else None


def isolated() -> bool:
    """True inside a network namespace whose only interface is loopback."""
    try:
        return os.listdir("/sys/class/net") == ["lo"]
    except OSError:
        return False


def iterc(*args: str, timeout: float | None = None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "iterplan_compiler", *args], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=timeout)


def prepare(work: Path, sitl: Path | None, examples: list[str], aircraft: list[str]) -> None:
    """Compile the controllers and write the aircraft parameter files into ``work``."""
    (work / "ctl").mkdir(parents=True, exist_ok=True)
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
def fly_sim(work: Path, sitl: Path, name: str, ac: str, planner: str | None) -> dict:
    out = work / "sim" / f"{name}-{ac}"
    args = ["run", str(work / "ctl" / f"{name}.py"), "--map", str(ROOT / "examples" / f"{name}.json"),
            "--no-plot", "--quiet", "--out", str(out), *EXAMPLES[name],
            "--param", str(sitl / "plane.parm")]
    for f in param_files(work, sitl, ac):
        args += ["--param", f]
    if planner:
        args += ["--planner", planner]
    t0 = time.monotonic()
    proc = iterc(*args, timeout=600)
    return summary(out, proc, time.monotonic() - t0)


# -- SITL ---------------------------------------------------------------------------------------
def start_sitl(sitl: Path, instance: int, workdir: Path, speedup: float,
               params: list[str]) -> int:
    cmd = [str(sitl / "start-sitl"), "--speedup", str(speedup), "--instance", str(instance),
           "--workdir", str(workdir)]
    for p in params:
        cmd += ["--param", p]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=30)
    if out.returncode != 0:
        raise RuntimeError(f"start-sitl failed: {out.stderr.strip()}")
    return int(out.stdout.strip())


def stop(pid: int) -> None:
    try:
        os.kill(pid, signal.SIGTERM)
    except ProcessLookupError:
        return
    for _ in range(50):
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return
        time.sleep(0.1)
    try:
        os.kill(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def fly_sitl(work: Path, sitl: Path, name: str, ac: str, rep: int, instance: int,
             speedup: float, planner: str | None) -> dict:
    tag = f"{name}-{ac}-{rep}"
    wd = work / "sitl" / tag
    out = wd / "out"
    wd.mkdir(parents=True, exist_ok=True)
    pid = start_sitl(sitl, instance, wd, speedup, param_files(work, sitl, ac))
    try:
        args = ["run", str(work / "ctl" / f"{name}.py"),
                "--map", str(ROOT / "examples" / f"{name}.json"), "--no-plot", "--quiet",
                "--out", str(out), *EXAMPLES[name], "--vehicle", "mavlink",
                "--connect", f"tcp:127.0.0.1:{5760 + 10 * instance}"]
        if planner:
            args += ["--planner", planner]
        t0 = time.monotonic()
        try:
            proc = iterc(*args, timeout=3600)
        except subprocess.TimeoutExpired as exc:
            proc = subprocess.CompletedProcess(exc.cmd, 124, "", "timed out")
        res = summary(out, proc, time.monotonic() - t0)
    finally:
        stop(pid)
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
                         "17, WP_LOITER_RAD 60); default both")
    ap.add_argument("--speedup", type=float, default=10.0, help="SITL speedup (default 10)")
    ap.add_argument("--jobs", type=int, default=2, help="SITL instances in parallel (default 2)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="SITL flights per row; the table shows medians (default 1)")
    ap.add_argument("--planner", choices=("course", "carrot"), default=None,
                    help="path follower for both (default: each vehicle's default)")
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
    prepare(work, sitl, examples, aircraft)

    sim = {(e, a): fly_sim(work, sitl, e, a, args.planner) for e in examples for a in aircraft}
    # Longest flights first, so that the parallel instances finish together.
    jobs = sorted(((e, a, r) for e in examples for a in aircraft for r in range(args.repeat)),
                  key=lambda j: -(sim[j[:2]]["duration_s"] or 0))
    sitl_res: dict[str, dict] = {}
    if not args.sim_only:
        print(f"flying {len(jobs)} SITL missions, {args.jobs} at a time, speedup "
              f"{args.speedup:g} (work dir {work})", file=sys.stderr, flush=True)
        sitl_res = run_sitl(work, sitl, jobs, max(1, args.jobs), args.speedup, args.planner)

    rows = []
    for e in examples:
        for a in aircraft:
            runs = [sitl_res[f"{e}|{a}|{r}"] for r in range(args.repeat)
                    if f"{e}|{a}|{r}" in sitl_res]
            s = sim[(e, a)]
            d_sitl = median(runs, "duration_s")
            d_sim = s["duration_s"] if s["rc"] == 0 else None
            ratio = d_sim / d_sitl if d_sim and d_sitl else None
            rows.append({
                "example": e, "aircraft": a,
                "sitl_s": d_sitl, "sim_s": d_sim, "ratio": ratio,
                "sitl_m": median(runs, "distance_m"), "sim_m": s["distance_m"],
                "sitl_misses": median(runs, "misses"), "sim_misses": s["misses"],
                "sitl_runs": ";".join(fmt(r.get("duration_s")) for r in runs),
                "sitl_failed": sum(1 for r in runs if r.get("rc") != 0),
                "within": None if ratio is None else abs(ratio - 1) <= TOLERANCE,
            })
            for r in runs:
                if r.get("rc") != 0:
                    print(f"SITL {e}/{a} failed (rc {r.get('rc')}): {r.get('error', '')[-600:]}",
                          file=sys.stderr)
            if s["rc"] != 0:
                print(f"sim {e}/{a} failed: {s['error'][-600:]}", file=sys.stderr)

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
          f"{args.repeat} flight(s) per row" + (" (medians)" if args.repeat > 1 else ""))
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
