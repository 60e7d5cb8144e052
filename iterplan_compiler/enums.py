"""The one base class for the project's option enums (bottom layer: no imports of its own)."""

from __future__ import annotations

import enum

__all__ = ["StrEnum"]


class StrEnum(str, enum.Enum):
    """An enum whose members are their string values (``enum.StrEnum`` is Python 3.11+; the
    project supports 3.10): ``str(m)`` and ``f"{m}"`` give the value, as the CLI prints it."""

    def __str__(self) -> str:
        return str(self.value)

    def __format__(self, spec: str) -> str:
        return format(str(self.value), spec)
