"""Resource limits of the compiler, as one policy (README "Limits").

Every limit has a default, a command-line flag that overrides it (added to the compiler
commands by :func:`add_arguments`, read back by :func:`apply`), and one diagnostic that names
the figure reached and the flag that raises it.  The stages read the *current* policy
(:func:`current`) when they check, so a flag applies to the whole run.

=====================  ======================  ==========================================
limit                  flag                    checked
=====================  ======================  ==========================================
integer size (bits)    ``--max-int-bits``      integer literals (before conversion) and
                                               every arithmetic result (``**`` and ``<<``
                                               before computing), E0208
states of a machine    ``--max-states``        while composing (each new state), E0402
temporal depth         ``--max-temporal-depth`` nesting of X/U/W/[]/<> in a formula,
                                               before building its automaton, E0603
temporal size          ``--max-temporal-ops``  distinct X/U/W/[]/<> subformulas of a
                                               formula (its automaton can have 2^n
                                               states), before building it, E0603
declarations           ``--max-declarations``  top-level definitions of one file, counted
                                               before parsing it (parsing is ~1 ms each), E0006
memory (MB)            ``--max-memory``        resident set size, sampled 4x a second by a
                                               watchdog thread (BDD nodes included), E0405
wall time (seconds)    ``--time-limit``        at the state-count check points, and by
                                               the watchdog (even inside a BDD operation),
                                               E0404
=====================  ======================  ==========================================

The watchdog (:func:`start_watchdog`, started by ``iterc`` itself, not by library callers)
ends the process with exit 1 and the diagnostic when the memory or time limit is passed,
wherever the program is -- a long BDD operation in CUDD included.

This module is stdlib-only and imports nothing else from iterplan.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import threading
import time
from dataclasses import dataclass, replace
from typing import Any

__all__ = ["Limits", "LimitReached", "add_arguments", "apply", "current", "set_limits",
           "int_too_large", "check_int", "deadline_passed"]


@dataclass(frozen=True)
class Limits:
    """The limits in force; ``0`` for ``time_limit`` means none."""

    max_int_bits: int = 1024
    max_states: int = 300_000
    max_temporal_depth: int = 12
    max_temporal_ops: int = 10
    max_declarations: int = 2_000
    max_memory_mb: int = 1_536
    time_limit: float = 0.0


DEFAULT = Limits()

#: limit field -> (flag, what it bounds), for messages and ``--help``
FLAGS: dict[str, tuple[str, str]] = {
    "max_int_bits": ("--max-int-bits", "bits of any integer value or literal"),
    "max_states": ("--max-states", "states of any composed machine (checked while composing)"),
    "max_temporal_depth": ("--max-temporal-depth",
                           "nesting depth of temporal operators (X U W [] <>) in a formula"),
    "max_temporal_ops": ("--max-temporal-ops",
                         "distinct temporal subformulas (X U W [] <>) in one formula"),
    "max_declarations": ("--max-declarations",
                         "top-level declarations in one file (checked before parsing)"),
    "max_memory_mb": ("--max-memory", "MB of memory (resident set) for the command"),
    "time_limit": ("--time-limit", "seconds of wall time for the command (0: none)"),
}

#: the diagnostic code of each limit
CODES: dict[str, str] = {"max_int_bits": "E0208", "max_states": "E0402",
                         "max_temporal_depth": "E0603", "max_temporal_ops": "E0603",
                         "max_declarations": "E0006", "max_memory_mb": "E0405",
                         "time_limit": "E0404"}

_current = DEFAULT
_started = time.monotonic()


class LimitReached(Exception):
    """A resource limit was reached; ``message`` names the figure and the flag."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field
        self.message = message

    @property
    def code(self) -> str:
        return CODES.get(self.field, "E0404")


def current() -> Limits:
    return _current


def set_limits(limits: Limits | None = None, **changes) -> Limits:
    """Install ``limits`` (or the current ones with ``changes``); returns the previous policy
    (so tests can restore it) and restarts the wall-time clock."""
    global _current, _started
    previous = _current
    base = limits if limits is not None else _current
    _current = replace(base, **changes) if changes else base
    _started = time.monotonic()
    return previous


def flag(field: str) -> str:
    return FLAGS[field][0]


def hint(field: str) -> str:
    """``(limit N, raise with --flag)`` for a message."""
    return f"the limit is {getattr(_current, field):,}; raise it with {flag(field)}"


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if v <= 0:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return v


def _seconds(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds, got {text!r}") from None
    if not math.isfinite(v) or v < 0:
        raise argparse.ArgumentTypeError(f"expected a non-negative number, got {text!r}")
    return v


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the limit flags to a compiler command's parser."""
    g = parser.add_argument_group("resource limits")
    for field, (name, what) in FLAGS.items():
        default = getattr(DEFAULT, field)
        g.add_argument(name, dest=f"limit_{field}", metavar="N", default=None,
                       type=_seconds if field == "time_limit" else _positive_int,
                       help=f"{what} (default {default:,})")


def apply(args: argparse.Namespace) -> Limits:
    """Install the limits given on the command line (defaults for the others)."""
    changes = {f: getattr(args, f"limit_{f}") for f in FLAGS
               if getattr(args, f"limit_{f}", None) is not None}
    set_limits(DEFAULT, **changes)
    return _current


# ------------------------------------------------------------------ integer size

_LOG2_10 = math.log2(10)


def literal_too_large(text: str) -> str | None:
    """A message if the integer literal ``text`` (decimal, ``0x`` hex or ``0`` octal) has more
    bits than allowed -- decided from its digit count, before converting it."""
    digits = text.lstrip("+-")
    if digits[:2] in ("0x", "0X"):
        bits = 4 * len(digits[2:].lstrip("0"))
    else:
        bits = math.ceil(len(digits.lstrip("0")) * _LOG2_10)
    if bits > _current.max_int_bits + 4:  # the digit estimate is a few bits generous
        return (f"integer literal of {len(digits):,} digits (about {bits:,} bits) is too "
                f"large: {hint('max_int_bits')}")
    return None


def int_too_large(v: int) -> str | None:
    """A message if ``v`` has more bits than allowed."""
    b = v.bit_length()
    if b > _current.max_int_bits:
        return f"integer value of {b:,} bits is too large: {hint('max_int_bits')}"
    return None


def check_int(v: int) -> int:
    """``v``, or :class:`LimitReached` if it is too large."""
    msg = int_too_large(v)
    if msg is not None:
        raise LimitReached("max_int_bits", msg)
    return v


def power_too_large(base_bits: int, exponent: int) -> str | None:
    """A message if ``x ** exponent`` with ``x`` of ``base_bits`` bits would be too large
    (decided before computing it)."""
    if base_bits <= 1 or exponent <= 1:
        return None
    bits = (base_bits - 1) * exponent
    if bits > _current.max_int_bits:
        return (f"power of about {bits:,} bits is too large: {hint('max_int_bits')}")
    return None


# ------------------------------------------------------------------ formula size

_TEMPORAL = frozenset({"Next", "Always", "Eventually", "Until", "WeakUntil"})


def formula_too_large(formula: object) -> str | None:
    """A message if ``formula`` (an :mod:`iterplan_compiler.ir.formulas` tree) nests temporal
    operators deeper than ``--max-temporal-depth`` or has more distinct temporal subformulas
    than ``--max-temporal-ops`` -- decided by one walk, before any automaton is built (the
    tableau's size is exponential in both)."""
    depth_max = 0
    temporal: set[object] = set()
    stack = [(formula, 0)]
    while stack:
        f, d = stack.pop()
        if type(f).__name__ in _TEMPORAL:
            d += 1
            try:
                temporal.add(f)  # structural: a repeated subformula counts once
            except (RecursionError, TypeError):  # hashing a very deep (or odd) tree
                temporal.add(id(f))
        depth_max = max(depth_max, d)
        for child in ("arg", "left", "right"):
            sub = getattr(f, child, None)
            if sub is not None:
                stack.append((sub, d))
    if depth_max > _current.max_temporal_depth:
        return (f"the formula nests temporal operators {depth_max} deep: "
                f"{hint('max_temporal_depth')}")
    if len(temporal) > _current.max_temporal_ops:
        return (f"the formula has {len(temporal)} temporal subformulas (its automaton may "
                f"have 2^{len(temporal)} states): {hint('max_temporal_ops')}")
    return None


# ------------------------------------------------------------------ state count, wall time


def states_message(n: int, what: str = "a machine") -> str:
    return f"{what} has more than {n:,} states: {hint('max_states')}"


def deadline_passed() -> str | None:
    """A message if the command has run longer than ``--time-limit``."""
    limit = _current.time_limit
    if limit and time.monotonic() - _started > limit:
        return (f"the command ran longer than {limit:g} s: the time limit is {limit:g} s; "
                f"raise it with {flag('time_limit')}")
    return None


def check_deadline() -> None:
    """:class:`LimitReached` if the command has run longer than ``--time-limit``."""
    msg = deadline_passed()
    if msg is not None:
        raise LimitReached("time_limit", msg)


def elapsed() -> float:
    return time.monotonic() - _started


# ------------------------------------------------------------------ watchdog (memory, time)


def rss_mb() -> float:
    """The process's resident set size in MB (peak RSS where /proc is not available)."""
    try:
        with open("/proc/self/statm") as f:
            pages = int(f.read().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (OSError, ValueError, IndexError, AttributeError):
        try:
            import resource

            peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
            return peak / (2**20 if sys.platform == "darwin" else 2**10)
        except (ImportError, OSError):
            return 0.0


_watchdog_stop: threading.Event | None = None
_stage = ["", 0]  # what the command is doing, and a count (states), for the progress line
PROGRESS_AFTER_S = 2.0


def progress(stage: str | None = None, count: int | None = None) -> None:
    """Tell the progress line what is happening (cheap: two assignments; safe anywhere)."""
    if stage is not None:
        _stage[0] = stage
    if count is not None:
        _stage[1] = count


class _ProgressLine:
    """A status line on stderr (a TTY only) once a command runs longer than 2 s: tqdm's
    spinner-less bar with the stage, the states explored, elapsed time and memory."""

    def __init__(self, label: str) -> None:
        self.label = label
        self.bar: Any = None  # a tqdm bar once shown
        self.enabled = _stderr_is_tty()

    def tick(self, mem: float) -> None:
        if not self.enabled or elapsed() < PROGRESS_AFTER_S:
            return
        if self.bar is None:
            try:
                from tqdm import tqdm
            except ImportError:  # pragma: no cover - tqdm is a dependency
                self.enabled = False
                return
            self.bar = tqdm(total=None, file=sys.stderr, leave=False, dynamic_ncols=True,
                            bar_format="{desc} {postfix}")
        stage, count = _stage
        self.bar.set_description_str(f"{self.label}: {stage or 'working'}", refresh=False)
        states = f"{count:,} states, " if count else ""
        self.bar.set_postfix_str(f"[{elapsed():.0f} s, {states}{mem:,.0f} MB]", refresh=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def _stderr_is_tty() -> bool:
    try:
        return sys.stderr.isatty() and os.environ.get("TERM") != "dumb"
    except (AttributeError, ValueError):
        return False


def watchdog_breach() -> tuple[str, str] | None:
    """``(code, message)`` if the memory or time limit is passed now."""
    mem = rss_mb()
    if mem > _current.max_memory_mb:
        return "E0405", (f"the command uses {mem:,.0f} MB of memory: "
                         f"{hint('max_memory_mb')} (MB)")
    msg = deadline_passed()
    if msg is not None:
        return "E0404", msg
    return None


def start_watchdog(interval: float = 0.25, *, exit_code: int = 1,
                   label: str = "iterc") -> None:
    """Check memory and time every ``interval`` s in a daemon thread; on a breach print
    ``iterc: error[CODE]: message`` and end the process at once with ``exit_code`` (outputs
    are written atomically, so nothing half-written is left).  On a TTY it also shows a
    progress line (:func:`progress`) once the command has run for 2 s."""
    global _watchdog_stop
    stop_watchdog()
    stop = threading.Event()
    _watchdog_stop = stop
    line = _ProgressLine(label)
    _stage[:] = ["", 0]

    def loop() -> None:
        while not stop.wait(interval):
            breach = watchdog_breach()
            if breach is None:
                try:
                    line.tick(rss_mb())
                except Exception:  # noqa: BLE001 - a display problem must not stop the work
                    line.enabled = False
                continue
            if breach is not None:
                line.close()
                try:
                    sys.stdout.flush()
                except (OSError, ValueError):
                    pass
                os.write(2, f"iterc: error[{breach[0]}]: {breach[1]}\n".encode())
                os._exit(exit_code)

        line.close()

    thread = threading.Thread(target=loop, name="iterplan-limits-watchdog", daemon=True)
    _threads[:] = [thread]
    thread.start()


_threads: list[threading.Thread] = []


def stop_watchdog() -> None:
    global _watchdog_stop
    if _watchdog_stop is not None:
        _watchdog_stop.set()
        _watchdog_stop = None
        for t in _threads:
            t.join(timeout=1.0)  # lets the progress line clear itself
        _threads.clear()
