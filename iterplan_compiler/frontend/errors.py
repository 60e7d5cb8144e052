"""Diagnostics several front-end modules share."""

from __future__ import annotations

from iterplan_compiler.diagnostics import Diagnostic, Span, error


def too_deep(path: str) -> Diagnostic:
    """E0005: the input nests deeper than the front-end's recursive walks allow."""
    return error("E0005", "expression or process nested too deeply to process (Python "
                 "recursion limit); split it into named parts", Span(path, 0, 0))
