"""Reader for the slugs input format (``slugsin``).

Format (as documented by slugs, ``doc/input_formats.md``):

* section headers ``[INPUT] [OUTPUT] [ENV_INIT] [SYS_INIT] [ENV_TRANS] [SYS_TRANS]
  [ENV_LIVENESS] [SYS_LIVENESS]``; lines starting with ``#`` and blank lines are ignored;
* ``[INPUT]``/``[OUTPUT]``: one Boolean variable name per line;
* every other section: one Boolean formula per line in *prefix* notation over the tokens
  ``! & | ^ 1 0``, variable names and primed names ``x'``; lines of INIT/TRANS sections are
  conjoined, each LIVENESS line is one justice condition;
* ``$ n e1 ... en`` evaluates ``n`` sub-formulas into a buffer and denotes the last one;
  inside it ``? k`` recalls the ``k``-th (0-based) entry of the innermost enclosing buffer.

The reader produces an immutable :class:`SlugsSpec` whose formulas are small expression
trees (:class:`Expr`).  ``? k`` references share the *same* node object as the buffer
entry, so a builder that memoises by node identity (see :func:`memo_key`) evaluates every
buffered sub-formula once, exactly like slugs does.

Diagnostics (codes ``G1xx``) carry ``file:line:col`` spans; the reader never raises for
bad input.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass, field

from iterplan_compiler.diagnostics import Diagnostic, Span, error, warning


class SpecFormat(enum.Enum):
    """Input format of a GR(1) file (``iterc solve --format``): ``slugsin`` (this module),
    ``structuredslugs`` (:mod:`structured`), or ``auto``: by the file's extension."""

    SLUGSIN = "slugsin"
    STRUCTUREDSLUGS = "structuredslugs"
    AUTO = "auto"

    def resolve(self, path: str) -> SpecFormat:
        """The concrete format of ``path``: ``AUTO`` is ``STRUCTUREDSLUGS`` for a file ending
        in ``.structuredslugs``, else ``SLUGSIN``; the others are themselves."""
        if self is not SpecFormat.AUTO:
            return self
        return (SpecFormat.STRUCTUREDSLUGS if path.endswith(".structuredslugs")
                else SpecFormat.SLUGSIN)


SECTIONS = (
    "INPUT",
    "OUTPUT",
    "ENV_INIT",
    "SYS_INIT",
    "ENV_TRANS",
    "SYS_TRANS",
    "ENV_LIVENESS",
    "SYS_LIVENESS",
)
FORMULA_SECTIONS = SECTIONS[2:]
_OPERATORS = {"!", "&", "|", "^", "$", "?", "0", "1"}


# --- expression trees ------------------------------------------------------------------
# Kept as plain tuples-in-slots classes: building a 100k-node tree must be cheap.


@dataclass(frozen=True, slots=True, eq=False)
class Expr:
    """A Boolean formula node.

    ``op`` is one of ``"const" "var" "not" "and" "or" "xor"``.  For ``const`` ``value`` is the
    Boolean; for ``var`` ``name`` is the variable and ``primed`` says next-state; ``args``
    holds the operands of the connectives.  Equality is identity (shared sub-formulas are
    the same object).
    """

    op: str
    args: tuple[Expr, ...] = ()
    name: str = ""
    primed: bool = False
    value: bool = False


TRUE = Expr("const", value=True)
FALSE = Expr("const", value=False)


@dataclass(frozen=True, slots=True)
class Line:
    """One formula line of a formula section, with the span of its first token."""

    expr: Expr
    span: Span


@dataclass(frozen=True)
class SlugsSpec:
    """A parsed slugsin specification.

    ``inputs``/``outputs`` are in declaration order (the default BDD variable order).
    ``sections`` maps each formula section name to its lines (possibly empty).
    """

    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    sections: dict[str, tuple[Line, ...]] = field(default_factory=dict)
    source: str = "<string>"

    def lines(self, section: str) -> tuple[Line, ...]:
        return self.sections.get(section, ())


def variables_of(expr: Expr) -> set[tuple[str, bool]]:
    """The set of ``(name, primed)`` pairs occurring in ``expr`` (shared nodes visited once)."""
    seen: set[int] = set()
    out: set[tuple[str, bool]] = set()
    stack = [expr]
    while stack:
        e = stack.pop()
        if id(e) in seen:
            continue
        seen.add(id(e))
        if e.op == "var":
            out.add((e.name, e.primed))
        else:
            stack.extend(e.args)
    return out


# --- tokenizer / parser ----------------------------------------------------------------


class _ParseError(Exception):
    def __init__(self, message: str, col: int, end_col: int | None = None):
        super().__init__(message)
        self.col = col
        self.end_col = end_col


def _tokens(text: str) -> list[tuple[str, int]]:
    """Whitespace-separated tokens with their 1-based columns."""
    out: list[tuple[str, int]] = []
    i, n = 0, len(text)
    while i < n:
        if text[i].isspace():
            i += 1
            continue
        j = i
        while j < n and not text[j].isspace():
            j += 1
        out.append((text[i:j], i + 1))
        i = j
    return out


def _buffer_count(toks: list[tuple[str, int]], pos: int, col: int) -> tuple[int, int]:
    """The positive count after a ``$`` at ``col`` (``toks[pos]``) and the next position."""
    if pos >= len(toks):
        raise _ParseError("'$' needs a count", col)
    ntok, ncol = toks[pos]
    if not ntok.isdigit() or int(ntok) == 0:
        raise _ParseError(f"'$' needs a positive count, got '{ntok}'", ncol, ncol + len(ntok))
    return int(ntok), pos + 1


def _buffer_ref(toks: list[tuple[str, int]], pos: int, col: int, buffers: list[list[Expr]]
                ) -> tuple[Expr, int]:
    """The innermost buffer's entry named by the index after a ``?`` at ``col``
    (``toks[pos]``) and the next position."""
    if pos >= len(toks):
        raise _ParseError("'?' needs an index", col)
    ktok, kcol = toks[pos]
    if not ktok.isdigit():
        raise _ParseError(f"'?' needs an index, got '{ktok}'", kcol, kcol + len(ktok))
    if not buffers:
        raise _ParseError("'?' outside of any '$' buffer", col)
    k = int(ktok)
    if k >= len(buffers[-1]):
        raise _ParseError(
            f"'? {k}' refers to buffer entry {k}, but only "
            f"{len(buffers[-1])} entries are defined so far", col, kcol + len(ktok))
    return buffers[-1][k], pos + 1


def _variable(tok: str, col: int, known: set[str]) -> Expr:
    """The (possibly primed) declared variable ``tok`` at ``col``."""
    primed = tok.endswith("'")
    name = tok[:-1] if primed else tok
    if not name or "'" in name:
        raise _ParseError(f"malformed variable name '{tok}'", col, col + len(tok))
    if name not in known:
        raise _ParseError(f"undeclared variable '{name}'", col, col + len(tok))
    return Expr("var", name=name, primed=primed)


def _reduce(node: Expr, stack: list[list], buffers: list[list[Expr]]) -> Expr | None:
    """Feed the complete operand ``node`` to the open frames, closing every frame it
    completes; the whole formula once the stack is empty, else None."""
    while True:
        if not stack:
            return node
        frame = stack[-1]
        frame[2].append(node)
        if len(frame[2]) < frame[1]:
            return None
        stack.pop()
        kind = frame[0]
        if kind == "buf":
            buffers.pop()
            node = frame[2][-1]
        else:
            node = Expr(kind, args=tuple(frame[2]))


def _parse_formula(toks: list[tuple[str, int]], known: set[str]) -> Expr:
    """Parse one prefix formula that must consume all of ``toks``.

    Iterative in spirit but recursive in depth of the *prefix* nesting only; slugsin files
    generated from arithmetic can nest thousands deep, so the recursion is replaced by an
    explicit stack machine.
    """
    pos = 0
    # Each frame: [kind, needed, collected, col, buffer(optional)]
    # kinds: "not" (1 arg), "and"/"or"/"xor" (2 args), "buf" (n args)
    stack: list[list] = []
    buffers: list[list[Expr]] = []
    result: Expr | None = None
    while True:
        # read one operand start
        if pos >= len(toks):
            col = toks[-1][1] + len(toks[-1][0]) if toks else 1
            raise _ParseError("formula ended early: an operand is missing", col)
        tok, col = toks[pos]
        pos += 1
        node: Expr | None = None
        if tok == "!":
            stack.append(["not", 1, [], col])
        elif tok in ("&", "|", "^"):
            stack.append([{"&": "and", "|": "or", "^": "xor"}[tok], 2, [], col])
        elif tok == "1":
            node = TRUE
        elif tok == "0":
            node = FALSE
        elif tok == "$":
            count, pos = _buffer_count(toks, pos, col)
            buf: list[Expr] = []
            buffers.append(buf)
            stack.append(["buf", count, buf, col])
        elif tok == "?":
            node, pos = _buffer_ref(toks, pos, col, buffers)
        else:
            node = _variable(tok, col, known)
        if node is not None:
            result = _reduce(node, stack, buffers)
        if result is not None:
            break
    if pos < len(toks):
        tok, col = toks[pos]
        raise _ParseError(f"unexpected extra token '{tok}' after a complete formula", col,
                          col + len(tok))
    return result


def parse_prefix(text: str, known: set[str]) -> Expr | None:
    """``text`` as one complete prefix formula over the variables ``known``, else None."""
    try:
        return _parse_formula(_tokens(text), known)
    except _ParseError:
        return None


def parse(text: str, path: str = "<string>") -> tuple[SlugsSpec | None, list[Diagnostic]]:
    """Parse slugsin ``text``; return the spec (``None`` on errors) and diagnostics.

    Codes: ``G101`` unknown section, ``G102`` content before any section, ``G103`` malformed
    formula, ``G104`` bad/duplicate variable declaration, ``G105`` (warning) repeated
    section header (the lines are appended, as slugs does).
    """
    diags: list[Diagnostic] = []
    section: str | None = None
    inputs: list[str] = []
    outputs: list[str] = []
    declared: dict[str, Span] = {}
    raw: dict[str, list[tuple[int, str]]] = {s: [] for s in FORMULA_SECTIONS}
    seen_sections: set[str] = set()
    for lineno, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        col0 = len(line) - len(line.lstrip()) + 1
        if stripped.startswith("["):
            name = stripped[1:-1] if stripped.endswith("]") else None
            if name not in SECTIONS:
                diags.append(error("G101", f"unknown section header '{stripped}' (expected one "
                                   f"of {', '.join('[' + s + ']' for s in SECTIONS)})",
                                   Span(path, lineno, col0, lineno, col0 + len(stripped))))
                section = None
                continue
            if name in seen_sections:
                diags.append(warning("G105", f"section [{name}] appears again; its lines are "
                                     "appended", Span(path, lineno, col0)))
            seen_sections.add(name)
            section = name
            continue
        if section is None:
            if not any(d.code in ("G101", "G102") for d in diags):
                diags.append(error("G102", "text before the first section header",
                                   Span(path, lineno, col0)))
            continue
        if section in ("INPUT", "OUTPUT"):
            toks = _tokens(line)
            name, col = toks[0]
            sp = Span(path, lineno, col, lineno, col + len(name))
            if len(toks) > 1:
                diags.append(error("G104", "one variable name per line expected", sp))
            elif name in _OPERATORS or "'" in name or name.isdigit():
                diags.append(error("G104", f"'{name}' is not a valid variable name", sp))
            elif name in declared:
                diags.append(error("G104", f"variable '{name}' declared twice", sp))
            else:
                declared[name] = sp
                (inputs if section == "INPUT" else outputs).append(name)
            continue
        raw[section].append((lineno, line))
    known = set(declared)
    sections: dict[str, tuple[Line, ...]] = {}
    for sec in FORMULA_SECTIONS:
        out: list[Line] = []
        for lineno, line in raw[sec]:
            toks = _tokens(line)
            try:
                expr = _parse_formula(toks, known)
            except _ParseError as exc:
                diags.append(error("G103", f"in [{sec}]: {exc}",
                                   Span(path, lineno, exc.col, lineno, exc.end_col)))
                continue
            out.append(Line(expr, Span(path, lineno, toks[0][1])))
        sections[sec] = tuple(out)
    if any(d.is_error for d in diags):
        return None, diags
    return SlugsSpec(tuple(inputs), tuple(outputs), sections, path), diags


def load(path: str, parser: Callable[[str, str], tuple[SlugsSpec | None, list[Diagnostic]]]
         | None = None) -> tuple[SlugsSpec | None, list[Diagnostic], str | None]:
    """Read and parse a GR(1) file; returns ``(spec, diagnostics, text)``.

    ``parser`` is :func:`parse` (slugsin) unless another front-end for the same
    :class:`SlugsSpec` is given (``structured.parse`` for structuredslugs).
    """
    try:
        # Undecodable bytes become U+FFFD, which the reader reports at their line and column;
        # a UTF-8 byte-order mark (as some editors write it) is dropped.
        with open(path, encoding="utf-8-sig", errors="replace") as fh:
            text = fh.read()
    except OSError as exc:
        return None, [error("G100", f"cannot read '{path}': {exc.strerror}", Span(path, 0, 0))], None
    spec, diags = (parser or parse)(text, path)
    return spec, diags, text


# --- writer ------------------------------------------------------------------------------


def to_prefix(expr: Expr) -> str:
    """Print an expression in slugsin prefix notation (shared nodes are printed inline)."""
    out: list[str] = []
    stack = [expr]
    sym = {"not": "!", "and": "&", "or": "|", "xor": "^"}
    while stack:
        e = stack.pop()
        if e.op == "const":
            out.append("1" if e.value else "0")
        elif e.op == "var":
            out.append(e.name + ("'" if e.primed else ""))
        else:
            out.append(sym[e.op])
            stack.extend(reversed(e.args))
    return " ".join(out)


def write(spec: SlugsSpec) -> str:
    """Serialise a spec back to slugsin text (deterministic)."""
    parts = ["[INPUT]", *spec.inputs, "", "[OUTPUT]", *spec.outputs, ""]
    for sec in FORMULA_SECTIONS:
        parts.append(f"[{sec}]")
        parts.extend(to_prefix(line.expr) for line in spec.lines(sec))
        parts.append("")
    return "\n".join(parts)
