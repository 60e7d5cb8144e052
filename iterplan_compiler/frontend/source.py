"""Reading spec files: bytes -> text, with binary input detected up front (E0008).

A binary file (an executable, an image, a compiled file given by mistake) would otherwise be
lexed byte by byte: dozens of "unexpected character" errors of raw bytes, and seconds of work on
a large file.  The check looks at the first :data:`SNIFF` bytes only, so it is instant for any
size: more than one NUL byte, or more than :data:`MAX_CONTROL` of the bytes being control
characters other than tab, newline, form feed and carriage return, means "not a text file"
(a stray NUL in a text file is left to the lexer, which reports it where it is).
"""

from __future__ import annotations

from pathlib import Path

SNIFF = 8192
MAX_CONTROL = 0.05
_CONTROL = bytes(b for b in range(32) if b not in (9, 10, 12, 13)) + b"\x7f"


def binary_at(data: bytes) -> tuple[int, int] | None:
    """``(line, column)`` of the first NUL or control byte when ``data`` (the start of a file)
    is not text, else None."""
    head = data[:SNIFF]
    if not head:
        return None
    control = len(head) - len(head.translate(None, _CONTROL))
    if head.count(b"\0") < 2 and control <= MAX_CONTROL * len(head):
        return None
    first = next(i for i, b in enumerate(head) if b == 0 or b in _CONTROL)
    line = head.count(b"\n", 0, first) + 1
    return line, first - (head.rfind(b"\n", 0, first) + 1) + 1


def text_binary_at(text: str) -> tuple[int, int] | None:
    """:func:`binary_at` for text already decoded (``text=`` callers, tests)."""
    return binary_at(text[:SNIFF].encode("utf-8", errors="replace"))


def decode(data: bytes) -> str:
    """Decode like every reader of spec files: UTF-8, a byte-order mark dropped, bad bytes as
    U+FFFD (the lexer then reports them with a position)."""
    return data.decode("utf-8-sig", errors="replace")


def read_spec(path: str | Path) -> str | tuple[int, int]:
    """The text of the spec file at ``path``, or where its first binary byte is when it is not
    a text file.  ``OSError`` propagates (the caller reports E0800 / E0801 with the OS's
    reason)."""
    data = Path(path).read_bytes()
    where = binary_at(data)
    return where if where is not None else decode(data)
