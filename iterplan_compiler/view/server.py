"""The live view's web server: aiohttp in its own thread, with its own event loop.

Routes (all read-only; nothing reaches the aircraft from the page):

* ``/`` — the page (``static/index.html``), ``/static/*`` its script and style;
* ``/leaflet/*`` — Leaflet, served from the ``xstatic-leaflet`` package (no CDN: the aircraft's
  companion computer has no internet);
* ``/ws`` — WebSocket: the map and the whole state on connect, then the hub's deltas (polled
  every ``poll`` seconds, so the executor's thread never waits for a page);
* ``/api/state`` — the cumulative state as JSON; ``/api/replay`` — a replayed run.

Importing this module imports aiohttp: only :mod:`iterplan_compiler.view.live` and
``iterc view`` do, after checking :func:`iterplan_compiler.view.missing_dependency`.
"""

from __future__ import annotations

import asyncio
import json
import threading
import time
from pathlib import Path

from aiohttp import WSMsgType, web

from iterplan_compiler.view.snapshot import Hub

STATIC = Path(__file__).parent / "static"


def _leaflet_dir() -> Path:
    import xstatic.pkg.leaflet as leaflet

    return Path(leaflet.BASE_DIR)


def _dumps(obj) -> str:
    return json.dumps(obj, separators=(",", ":"), allow_nan=False, default=_default)


def _default(o):
    try:
        import numpy as np

        if isinstance(o, np.generic):
            return o.item()
    except ImportError:  # pragma: no cover
        pass
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def make_app(hub: Hub, poll: float = 0.2) -> web.Application:
    app = web.Application()
    sockets: set[web.WebSocketResponse] = set()

    async def index(request: web.Request) -> web.StreamResponse:
        return web.FileResponse(STATIC / "index.html",
                                headers={"Cache-Control": "no-store"})

    async def state(request: web.Request) -> web.Response:
        return web.Response(text=_dumps(hub.state()), content_type="application/json",
                            headers={"Cache-Control": "no-store"})

    async def replay(request: web.Request) -> web.Response:
        if hub.replay is None:
            raise web.HTTPNotFound(text="not a replay")
        return web.Response(text=_dumps(hub.replay), content_type="application/json")

    async def mode(request: web.Request) -> web.Response:
        return web.json_response({"mode": "replay" if hub.replay is not None else "live"})

    async def ws_handler(request: web.Request) -> web.WebSocketResponse:
        ws = web.WebSocketResponse(heartbeat=20.0)
        await ws.prepare(request)
        sockets.add(ws)
        try:
            seq, msgs = hub.full()
            for m in msgs:
                await ws.send_str(_dumps(m))
            reader = asyncio.ensure_future(_drain(ws))
            while not ws.closed and not reader.done():
                await asyncio.sleep(poll)
                deltas = hub.since(seq)
                if deltas is None:                 # fell behind: start again from the whole
                    seq, deltas = hub.full()
                    deltas = deltas[1:]
                elif deltas:
                    seq = deltas[-1]["seq"]
                for m in deltas:
                    await ws.send_str(_dumps(m))
            reader.cancel()
        except ConnectionResetError:      # the page went away
            pass
        finally:
            sockets.discard(ws)
        return ws

    async def on_shutdown(app: web.Application) -> None:
        for ws in list(sockets):
            await ws.close(code=1001, message=b"server shutdown")

    app.router.add_get("/", index)
    app.router.add_get("/api/state", state)
    app.router.add_get("/api/replay", replay)
    app.router.add_get("/api/mode", mode)
    app.router.add_get("/ws", ws_handler)
    app.router.add_static("/static/", STATIC)
    app.router.add_static("/leaflet/", _leaflet_dir())
    app.on_shutdown.append(on_shutdown)
    return app


async def _drain(ws: web.WebSocketResponse) -> None:
    """Read (and ignore) what the page sends: the view is read-only."""
    async for msg in ws:
        if msg.type in (WSMsgType.ERROR, WSMsgType.CLOSE):
            break


class ViewServer:
    """Serves ``hub`` on ``host:port`` (port 0: a free one) from a daemon thread."""

    def __init__(self, hub: Hub, host: str = "127.0.0.1", port: int = 0, poll: float = 0.2):
        self.hub = hub
        self.host = host
        self.port = port
        self.poll = poll
        self._loop: asyncio.AbstractEventLoop | None = None
        self._runner: web.AppRunner | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None
        self.cpu_s = 0.0

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    def start(self, timeout: float = 10.0) -> ViewServer:
        self._thread = threading.Thread(target=self._serve, name="iterplan-view", daemon=True)
        self._thread.start()
        if not self._ready.wait(timeout):
            raise OSError("the view server did not start")
        if self._error is not None:
            raise self._error
        return self

    def _serve(self) -> None:
        loop = asyncio.new_event_loop()
        self._loop = loop
        asyncio.set_event_loop(loop)
        try:
            runner = web.AppRunner(make_app(self.hub, self.poll), access_log=None,
                                   handle_signals=False, shutdown_timeout=1.0)
            loop.run_until_complete(runner.setup())
            site = web.TCPSite(runner, self.host, self.port)
            loop.run_until_complete(site.start())
            self._runner = runner
            self.port = int(runner.addresses[0][1])
        except BaseException as exc:  # noqa: BLE001 - reported to start()
            self._error = exc
            self._ready.set()
            loop.close()
            return
        self._ready.set()
        try:
            loop.run_forever()
        finally:
            loop.run_until_complete(runner.cleanup())
            loop.close()
            self.cpu_s = time.thread_time()      # CPU this thread used (loop_bench --view)

    def stop(self, timeout: float = 5.0) -> None:
        loop, thread = self._loop, self._thread
        if loop is None or thread is None or not thread.is_alive():
            return
        loop.call_soon_threadsafe(loop.stop)
        thread.join(timeout)
