"""Diagnostics as values: stable codes, severities, source spans, one renderer.

Every stage returns diagnostics instead of raising for bad *user input*; exceptions mean
compiler bugs.  Only :func:`render` formats ``file:line:col: error[CODE]: message`` followed by
the source line and a caret.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field


class Severity(enum.Enum):
    """How bad a diagnostic is; ``ERROR`` stops the pipeline after the current stage."""

    ERROR = "error"
    WARNING = "warning"
    NOTE = "note"


@dataclass(frozen=True, slots=True)
class Span:
    """A half-open region of a source file; lines and columns are 1-based."""

    file: str
    line: int
    column: int
    end_line: int | None = None
    end_column: int | None = None

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


NO_SPAN = Span("<unknown>", 0, 0)


@dataclass(frozen=True, slots=True)
class Related:
    """A secondary location attached to a diagnostic (e.g. the first of two definitions)."""

    span: Span
    message: str


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """One message about the user's input.

    ``code`` is stable across releases (tests and users may match on it), e.g. ``E101``.
    """

    code: str
    severity: Severity
    message: str
    span: Span = NO_SPAN
    related: tuple[Related, ...] = field(default=())

    @property
    def is_error(self) -> bool:
        return self.severity is Severity.ERROR


def error(code: str, message: str, span: Span = NO_SPAN, *related: Related) -> Diagnostic:
    """Build an error diagnostic."""
    return Diagnostic(code, Severity.ERROR, message, span, tuple(related))


def warning(code: str, message: str, span: Span = NO_SPAN, *related: Related) -> Diagnostic:
    """Build a warning diagnostic."""
    return Diagnostic(code, Severity.WARNING, message, span, tuple(related))


def has_errors(diags: Iterable[Diagnostic]) -> bool:
    """Return True if any diagnostic is an error."""
    return any(d.is_error for d in diags)


class DiagnosticError(Exception):
    """Raised by a driver when a stage produced errors; carries the diagnostics.

    Stages themselves return diagnostics; only drivers and the CLI raise/catch this.
    """

    def __init__(self, diagnostics: Sequence[Diagnostic]):
        self.diagnostics = tuple(diagnostics)
        super().__init__("; ".join(d.message for d in self.diagnostics[:3]))


def _caret_line(source_line: str, column: int, end_column: int | None) -> str:
    prefix = "".join("\t" if ch == "\t" else " " for ch in source_line[: max(column - 1, 0)])
    width = 1
    if end_column is not None and end_column > column:
        width = end_column - column
    return prefix + "^" + "~" * (width - 1)


def render_one(diag: Diagnostic, sources: dict[str, str] | None = None) -> str:
    """Format one diagnostic, with the source line and a caret when the source is known."""
    sources = sources or {}
    out: list[str] = []

    def located(span: Span, head: str) -> None:
        if span.line > 0:
            out.append(f"{span}: {head}")
            text = sources.get(span.file)
            if text is not None:
                lines = text.splitlines()
                if 0 < span.line <= len(lines):
                    src = lines[span.line - 1]
                    end = span.end_column if span.end_line in (None, span.line) else None
                    out.append("    " + src)
                    out.append("    " + _caret_line(src, span.column, end))
        else:
            out.append(head if span.file == NO_SPAN.file else f"{span.file}: {head}")

    located(diag.span, f"{diag.severity.value}[{diag.code}]: {diag.message}")
    for rel in diag.related:
        located(rel.span, f"note: {rel.message}")
    return "\n".join(out)


def render(diags: Iterable[Diagnostic], sources: dict[str, str] | None = None) -> str:
    """Format diagnostics in order, one block each, separated by newlines."""
    return "\n".join(render_one(d, sources) for d in diags)
