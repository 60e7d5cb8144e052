"""What a mission run reads and writes, shared by ``iterc run`` and the MAVProxy module:
the output folder check (before take-off), the output files written however a run ends, and
the ``--until LABEL[:K]`` end condition."""

from __future__ import annotations

import argparse
import csv
import io
import math
import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from iterplan_compiler.outputs import (
    OutputError,
    atomic_write_text,
    check_writable_dir,
    refuse_overwrite_input,
)
from iterplan_compiler.runtime.bindings import canon

OUTPUTS = ("track.csv", "track.geojson", "events.csv", "summary.json", "track.png",
           "commands.csv")


def check_out(out: Path, inputs: list[Path]) -> str | None:
    """Problems with ``--out`` found before the mission (so a flight's log is never lost):
    not a writable folder, or a folder whose outputs would overwrite an input file."""
    try:
        refuse_overwrite_input(out, inputs)
        check_writable_dir(out)
        for name in OUTPUTS:
            refuse_overwrite_input(out / name, inputs)
    except OutputError as exc:
        return f"--out {out}: {exc}"
    return None


def write_outputs(result: Any, out: Path, vehicle: Any, plot: bool) -> None:
    """Every output file written atomically (``outputs.py``); files of a previous run are
    removed first and ``summary.json`` comes last, so a folder with a ``summary.json`` holds
    one whole set (``ok``/``reason`` in it say whether the mission completed).  A second
    Ctrl-C must not cut the outputs short."""
    with _interrupts_deferred():
        for stale in OUTPUTS:               # never leave a previous run's files beside these
            (out / stale).unlink(missing_ok=True)
        result.write_track_csv(out / "track.csv")
        result.write_geojson(out / "track.geojson")
        result.write_events_csv(out / "events.csv")
        log = getattr(vehicle, "command_log", None)
        if log is not None:
            buf = io.StringIO(newline="")
            w = csv.writer(buf)
            w.writerow(["t", "command", "detail"])
            for t, name, detail in log:
                w.writerow([f"{t:.2f}", name, detail])
            atomic_write_text(out / "commands.csv", buf.getvalue())
        if plot:
            result.plot(out / "track.png")
        result.write_summary(out / "summary.json")    # last: its presence marks a whole set


@contextmanager
def _interrupts_deferred() -> Iterator[None]:
    """Ignore SIGINT/SIGTERM while the outputs are written (the mission has ended anyway)."""
    try:
        old = {s: signal.signal(s, signal.SIG_IGN) for s in (signal.SIGINT, signal.SIGTERM)}
    except ValueError:
        yield
        return
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0 (speeds, radii, times)."""
    return _finite(text, 0.0, strict=True)


def non_negative_float(text: str) -> float:
    """argparse type: a finite number >= 0 (factors, seconds where 0 means "none")."""
    return _finite(text, 0.0, strict=False)


def _finite(text: str, low: float, strict: bool) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(v) or v < low or (strict and v == low):
        raise argparse.ArgumentTypeError(
            f"must be a {'positive' if strict else 'non-negative'} number, not {text}")
    return v


@contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM and SIGINT raise KeyboardInterrupt inside the block: a mission then ends in its
    safe state with its outputs instead of being killed.  SIGINT is set here too, because a
    process started in the background by a non-interactive shell inherits it *ignored* (and
    Python then installs no Ctrl-C handler): a mission must stay interruptible however it was
    started."""
    def handler(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt(f"signal {signum}")
    try:
        old: dict[int, Any] = {s: signal.signal(s, handler)
                               for s in (signal.SIGTERM, signal.SIGINT)}
    except ValueError:          # not the main thread (an embedding application)
        yield
        return
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def parse_until(text: str) -> tuple[str, int] | None:
    """``LABEL`` or ``LABEL:K`` -> (canonical label, K), or None if malformed."""
    label, _, count = text.partition(":")
    label = canon(label)
    if not label:
        return None
    if not count:
        return label, 1
    try:
        k = int(count)
    except ValueError:
        return None
    return (label, k) if k >= 1 else None


def until_hook(label: str, k: int) -> Callable[[str, str], bool]:
    """Executor ``on_event`` hook: True (end the mission) at the k-th event ``label``."""
    seen = [0]

    def hook(kind: str, event: str) -> bool:
        if canon(event) != label:
            return False
        seen[0] += 1
        return seen[0] >= k
    return hook
