"""A tiny line emitter for generated source text.

Back-ends build text through :class:`Emitter` instead of concatenating strings with
hand-counted indentation, so nesting is visible in the back-end's own code.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager


class Emitter:
    """Accumulate lines at the current indentation; :meth:`text` joins them with ``\\n``."""

    def __init__(self, indent_unit: str = "    ") -> None:
        self._lines: list[str] = []
        self._level = 0
        self._unit = indent_unit

    def line(self, text: str = "") -> None:
        """Append one line (an empty ``text`` gives a blank line without trailing spaces)."""
        self._lines.append(self._unit * self._level + text if text else "")

    def lines(self, *texts: str) -> None:
        """Append several lines at the current indentation."""
        for t in texts:
            self.line(t)

    @contextmanager
    def indent(self) -> Iterator[None]:
        """Indent the lines emitted inside the ``with`` block by one unit."""
        self._level += 1
        try:
            yield
        finally:
            self._level -= 1

    def text(self) -> str:
        """Return the accumulated text, ending with exactly one newline."""
        return "\n".join(self._lines).rstrip("\n") + "\n"
