"""One SITL scenario, run inside a private network namespace (see harness.py).

``python -m tests.sitl.scenario SPEC.json`` starts ArduPlane SITL instance(s) with
``../shared/sitl/start-sitl``, flies ``iterc run ... --vehicle mavlink`` against SERIAL0, and
watches (or plays the pilot) through a second MAVLink link on SERIAL1.  The spec says what to do
mid-mission (``fault``); the result (exit code, outputs, observations) is printed as one JSON
line.  Nothing is asserted here: the tests in this folder judge the result.

Faults (``fault``): ``none``; ``pilot_rtl`` (the observer switches to RTL); ``gps_off``
(PARAM_SET SIM_GPS_DISABLE 1); ``kill_sitl`` (SITL killed: link loss); ``sigint`` (Ctrl-C to
iterc).  They are injected ``fault_after`` simulated seconds after the vehicle entered GUIDED.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402

from iterplan_compiler.runtime.mapfile import load_map

mav = mavutil.mavlink
MODE_NAMES = dict(mavutil.mode_mapping_apm)
MODES = {v: k for k, v in MODE_NAMES.items()}


class Observer:
    """A second GCS on SERIAL1: sees mode, armed state and position; can change the mode."""

    def __init__(self, port: int, frame: Any, timeout: float = 30.0):
        self.m = mavutil.mavlink_connection(f"tcp:127.0.0.1:{port}", source_system=253,
                                            source_component=191, autoreconnect=False)
        self.frame = frame
        self.mode, self.armed, self.t, self.x, self.y, self.alt = "?", False, 0.0, 0.0, 0.0, 0.0
        self.samples: list[tuple[float, str, bool, float, float, float]] = []
        self.acks: dict[int, int] = {}
        self.params: dict[str, float] = {}
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            self.m.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            if self.m.recv_match(type="HEARTBEAT", blocking=True, timeout=0.5):
                break
        for msg_id, hz in ((mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 4.0),
                           (mav.MAVLINK_MSG_ID_HEARTBEAT, 2.0)):
            self.m.mav.command_long_send(1, 1, mav.MAV_CMD_SET_MESSAGE_INTERVAL, 0, msg_id,
                                         1e6 / hz, 0, 0, 0, 0, 0)

    def pump(self, wall: float) -> None:
        end = time.monotonic() + wall
        while True:
            left = end - time.monotonic()
            msg = self.m.recv_match(blocking=left > 0, timeout=max(left, 0.0) or None)
            if msg is None:
                if left <= 0:
                    return
                continue
            if msg.get_srcSystem() != 1:
                continue
            t = msg.get_type()
            if t == "HEARTBEAT" and msg.get_srcComponent() == 1:
                self.mode = MODE_NAMES.get(msg.custom_mode, str(msg.custom_mode))
                self.armed = bool(msg.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
            elif t == "GLOBAL_POSITION_INT":
                self.t = msg.time_boot_ms / 1000.0
                self.x, self.y = self.frame.to_enu(msg.lat / 1e7, msg.lon / 1e7)
                self.alt = msg.relative_alt / 1000.0
                self.samples.append((self.t, self.mode, self.armed, self.x, self.y, self.alt))
            elif t == "COMMAND_ACK":
                self.acks[msg.command] = msg.result
            elif t == "PARAM_VALUE":
                self.params[msg.param_id.rstrip("\x00")] = msg.param_value

    def wait(self, cond, wall: float) -> bool:
        end = time.monotonic() + wall
        while time.monotonic() < end:
            if cond():
                return True
            self.pump(0.1)
        return cond()

    def set_mode(self, name: str) -> None:
        self.m.mav.command_long_send(1, 1, mav.MAV_CMD_DO_SET_MODE, 0,
                                     mav.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MODES[name],
                                     0, 0, 0, 0, 0)

    def set_param(self, name: str, value: float) -> None:
        self.m.mav.param_set_send(1, 1, name.encode(), value, mav.MAV_PARAM_TYPE_REAL32)

    def close(self) -> None:
        try:
            self.m.close()
        except OSError:
            pass


def start_sitl(sitl: Path, instance: int, workdir: Path, speedup: float,
               params: list[str], home: str | None = None) -> int:
    """``start-sitl`` (optionally at ``home`` = "LAT,LON,ALT,HDG"); the holder's PID."""
    cmd = [str(sitl / "start-sitl"), "--speedup", str(speedup), "--instance", str(instance),
           "--workdir", str(workdir)]
    if home:
        cmd += ["--home", home]
    for p in params:
        cmd += ["--param", p]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=30)
    if out.returncode != 0:
        raise RuntimeError(f"start-sitl failed: {out.stderr.strip()}")
    return int(out.stdout.strip())


def sitl_pids(workdir: Path) -> list[int]:
    """ArduPlane processes running in ``workdir`` (SITL may outlive its holder)."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            if (d / "comm").read_text().strip() == "arduplane" \
                    and Path(os.readlink(d / "cwd")) == workdir.resolve():
                out.append(int(d.name))
        except OSError:
            continue
    return out


def stop(pid: int, workdir: Path | None = None) -> None:
    """Stop the holder, then SIGKILL whatever SITL process is left in ``workdir``."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        try:
            os.kill(pid, sig)
        except ProcessLookupError:
            break
        time.sleep(0.3)
    for p in sitl_pids(workdir) if workdir is not None else []:
        try:
            os.kill(p, signal.SIGKILL)
        except ProcessLookupError:
            pass


def iterc_run(spec: dict, port: int, out: Path, extra: list[str]) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "iterplan_compiler", "run", spec["controller"],
           "--map", spec["map"], "--vehicle", "mavlink", "--connect", f"tcp:127.0.0.1:{port}",
           "--out", str(out), "--no-plot", *spec.get("args", []), *extra]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def finish(proc: subprocess.Popen, wall: float) -> dict:
    try:
        so, se = proc.communicate(timeout=wall)
    except subprocess.TimeoutExpired:
        proc.kill()
        so, se = proc.communicate()
        return {"rc": None, "stdout": so, "stderr": se + "\n[scenario: iterc timed out]"}
    return {"rc": proc.returncode, "stdout": so, "stderr": se}


def outputs(out: Path) -> dict:
    res: dict[str, Any] = {}
    if (out / "summary.json").exists():
        res["summary"] = json.loads((out / "summary.json").read_text())
    for name in ("events.csv", "commands.csv", "track.csv"):
        f = out / name
        res[name] = f.read_text() if f.exists() else None
    return res


def main(spec_path: str) -> int:
    spec = json.loads(Path(spec_path).read_text())
    sitl = Path(spec["sitl"])
    work = Path(spec["workdir"])
    inst = int(spec.get("instance", 0))
    port0, port1 = 5760 + 10 * inst, 5762 + 10 * inst
    grid = load_map(spec["map"])
    result: dict[str, Any] = {"spec": spec}
    t_start = time.monotonic()
    pid = start_sitl(sitl, inst, work / "sitl", float(spec.get("speedup", 10)),
                     spec.get("params", []))
    obs: Observer | None = None
    try:
        proc = iterc_run(spec, port0, work / "out", [])
        time.sleep(0.5)              # SERIAL0's client first: SITL boots on it
        obs = Observer(port1, grid.frame)
        fault = spec.get("fault", "none")
        if fault != "none":
            guided_at: list[float] = []

            def due() -> bool:
                if obs.mode == "GUIDED" and obs.armed and not guided_at:
                    guided_at.append(obs.t)
                return bool(guided_at) and obs.t - guided_at[0] >= spec.get("fault_after", 40)
            if obs.wait(lambda: due() or proc.poll() is not None, spec.get("wall", 240)) \
                    and proc.poll() is None:
                result["fault_t"] = obs.t
                result["fault_wall"] = time.monotonic()
                if fault == "pilot_rtl":
                    obs.set_mode("RTL")
                elif fault == "gps_off":
                    obs.set_param("SIM_GPS_DISABLE", 1)
                elif fault == "sigint":
                    proc.send_signal(signal.SIGINT)
                elif fault == "kill_sitl":
                    obs.close()
                    obs = None
                    stop(pid, work / "sitl")
        if obs is not None:
            # Watch until iterc ends (keeps the observer's receive buffer drained).
            end = time.monotonic() + spec.get("wall", 240)
            while proc.poll() is None and time.monotonic() < end:
                obs.pump(0.2)
        result.update(finish(proc, 5 if proc.poll() is not None else 30))
        result["end_wall"] = time.monotonic()
        if "fault_wall" in result:
            result["fault_to_exit_wall"] = result["end_wall"] - result["fault_wall"]
        result.update(outputs(work / "out"))
        if obs is not None:
            end_t = obs.t
            obs.wait(lambda: obs.t >= end_t + spec.get("watch_after", 40), 30)
            result["after"] = [s for s in obs.samples if s[0] >= end_t]
            result["before_end"] = [s for s in obs.samples if s[0] < end_t][-400:]
            cx, cy = grid.centre_point()
            result["map_centre"] = [cx, cy]
            second = spec.get("second_run")
            if second:
                # A second mission through SERIAL1 while the aircraft is still flying.
                obs.close()
                obs = None
                # SITL's TCP serial port takes one client and listens again only once it has
                # seen the observer go; connecting at once could sit in the listen backlog
                # with no heartbeat (seen once under load: "no autopilot heartbeat").
                time.sleep(2.0)
                proc2 = iterc_run({**spec, "args": second}, port1, work / "out2", [])
                result["second"] = finish(proc2, spec.get("wall", 240))
                result["second"].update(outputs(work / "out2"))
    finally:
        if obs is not None:
            obs.close()
        stop(pid, work / "sitl")
    result["wall_s"] = round(time.monotonic() - t_start, 1)
    print(json.dumps(result, default=lambda o: list(o) if isinstance(o, tuple) else str(o)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
