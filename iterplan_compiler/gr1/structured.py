"""Reader for slugs' higher-level ``structuredslugs`` format, translated to :class:`SlugsSpec`.

Format (our reading of slugs' documentation; written from the description, not slugs' code):

* the same section headers as slugsin (``[INPUT] [OUTPUT] [ENV_INIT] ... [SYS_LIVENESS]``),
  ``#`` comments and blank lines ignored;
* ``[INPUT]``/``[OUTPUT]``: one declaration per line, ``name`` (Boolean) or ``name: lo...hi``
  (bounded integer, ``lo <= hi``, both may be negative);
* formula lines use *infix* notation.  Precedence, loosest first: ``<->``, ``->`` (right
  associative), ``|``, ``^``, ``&``, prefix ``!``, comparisons ``= != < <= > >=`` (not
  chained), ``+ -`` (left associative), unary ``-``; atoms are ``TRUE``, ``FALSE``, integer
  literals, variables, primed variables ``x'`` and parentheses.  ``==``, ``&&``, ``||`` are
  accepted as synonyms.

Translation: an integer variable ``x: lo...hi`` becomes ``ceil(log2(hi-lo+1))`` Boolean
variables ``x@0 ... x@k-1`` holding ``x - lo`` in binary, least significant bit first.  When
the range does not fill all bit patterns, ``x <= hi`` is added to the declaring player's INIT
section and ``x' <= hi`` to its TRANS section (slugs does the same), so no player can move to
an unused encoding.  Integer *terms* are evaluated as value tables ``{value: condition}`` over
mathematical integers (no wrap-around), so ``x' = x + 1`` at ``x = hi`` is simply unsatisfiable
for the player owning ``x``.  The table size is bounded (:data:`MAX_TERM_VALUES`,
:data:`MAX_PAIRS`); larger terms are diagnostic ``G114``.

Diagnostics: ``G110`` section/structure errors, ``G111`` bad declaration, ``G112`` syntax
error in a formula, ``G113`` type error (integer where a Boolean is needed or vice versa) or
undeclared variable, ``G114`` term too large.  The reader never raises for bad input.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from iterplan_compiler.diagnostics import Diagnostic, Span, error
from iterplan_compiler.gr1 import slugsin
from iterplan_compiler.gr1.slugsin import (
    FALSE,
    FORMULA_SECTIONS,
    SECTIONS,
    TRUE,
    Expr,
    Line,
    SlugsSpec,
)

MAX_TERM_VALUES = 1 << 12
MAX_PAIRS = 1 << 18

_DECL = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)\s*(?::\s*(-?\d+)\s*\.\.\.\s*(-?\d+))?$")
_TOKEN = re.compile(
    r"\s*(?:(?P<num>\d+)|(?P<id>[A-Za-z_][A-Za-z0-9_]*'?)"
    r"|(?P<op><->|->|<=|>=|!=|==|&&|\|\||[!&|^()=<>+\-]))"
)
_SYNONYM = {"==": "=", "&&": "&", "||": "|"}
_COMPARISONS = ("=", "!=", "<", "<=", ">", ">=")


@dataclass(frozen=True)
class IntVar:
    """An integer variable: its range and the names of its bits (LSB first)."""

    lo: int
    hi: int
    bits: tuple[str, ...]


class _Error(Exception):
    def __init__(self, code: str, message: str, col: int, end_col: int | None = None):
        super().__init__(message)
        self.code = code
        self.col = col
        self.end_col = end_col


# --- Boolean helpers with constant folding (keeps translated trees small) ----------------


def _not(a: Expr) -> Expr:
    if a.op == "const":
        return FALSE if a.value else TRUE
    if a.op == "not":
        return a.args[0]
    return Expr("not", args=(a,))


def _and(a: Expr, b: Expr) -> Expr:
    if a.op == "const":
        return b if a.value else FALSE
    if b.op == "const":
        return a if b.value else FALSE
    return Expr("and", args=(a, b))


def _or(a: Expr, b: Expr) -> Expr:
    if a.op == "const":
        return TRUE if a.value else b
    if b.op == "const":
        return TRUE if b.value else a
    return Expr("or", args=(a, b))


def _xor(a: Expr, b: Expr) -> Expr:
    if a.op == "const":
        return _not(b) if a.value else b
    if b.op == "const":
        return _not(a) if b.value else a
    return Expr("xor", args=(a, b))


def _or_all(items: list[Expr]) -> Expr:
    # Balanced, so deep ranges do not produce deep (recursion-hungry) trees.
    if not items:
        return FALSE
    while len(items) > 1:
        items = [_or(items[i], items[i + 1]) if i + 1 < len(items) else items[i]
                 for i in range(0, len(items), 2)]
    return items[0]


def _bit(name: str, primed: bool) -> Expr:
    return Expr("var", name=name, primed=primed)


def _encodes(var: IntVar, value: int, primed: bool) -> Expr:
    """The bits of ``var`` hold ``value`` (``lo <= value <= hi``)."""
    k = value - var.lo
    out = TRUE
    for i, name in enumerate(var.bits):
        b = _bit(name, primed)
        out = _and(out, b if (k >> i) & 1 else _not(b))
    return out


def _at_most(var: IntVar, k: int, primed: bool) -> Expr:
    """The unsigned number held in the bits of ``var`` is ``<= k`` (MSB-first comparator)."""
    out = TRUE  # equal so far on the lower bits considered -> <=
    for i, name in enumerate(var.bits):
        b = _bit(name, primed)
        # processing from LSB upwards: result(i) = (b_i < k_i) | (b_i == k_i & result(i-1))
        out = _or(_not(b), out) if (k >> i) & 1 else _and(_not(b), out)
    return out


def _int_var(name: str, lo: int, hi: int) -> IntVar:
    n = (hi - lo).bit_length()
    return IntVar(lo, hi, tuple(f"{name}@{i}" for i in range(n)))


# --- formula parser: returns ("bool", Expr) or ("int", {value: Expr}) --------------------

_Val = tuple[str, object]


class _Parser:
    def __init__(self, text: str, bools: set[str], ints: dict[str, IntVar]):
        self.toks: list[tuple[str, str, int]] = []  # (kind, text, col)
        pos = 0
        while pos < len(text):
            if text[pos:].strip() == "":
                break
            m = _TOKEN.match(text, pos)
            if m is None or m.end() == pos:
                col = pos + len(text[pos:]) - len(text[pos:].lstrip()) + 1
                raise _Error("G112", f"unexpected character '{text[col - 1]}'", col, col + 1)
            kind = m.lastgroup or "op"
            tok = m.group(kind)
            self.toks.append((kind, _SYNONYM.get(tok, tok), m.start(kind) + 1))
            pos = m.end()
        self.end_col = len(text.rstrip()) + 1
        self.pos = 0
        self.bools = bools
        self.ints = ints

    def peek(self) -> tuple[str, str, int]:
        return self.toks[self.pos] if self.pos < len(self.toks) else ("eof", "", self.end_col)

    def take(self) -> tuple[str, str, int]:
        t = self.peek()
        self.pos += 1
        return t

    def formula(self) -> Expr:
        if not self.toks:
            raise _Error("G112", "empty formula", 1)
        col = self.peek()[2]
        v = self.iff()
        kind, tok, c = self.peek()
        if kind != "eof":
            raise _Error("G112", f"unexpected '{tok}' after a complete formula", c, c + len(tok))
        return self.want_bool(v, col)

    # Boolean levels
    def want_bool(self, v: _Val, col: int) -> Expr:
        if v[0] != "bool":
            raise _Error("G113", "an integer term is used where a Boolean formula is needed "
                         "(compare it with '=', '<', ...)", col)
        return v[1]  # type: ignore[return-value]

    def want_int(self, v: _Val, col: int) -> dict[int, Expr]:
        if v[0] != "int":
            raise _Error("G113", "a Boolean formula is used where an integer term is needed", col)
        return v[1]  # type: ignore[return-value]

    def iff(self) -> _Val:
        col = self.peek()[2]
        left = self.implies()
        while self.peek()[1] == "<->" and self.peek()[0] == "op":
            self.take()
            rcol = self.peek()[2]
            right = self.implies()
            left = ("bool", _not(_xor(self.want_bool(left, col), self.want_bool(right, rcol))))
        return left

    def implies(self) -> _Val:
        col = self.peek()[2]
        left = self.binary(0)
        if self.peek()[1] == "->" and self.peek()[0] == "op":
            self.take()
            rcol = self.peek()[2]
            right = self.implies()  # right associative
            return ("bool", _or(_not(self.want_bool(left, col)), self.want_bool(right, rcol)))
        return left

    _LEVELS = (("|", _or), ("^", _xor), ("&", _and))

    def binary(self, level: int) -> _Val:
        if level == len(self._LEVELS):
            return self.unary()
        sym, fn = self._LEVELS[level]
        col = self.peek()[2]
        left = self.binary(level + 1)
        while self.peek()[0] == "op" and self.peek()[1] == sym:
            self.take()
            rcol = self.peek()[2]
            right = self.binary(level + 1)
            left = ("bool", fn(self.want_bool(left, col), self.want_bool(right, rcol)))
        return left

    def unary(self) -> _Val:
        kind, tok, col = self.peek()
        if kind == "op" and tok == "!":
            self.take()
            icol = self.peek()[2]
            return ("bool", _not(self.want_bool(self.unary(), icol)))
        return self.comparison()

    def comparison(self) -> _Val:
        col = self.peek()[2]
        left = self.additive()
        kind, tok, ocol = self.peek()
        if kind == "op" and tok in _COMPARISONS:
            self.take()
            rcol = self.peek()[2]
            right = self.additive()
            if left[0] == "bool" and right[0] == "bool" and tok in ("=", "!="):
                # Boolean equality, as a convenience: a = b is a <-> b.
                x = _xor(left[1], right[1])  # type: ignore[arg-type]
                return ("bool", x if tok == "!=" else _not(x))
            a = self.want_int(left, col)
            b = self.want_int(right, rcol)
            if len(a) * len(b) > MAX_PAIRS:
                raise _Error("G114", f"comparison over {len(a)} x {len(b)} values is too large "
                             f"(limit {MAX_PAIRS})", col)
            test = {"=": int.__eq__, "!=": int.__ne__, "<": int.__lt__, "<=": int.__le__,
                    ">": int.__gt__, ">=": int.__ge__}[tok]
            terms = [_and(ca, cb) for va, ca in sorted(a.items()) for vb, cb in sorted(b.items())
                     if test(va, vb)]
            out = ("bool", _or_all(terms))
            nk, ntok, ncol = self.peek()
            if nk == "op" and ntok in _COMPARISONS:
                raise _Error("G112", "comparisons do not chain; use '&'", ncol, ncol + len(ntok))
            return out
        return left

    def additive(self) -> _Val:
        col = self.peek()[2]
        left = self.negation()
        while self.peek()[0] == "op" and self.peek()[1] in ("+", "-"):
            op = self.take()[1]
            rcol = self.peek()[2]
            right = self.negation()
            a = self.want_int(left, col)
            b = self.want_int(right, rcol)
            if len(a) * len(b) > MAX_PAIRS:
                raise _Error("G114", f"'{op}' over {len(a)} x {len(b)} values is too large",
                             col)
            table: dict[int, list[Expr]] = {}
            for va, ca in a.items():
                for vb, cb in b.items():
                    table.setdefault(va + vb if op == "+" else va - vb, []).append(_and(ca, cb))
            if len(table) > MAX_TERM_VALUES:
                raise _Error("G114", f"integer term with {len(table)} possible values is too "
                             f"large (limit {MAX_TERM_VALUES})", col)
            left = ("int", {v: _or_all(cs) for v, cs in sorted(table.items())})
        return left

    def negation(self) -> _Val:
        kind, tok, col = self.peek()
        if kind == "op" and tok == "-":
            self.take()
            icol = self.peek()[2]
            inner = self.want_int(self.negation(), icol)
            return ("int", {-v: c for v, c in inner.items()})
        return self.atom()

    def atom(self) -> _Val:
        kind, tok, col = self.take()
        if kind == "eof":
            raise _Error("G112", "formula ended early: an operand is missing", col)
        if kind == "num":
            return ("int", {int(tok): TRUE})
        if kind == "id":
            primed = tok.endswith("'")
            name = tok[:-1] if primed else tok
            if not primed and name in ("TRUE", "FALSE"):
                return ("bool", TRUE if name == "TRUE" else FALSE)
            if name in self.bools:
                return ("bool", _bit(name, primed))
            if name in self.ints:
                var = self.ints[name]
                return ("int", {v: _encodes(var, v, primed) for v in range(var.lo, var.hi + 1)})
            raise _Error("G113", f"undeclared variable '{name}'", col, col + len(tok))
        if tok == "(":
            v = self.iff()
            k2, t2, c2 = self.take()
            if t2 != ")" or k2 != "op":
                raise _Error("G112", f"expected ')' (to close '(' at column {col}), "
                             f"got '{t2 or 'end of line'}'", c2, c2 + max(len(t2), 1))
            return v
        raise _Error("G112", f"unexpected '{tok}'; an operand is expected", col, col + len(tok))


def _prefix_line(line: str, known: set[str]) -> Expr | None:
    """The line as a slugsin *prefix* formula, or None if it is not one.

    slugs' structured compiler passes lines that already are slugs Polish notation through
    unchanged; we do the same.  No line means different things in both notations: a prefix
    formula over more than one operand starts with an operator (``& a b``), which no infix
    formula does except ``!``, and ``! a`` means the same in both.
    """
    return slugsin.parse_prefix(line, known)


def _parse_sections(raw: dict[str, list[tuple[int, str]]], sections: dict[str, list[Line]],
                    bools: set[str], ints: dict[str, IntVar], path: str,
                    diags: list[Diagnostic]) -> None:
    """Parse every formula line (prefix pass-through first, then infix) into ``sections``."""
    known = set(bools) | {b for var in ints.values() for b in var.bits}
    for sec in FORMULA_SECTIONS:
        for lineno, line in raw[sec]:
            col0 = len(line) - len(line.lstrip()) + 1
            try:
                expr = _prefix_line(line, known) or _Parser(line, bools, ints).formula()
            except _Error as exc:
                diags.append(error(exc.code, f"in [{sec}]: {exc}",
                                   Span(path, lineno, exc.col, lineno, exc.end_col)))
                continue
            except RecursionError:
                diags.append(error("G112", f"in [{sec}]: formula nested too deeply",
                                   Span(path, lineno, col0)))
                continue
            sections[sec].append(Line(expr, Span(path, lineno, col0)))


@dataclass
class _Decls:
    """The declarations read so far (filled in by :func:`_declare`)."""

    inputs: list[str] = field(default_factory=list)
    outputs: list[str] = field(default_factory=list)
    bools: set[str] = field(default_factory=set)
    ints: dict[str, IntVar] = field(default_factory=dict)
    owner: dict[str, str] = field(default_factory=dict)  # integer variable -> "ENV" | "SYS"
    decl_span: dict[str, Span] = field(default_factory=dict)


def _declare(decls: _Decls, stripped: str, section: str, sp: Span,
             diags: list[Diagnostic]) -> None:
    """Record the declaration ``stripped`` of an INPUT/OUTPUT ``section`` (G111, G114)."""
    m = _DECL.match(stripped)
    if m is None:
        diags.append(error("G111", f"bad declaration '{stripped}' (expected 'name' or "
                           "'name: lo...hi')", sp))
        return
    name = m.group(1)
    if name in ("TRUE", "FALSE"):
        diags.append(error("G111", f"'{name}' is reserved", sp))
        return
    if name in decls.decl_span:
        diags.append(error("G111", f"variable '{name}' declared twice", sp))
        return
    decls.decl_span[name] = sp
    names = decls.inputs if section == "INPUT" else decls.outputs
    if m.group(2) is None:
        decls.bools.add(name)
        names.append(name)
        return
    lo, hi = int(m.group(2)), int(m.group(3))
    if lo > hi:
        diags.append(error("G111", f"empty range {lo}...{hi} for '{name}'", sp))
        return
    if hi - lo + 1 > MAX_TERM_VALUES:
        diags.append(error("G114", f"range of '{name}' has {hi - lo + 1} values "
                           f"(limit {MAX_TERM_VALUES})", sp))
        return
    var = _int_var(name, lo, hi)
    decls.ints[name] = var
    decls.owner[name] = "ENV" if section == "INPUT" else "SYS"
    names.extend(var.bits)


def _range_lines(decls: _Decls) -> dict[str, list[Line]]:
    """Sections holding only the range constraints of the integer variables whose range
    does not fill their bits (INIT and TRANS of the owner)."""
    # Bit names must not collide with declared Boolean names (e.g. a Boolean called 'x@0'
    # cannot be declared, since '@' is not allowed in names, so this cannot happen).
    sections: dict[str, list[Line]] = {s: [] for s in FORMULA_SECTIONS}
    for name, var in decls.ints.items():
        size = var.hi - var.lo + 1
        if size == 1 << len(var.bits):
            continue
        sp = decls.decl_span[name]
        who = decls.owner[name]
        sections[f"{who}_INIT"].append(Line(_at_most(var, size - 1, False), sp))
        sections[f"{who}_TRANS"].append(Line(_at_most(var, size - 1, True), sp))
    return sections


def parse(text: str, path: str = "<string>") -> tuple[SlugsSpec | None, list[Diagnostic]]:
    """Parse structuredslugs ``text`` into an equivalent Boolean :class:`SlugsSpec`.

    Returns ``(None, diagnostics)`` when there are errors.  Integer variables become bits
    named ``name@i`` (see the module docstring); the spec's ``inputs``/``outputs`` list the
    bits in declaration order, LSB first, which is the default BDD order of the solver.
    """
    diags: list[Diagnostic] = []
    section: str | None = None
    decls = _Decls()
    raw: dict[str, list[tuple[int, str]]] = {s: [] for s in FORMULA_SECTIONS}
    for lineno, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        col0 = len(line) - len(line.lstrip()) + 1
        if stripped.startswith("["):
            name = stripped[1:-1] if stripped.endswith("]") else None
            if name not in SECTIONS:
                diags.append(error("G110", f"unknown section header '{stripped}'",
                                   Span(path, lineno, col0, lineno, col0 + len(stripped))))
                section = None
                continue
            section = name
            continue
        if section is None:
            if not any(d.code == "G110" for d in diags):
                diags.append(error("G110", "text before the first section header",
                                   Span(path, lineno, col0)))
            continue
        if section in ("INPUT", "OUTPUT"):
            _declare(decls, stripped, section,
                     Span(path, lineno, col0, lineno, col0 + len(stripped)), diags)
            continue
        raw[section].append((lineno, line))
    sections = _range_lines(decls)
    _parse_sections(raw, sections, decls.bools, decls.ints, path, diags)
    if any(d.is_error for d in diags):
        return None, diags
    return SlugsSpec(tuple(decls.inputs), tuple(decls.outputs),
                     {s: tuple(v) for s, v in sections.items()}, path), diags


def load(path: str) -> tuple[SlugsSpec | None, list[Diagnostic], str | None]:
    """Read and translate a structuredslugs file; returns ``(spec, diagnostics, text)``."""
    return slugsin.load(path, parser=parse)
