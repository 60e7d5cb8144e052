"""One MAVProxy scenario against ArduPlane SITL, run inside a private network namespace.

``python -m tests.sitl.mavproxy_scenario SPEC.json`` starts SITL (``start-sitl``, instance 3 by
default: SERIAL0 on tcp 5790, so it never meets the other SITL tests' instances), starts MAVProxy
on SERIAL0 with its console on a pipe (``--default-modules=``: only our module, unless
``default_modules`` is true), types
``module load iterplan`` and ``iterplan run CONTROLLER MAP --out OUT ...``, polls
``iterplan status`` every 2 s, optionally acts mid-mission (``action``: ``stop`` types
``iterplan stop``, ``unload`` types ``module unload iterplan``, ``quit`` closes MAVProxy's
stdin, i.e. MAVProxy exits; after ``action_after`` arrivals as ``iterplan status`` reports them),
then closes MAVProxy's stdin and prints one JSON line: MAVProxy's exit code and console
output, the mission outputs, wall times.  Nothing is asserted here (see
test_sitl_mavproxy.py).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from tests.sitl.scenario import outputs, start_sitl, stop

ROOT = Path(__file__).resolve().parents[2]


class Console:
    """MAVProxy with its console on pipes: ``type`` a command, ``lines`` of output so far."""

    def __init__(self, cmd: list[str], env: dict[str, str], cwd: Path):
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True, env=env, cwd=cwd,
                                     bufsize=1)
        self.lines: list[tuple[float, str]] = []
        self.t0 = time.monotonic()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.append((round(time.monotonic() - self.t0, 2), line.rstrip("\n")))

    def type(self, command: str) -> None:
        if self.proc.poll() is None and self.proc.stdin and not self.proc.stdin.closed:
            try:
                self.proc.stdin.write(command + "\n")
                self.proc.stdin.flush()
            except (BrokenPipeError, OSError):
                pass

    def close_stdin(self) -> None:
        try:
            if self.proc.stdin:
                self.proc.stdin.close()
        except OSError:
            pass

    def seen(self, pattern: str, since: int = 0) -> re.Match | None:
        rx = re.compile(pattern)
        for _, line in self.lines[since:]:
            m = rx.search(line)
            if m:
                return m
        return None

    def wait_for(self, pattern: str, wall: float, since: int = 0) -> re.Match | None:
        end = time.monotonic() + wall
        while time.monotonic() < end:
            m = self.seen(pattern, since)
            if m or self.proc.poll() is not None:
                return m or self.seen(pattern, since)
            time.sleep(0.1)
        return None

    def text(self) -> str:
        return "\n".join(f"[{t:7.2f}] {s}" for t, s in self.lines)


END = r"iterplan: (mission completed|mission ended early|error:)"


def main(spec_path: str) -> int:
    spec = json.loads(Path(spec_path).read_text())
    sitl, work = Path(spec["sitl"]), Path(spec["workdir"])
    inst = int(spec.get("instance", 3))
    wall = float(spec.get("wall", 240))
    out = work / "out"
    result: dict[str, Any] = {"spec": spec}
    t_start = time.monotonic()
    pid = start_sitl(sitl, inst, work / "sitl", float(spec.get("speedup", 10)), [])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    cmd = [sys.executable, "-m", "MAVProxy.mavproxy", "--master",
           f"tcp:127.0.0.1:{5760 + 10 * inst}", "--state-basedir", str(work / "mavproxy")]
    if not spec.get("default_modules"):          # MAVProxy's usual modules (wp, param, ...)
        cmd.append("--default-modules=")
    con = Console(cmd, env, work)
    try:
        con.type(f"module load {spec.get('module', 'iterplan')}")
        result["loaded"] = bool(con.wait_for(r"Loaded module iterplan", 30))
        run = ["iterplan", "run", spec["controller"], spec["map"], "--out", str(out),
               *spec.get("args", [])]
        con.type(" ".join(run))
        action, after = spec.get("action", "none"), int(spec.get("action_after", 2))
        end = time.monotonic() + wall
        next_status = 0.0
        while time.monotonic() < end and con.proc.poll() is None and not con.seen(END):
            if time.monotonic() >= next_status:
                mark = len(con.lines)
                con.type("iterplan status")
                next_status = time.monotonic() + 2.0
                m = con.wait_for(r"(\d+) arrivals", 1.5, since=mark)
                if action != "none" and "action_wall" not in result and m \
                        and int(m.group(1)) >= after:
                    result["action_wall"] = round(time.monotonic() - t_start, 1)
                    result["action_arrivals"] = int(m.group(1))
                    if action == "stop":
                        con.type("iterplan stop")
                    elif action == "unload":
                        con.type("module unload iterplan")
                    elif action == "quit":
                        con.close_stdin()
                        break
            time.sleep(0.1)
        if action != "quit":
            con.wait_for(END, 30)
            con.wait_for(r"iterplan:   safe state:", 10)
            mark = len(con.lines)
            con.type("iterplan status")
            con.wait_for(r"mission (done|failed)", 5, since=mark)
            result["mission_wall"] = round(time.monotonic() - t_start, 1)
            con.close_stdin()                 # EOF on the console: MAVProxy exits
        try:
            con.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            con.proc.terminate()
            try:
                con.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                con.proc.kill()
                con.proc.wait()
            result["mavproxy_killed"] = True
        con._reader.join(timeout=5)
        result["rc"] = con.proc.returncode
    finally:
        if con.proc.poll() is None:
            con.proc.kill()
        stop(pid, work / "sitl")
    result["console"] = con.text()
    result.update(outputs(out))
    result["wall_s"] = round(time.monotonic() - t_start, 1)
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
