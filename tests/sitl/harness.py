"""Running scenarios against real ArduPlane SITL (``../shared/sitl`` beside the clone).

SITL binds its TCP ports on 0.0.0.0, so SITL and its clients run only inside a private network
namespace with nothing but loopback (``in-netns``).  When this test process is already in such
a namespace (``.ci/run`` starts this suite with ``in-netns``) a scenario runs as a plain
subprocess; otherwise it is re-run under ``in-netns`` (needs root, as on CI and the development
machines).  Each scenario is ``python -m tests.sitl.scenario SPEC.json`` and prints one JSON
line; see scenario.py.
"""

from __future__ import annotations

import json
import math
import os
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
SPEEDUP = float(os.environ.get("ITERPLAN_SITL_SPEEDUP", "10"))


def sitl_dir() -> Path | None:
    """The SITL kit: $ITERPLAN_SITL_DIR, else ../shared/sitl beside the repository."""
    env = os.environ.get("ITERPLAN_SITL_DIR")
    d = Path(env) if env else ROOT.parent / "shared" / "sitl"
    return d if (d / "arduplane").exists() and (d / "start-sitl").exists() else None


def isolated() -> bool:
    """True inside a network namespace whose only interface is loopback.  (Asked of the
    kernel through netlink: /sys/class/net shows the namespace sysfs was mounted in, i.e. the
    host's interfaces under ``in-netns``, which would make every caller re-isolate itself.)"""
    try:
        names = [name for _, name in socket.if_nameindex()]
    except OSError:
        return False
    return names == ["lo"]


def run_scenario(tmp: Path, module: str = "tests.sitl.scenario", **spec: Any) -> dict:
    """Run scenario ``module`` (``python -m MODULE SPEC.json``) with ``spec``; its JSON result."""
    sitl = sitl_dir()
    assert sitl is not None
    tmp.mkdir(parents=True, exist_ok=True)
    spec = {"sitl": str(sitl), "workdir": str(tmp), "speedup": SPEEDUP, **spec}
    path = tmp / "scenario.json"
    path.write_text(json.dumps(spec))
    cmd = [sys.executable, "-m", module, str(path)]
    if not isolated():
        cmd = [str(sitl / "in-netns"), *cmd]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=env,
                             timeout=spec.get("wall", 240) + 120)
    except subprocess.TimeoutExpired:
        from tests.sitl.scenario import sitl_pids
        for pid in sitl_pids(tmp / "sitl"):      # never leave a SITL behind
            os.kill(pid, 9)
        raise
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("{")]
    if out.returncode != 0 or not lines:
        raise AssertionError(f"scenario failed (exit {out.returncode}):\n{out.stderr[-4000:]}")
    res = json.loads(lines[-1])
    (tmp / "result.json").write_text(json.dumps(res, indent=1))
    return res


def describe(res: dict) -> str:
    """What a failing assertion should show: iterc's output and the mission summary."""
    s = res.get("summary", {})
    return (f"rc={res.get('rc')} summary={json.dumps(s)}\n--- stdout\n{res.get('stdout', '')}"
            f"\n--- stderr (tail)\n{res.get('stderr', '')[-3000:]}")


def events(res: dict, kind: str | None = None) -> list[list[str]]:
    rows = [r.split(",") for r in (res.get("events.csv") or "").splitlines()[1:]]
    return [r for r in rows if kind is None or r[1] == kind]


def commands(res: dict) -> list[tuple[float, str]]:
    rows = [r.split(",", 2) for r in (res.get("commands.csv") or "").splitlines()[1:]]
    return [(float(r[0]), r[1]) for r in rows]


def loiter_over(samples: list, centre: tuple[float, float], radius: float,
                mode: str = "GUIDED") -> tuple[bool, str]:
    """Did the aircraft (observer samples t, mode, armed, x, y, alt) end up circling ``centre``
    in ``mode``?  Judged on the last 20 s of samples, which must really cover 20 s (at the
    observer's 4 Hz, at least 40 samples): a link that delivered one or a few stale samples
    fails here with what it saw instead of being judged on them."""
    if not samples:
        return False, "no samples"
    t_end = samples[-1][0]
    tail = [s for s in samples if s[0] >= t_end - 20]
    if t_end - samples[0][0] < 20 or len(tail) < 40:
        return False, (f"observer samples cover only {t_end - samples[0][0]:.1f} s "
                       f"({len(samples)} samples, {len(tail)} in the last 20 s)")
    modes = {s[1] for s in tail}
    d = [math.hypot(s[3] - centre[0], s[4] - centre[1]) for s in tail]
    ok = modes == {mode} and all(s[2] for s in tail) and max(d) < 2.0 * radius + 60
    return ok, f"modes {modes}, distance to centre {min(d):.0f}-{max(d):.0f} m"


def fault_injected(res: dict) -> bool:
    """The scenario's fault was injected mid-mission (else the fault tests judge nothing)."""
    return res.get("fault_t") is not None and "fault_missed" not in res


def log_events(res: dict, grid: Any) -> list:
    """events.csv as the LogEvents the example behaviour checks read: the cell of an
    ``arrived`` / ``take.photo`` / ``visited.*`` is the one the planner last arrived at."""
    from iterplan_compiler.experiments.missions import LogEvent
    from iterplan_compiler.runtime.mapfile import parse_cell_name

    out, here = [], -1
    for r in events(res):
        t, kind, label, cell = float(r[0]), r[1], r[2], r[7]
        if kind == "p" and label.startswith("arrived") and cell:
            here = int(parse_cell_name(grid, cell))
        if kind in ("u", "c"):
            c = here if label in ("arrived", "take.photo", "store.target") \
                or label.startswith("visited.") else -1
            out.append(LogEvent(t, label, c, float(r[4]), float(r[5])))
    return out
