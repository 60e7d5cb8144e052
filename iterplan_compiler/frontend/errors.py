"""Diagnostics and error types several front-end modules share."""

from __future__ import annotations

from typing import TYPE_CHECKING

from iterplan_compiler.diagnostics import Diagnostic, Span, error

if TYPE_CHECKING:  # the front-end imports Lark only to parse (see syntax_cache)
    from lark import Token


def too_deep(path: str) -> Diagnostic:
    """E0005: the input nests deeper than the front-end's recursive walks allow."""
    return error("E0005", "expression or process nested too deeply to process (Python "
                 "recursion limit); split it into named parts", Span(path, 0, 0))


def tok_span(path: str, tok: Token) -> Span:
    end_col = tok.end_column if tok.end_line == tok.line else None
    return Span(path, tok.line or 0, tok.column or 0, tok.end_line, end_col)


class Malformed(Exception):
    """A declaration the grammar accepted but that is not valid FSP."""

    def __init__(self, diag: Diagnostic):
        super().__init__(diag.message)
        self.diag = diag
