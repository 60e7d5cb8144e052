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
wall time (seconds)    ``--time-limit``        at the state-count check points, E0404
=====================  ======================  ==========================================

This module is stdlib-only and imports nothing else from iterplan.
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass, replace

__all__ = ["Limits", "LimitReached", "add_arguments", "apply", "current", "set_limits",
           "int_too_large", "check_int", "deadline_passed"]


@dataclass(frozen=True)
class Limits:
    """The limits in force; ``0`` for ``time_limit`` means none."""

    max_int_bits: int = 1024
    max_states: int = 300_000
    max_temporal_depth: int = 12
    time_limit: float = 0.0


DEFAULT = Limits()

#: limit field -> (flag, what it bounds), for messages and ``--help``
FLAGS: dict[str, tuple[str, str]] = {
    "max_int_bits": ("--max-int-bits", "bits of any integer value or literal"),
    "max_states": ("--max-states", "states of any composed machine (checked while composing)"),
    "max_temporal_depth": ("--max-temporal-depth",
                           "nesting depth of temporal operators (X U W [] <>) in a formula"),
    "time_limit": ("--time-limit", "seconds of wall time for the command (0: none)"),
}

_current = DEFAULT
_started = time.monotonic()


class LimitReached(Exception):
    """A resource limit was reached; ``message`` names the figure and the flag."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field
        self.message = message


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
