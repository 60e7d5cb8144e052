"""Diagnostics as values: stable codes, severities, source spans, one renderer, one registry.

Every stage returns diagnostics instead of raising for bad *user input*; exceptions mean
compiler bugs.  Only :func:`render` formats ``file:line:col: error[CODE]: message`` followed by
the source line and a caret.

Every code a stage may emit is listed in :data:`CODES` with its stage and meaning (a test
checks that every code literal in ``iterplan_compiler`` is registered).  The scheme is one
letter and four digits: ``E`` error, ``W`` warning; the hundreds give the stage
(:class:`Stage`).  The ``G`` codes of the GR(1) input formats (``iterc solve``, package
``gr1``) are a separate family of three digits.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field


class Stage(enum.Enum):
    """The pipeline stage (or command) a diagnostic code belongs to."""

    INPUT = "input"            # E00xx reading, lexing and parsing
    NAMES = "names"            # E01xx declarations and references
    EXPRESSIONS = "expressions"  # E02xx constant expressions, ranges, sets
    PROCESSES = "processes"    # E03xx sequential processes
    COMPOSITION = "composition"  # E04xx composition, operators, resource limits
    FLUENTS = "fluents"        # E05xx fluents
    FORMULAS = "formulas"      # E06xx FLTL formulas, asserts, safety automata, verify
    SPECS = "specs"            # E07xx controllerSpec
    FILES = "files"            # E08xx files and includes
    SYNTHESIS = "synthesis"    # E09xx synthesis problems and verdicts
    EMIT = "emit"              # E10xx back-ends
    LTSA = "ltsa"              # E13xx LTSA analyses and the animator
    GR1 = "gr1"                # Gxxx slugsin / structured slugs input


@dataclass(frozen=True, slots=True)
class CodeInfo:
    """What a diagnostic code means and which stage emits it."""

    stage: Stage
    meaning: str


def _codes(stage: Stage, *pairs: tuple[str, str]) -> dict[str, CodeInfo]:
    return {code: CodeInfo(stage, meaning) for code, meaning in pairs}


#: The diagnostic-code registry: code -> (stage, meaning).  Codes are stable across releases.
CODES: dict[str, CodeInfo] = {
    **_codes(Stage.INPUT,
             ("E0001", "syntax error"),
             ("E0002", "unexpected character"),
             ("E0003", "unexpected end of input"),
             ("E0004", "malformed construct (accepted by the grammar, not valid FSP)"),
             ("E0005", "input nested too deeply to process"),
             ("E0006", "more top-level declarations than --max-declarations"),
             ("E0007", "unterminated comment"),
             ("E0008", "not a text file")),
    **_codes(Stage.NAMES,
             ("E0101", "duplicate definition or reserved name"),
             ("E0102", "undefined process or composite, or wrong number of parameters"),
             ("E0103", "operator keywords out of order"),
             ("E0104", "a command names no process or composite of the spec"),
             ("E0150", "unsupported construct"),
             ("W0151", "declaration parsed and ignored")),
    **_codes(Stage.EXPRESSIONS,
             ("E0201", "undefined name in an expression"),
             ("E0202", "type error"),
             ("E0203", "division by zero"),
             ("E0204", "empty range"),
             ("E0205", "range too large"),
             ("E0206", "bad def call"),
             ("E0207", "non-integer index"),
             ("E0208", "integer larger than --max-int-bits"),
             ("E0209", "a set an included declaration needs is declared nowhere")),
    **_codes(Stage.PROCESSES,
             ("W0301", "local process defined to be ERROR"),
             ("E0302", "local process defined twice"),
             ("E0303", "local process defined only in terms of itself"),
             ("E0305", "sequential composition error"),
             ("E0306", "tau used as an action label"),
             ("E0307", "process instances nested without bound")),
    **_codes(Stage.COMPOSITION,
             ("E0401", "recursive composition"),
             ("E0402", "state explosion (more than --max-states)"),
             ("E0403", "composite operator failed"),
             ("E0404", "time limit reached"),
             ("E0405", "memory limit reached")),
    **_codes(Stage.FLUENTS,
             ("E0501", "fluent initiating and terminating sets overlap")),
    **_codes(Stage.FORMULAS,
             ("E0601", "undefined name in a formula"),
             ("E0602", "recursive assert"),
             ("E0603", "formula too deep or too large"),
             ("W0603", "formula not usable"),
             ("E0604", "formula names an unknown fluent"),
             ("W0604", "ltl_property/constraint is unsatisfiable"),
             ("E0605", "ltl_property/constraint is not a safety formula"),
             ("E0606", "formula automaton beyond the state limit or nested too deeply"),
             ("E0607", "iterc verify: no assert with that name"),
             ("E0608", "iterc verify: --on names no process or composite")),
    **_codes(Stage.SPECS,
             ("E0701", "undefined controllerSpec or name in a controllerSpec"),
             ("W0702", "controllerSpec field ignored"),
             ("W0704", "a controllable action no process can do")),
    **_codes(Stage.FILES,
             ("E0800", "cannot read a file"),
             ("E0801", "included file not found"),
             ("E0802", "include cycle")),
    **_codes(Stage.SYNTHESIS,
             ("E0901", "synthesis failed or the specification is unrealizable"),
             ("W0902", "unrealizable: the plant is returned instead"),
             ("W0903", "checkCompatibility: assumptions not compatible with the plant"),
             ("E0904", "no (such) controller composite"),
             ("W0905", "a warning synthesis reported while posing the game"),
             ("E0906", "a goal names an unknown fluent"),
             ("E0907", "a goal formula is not propositional"),
             ("E0908", "the game is too large for the explicit solver"),
             ("E0909", "synthesis is not available in this build step")),
    **_codes(Stage.EMIT,
             ("E1001", "synthesis returned something that is not an emittable controller"),
             ("E1002", "the model built no LTS and gave no reason")),
    **_codes(Stage.LTSA,
             ("E1301", "deadlock reachable"),
             ("E1302", "ERROR reachable"),
             ("E1303", "progress property violated"),
             ("E1311", "animator: bad script command"),
             ("E1312", "animator: no spec")),
    **_codes(Stage.GR1,
             ("G100", "slugsin: cannot read the input"),
             ("G101", "slugsin: unknown section"),
             ("G102", "slugsin: content before any section"),
             ("G103", "slugsin: malformed formula"),
             ("G104", "slugsin: bad or duplicate variable declaration"),
             ("G105", "slugsin: a section appears again (warning)"),
             ("G110", "structuredslugs: unknown section or text before the first"),
             ("G111", "structuredslugs: bad variable declaration"),
             ("G112", "structuredslugs: malformed formula"),
             ("G113", "structuredslugs: type error or undeclared variable"),
             ("G114", "structuredslugs: term or range too large"),
             ("G201", "GR(1): primed variable in an INIT section"),
             ("G202", "GR(1): ENV_TRANS mentions next-state outputs")),
}


def describe(code: str) -> CodeInfo:
    """The registry entry of ``code`` (``KeyError`` for an unregistered code)."""
    return CODES[code]


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

    ``code`` is stable across releases (tests and users may match on it), e.g. ``E0101``; see :data:`CODES`.
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


def render_one(diag: Diagnostic, sources: Mapping[str, str] | None = None) -> str:
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


def render(diags: Iterable[Diagnostic], sources: Mapping[str, str] | None = None) -> str:
    """Format diagnostics in order, one block each, separated by newlines."""
    return "\n".join(render_one(d, sources) for d in diags)
