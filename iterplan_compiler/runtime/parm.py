"""ArduPilot parameter files (``.parm``): ``NAME VALUE`` per line (``,`` or tabs also
separate), ``#`` starts a comment.  Later files win, like ``--defaults a.parm,b.parm``."""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from pathlib import Path

_NAME = re.compile(r"^[A-Z][A-Z0-9_]{0,15}$")


class ParmError(ValueError):
    """A parameter file is malformed; the message names file and line."""


def read_parm(paths: Iterable[str | Path]) -> dict[str, float]:
    """Parameters of ``paths`` (later files win); raises :class:`ParmError`."""
    out: dict[str, float] = {}
    for path in paths:
        try:
            text = Path(path).read_text(encoding="utf-8", errors="replace")
        except OSError as exc:
            raise ParmError(f"{path}: cannot read: {exc.strerror or exc}") from None
        for no, raw in enumerate(text.splitlines(), 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            parts = re.split(r"[\s,]+", line)
            if len(parts) != 2 or not _NAME.match(parts[0]):
                raise ParmError(f"{path}:{no}: expected 'NAME VALUE', got {raw.strip()!r}")
            try:
                value = float(parts[1])
            except ValueError:
                raise ParmError(f"{path}:{no}: {parts[0]}: {parts[1]!r} is not a number") \
                    from None
            if not math.isfinite(value):
                raise ParmError(f"{path}:{no}: {parts[0]}: value must be finite")
            out[parts[0]] = value
    return out
