"""A live view for one mission: hub + observer + server, as ``iterc run --view`` uses it."""

from __future__ import annotations

import time
from typing import Any

from iterplan_compiler.view import missing_dependency
from iterplan_compiler.view.snapshot import Hub, Observer, map_message


class ViewError(RuntimeError):
    """The view cannot start (missing dependency, bad address, port in use)."""


def parse_address(text: str) -> tuple[str, int]:
    """``HOST:PORT``, ``HOST``, ``:PORT`` or ``PORT`` -> (host, port); default 127.0.0.1:0."""
    text = text.strip()
    host, port = "127.0.0.1", "0"
    if text.startswith("[") and "]" in text:             # [::1]:8080
        host, _, rest = text[1:].partition("]")
        port = rest.lstrip(":") or "0"
    elif text.count(":") == 1:
        host, port = text.split(":")
        host = host or "127.0.0.1"
    elif text.isdigit():
        port = text
    elif text:
        host = text
    try:
        p = int(port)
    except ValueError:
        raise ViewError(f"--view expects HOST:PORT, not {text!r}") from None
    if not 0 <= p <= 65535:
        raise ViewError(f"--view: port {p} out of range")
    return host, p


def wait(seconds: float | None) -> None:
    """Sleep ``seconds`` (None: forever) while the server thread serves; Ctrl-C ends it."""
    end = None if seconds is None else time.monotonic() + seconds
    try:
        while end is None or time.monotonic() < end:
            time.sleep(0.2 if end is None else max(0.0, min(0.2, end - time.monotonic())))
    except KeyboardInterrupt:
        pass


class LiveView:
    """Serves the live page for a mission over ``grid``; :attr:`observe` is the executor hook."""

    def __init__(self, grid: Any, address: str = "127.0.0.1:0", *, title: str = "",
                 rate: float = 5.0):
        problem = missing_dependency()
        if problem:
            raise ViewError(problem)
        from iterplan_compiler.view.server import ViewServer

        host, port = parse_address(address)
        self.hub = Hub(map_message(grid, title))
        self.observe = Observer(self.hub, rate=rate)
        self.server = ViewServer(self.hub, host, port)
        try:
            self.server.start()
        except OSError as exc:
            raise ViewError(f"cannot serve the view on {host}:{port}: "
                            f"{exc.strerror or exc}") from None

    @property
    def url(self) -> str:
        return self.server.url

    def linger(self, seconds: float | None) -> None:
        """Keep serving the final state for ``seconds`` (None: until Ctrl-C / SIGTERM)."""
        wait(seconds)

    def close(self) -> None:
        self.server.stop()
