"""LKH-3 (through ``elkai``) run in a forked child, so that LKH cannot take the runtime down.

LKH stops the whole process on an internal assertion: on ArduPlane SITL, 10 of 24 flights of a
10-cell Cover with the ``tour`` sorter hit ``LinKernighan: Assertion `Gain % Precision == 0'
failed``.  The cause was an overflow: the first tour was planned from ArduPlane's position
before its EKF had an origin (near lat/lon 0, 0: 14,000 km away), so the matrix held entries
of 2.8e9, which LKH multiplies by 100 in 32-bit ints.  Both ends are fixed (the MAVLink
monitor ignores positions before home; :func:`integer_matrix` keeps entries below
:data:`MAX_ENTRY`), and the isolation stays as the defence: an ``abort()`` cannot be caught
in Python, and on the aircraft it would end the runtime in the air.  So every solve runs in a
child process (``os.fork``: no re-import, ~5 ms): the tour comes back through a pipe, and a
child that dies, fails or overruns :data:`TIMEOUT_S` becomes an :class:`LKHError` that the
callers answer with their other methods (the tour sorter's sweep and greedy orders, the ideal's
lower bound) and a ``RuntimeWarning``.  Where ``fork`` does not exist (Windows) LKH runs
in-process, as before.
"""

from __future__ import annotations

import faulthandler
import json
import os
import select
import signal
import time

import numpy as np

#: A solve that takes longer is abandoned (LKH on 2 x 165 + 1 nodes takes ~3 s here).
TIMEOUT_S = 120.0
#: Largest matrix entry handed to LKH.  LKH multiplies every cost by its PRECISION (100) in
#: 32-bit ints; entries of 2.8e9 (a tour planned from a pose 14,000 km away: ArduPlane's
#: position before its EKF has an origin) overflowed into that assertion.  1e7 x 100 leaves
#: a factor 2 below INT_MAX.
MAX_ENTRY = 10_000_000


class LKHError(RuntimeError):
    """LKH failed (its child process died, failed or overran); the message says how."""


def integer_matrix(costs: np.ndarray, unit: float) -> np.ndarray:
    """``costs`` in integer multiples of ``1 / unit`` (e.g. ``unit`` 10: decimetres), with a
    coarser unit where that would put an entry above :data:`MAX_ENTRY` (the order of a tour
    only needs the costs' ratios)."""
    top = float(np.max(costs)) if costs.size else 0.0
    if top * unit > MAX_ENTRY:
        unit = MAX_ENTRY / top
    return np.rint(costs * unit).astype(np.int64)


def solve_matrix(matrix: np.ndarray, *, asymmetric: bool, trials: int | None = None) -> list[int]:
    """A closed tour (0-based, the first node repeated at the end) of the integer distance
    ``matrix`` by LKH-3: one run, LKH's fixed seed (deterministic), at most ``trials`` trials
    (LKH's default: the dimension).  Raises :class:`LKHError`."""
    n = len(matrix)
    params = "RUNS = 1\nPROBLEM_FILE = :stdin:\n"
    if trials is not None:
        params += f"MAX_TRIALS = {int(trials)}\n"
    rows = "\n".join(" ".join(map(str, r)) for r in np.asarray(matrix, np.int64).tolist())
    problem = (f"TYPE : {'ATSP' if asymmetric else 'TSP'}\nDIMENSION : {n}\n"
               "EDGE_WEIGHT_TYPE : EXPLICIT\nEDGE_WEIGHT_FORMAT : FULL_MATRIX\n"
               f"EDGE_WEIGHT_SECTION\n{rows}\n")
    tour = [i - 1 for i in _solve(params, problem)]
    if sorted(tour) != list(range(n)):
        raise LKHError(f"LKH returned no tour of the {n} nodes")
    return [*tour, tour[0]]


def _solve(params: str, problem: str) -> list[int]:
    from elkai import _elkai  # the library's solver entry point: takes LKH parameter text

    if not hasattr(os, "fork"):
        return list(_elkai.solve_problem(params, problem))
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:                                    # the child: solve, report, leave
        status = 1
        try:
            os.close(r)
            faulthandler.disable()      # LKH prints its own message; no Python dump
            out = json.dumps(list(_elkai.solve_problem(params, problem))).encode()
            while out:
                out = out[os.write(w, out):]
            status = 0
        finally:
            os._exit(status)
    os.close(w)
    reply: bytes | None = None
    try:
        reply = _read_all(r, time.monotonic() + TIMEOUT_S)
    finally:                            # also on Ctrl-C: no child is left behind
        os.close(r)
        if reply is None:
            os.kill(pid, signal.SIGKILL)
        _, status = os.waitpid(pid, 0)
    if reply is None:
        raise LKHError(f"LKH took longer than {TIMEOUT_S:g} s")
    if os.WIFSIGNALED(status):
        raise LKHError(f"LKH died ({signal.Signals(os.WTERMSIG(status)).name})")
    if os.WEXITSTATUS(status) != 0:
        raise LKHError(f"LKH failed (exit status {os.WEXITSTATUS(status)})")
    return [int(i) for i in json.loads(reply)]


def _read_all(fd: int, deadline: float) -> bytes | None:
    """Everything written to ``fd`` until its writer closes it, or None at ``deadline``."""
    chunks: list[bytes] = []
    while True:
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([fd], [], [], left)[0]:
            return None
        chunk = os.read(fd, 1 << 16)
        if not chunk:
            return b"".join(chunks)
        chunks.append(chunk)
