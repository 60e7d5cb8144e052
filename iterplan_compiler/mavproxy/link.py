"""A pymavlink-style connection over a link that MAVProxy owns.

:class:`ModuleLink` is the ``conn`` object a :class:`~iterplan_compiler.runtime.mavlink.
MavlinkVehicle` needs (``recv_match``, ``mav``, ``close``), so the runtime runs unchanged inside
a MAVProxy module:

receiving
    MAVProxy reads the link in its main loop and hands every message from the target vehicle to
    the module's ``mavlink_packet``, which calls :meth:`ModuleLink.feed`; the mission thread
    takes them with :meth:`ModuleLink.recv_match` (a bounded, thread-safe queue: if the mission
    thread stalls, the oldest messages are dropped rather than MAVProxy's memory growing).
sending
    ``mav`` forwards ``xxx_send(...)`` to the current master link's ``mav`` (looked up at every
    call, so MAVProxy's ``link``/``reset`` commands are followed; with no link the send is
    dropped, never raised, so the vehicle's heartbeat thread keeps running).  Sends from the
    mission thread and MAVProxy's own sends (heartbeats, stream requests, other modules) are
    serialized by one lock installed around that link's ``MAVLink.send`` (packing, sequence
    numbers, signing and the socket write happen under it).
stopping
    :meth:`ModuleLink.interrupt` makes the *next* ``recv_match`` raise ``KeyboardInterrupt``
    once, which the executor treats like Ctrl-C in ``iterc run``: it commands the ``--on-end``
    safe state and ends the mission.  The runtime calls ``recv_match`` all the time (every tick,
    every wait for an ACK), so the interrupt lands within a fraction of a second.

Nothing here imports MAVProxy: the class works with any object whose ``master`` has a pymavlink
``mav`` (unit-testable without MAVProxy).
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

#: Attribute set on a pymavlink ``MAVLink`` object whose ``send`` we wrapped with a lock.
_LOCK_ATTR = "_iterplan_send_lock"


def serialize_sends(mav: Any) -> threading.RLock:
    """Wrap ``mav.send`` (a pymavlink ``MAVLink`` object) in a re-entrant lock, once; returns
    the lock.  Every ``xxx_send`` of pymavlink goes through ``self.send``, so this serializes
    all senders on that link, MAVProxy's included."""
    lock = getattr(mav, _LOCK_ATTR, None)
    if lock is not None:
        return lock
    lock = threading.RLock()
    original = mav.send             # the bound class method

    def send(*args: Any, **kwargs: Any) -> None:
        with lock:
            original(*args, **kwargs)

    mav.send = send                  # instance attribute shadows the class method
    setattr(mav, _LOCK_ATTR, lock)
    return lock


def unserialize_sends(mav: Any) -> None:
    """Undo :func:`serialize_sends` (restores the class's ``send``)."""
    if getattr(mav, _LOCK_ATTR, None) is not None:
        try:
            del mav.send
            delattr(mav, _LOCK_ATTR)
        except AttributeError:
            pass


class _Sender:
    """``conn.mav`` of a :class:`ModuleLink`: ``xxx_send`` calls go to the current master."""

    def __init__(self, link: ModuleLink):
        self._link = link

    def __getattr__(self, name: str) -> Callable[..., None]:
        link = self._link

        def call(*args: Any, **kwargs: Any) -> None:
            if link.closed:
                return
            mav = link.master_mav()
            if mav is None:
                return                      # no link right now: drop (heartbeats go on trying)
            serialize_sends(mav)
            link.patched[id(mav)] = mav
            getattr(mav, name)(*args, **kwargs)
        call.__name__ = name
        return call


class ModuleLink:
    """A MAVLink connection object fed by a MAVProxy module; see the module docstring.

    ``get_master`` returns MAVProxy's current master link (``MPModule.master``) or None;
    when ``stop_event`` (MAVProxy's shutdown flag) is set, the next :meth:`recv_match` raises
    ``KeyboardInterrupt`` as after :meth:`interrupt` (at most one interrupt per link).
    """

    def __init__(self, get_master: Callable[[], Any], maxlen: int = 50_000,
                 stop_event: threading.Event | None = None):
        self._get_master = get_master
        self._stop_event = stop_event
        self._stop_seen = False
        self._queue: deque[Any] = deque(maxlen=maxlen)
        self._cv = threading.Condition()
        self._interrupt = False
        self.closed = False
        self.received = 0
        self.patched: dict[int, Any] = {}     # the MAVLink objects whose send we locked
        self.mav = _Sender(self)

    def master_mav(self) -> Any:
        try:
            master = self._get_master()
        except Exception:  # noqa: BLE001 - MAVProxy without links raises IndexError
            return None
        return getattr(master, "mav", None) if master is not None else None

    # -- MAVProxy side --------------------------------------------------------------------------
    def feed(self, msg: Any) -> None:
        """A message from the vehicle (called from MAVProxy's main loop)."""
        if self.closed:
            return
        with self._cv:
            self._queue.append(msg)
            self.received += 1
            self._cv.notify()

    def interrupt(self) -> bool:
        """Make the next :meth:`recv_match` raise ``KeyboardInterrupt``.  Only the first request
        (this or MAVProxy's shutdown flag) ever does: a second one would cut the safe end
        short.  Returns whether this call was that first request."""
        with self._cv:
            if self._stop_seen:
                return False
            self._stop_seen = True
            self._interrupt = True
            self._cv.notify_all()
            return True

    # -- pymavlink connection API used by MavlinkVehicle -----------------------------------------
    def recv_match(self, condition: Any = None, type: Any = None,  # noqa: A002 - pymavlink's name
                   blocking: bool = False, timeout: float | None = None) -> Any:
        """The next message (of ``type``, a name or a list of names, if given) or None: like
        pymavlink's ``recv_match`` (``condition`` is not supported and must be None)."""
        if condition is not None:
            raise NotImplementedError("ModuleLink.recv_match: condition is not supported")
        types = {type} if isinstance(type, str) else (set(type) if type else None)
        deadline = None if timeout is None else time.monotonic() + timeout
        with self._cv:
            while True:
                if self._stop_event is not None and not self._stop_seen \
                        and self._stop_event.is_set():
                    self._stop_seen = True
                    self._interrupt = True
                if self._interrupt:
                    self._interrupt = False
                    raise KeyboardInterrupt("iterplan stop")
                if self._queue:
                    msg = self._queue.popleft()
                    if types is None or msg.get_type() in types:
                        return msg
                    continue
                if not blocking or self.closed:
                    return None
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    return None
                # Wake up now and then to notice MAVProxy's shutdown flag.
                self._cv.wait(0.2 if left is None else min(left, 0.2))

    def close(self) -> None:
        """Stop listening (MAVProxy's link itself stays open: it is not ours)."""
        with self._cv:
            self.closed = True
            self._queue.clear()
            self._cv.notify_all()
