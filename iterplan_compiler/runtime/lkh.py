"""LKH-3 (through ``elkai``) run in a forked child, so that LKH cannot take the runtime down.

LKH stops the whole process on an internal assertion: on ArduPlane SITL, one flight in six
of a 10-cell Cover with the ``tour`` sorter died at take-off with ``LinKernighan: Assertion
`Gain % Precision == 0' failed`` (the same matrices re-solved in-process did not fail again:
it depends on LKH's state, not only on the input).  An ``abort()`` cannot be caught in
Python, and on the aircraft it would end the runtime in the air.  So every solve runs in a
child process (``os.fork``: no re-import, ~5 ms): the tour comes back through a pipe, and a
child that dies, fails or overruns :data:`TIMEOUT_S` becomes an :class:`LKHError` that the
callers answer with their other methods (the tour sorter's sweep and greedy orders, the ideal's
lower bound).  Where ``fork`` does not exist (Windows) LKH runs in-process, as before.
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


class LKHError(RuntimeError):
    """LKH failed (its child process died, failed or overran); the message says how."""


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
