"""``-v`` / ``-q``: the solver's progress on stderr, for the commands that may run long
(``iterc synth``, ``iterc solve``).  Default: on when stderr is a terminal."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable


def add_flags(parser: argparse.ArgumentParser) -> None:
    talk = parser.add_mutually_exclusive_group()
    talk.add_argument("-v", "--verbose", action="store_true",
                      help="print the solver's progress on stderr (default when stderr is "
                           "a terminal)")
    talk.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")


def progress(args: argparse.Namespace) -> Callable[[str], None] | None:
    """Progress lines on stderr (``[12.3 s] …``, seconds since the solve began), or None."""
    if args.quiet or not (args.verbose or sys.stderr.isatty()):
        return None
    start = time.perf_counter()

    def say(msg: str) -> None:
        print(f"[{time.perf_counter() - start:7.1f} s] {msg}", file=sys.stderr, flush=True)

    return say
