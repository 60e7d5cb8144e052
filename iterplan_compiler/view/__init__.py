"""Live mission view: a web page with the map, the aircraft, the iterator and the controller.

``iterc run ... --view`` and ``iterc demo --view`` serve it while the mission flies; ``iterc view
RUN_DIR`` replays a finished run from its output files.  See ``docs/runtime.md`` ("Live view").

Layout (the runtime never imports this package; this package imports the web framework lazily):

* :mod:`.snapshot` — :class:`~.snapshot.Observer`, the executor's ``RunConfig.observe`` hook: at
  most ``rate`` times per wall second it copies the few things that changed (pose, track tail,
  iterator counters, controller state, new log entries) into a :class:`~.snapshot.Hub`.  Only
  NumPy and the standard library: cheap and safe in the executor's thread.
* :mod:`.server` — the aiohttp application (page, Leaflet from the ``xstatic-leaflet`` package,
  a WebSocket that streams the hub's deltas), run in its own thread with its own event loop.
* :mod:`.replay` — a finished run's ``track.csv``/``events.csv``/``summary.json`` as the page's
  replay data (time slider).
* :mod:`.cli` — the ``--view``/``--realtime``/``--view-linger`` flags shared by ``iterc run``
  and ``iterc demo``.

The dependencies are the optional group ``iterplan[view]`` (aiohttp, xstatic-leaflet).
"""

from __future__ import annotations

MISSING = ("the live view needs the optional dependencies: pip install 'iterplan[view]' "
           "(aiohttp, xstatic-leaflet)")


def missing_dependency() -> str | None:
    """None if the view's dependencies import, else a message saying what to install."""
    try:
        import aiohttp  # noqa: F401
        import xstatic.pkg.leaflet  # noqa: F401
    except ImportError as exc:
        return f"{MISSING}: {exc}"
    return None
