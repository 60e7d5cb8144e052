"""One SITL scenario, run inside a private network namespace (see harness.py).

``python -m tests.sitl.scenario SPEC.json`` starts ArduPlane SITL instance(s) with
``../shared/sitl/start-sitl``, flies ``iterc run ... --vehicle mavlink`` against SERIAL0, and
watches (or plays the pilot) through a second MAVLink link on SERIAL1.  The spec says what to do
mid-mission (``fault``); the result (exit code, outputs, observations) is printed as one JSON
line.  Nothing is asserted here: the tests in this folder judge the result.

Faults (``fault``): ``none``; ``pilot_rtl`` (the observer switches to RTL); ``gps_off``
(PARAM_SET SIM_GPS_DISABLE 1); ``kill_sitl`` (SITL killed: link loss); ``sigint`` (Ctrl-C to
iterc).  They are injected ``fault_after`` simulated seconds after the vehicle entered GUIDED;
the result says when (``fault_t``, observer time) or why not (``fault_missed``: iterc ended
first), and what the observer link did (``observer``: connections, stalls with SITL's state).
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


class ObserverError(RuntimeError):
    """The observer link does not deliver live telemetry: the scenario cannot judge anything."""


class Observer:
    """A second GCS on SERIAL1: sees mode, armed state and position; can change the mode.

    SITL listens on SERIAL1 only once it has booted, i.e. after iterc's SERIAL0 connection, and
    takes one client there at a time.  The observer therefore (re)connects until ``timeout`` and
    counts as up only once it has seen the autopilot's HEARTBEAT *and* GLOBAL_POSITION_INT with
    advancing boot time; a link that goes quiet (EOF, no message for ``stale`` s of wall time) is
    reconnected, and an observer that cannot get live telemetry raises :class:`ObserverError`
    (the scenario then fails loudly instead of judging stale or missing samples)."""

    def __init__(self, port: int, frame: Any, timeout: float = 60.0, stale: float = 10.0,
                 alive: Any = None, inspect: Any = None):
        self.port, self.frame, self.timeout, self.stale = port, frame, timeout, stale
        self.alive = alive or (lambda: True)          # False: nobody will boot SITL any more
        self.inspect = inspect or (lambda: None)      # what SITL is doing, for a stall report
        self.mode, self.armed, self.t, self.x, self.y, self.alt = "?", False, 0.0, 0.0, 0.0, 0.0
        self.samples: list[tuple[float, str, bool, float, float, float]] = []
        self.acks: dict[int, int] = {}
        self.params: dict[str, float] = {}
        self.t0 = time.monotonic()
        # What the link did (in the scenario's result): connections, EOFs, stalls, messages.
        self.diag: dict[str, Any] = {"connects": [], "eof": 0, "stalls": 0, "hb": 0, "pos": 0}
        self.m: Any = None
        self._connect()

    def _wall(self) -> float:
        return round(time.monotonic() - self.t0, 2)

    def _lost(self) -> None:
        self.diag["eof"] += 1
        self._eof = True

    def _connect(self) -> None:
        """Connect (again) and wait for live telemetry; ObserverError if none by the deadline."""
        end = time.monotonic() + self.timeout
        why = "not connected"
        while time.monotonic() < end:
            self.close()
            try:
                self.m = mavutil.mavlink_connection(
                    f"tcp:127.0.0.1:{self.port}", source_system=253, source_component=191,
                    autoreconnect=False, retries=0)
            except OSError as exc:          # SERIAL1 listens only once SITL has booted
                self.m, why = None, f"connect: {exc}"
                if not self.diag["connects"] and not self.alive():   # SITL will never boot
                    break
                time.sleep(0.2)
                continue
            self._eof = False
            self.m.handle_eof = self.m.handle_disconnect = self._lost
            why = self._await_live(min(end, time.monotonic() + 20.0))
            if why is None:
                self.diag["connects"].append(self._wall())
                return
        self.close()
        raise ObserverError(f"observer on SERIAL1 (tcp {self.port}): no live telemetry within "
                            f"{self.timeout:.0f} s ({why}; {self.diag})")

    def _await_live(self, end: float) -> str | None:
        """None once HEARTBEAT and two GLOBAL_POSITION_INT with advancing time have arrived
        and the autopilot accepted the message intervals (positions at the default stream
        rate also arrive without it, ~1 Hz: too sparse for the scenarios' judgements)."""
        hb0, pos_t, asked = self.diag["hb"], [], 0.0
        cmd = mav.MAV_CMD_SET_MESSAGE_INTERVAL
        self.acks.pop(cmd, None)
        while time.monotonic() < end and not self._eof:
            if time.monotonic() - asked > 1.0 and self.acks.get(cmd) != mav.MAV_RESULT_ACCEPTED:
                self._request()                  # until it is accepted: ask again
                asked = time.monotonic()
            n = len(self.samples)
            self._pump_once(0.2)
            pos_t += [s[0] for s in self.samples[n:]]
            if (self.diag["hb"] > hb0 and len(pos_t) >= 2 and pos_t[-1] > pos_t[0]
                    and self.acks.get(cmd) == mav.MAV_RESULT_ACCEPTED):
                self.last_rx = time.monotonic()
                return None
        ok = "accepted" if self.acks.get(cmd) == mav.MAV_RESULT_ACCEPTED else "not accepted"
        return ("EOF" if self._eof else
                f"{self.diag['hb'] - hb0} heartbeats, {len(pos_t)} positions, interval "
                f"request {ok}")

    def _request(self) -> None:
        self.m.mav.heartbeat_send(mav.MAV_TYPE_GCS, mav.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        for msg_id, hz in ((mav.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 4.0),
                           (mav.MAVLINK_MSG_ID_HEARTBEAT, 2.0)):
            self.m.mav.command_long_send(1, 1, mav.MAV_CMD_SET_MESSAGE_INTERVAL, 0, msg_id,
                                         1e6 / hz, 0, 0, 0, 0, 0)

    def pump(self, wall: float) -> None:
        """Read for ``wall`` s; a link gone quiet (EOF, or no message from the autopilot for
        ``stale`` s) is reconnected (ObserverError if that fails)."""
        end = time.monotonic() + wall
        while True:
            self._pump_once(max(end - time.monotonic(), 0.0))
            if self._eof or time.monotonic() - self.last_rx > self.stale:
                self.diag["stalls"] += 1
                self.diag.setdefault("stalled_at", []).append(
                    [self._wall(), self.t, "EOF" if self._eof else "quiet", self.inspect()])
                self._connect()
            if time.monotonic() >= end:
                return

    def _pump_once(self, wall: float) -> None:
        end = time.monotonic() + wall
        while not self._eof:
            left = end - time.monotonic()
            try:
                msg = self.m.recv_match(blocking=left > 0, timeout=max(left, 0.0) or None)
            except OSError:                 # connection reset: as EOF
                self._lost()
                break
            if msg is None:
                if left <= 0:
                    return
                continue
            if msg.get_srcSystem() != 1:
                continue
            self.last_rx = time.monotonic()
            t = msg.get_type()
            if t == "HEARTBEAT" and msg.get_srcComponent() == 1:
                self.diag["hb"] += 1
                self.mode = MODE_NAMES.get(msg.custom_mode, str(msg.custom_mode))
                self.armed = bool(msg.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
            elif t == "GLOBAL_POSITION_INT":
                self.diag["pos"] += 1
                self.t = msg.time_boot_ms / 1000.0
                self.x, self.y = self.frame.to_enu(msg.lat / 1e7, msg.lon / 1e7)
                self.alt = msg.relative_alt / 1000.0
                self.samples.append((self.t, self.mode, self.armed, self.x, self.y, self.alt))
            elif t == "COMMAND_ACK":
                self.acks[msg.command] = msg.result
            elif t == "PARAM_VALUE":
                self.params[msg.param_id.rstrip("\x00")] = msg.param_value
        time.sleep(min(max(end - time.monotonic(), 0.0), 0.05))   # EOF: no busy loop

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
        if self.m is None:
            return
        try:
            self.m.close()
        except (OSError, AttributeError):
            pass
        self.m = None


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


def sitl_state(workdir: Path) -> list[dict]:
    """Each SITL process's scheduler state, kernel wait channel and syscall, and the TCP
    queues of the namespace (what a stalled observer link reports)."""
    out: list[dict] = []
    for p in sitl_pids(workdir):
        d: dict[str, Any] = {"pid": p}
        for name in ("wchan", "syscall"):
            try:
                d[name] = Path(f"/proc/{p}/{name}").read_text().strip()[:80]
            except OSError as exc:
                d[name] = str(exc)
        try:
            d["state"] = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            pass
        out.append(d)
    try:
        ss = subprocess.run(["ss", "-tn"], capture_output=True, text=True, timeout=5).stdout
        out.append({"ss": ss[-1500:]})
    except (OSError, subprocess.SubprocessError):
        pass
    return out


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
    # Ctrl-C must reach iterc as it reaches it from a terminal.  A process started in the
    # background by a non-interactive shell (a CI job run with `&`, nohup, ...) inherits SIGINT
    # *ignored*, exec keeps that, and Python then installs no KeyboardInterrupt handler: the
    # `sigint` fault would be delivered and silently ignored (the mission just completes).
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_default_sigint)


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def sigint_ignored(pid: int) -> bool | None:
    """Does process ``pid`` ignore SIGINT (its SigIgn mask in /proc)?  None if unknown."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("SigIgn:"):
                return bool(int(line.split()[1], 16) & (1 << (signal.SIGINT - 1)))
    except (OSError, ValueError):
        pass
    return None


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
        obs = Observer(port1, grid.frame, alive=lambda: proc.poll() is None,
                       inspect=lambda: sitl_state(work / "sitl"))
        fault = spec.get("fault", "none")
        if fault != "none":
            guided_at: list[float] = []

            def due() -> bool:
                if obs.mode == "GUIDED" and obs.armed and not guided_at:
                    guided_at.append(obs.t)
                return bool(guided_at) and obs.t - guided_at[0] >= spec.get("fault_after", 40)
            obs.wait(lambda: due() or proc.poll() is not None, spec.get("wall", 240))
            result["guided_t"] = guided_at[0] if guided_at else None
            if due() and proc.poll() is None:
                # The tests assert that the fault was injected (fault_t) mid-mission.
                result["fault_t"] = obs.t
                result["fault_wall"] = time.monotonic()
                if fault == "pilot_rtl":
                    obs.set_mode("RTL")
                elif fault == "gps_off":
                    obs.set_param("SIM_GPS_DISABLE", 1)
                elif fault == "sigint":
                    result["iterc_ignores_sigint"] = sigint_ignored(proc.pid)
                    proc.send_signal(signal.SIGINT)
                elif fault == "kill_sitl":
                    result["observer"] = obs.diag
                    obs.close()
                    obs = None
                    stop(pid, work / "sitl")
            else:
                result["fault_missed"] = (
                    f"{fault} not injected: iterc ended (rc {proc.poll()}) before it was due; "
                    f"observer saw GUIDED+armed at t={result['guided_t']}, last t={obs.t}, "
                    f"mode {obs.mode}, armed {obs.armed}, link {obs.diag}")
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
            obs.pump(0.0)           # catch up on what arrived while iterc's output was read
            end_t = obs.t
            obs.wait(lambda: obs.t >= end_t + spec.get("watch_after", 40), 60)
            result["observer"] = obs.diag
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
