"""The live view without a browser: observer and hub, the server's routes and WebSocket,
``iterc run --view`` flags, the replay of a run folder, and imports without the view's extras."""

from __future__ import annotations

import asyncio
import json
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from iterplan_compiler.cli import main
from iterplan_compiler.runtime.executor import Executor, RunConfig
from iterplan_compiler.runtime.grid import GridMap
from iterplan_compiler.runtime.mapfile import load_map
from iterplan_compiler.runtime.planner import PlannerMode
from iterplan_compiler.runtime.sim import SimVehicle
from iterplan_compiler.view import missing_dependency
from iterplan_compiler.view.snapshot import Hub, Observer, map_message
from tests.runtime.fire_patrol import TABLE

ROOT = Path(__file__).resolve().parents[2]
FIRE_MAP = ROOT / "examples" / "fire_patrol.json"
needs_view = pytest.mark.skipif(missing_dependency() is not None,
                                reason=str(missing_dependency()))

BLOCK = (
    "import sys\n"
    "class Block:\n"
    "    def find_spec(self, name, path=None, target=None):\n"
    "        if name.split('.')[0] in ('aiohttp', 'xstatic', 'lark', 'dd', 'selenium'):\n"
    "            raise ImportError('blocked ' + name)\n"
    "sys.meta_path.insert(0, Block())\n"
)


def test_runtime_and_run_command_import_without_the_view_extras():
    code = BLOCK + (
        "import importlib, pkgutil\n"
        "import iterplan_compiler.runtime as r\n"
        "for m in pkgutil.iter_modules(r.__path__):\n"
        "    importlib.import_module('iterplan_compiler.runtime.' + m.name)\n"
        "import iterplan_compiler.commands.run, iterplan_compiler.view.cli\n"
        "import iterplan_compiler.view.live, iterplan_compiler.view.snapshot\n"
        "from iterplan_compiler.view import missing_dependency\n"
        "assert 'iterplan[view]' in missing_dependency()\n"
        "assert 'aiohttp' not in sys.modules\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def _fly(observe, **kw):
    g = load_map(FIRE_MAP)
    v = SimVehicle(home=g.home, heading=g.arrival_heading)
    cfg = RunConfig(ideal_compute=True, observe=observe, **kw)
    return g, Executor(TABLE, g, v, config=cfg).run()


def test_observer_fills_the_hub_with_small_deltas():
    g = load_map(FIRE_MAP)
    hub = Hub(map_message(g, "fp"))
    ticks = iter(range(10**9))
    obs = Observer(hub, rate=1.0, clock=lambda: float(next(ticks)))   # every tick
    deltas = []
    orig = hub.publish
    hub.publish = lambda d: (deltas.append(d), orig(d))[1]   # type: ignore[method-assign]
    _, result = _fly(obs)
    assert result.ok
    assert len(deltas) > 100 and obs.snapshots == len(deltas)
    for d in deltas:
        json.dumps(d, allow_nan=False)
    for d in deltas[1:]:          # (the first one brings the take-off's track)
        assert len(d.get("track", ())) <= 5 and len(d.get("log", ())) <= 40
    st = hub.state()
    assert st["phase"] == "mission completed" and st["final"]["ok"]
    assert st["it"]["done"] == 64 and st["it"]["next"] is None and st["it"]["remaining"] == 0
    assert sorted(st["done_new"]) == list(range(64))
    assert len(st["track"]) >= len(result.track) - 2
    assert st["counts"]["arrived"] == 9 and len(st["photos"]) == 2
    assert st["overhead_pct"] == result.summary["overhead_pct"]
    assert st["mode"] and st["link_ok"] is True and st["simulated"] is True
    # Paths were planned (and cleared at the end); the sorter's first few were shown.
    assert any(d.get("path") for d in deltas) and st["path"] == []
    assert any(d["it"]["first"] for d in deltas)
    # ... and they are what R offers next: after a single remove.next, n is the former first.
    pairs = [(a["it"], b["it"]) for a, b in zip(deltas, deltas[1:], strict=False)
             if b["it"]["done"] == a["it"]["done"] + 1 and a["it"]["first_cells"]]
    assert pairs and all(b["next_cell"] == a["first_cells"][0] for a, b in pairs)
    assert {tuple(a) for d in deltas for a in d["ctrl"]["enabled"]} >= {("arrived", False)}
    # A live overhead figure is shown during the flight.
    assert any(d["overhead_pct"] is not None for d in deltas[:-1])


def test_observer_is_throttled_and_does_not_change_the_mission():
    _, plain = _fly(None)
    hub = Hub()
    obs = Observer(hub, rate=5.0)
    _, seen = _fly(obs)
    assert seen.summary == plain.summary
    assert seen.log == plain.log
    # A mission of ~120 simulated s runs in well under a second: a handful of snapshots.
    assert obs.snapshots <= 20 and hub.final


def test_hub_since_and_full():
    hub = Hub({"type": "map"}, keep=3)
    assert hub.since(0) == []
    for i in range(5):
        hub.publish({"type": "state", "t": i, "track": [[i, i]], "log": [[i, "c", "a", 0, ""]]})
    assert hub.since(4) == hub.since(3)[1:] and len(hub.since(3)) == 2
    assert hub.since(5) == []
    assert hub.since(0) is None            # dropped: the page starts again from full()
    seq, msgs = hub.full()
    assert seq == 5 and msgs[0] == {"type": "map"}
    assert msgs[1]["t"] == 4 and len(msgs[1]["track"]) == 5 and msgs[1]["full"]


def test_map_message_on_a_big_map_draws_only_sensor_cells():
    g = GridMap.from_size(300, 300)
    g.set_sensor("inP", [5, 7, 90000 - 1])
    m = map_message(g)
    assert not m["per_cell"] and m["locations"] == 90000 and m["cells"] == [5, 7, 89999]
    small = map_message(load_map(FIRE_MAP))
    assert small["per_cell"] and len(small["rects"]) == 64
    names = {s["name"]: s for s in small["sensors"]}
    assert names["inP"]["colour"] == "#ff8c00" and names["fire"]["count"] == 2


def test_parse_address():
    from iterplan_compiler.view.live import ViewError, parse_address
    assert parse_address("127.0.0.1:0") == ("127.0.0.1", 0)
    assert parse_address("0.0.0.0:8080") == ("0.0.0.0", 8080)
    assert parse_address(":9000") == ("127.0.0.1", 9000)
    assert parse_address("9000") == ("127.0.0.1", 9000)
    assert parse_address("localhost") == ("localhost", 0)
    assert parse_address("[::1]:81") == ("::1", 81)
    for bad in ("host:x", "h:70000"):
        with pytest.raises(ViewError):
            parse_address(bad)


@needs_view
def test_server_routes_and_websocket():
    import aiohttp

    from iterplan_compiler.view.server import ViewServer

    g = load_map(FIRE_MAP)
    hub = Hub(map_message(g, "fp"))
    server = ViewServer(hub, "127.0.0.1", 0, poll=0.05).start()
    try:
        assert server.port > 0 and server.url.startswith("http://127.0.0.1:")

        async def client():
            async with aiohttp.ClientSession() as s:
                async with s.get(server.url) as r:
                    assert r.status == 200 and "leaflet" in await r.text()
                for path in ("/static/view.js", "/static/view.css", "/leaflet/leaflet.js",
                             "/leaflet/leaflet.css"):
                    async with s.get(server.url + path.lstrip("/")) as r:
                        assert r.status == 200, path
                async with s.get(server.url + "api/mode") as r:
                    assert (await r.json())["mode"] == "live"
                async with s.get(server.url + "api/replay") as r:
                    assert r.status == 404
                async with s.ws_connect(server.url + "ws") as ws:
                    first = await ws.receive_json(timeout=5)
                    second = await ws.receive_json(timeout=5)
                    assert first["type"] == "map" and second["full"]
                    hub.publish({"type": "state", "t": 1.5, "track": [[1.0, 2.0]]})
                    d = await ws.receive_json(timeout=5)
                    assert d["t"] == 1.5 and d["seq"] == 1 and not d.get("full")
                    await ws.send_str("anything")         # ignored: read-only
                    hub.publish({"type": "state", "t": 2.0})
                    assert (await ws.receive_json(timeout=5))["t"] == 2.0
                async with s.get(server.url + "api/state") as r:
                    st = await r.json()
                    assert st["t"] == 2.0 and st["track"] == [[1.0, 2.0]]

        asyncio.run(client())
    finally:
        server.stop()
    assert not server._thread.is_alive()


def _files(tmp_path):
    ctl = tmp_path / "fire_patrol_ctl.py"
    shutil.copy(ROOT / "tests" / "runtime" / "fire_patrol.py", ctl)
    return ctl


@needs_view
def test_run_with_view_prints_the_url_and_ends(tmp_path, capsys):
    ctl = _files(tmp_path)
    out = tmp_path / "out"
    rc = main(["run", str(ctl), "--map", str(FIRE_MAP), "--out", str(out), "--quiet",
               "--no-plot", "--view", "--realtime", "0", "--view-linger", "0.2"])
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    assert "live view: http://127.0.0.1:" in cap.out and "mission completed" in cap.out
    assert "final state served" in cap.err and (out / "summary.json").is_file()


def test_run_view_errors(tmp_path, capsys, monkeypatch):
    ctl = _files(tmp_path)
    base = ["run", str(ctl), "--map", str(FIRE_MAP), "--out", str(tmp_path / "o"), "--quiet"]
    assert main([*base, "--view", "host:notaport"]) == 1
    assert "HOST:PORT" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([*base, "--realtime", "-1"])
    assert "--realtime: must be a non-negative number, not -1" in capsys.readouterr().err
    import iterplan_compiler.view.live as live
    monkeypatch.setattr(live, "missing_dependency", lambda: "needs pip install 'iterplan[view]'")
    assert main([*base, "--view"]) == 1
    assert "iterplan[view]" in capsys.readouterr().err


@needs_view
def test_run_view_port_in_use(tmp_path, capsys):
    ctl = _files(tmp_path)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        rc = main(["run", str(ctl), "--map", str(FIRE_MAP), "--out", str(tmp_path / "o"),
                   "--quiet", "--view", f"127.0.0.1:{port}"])
    assert rc == 1 and "cannot serve the view" in capsys.readouterr().err


def test_realtime_flag_defaults():
    import argparse

    from iterplan_compiler.view.cli import add_view_arguments, realtime
    p = argparse.ArgumentParser()
    add_view_arguments(p)
    assert realtime(p.parse_args([])) is None
    assert realtime(p.parse_args(["--view"])) == 1.0
    assert realtime(p.parse_args(["--view", "--realtime", "20"])) == 20.0
    assert realtime(p.parse_args(["--view", "--realtime", "0"])) is None
    assert realtime(p.parse_args(["--realtime"])) == 1.0


def test_replay_of_a_run_folder(tmp_path, capsys):
    from iterplan_compiler.view.replay import ReplayError, load_run

    ctl = _files(tmp_path)
    out = tmp_path / "out"
    assert main(["run", str(ctl), "--map", str(FIRE_MAP), "--out", str(out), "--quiet",
                 "--no-plot", "--ideal-compute"]) == 0
    capsys.readouterr()
    data = load_run(out, load_map(FIRE_MAP))
    ts = [r[0] for r in data["track"]]
    assert ts == sorted(ts) and data["t0"] < 0 < data["t1"]     # take-off before t = 0
    assert [e[0] for e in data["events"]] == sorted(e[0] for e in data["events"])
    assert len(data["arrivals"]) == 9 and all(a[3] is not None for a in data["arrivals"])
    assert len(data["photos"]) == 2 and data["summary"]["ok"]
    assert data["map"]["per_cell"]
    json.dumps(data, allow_nan=False)
    # Without the map: positions from the track's own lat/lon columns.
    bare = load_run(out)
    assert bare["map"] is None
    a, b = data["arrivals"][0], bare["arrivals"][0]
    assert abs(a[1] - b[1]) < 1e-5 and abs(a[2] - b[2]) < 1e-5
    with pytest.raises(ReplayError, match="lacks"):
        load_run(tmp_path)
    assert main(["view", str(tmp_path / "nope")]) == 1
    assert "not a folder" in capsys.readouterr().err


@needs_view
def test_view_command_serves_the_replay(tmp_path):
    ctl = _files(tmp_path)
    out = tmp_path / "out"
    assert main(["run", str(ctl), "--map", str(FIRE_MAP), "--out", str(out), "--quiet",
                 "--no-plot", "--ideal-compute"]) == 0
    proc = subprocess.Popen([sys.executable, "-m", "iterplan_compiler", "view", str(out),
                             "--map", str(FIRE_MAP), "--linger", "60"],
                            stdout=subprocess.PIPE, text=True, cwd=ROOT)
    try:
        line = proc.stdout.readline()
        assert "replay view: http://127.0.0.1:" in line
        url = line.split()[2]
        import urllib.request
        with urllib.request.urlopen(url + "api/mode", timeout=10) as r:
            assert json.load(r)["mode"] == "replay"
        with urllib.request.urlopen(url + "api/replay", timeout=10) as r:
            data = json.load(r)
        assert data["summary"]["ok"] and len(data["arrivals"]) == 9
    finally:
        proc.terminate()
        assert proc.wait(20) == 0
        proc.stdout.close()
    # terminated right after the announcement (no requests in between): still a clean exit,
    # the SIGTERM handler is in place before the URL is printed
    for _ in range(3):
        proc = subprocess.Popen([sys.executable, "-m", "iterplan_compiler", "view", str(out),
                                 "--map", str(FIRE_MAP), "--linger", "60"],
                                stdout=subprocess.PIPE, text=True, cwd=ROOT)
        assert "replay view:" in proc.stdout.readline()
        proc.terminate()
        assert proc.wait(20) == 0
        proc.stdout.close()


@needs_view
def test_demo_with_view(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("ITERPLAN_NO_BROWSER", "1")
    rc = main(["demo", "--out", str(tmp_path / "d"), "--quiet", "--view", "--realtime", "0",
               "--view-linger", "0"])
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    assert "live view: http://127.0.0.1:" in cap.out and "all patrol cells visited yes" in cap.out


def test_observer_on_a_mavlink_vehicle():
    """Mode and link health come from the MAVLink vehicle (loopback ArduPlane peer)."""
    from iterplan_compiler.runtime.mavlink import MavlinkVehicle
    from tests.runtime.test_mavlink import FAST, MAP, start_peer

    grid = load_map(data=MAP)
    peer, _sim, url = start_peer(grid)
    hub = Hub(map_message(grid))
    deltas = []
    orig = hub.publish
    hub.publish = lambda d: (deltas.append(d), orig(d))[1]   # type: ignore[method-assign]
    try:
        v = MavlinkVehicle.connect(url, grid.frame, FAST)
        try:
            cfg = RunConfig(planner_mode=PlannerMode.CARROT, max_wall=120,
                            observe=Observer(hub, rate=20))
            r = Executor(TABLE, grid, v, config=cfg).run()
        finally:
            v.close()
    finally:
        peer.stop()
    assert r.ok, r.reason
    st = hub.state()
    assert st["simulated"] is False and st["link_ok"] is True
    assert {d["mode"] for d in deltas} >= {"GUIDED"}
    assert st["phase"] == "mission completed" and st["it"]["done"] == 30
    assert len(deltas) > 5 and st["counts"]["arrived"] == 3
