"""Evaluation of expressions and expansion of label elements (``mtsa-semantics.md`` §1.3–1.4).

Values are ``int`` / ``Fraction`` (numbers; ``/`` is exact real division) or ``str`` (labels).
An :class:`Env` holds the global tables (constants, ranges, sets, defs) and the variables bound
in the current construct.  Errors in user input raise :class:`EvalError` carrying a diagnostic;
callers turn it into a returned diagnostic (never a traceback).

Codes: E0201 undefined name, E0202 type error (label used as a number), E0203 division by zero,
E0204 empty range, E0206 bad def call, E0207 non-integer index.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from collections.abc import Set as AbstractSet
from dataclasses import dataclass, field
from fractions import Fraction

from iterplan_compiler import limits
from iterplan_compiler.diagnostics import Diagnostic, Span, error
from iterplan_compiler.frontend import syntax as S

Value = int | Fraction | str


class EvalError(Exception):
    """A user error found while evaluating; ``diag`` is the diagnostic to report.

    ``consequential`` errors follow from an error already reported (a use of a ``const`` or
    ``range`` whose own declaration failed): callers do not report them again (:func:`report`),
    so one mistake gives one diagnostic, not a cascade of "undefined".
    """

    def __init__(self, diag: Diagnostic, consequential: bool = False):
        super().__init__(diag.message)
        self.diag = diag
        self.consequential = consequential


def report(diags: list[Diagnostic], e: EvalError) -> None:
    """Append ``e``'s diagnostic to ``diags`` unless it is consequential."""
    if not e.consequential:
        diags.append(e.diag)


def fail(code: str, message: str, span: Span) -> EvalError:
    return EvalError(error(code, message, span))


@dataclass(frozen=True)
class Tables:
    """Global, already-evaluated declarations."""

    consts: Mapping[str, Value] = field(default_factory=dict)
    ranges: Mapping[str, tuple[int, int]] = field(default_factory=dict)
    sets: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    defs: Mapping[str, S.DefDecl] = field(default_factory=dict)
    #: names whose declaration failed to evaluate (already reported)
    failed: AbstractSet[str] = frozenset()

    def kind_of(self, name: str) -> str | None:
        """What ``name`` is declared as (``"constant"``, ``"range"``, ``"set"``), if anything."""
        for kind, table in (("constant", self.consts), ("range", self.ranges),
                            ("set", self.sets)):
            if name in table:
                return kind
        return None


def undefined(wanted: str, name: str, span: Span, tables: Tables) -> EvalError:
    """E0201 for ``name`` used as a ``wanted`` (e.g. ``"constant"``) that is not one.

    A name whose declaration failed gives a consequential error (not reported again); a name
    declared as something else says what it is ("S is a set, not a constant")."""
    if name in tables.failed:
        return EvalError(error("E0201", f"'{name}' cannot be used: its declaration has errors",
                               span), consequential=True)
    kind = tables.kind_of(name)
    if kind is not None and not wanted.startswith(kind) and kind not in wanted.split(" or "):
        return fail("E0201", f"'{name}' is a {kind}, not a {wanted}", span)
    return fail("E0201", f"undefined {wanted} '{name}'", span)


@dataclass(frozen=True)
class Env:
    """Evaluation environment: tables + parameters (upper names) + bound variables."""

    tables: Tables
    params: Mapping[str, Value] = field(default_factory=dict)
    vars: Mapping[str, Value] = field(default_factory=dict)

    def bind(self, name: str, value: Value, span: Span) -> Env:
        # MTSA rejects re-binding in some contexts but corpus files that MTSA compiles rebind
        # (`c[id:R].to[id:S]`); we let the inner binding shadow the outer one.
        return Env(self.tables, self.params, {**self.vars, name: value})

    def with_params(self, params: Mapping[str, Value]) -> Env:
        return Env(self.tables, {**self.params, **params}, self.vars)

    def key(self) -> tuple:
        """A hashable summary (used to cache compiled continuations)."""
        return tuple(sorted((k, str(v)) for k, v in self.vars.items()))


def fmt(v: Value) -> str:
    """How a value appears inside a label (``a.3``, ``a.3.5`` for 7/2, ``a.n`` for a label)."""
    if isinstance(v, str):
        return v
    if isinstance(v, Fraction):
        if v.denominator == 1:
            return str(v.numerator)
        return str(float(v))
    return str(v)


def _num(v: Value, span: Span) -> int | Fraction:
    if isinstance(v, str):
        raise fail("E0202", f"label '{v}' used where a number is expected", span)
    return v


def _norm(v: int | Fraction) -> int | Fraction:
    if isinstance(v, Fraction) and v.denominator == 1:
        return int(v.numerator)
    return v


def truth(v: Value, span: Span) -> bool:
    return _num(v, span) > 0 if not isinstance(v, str) else True


def to_int(v: Value, span: Span) -> int:
    n = _num(v, span)
    if isinstance(n, Fraction):
        if n.denominator != 1:
            raise fail("E0207", f"expected an integer, got {fmt(n)}", span)
        return int(n.numerator)
    return n


def evaluate(e: S.Expr, env: Env, depth: int = 0) -> Value:
    """Evaluate an expression (def calls are expanded, with a recursion limit)."""
    if isinstance(e, S.Num):
        return e.value
    if isinstance(e, S.Var):
        if e.name in env.vars:
            return env.vars[e.name]
        raise fail("E0201", f"undefined variable '{e.name}'", e.span)
    if isinstance(e, S.Name):
        if e.name in env.params:
            return env.params[e.name]
        if e.name in env.tables.consts:
            return env.tables.consts[e.name]
        raise undefined("constant", e.name, e.span, env.tables)
    if isinstance(e, S.Call):
        d = env.tables.defs.get(e.name)
        if d is None:
            raise fail("E0206", f"undefined def '{e.name}'", e.span)
        if len(d.params) != len(e.args) or depth > 50:
            raise fail("E0206", f"def '{e.name}' expects {len(d.params)} arguments", e.span)
        args = {p: evaluate(a, env, depth + 1) for p, a in zip(d.params, e.args, strict=True)}
        return evaluate(d.body, Env(env.tables, env.params, {**env.vars, **args}), depth + 1)
    if isinstance(e, S.LabelConst):
        labels = expand_label(e.label, env)
        if len(labels) != 1:
            raise fail("E0202", "a label constant must denote exactly one label", e.span)
        return labels[0]
    if isinstance(e, S.Card):
        return len(expand_set(e.set, env))
    if isinstance(e, S.At):
        items = expand_set(e.set, env)
        i = to_int(evaluate(e.index, env, depth), e.span)
        if not 0 <= i < len(items):
            raise fail("E0202", f"index {i} outside the set (size {len(items)})", e.span)
        return items[i]
    if isinstance(e, S.Unary):
        v = evaluate(e.arg, env, depth)
        if e.op == "-":
            return -_num(v, e.span)
        if e.op == "+":
            return _num(v, e.span)
        if e.op == "!":
            return 1 if _num(v, e.span) <= 0 else 0
        return ~to_int(v, e.span)
    if isinstance(e, S.Cond):
        c = evaluate(e.cond, env, depth)
        return evaluate(e.then if truth(c, e.span) else e.other, env, depth)
    if isinstance(e, S.Binary):
        a = evaluate(e.left, env, depth)
        if e.op == "&&":
            return int(truth(a, e.span) and truth(evaluate(e.right, env, depth), e.span))
        if e.op == "||":
            return int(truth(a, e.span) or truth(evaluate(e.right, env, depth), e.span))
        b = evaluate(e.right, env, depth)
        if e.op in ("==", "!="):
            if isinstance(a, str) or isinstance(b, str):
                same = fmt(a) == fmt(b)
            else:
                same = a == b
            return int(same if e.op == "==" else not same)
        x, y = _num(a, e.span), _num(b, e.span)
        return _sized(_arith(e.op, x, y, e.span), e.span)
    raise fail("E0202", "unsupported expression", getattr(e, "span", Span("<expr>", 0, 0)))


def _sized(v: Value, span: Span) -> Value:
    """``v``, or E0208 when it has more bits than ``--max-int-bits`` (see limits.py)."""
    if isinstance(v, int):
        msg = limits.int_too_large(v)
    elif isinstance(v, Fraction):
        msg = limits.int_too_large(v.numerator) or limits.int_too_large(v.denominator)
    else:
        return v
    if msg is not None:
        raise fail("E0208", msg, span)
    return v


def _arith(op: str, x: int | Fraction, y: int | Fraction, span: Span) -> Value:
    """A binary arithmetic, comparison or bit operator on two numbers."""
    if op in ("**", "<<"):
        yi = to_int(y, span)
        if op == "<<":
            msg = limits.power_too_large(2, yi) if yi > 0 else None
        elif isinstance(x, Fraction):
            msg = (limits.power_too_large(x.numerator.bit_length() + 1, abs(yi))
                   or limits.power_too_large(x.denominator.bit_length() + 1, abs(yi)))
        else:
            msg = limits.power_too_large(abs(x).bit_length() + (1 if abs(x) > 1 else 0),
                                         abs(yi))
        if msg is not None:
            raise fail("E0208", msg, span)
    if op == "+":
        return _norm(x + y)
    if op == "-":
        return _norm(x - y)
    if op == "*":
        return _norm(x * y)
    if op in ("/", "\\", "%"):
        if y == 0:
            raise fail("E0203", "division by zero", span)
        if op == "/":
            return _norm(Fraction(x) / Fraction(y))
        if op == "\\":
            q = abs(Fraction(x)) // abs(Fraction(y))  # truncation toward zero (Java)
            return int(q if (x >= 0) == (y >= 0) else -q)
        xi, yi = to_int(x, span), to_int(y, span)
        r = abs(xi) % abs(yi)
        return r if xi >= 0 else -r
    if op == "**":
        if x == 0 and to_int(y, span) < 0:
            raise fail("E0203", "division by zero (0 to a negative power)", span)
        return _norm(Fraction(x) ** to_int(y, span))
    if op == "<":
        return int(x < y)
    if op == "<=":
        return int(x <= y)
    if op == ">":
        return int(x > y)
    if op == ">=":
        return int(x >= y)
    xi, yi = to_int(x, span), to_int(y, span)
    if op in ("<<", ">>") and yi < 0:
        raise fail("E0202", f"negative shift count {yi}", span)
    if op == "<<":
        return xi << yi
    if op == ">>":
        return xi >> yi
    if op == "&":
        return xi & yi
    if op == "|":
        return xi | yi
    if op == "^":
        return xi ^ yi
    raise fail("E0202", f"unsupported operator {op}", span)


# A range is expanded into one label per value; past this size elaboration would run for
# minutes and exhaust memory, so it is reported instead (MTSA has no such limit and hangs).
MAX_RANGE = 1_000_000


def _checked_range(a: int, b: int, span: Span) -> list[Value]:
    if b - a + 1 > MAX_RANGE:
        raise fail("E0205", f"range {a}..{b} has {b - a + 1} values; at most {MAX_RANGE:,} "
                   "are expanded", span)
    return list(range(a, b + 1))


def range_values(lo: S.Expr, hi: S.Expr, env: Env, span: Span) -> list[Value]:
    a = to_int(evaluate(lo, env), span)
    b = to_int(evaluate(hi, env), span)
    if a > b:
        raise fail("E0204", f"empty range {a}..{b}", span)
    return _checked_range(a, b, span)


def bind_values(b: S.Bind, env: Env) -> list[Value]:
    """Values a binding ``[i:R]`` ranges over."""
    r = b.range
    if isinstance(r, S.RangeName):
        if r.name in env.tables.ranges:
            lo, hi = env.tables.ranges[r.name]
            return _checked_range(lo, hi, r.span)
        if r.name in env.tables.sets:
            return list(env.tables.sets[r.name])
        raise undefined("range or set", r.name, r.span, env.tables)
    if isinstance(r, S.RangeLit):
        return range_values(r.low, r.high, env, r.span)
    return list(expand_set(r, env))


def part_values(p: S.Part, env: Env) -> Iterator[tuple[str, Env]]:
    """Expand one label part to (text, env-with-its-bindings) alternatives."""
    if isinstance(p, S.Ident):
        yield p.name, env
    elif isinstance(p, S.SetName):
        if p.name in env.tables.sets:
            for s in env.tables.sets[p.name]:
                yield s, env
        else:
            raise undefined("set", p.name, p.span, env.tables)
    elif isinstance(p, S.Index):
        if isinstance(p.expr, S.Name) and p.expr.name not in env.params \
                and p.expr.name not in env.tables.consts:
            name = p.expr.name
            if name in env.tables.ranges:
                lo, hi = env.tables.ranges[name]
                for v in _checked_range(lo, hi, p.span):
                    yield str(v), env
                return
            if name in env.tables.sets:
                for s in env.tables.sets[name]:
                    yield s, env
                return
        yield fmt(evaluate(p.expr, env)), env
    elif isinstance(p, S.RangeIndex):
        for v in range_values(p.low, p.high, env, p.span):
            yield fmt(v), env
    elif isinstance(p, S.Bind):
        for v in bind_values(p, env):
            yield fmt(v), env.bind(p.var, v, p.span)
    else:  # SetLit
        for s in expand_set(p, env):
            yield s, env


def expand_label_env(lab: S.LabelExpr, env: Env) -> list[tuple[str, Env]]:
    """Expand a label element to (label, env) pairs; bindings flow into ``env``.

    Set differences cannot carry bindings out (their result is a plain set).
    """
    if isinstance(lab, S.SetDiff):
        base = expand_label_env(lab.base, env)
        minus: set[str] = set()
        for m in lab.minus:
            minus.update(x for x, _ in expand_label_env(m, env))
        return [(x, env) for x, _ in base if x not in minus]
    acc: list[tuple[str, Env]] = [("", env)]
    for part in lab.parts:
        nxt: list[tuple[str, Env]] = []
        for prefix, e in acc:
            for text, e2 in part_values(part, e):
                nxt.append((f"{prefix}.{text}" if prefix else text, e2))
        acc = nxt
    return acc


def expand_label(lab: S.LabelExpr, env: Env) -> list[str]:
    """The labels a label element denotes, duplicates removed, first occurrence order."""
    return list(dict.fromkeys(x for x, _ in expand_label_env(lab, env)))


def expand_set(s: S.LabelSetRef, env: Env) -> tuple[str, ...]:
    """Labels of a set literal or named set."""
    if isinstance(s, S.SetName):
        if s.name in env.tables.sets:
            return env.tables.sets[s.name]
        raise undefined("set", s.name, s.span, env.tables)
    out: dict[str, None] = {}
    for item in s.items:
        for x in expand_label(item, env):
            out[x] = None
    return tuple(out)


def expand_relabels(items: tuple[S.RelabelItem, ...], env: Env) -> dict[str, list[str]]:
    """Relabelling ``{new/old, ...}`` → ``{old: [new, ...]}`` (bindings flow from ``new`` into
    ``old``, or, if that fails, the other way)."""
    out: dict[str, list[str]] = {}
    for it in items:
        if isinstance(it, S.RelabelForall):
            for e2 in bind_all(it.binds, env):
                for k, vs in expand_relabels(it.items, e2).items():
                    out.setdefault(k, []).extend(v for v in vs if v not in out.get(k, []))
            continue
        # MTSA (like LTSA) expands the new label first, so its bindings flow into the old one
        # (`{f[i:1..2].out/f[i+1].in}`); we also accept the reverse (`{n[i]/o[i:R]}`).
        try:
            pairs = [(old, new) for new, e2 in expand_label_env(it.new, env)
                     for old in expand_label(it.old, e2)]
        except EvalError as first:
            try:
                pairs = [(old, new) for old, e2 in expand_label_env(it.old, env)
                         for new in expand_label(it.new, e2)]
            except EvalError:
                raise first from None
        for old, new in pairs:
            lst = out.setdefault(old, [])
            if new not in lst:
                lst.append(new)
    return out


def bind_all(binds: tuple[S.Bind, ...], env: Env) -> Iterator[Env]:
    """Every environment obtained by binding ``binds`` in order (cartesian product)."""
    if not binds:
        yield env
        return
    first, rest = binds[0], binds[1:]
    for v in bind_values(first, env):
        yield from bind_all(rest, env.bind(first.var, v, first.span))
