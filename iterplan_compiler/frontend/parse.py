"""Parsing: FSP text → :class:`~iterplan_compiler.frontend.syntax.SpecFile` + diagnostics.

The Lark grammar (``grammar/fsp.lark``) is LALR(1) with the contextual lexer.  Syntax errors
do not stop the parse: the error handler records a diagnostic (E0001), pops the parser stack
back to a declaration boundary, skips the input up to the next top-level ``.`` and resumes, so
every syntax error of a file is reported in one run.  A few rare constructs (probabilistic
choice, MTS ``?`` actions, ...) are reported as "unsupported construct" (E0150) instead.

Diagnostic codes of this module: E0001 syntax error, E0002 unexpected character,
E0003 unexpected end of input, E0004 malformed construct (parse tree accepted by the
permissive grammar but not valid FSP), E0150 unsupported construct, W0151 ignored declaration.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.resources
import os
import re
import sys

import lark
from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from iterplan_compiler import limits
from iterplan_compiler.diagnostics import Diagnostic, Span, error
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.frontend.errors import Malformed, tok_span
from iterplan_compiler.frontend.tree_to_ast import TreeToAst
from iterplan_compiler.outputs import user_cache_dir

_MAX_ERRORS = 50

# Rare constructs recognised by their first token (a reserved word of MTSA we do not support).
_UNSUPPORTED_WORDS = {
    "import", "updatingController", "graphUpdate", "controlstack", "tier", "exploration",
    "distribution", "eTS", "uTS", "prechart", "mainchart", "oldController", "mapping",
    "oldGoal", "newGoal", "transition", "initialState", "transitions",
}


def _cache_file(grammar: str) -> str | bool:
    """Where Lark may keep the analysed parse table between runs (building it takes ~1 s, which
    every ``iterc`` call would pay).  A per-user directory, not the shared temp dir, because
    the cache is a pickle.  The file name carries a hash of the grammar and of the Lark
    version, so installs with different grammars (several checkouts, an upgrade) keep their
    own tables instead of rebuilding and overwriting one file in turn; Lark also checks the
    hash stored inside and rebuilds a stale or unreadable file.  ``ITERPLAN_NO_CACHE=1`` or an
    unwritable home disable it (:func:`~iterplan_compiler.outputs.user_cache_dir`)."""
    folder = user_cache_dir("lark")
    if folder is None:
        return False
    key = hashlib.sha256(f"{lark.__version__}\n{grammar}".encode()).hexdigest()[:16]
    return os.path.join(str(folder), f"fsp-lark-py{sys.version_info[0]}{sys.version_info[1]}-{key}.pickle")


_OPTIONS: dict[str, object] = dict(parser="lalr", lexer="contextual", propagate_positions=True,
                                   maybe_placeholders=True)


def _grammar_text() -> str:
    return importlib.resources.files("iterplan_compiler.grammar").joinpath("fsp.lark").read_text(
        encoding="utf-8")


@functools.lru_cache(maxsize=1)
def parser() -> Lark:
    """The (cached) Lark LALR parser of ``fsp.lark``: from Lark's own cache in the user's
    folder, else built from the grammar."""
    text = _grammar_text()
    cache = _cache_file(text)
    if cache:
        try:
            return Lark(text, cache=cache, **_OPTIONS)
        except Exception:  # noqa: BLE001 - a broken cache must never stop the compiler
            pass
    return Lark(text, cache=False, **_OPTIONS)


_DOT_RE = re.compile(r'//[^\n]*|/\*.*?\*/|"[^"\n]*"|\d\.\d|\.\.|\.(?![A-Za-z_\[{])', re.S)


_COMMENT_RE = re.compile(r'//[^\n]*|"[^"\n]*"|/\*.*?\*/|(/\*)', re.S)


def _unterminated_comment(text: str) -> int | None:
    """Offset of a ``/*`` that is never closed (outside strings and line comments), if any."""
    if "/*" not in text:
        return None
    for m in _COMMENT_RE.finditer(text):
        if m.group(1):
            return m.start()
    return None


def _position(text: str, offset: int) -> tuple[int, int]:
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def _describe(tok: Token) -> str:
    if tok.type == "$END":
        return "end of input"
    return f"'{tok.value}'"


def parse_text(text: str, path: str = "<input>", *, allow_mts: bool = False
               ) -> tuple[S.SpecFile, list[Diagnostic]]:
    """Parse ``text``; return the AST of every well-formed declaration and all diagnostics.

    MTS maybe actions (``a?``) are rejected (E0150, the declaration is dropped) unless
    ``allow_mts``: then they are kept as label parts named ``a?`` (the printer's round trip
    uses this; elaboration has no modal semantics, so :func:`frontend.load` never sets it).
    """
    diags: list[Diagnostic] = []
    too_many = _too_many_declarations(text, path)
    if too_many is not None:
        return S.SpecFile(path, ()), [too_many]
    open_comment = _unterminated_comment(text)
    if open_comment is not None:
        # Report the comment at its start and parse what precedes it (not "unexpected '/'").
        line, col = _position(text, open_comment)
        diags.append(error("E0007", "unterminated comment: this '/*' has no closing '*/'",
                           Span(path, line, col, line, col + 2)))
        text = text[:open_comment]
    lark = parser()
    decl_states = _decl_start_states(lark)

    def on_error(e: UnexpectedInput) -> bool:
        if len(diags) >= _MAX_ERRORS:
            return False
        ip = e.interactive_parser  # type: ignore[attr-defined]
        state = ip.parser_state
        lexer_state = ip.lexer_thread.state
        if isinstance(e, UnexpectedToken):
            tok = e.token
            if tok.type == "$END":
                if open_comment is not None:
                    return False  # the declaration the comment cut off: already reported
                diags.append(error("E0003", "unexpected end of input (missing '.'?)",
                                   Span(path, tok.line or e.line, tok.column or e.column)))
                return False
            diags.append(_token_error(path, tok, e.expected, text))
            err_pos = tok.end_pos if tok.end_pos is not None else tok.start_pos
            skip_from = err_pos
            at_dot = tok.type == "DOT"
        elif isinstance(e, UnexpectedCharacters):
            pos = e.pos_in_stream or 0
            diags.append(error("E0002", f"unexpected character {text[pos]!r}",
                               Span(path, e.line, e.column, e.line, e.column + 1)))
            skip_from = pos
            at_dot = False
        else:  # pragma: no cover - UnexpectedEOF is not raised by the LALR front end
            return False
        # Pop partial declarations: back to a state that can start a new declaration.
        while len(state.state_stack) > 1 and state.state_stack[-1] not in decl_states:
            state.state_stack.pop()
            if state.value_stack:
                state.value_stack.pop()
        if not at_dot and lexer_state is not None:
            nxt = _next_top_level_dot(text, skip_from)
            line_ctr = lexer_state.line_ctr
            if nxt > line_ctr.char_pos:
                line_ctr.feed(text[line_ctr.char_pos:nxt])
        return True

    try:
        tree = lark.parse(text, on_error=on_error)
    except (UnexpectedToken, UnexpectedCharacters, UnexpectedEOF):
        if not diags:  # pragma: no cover - on_error always records before giving up
            diags.append(error("E0001", "syntax error", Span(path, 1, 1)))
        return S.SpecFile(path, ()), diags
    builder = TreeToAst(path, diags, allow_mts=allow_mts)
    decls = []
    for child in tree.children:
        if not isinstance(child, Tree):
            continue
        try:
            d = builder.decl(child)
        except Malformed as m:
            diags.append(m.diag)
            continue
        if d is not None:
            decls.append(d)
    return S.SpecFile(path, tuple(decls)), diags


def _too_many_declarations(text: str, path: str) -> Diagnostic | None:
    """E0006 past ``--max-declarations`` top-level ``.`` (checked before parsing)."""
    cap = limits.current().max_declarations
    n_decls = 0
    for m in _DOT_RE.finditer(text):
        if m.group(0) == ".":
            n_decls += 1
            if n_decls > cap:
                line = text.count("\n", 0, m.start()) + 1
                return error("E0006", f"the file has more than {cap:,} top-level declarations: "
                             f"{limits.hint('max_declarations')}", Span(path, line, 1))
    return None


def _next_top_level_dot(text: str, pos: int) -> int:
    """Index just after the next ``.`` that ends a definition at or after ``pos``."""
    for m in _DOT_RE.finditer(text, pos):
        if m.group(0) == ".":
            return m.end()
    return len(text)


@functools.lru_cache(maxsize=1)
def _decl_start_states_cached(lark_id: int, lark: Lark) -> frozenset[int]:
    table = lark.parser.parser.parser.parse_table  # LALR_Parser → _Parser → table
    out = set()
    for st, actions in table.states.items():
        if "CONST" in actions and actions["CONST"][0].name == "Shift":
            out.add(st)
    return frozenset(out)


def _decl_start_states(lark: Lark) -> frozenset[int]:
    return _decl_start_states_cached(id(lark), lark)


def _token_error(path: str, tok: Token, expected: set[str], text: str) -> Diagnostic:
    span = tok_span(path, tok)
    value = str(tok.value)
    if tok.type == "REAL":
        return error("E0150", "unsupported construct: probabilistic choice "
                     "(real-valued probabilities need MTSA's 'probabilistic mdp')", span)
    if value in _UNSUPPORTED_WORDS:
        return error("E0150", f"unsupported construct: '{value}' declarations", span)
    if value in ("++", "+ca", "+cr"):
        return error("E0150", "unsupported construct: MTS merge operators", span)
    keywords, starters = _declaration_keywords(parser())
    opening = expected & keywords
    # Top-level keywords are acceptable here only because the declaration before could end;
    # listing them all would hide what the current construct accepts: one phrase instead.
    exp = sorted(t for t in expected - (starters if opening else keywords) if t != "$END")
    shown = [_pretty_terminal(t) for t in exp[:8]]
    if len(exp) > 8:
        shown.append("...")
    if opening:
        shown.append("a new declaration")
    elif "$END" in expected:
        shown.append("end of input")
    message = f"syntax error: unexpected {_describe(tok)}; expected " + (
        f"one of: {', '.join(shown)}" if len(shown) > 1 else "".join(shown) or "nothing")
    hint = _formula_hint(text, tok)
    return error("E0001", message + (f"; {hint}" if hint else ""), span)


_DECL_KEYWORD_RE = re.compile(
    r"\b(assert|ltl_property|constraint|const|range|set|fluent|def|controllerSpec|progress|"
    r"menu|animation|include)\b")


def _formula_hint(text: str, tok: Token) -> str | None:
    """For a binary operator after a complete ``assert``/``ltl_property``/``constraint`` body:
    the body is one unary formula, so suggest parenthesising it."""
    if str(tok.value) not in ("&&", "||", "->", "<->", "U", "W") or tok.start_pos is None:
        return None
    before = text[:tok.start_pos]
    matches = list(_DECL_KEYWORD_RE.finditer(before))
    last = matches[-1] if matches else None
    if last is None or last.group(1) not in ("assert", "ltl_property", "constraint"):
        return None
    head = before[last.start():]
    if head.count("=") != 1 or "." in head.replace("..", ""):
        return None
    name, _, body = head.partition("=")
    line_end = text.find("\n", tok.start_pos)
    rest = text[tok.start_pos: len(text) if line_end < 0 else line_end]
    rest = rest.split("//")[0].split("/*")[0].strip()
    return (f"the body of {last.group(1)} is one formula: parenthesise it, "
            f"`{name.strip()} = ({body.strip()} {rest})`")


@functools.lru_cache(maxsize=1)
def _declaration_keywords(lark: Lark) -> tuple[frozenset[str], frozenset[str]]:
    """``(keywords, starters)``: the terminals a declaration-start state shifts, and those of
    them that are keywords (``const``, ``assert``, ...)."""
    table = lark.parser.parser.parser.parse_table
    names = {t.name: t.pattern for t in lark.terminals}
    out: set[str] = set()
    starters: set[str] = set()
    for st in _decl_start_states(lark):
        for term in table.states[st]:
            starters.add(term)
            pattern = names.get(term)
            if pattern is not None and pattern.type == "str" and pattern.value.isidentifier():
                out.add(term)
    return frozenset(out), frozenset(starters)


_TERMINAL_NAMES = {
    "DOT": "'.'", "COMMA": "','", "LPAR": "'('", "RPAR": "')'", "LSQB": "'['", "RSQB": "']'",
    "LBRACE": "'{'", "RBRACE": "'}'", "EQUAL": "'='", "UPPER_ID": "Name", "LOWER_ID": "name",
    "INT": "number", "COLON": "':'", "VBAR": "'|'", "PLUS": "'+'", "MINUS": "'-'",
    "SLASH": "'/'", "BACKSLASH": "'\\'", "SEMICOLON": "';'", "LDOT": "'.'", "STRING": "string",
    "LESSTHAN": "'<'", "MORETHAN": "'>'", "TILDE": "'~'", "BANG": "'!'", "AT": "'@'",
}


def _pretty_terminal(name: str) -> str:
    if name in _TERMINAL_NAMES:
        return _TERMINAL_NAMES[name]
    try:
        pattern = next(t.pattern for t in parser().terminals if t.name == name)
    except StopIteration:
        return name
    if pattern.type == "str":
        return f"'{pattern.value}'"
    return name
