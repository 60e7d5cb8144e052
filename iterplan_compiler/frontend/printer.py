"""FSP printer: :mod:`syntax` tree → canonical FSP text.

Contract: for every tree ``t`` produced by :func:`~iterplan_compiler.frontend.parse.parse_text`,
``parse_text(print_spec(t))`` yields a tree equal to ``t`` (spans are excluded from equality).
``tests/frontend/test_printer.py`` checks this on hand-written specs and on every file of the
MTSA conformance corpus that parses.

Formatting is canonical (one declaration per paragraph, local processes on their own lines,
one space around binary operators, ``a -> b``) and parentheses are emitted only where MTSA's
precedence needs them:

* expressions (§1.3): ``?:`` < ``||`` < ``&&`` < ``|`` < ``^`` < ``&`` < ``== !=`` <
  ``< <= > >=`` < ``<< >>`` < ``+ -`` < ``* / \\ %`` < ``**`` (right-assoc) < unary; all other
  binary operators are left-associative.  ``const``/``range`` bounds, ``initially`` and
  ``rigid`` take the *additive* sub-grammar, so anything looser is parenthesised there;
* formulas (§1.9): unary operators bind tightest, then ``&&``, then the non-associative
  ``U W -> <->``, then ``||``; the right-hand side of a declaration is a unary formula, so a
  top-level binary formula is parenthesised.

Declarations the front-end ignores (``menu``, ``animation``) keep only their kind
and name in the tree; they print as an empty declaration of that kind (which parses back to the
same node).
"""

from __future__ import annotations

from fractions import Fraction

from iterplan_compiler.frontend import syntax as S

__all__ = ["print_spec", "print_decl", "print_expr", "print_label", "print_formula",
           "print_state", "print_cbody"]

# ------------------------------------------------------------------ expressions

_PREC = {
    "||": 1, "&&": 2, "|": 3, "^": 4, "&": 5, "==": 6, "!=": 6,
    "<": 7, "<=": 7, ">": 7, ">=": 7, "<<": 8, ">>": 8, "+": 9, "-": 9,
    "*": 10, "/": 10, "\\": 10, "%": 10, "**": 11,
}
_COND, _ADD, _UNARY, _ATOM = 0, 9, 12, 13


def _expr_prec(e: S.Expr) -> int:
    if isinstance(e, S.Cond):
        return _COND
    if isinstance(e, S.Binary):
        return _PREC[e.op]
    if isinstance(e, S.Unary):
        return _UNARY
    return _ATOM


def _num(v: int | Fraction) -> str:
    if isinstance(v, Fraction):
        # A REAL literal was a finite decimal, so the denominator divides some power of 10.
        whole, rest = divmod(v.numerator, v.denominator)
        digits = ""
        while True:
            rest *= 10
            d, rest = divmod(rest, v.denominator)
            digits += str(d)
            if rest == 0 or len(digits) > 40:
                break
        return f"{whole}.{digits}"
    return str(v)


def print_expr(e: S.Expr, min_prec: int = _COND) -> str:
    """``e`` as text, parenthesised if its precedence is below ``min_prec``."""
    p = _expr_prec(e)
    text = _expr(e)
    return f"({text})" if p < min_prec else text


def _expr(e: S.Expr) -> str:
    if isinstance(e, S.Num):
        return _num(e.value)
    if isinstance(e, (S.Var, S.Name)):
        return e.name
    if isinstance(e, S.Call):
        return f"{e.name}({', '.join(print_expr(a) for a in e.args)})"
    if isinstance(e, S.LabelConst):
        return "'" + print_label(e.label)
    if isinstance(e, S.Card):
        return "#" + _label_set(e.set)
    if isinstance(e, S.At):
        return f"@({_label_set(e.set)}, {print_expr(e.index)})"
    if isinstance(e, S.Unary):
        # `- -x` must not become `--x`; a space is harmless for every unary operator pair.
        arg = print_expr(e.arg, _UNARY)
        sep = " " if arg[:1] in "+-!~" else ""
        return f"{e.op}{sep}{arg}"
    if isinstance(e, S.Binary):
        p = _PREC[e.op]
        if e.op == "**":  # right-associative
            left, right = print_expr(e.left, p + 1), print_expr(e.right, p)
        else:
            left, right = print_expr(e.left, p), print_expr(e.right, p + 1)
        return f"{left} {e.op} {right}"
    if isinstance(e, S.Cond):
        # grammar: or_expr "?" expr ":" expr
        return (f"{print_expr(e.cond, 1)} ? {print_expr(e.then)} : "
                f"{print_expr(e.other)}")
    raise TypeError(f"not an expression: {e!r}")  # pragma: no cover - closed node set


# ------------------------------------------------------------------ labels and sets


def _bind(b: S.Bind) -> str:
    r = b.range
    if isinstance(r, S.RangeName):
        rng = r.name
    elif isinstance(r, S.RangeLit):
        rng = f"{print_expr(r.low)}..{print_expr(r.high)}"
    else:
        rng = _set_lit(r)
    return f"[{b.var}:{rng}]"


def _part(p: S.Part) -> str:
    if isinstance(p, (S.Ident, S.SetName)):
        return p.name
    if isinstance(p, S.Index):
        return f"[{print_expr(p.expr)}]"
    if isinstance(p, S.RangeIndex):
        return f"[{print_expr(p.low)}..{print_expr(p.high)}]"
    if isinstance(p, S.Bind):
        return _bind(p)
    if isinstance(p, S.SetLit):
        return _set_lit(p)
    raise TypeError(f"not a label part: {p!r}")  # pragma: no cover


def _label_elem(lab: S.Label) -> str:
    out = ""
    for i, p in enumerate(lab.parts):
        text = _part(p)
        if i and not isinstance(p, (S.Index, S.RangeIndex, S.Bind)):
            out += "."  # brackets attach directly (`a[1]`), names and sets after a dot
        out += text
    return out


def print_label(lab: S.LabelExpr) -> str:
    """A label element or set difference ``A \\ B``."""
    if isinstance(lab, S.SetDiff):
        return " \\ ".join([_label_elem(lab.base), *(_label_elem(m) for m in lab.minus)])
    return _label_elem(lab)


def _set_lit(s: S.SetLit) -> str:
    return "{" + ", ".join(print_label(i) for i in s.items) + "}"


def _label_set(s: S.LabelSetRef) -> str:
    return s.name if isinstance(s, S.SetName) else _set_lit(s)


def _relabels(items: tuple[S.RelabelItem, ...]) -> str:
    out = []
    for it in items:
        if isinstance(it, S.RelabelPair):
            out.append(f"{print_label(it.new)}/{print_label(it.old)}")
        else:
            out.append("forall " + "".join(_bind(b) for b in it.binds) + " "
                       + _relabels(it.items))
    return "{" + ", ".join(out) + "}"


# ------------------------------------------------------------------ processes


def _state_ref(r: S.StateRef) -> str:
    text = r.name
    if r.args is not None:
        text += "(" + ", ".join(print_expr(a) for a in r.args) + ")"
    return text + "".join(f"[{print_expr(i)}]" for i in r.indices)


def print_state(s: S.StateExpr, indent: str = "") -> str:
    """A state expression; choices of more than one branch break lines under ``indent``."""
    if isinstance(s, S.StateRef):
        return _state_ref(s)
    if isinstance(s, S.SeqComp):
        return "; ".join(_state_ref(i) for i in s.items)
    if isinstance(s, S.IfState):
        text = f"if {print_expr(s.cond)} then {print_state(s.then, indent)}"
        if s.other is not None:
            text += f" else {print_state(s.other, indent)}"
        return text
    if isinstance(s, S.Choices):
        inner = indent + "\t"
        branches = [_choice(c, inner) for c in s.choices]
        head = "(" + ("" if not s.foreach else
                      "foreach " + "".join(_bind(b) for b in s.foreach) + " ")
        if len(branches) <= 1 or sum(len(b) for b in branches) < 60:
            return head + " | ".join(branches) + ")"
        return head + f"\n{inner}| ".join(branches) + ")"
    raise TypeError(f"not a state expression: {s!r}")  # pragma: no cover


def _choice(c: S.Choice, indent: str) -> str:
    guard = "" if c.guard is None else f"when {print_expr(c.guard)} "
    chain = " -> ".join(print_label(lab) for lab in c.labels)
    return f"{guard}{chain} -> {print_state(c.target, indent)}"


def _tail(t: S.Tail) -> str:
    if t.kind == "relabel":
        return "/" + _relabels(t.relabels)
    if t.kind == "spec":
        return "~{" + t.name + "}"
    op = {"extend": "+", "hide": "\\", "expose": "@", "error_set": "!", "high": "<<",
          "low": ">>"}[t.kind]
    assert t.labels is not None
    return f"{op}{_label_set(t.labels)}"


def _params(ps: tuple[S.Param, ...]) -> str:
    if not ps:
        return ""
    return "(" + ", ".join(f"{p.name}={print_expr(p.default)}" for p in ps) + ")"


def _keywords(kws: tuple[str, ...]) -> str:
    return "".join(k + " " for k in kws)


def _tails(tails: tuple[S.Tail, ...]) -> str:
    return "".join(" " + _tail(t) for t in tails)


def _process(d: S.ProcessDecl) -> str:
    head = f"{_keywords(d.keywords)}{d.name}{_params(d.params)}{'@' if d.accept else ''}"
    text = f"{head} = {print_state(d.body)}"
    for loc in d.locals:
        idx = "".join(_part(p) for p in loc.indices)
        text += (f",\n{loc.name}{idx}{'@' if loc.accept else ''} = "
                 f"{print_state(loc.body)}")
    return text + _tails(d.tails) + "."


# ------------------------------------------------------------------ composites


def print_cbody(b: S.CBody) -> str:
    """A composite body."""
    if isinstance(b, S.CRef):
        args = "" if not b.args else "(" + ", ".join(print_expr(a) for a in b.args) + ")"
        return b.name + args
    if isinstance(b, S.CPar):
        return "(" + " || ".join(print_cbody(i) for i in b.items) + ")"
    if isinstance(b, S.CForall):
        return "forall " + "".join(_bind(x) for x in b.binds) + " " + print_cbody(b.body)
    if isinstance(b, S.CIf):
        text = f"if {print_expr(b.cond)} then {print_cbody(b.then)}"
        if b.other is not None:
            text += f" else {print_cbody(b.other)}"
        return text
    if isinstance(b, S.CItem):
        pre = "".join(print_label(p.label) + ("::" if p.share else ":") for p in b.prefixes)
        rel = "" if b.relabels is None else " / " + _relabels(b.relabels)
        return pre + print_cbody(b.prim) + rel
    raise TypeError(f"not a composite body: {b!r}")  # pragma: no cover


def _composite(d: S.CompositeDecl) -> str:
    return (f"{_keywords(d.keywords)}||{d.name}{_params(d.params)} = {print_cbody(d.body)}"
            f"{_tails(d.tails)}.")


# ------------------------------------------------------------------ formulas

_F_OR, _F_MID, _F_AND, _F_UNARY = 1, 2, 3, 4


def _f_prec(f: S.FNode) -> int:
    if isinstance(f, S.FBinary):
        return {"||": _F_OR, "&&": _F_AND}.get(f.op, _F_MID)
    return _F_UNARY


def print_formula(f: S.FNode, min_prec: int = _F_UNARY) -> str:
    """A formula; by default as a *unary* formula (the form a declaration's RHS takes)."""
    text = _formula(f)
    return f"({text})" if _f_prec(f) < min_prec else text


def _formula(f: S.FNode) -> str:
    if isinstance(f, S.FUnary):
        arg = print_formula(f.arg)
        return f"X {arg}" if f.op == "X" else f"{f.op}{arg}"
    if isinstance(f, S.FBinary):
        if f.op == "||":  # left-folded chain
            return f"{print_formula(f.left, _F_OR)} || {print_formula(f.right, _F_MID)}"
        if f.op == "&&":
            return f"{print_formula(f.left, _F_AND)} && {print_formula(f.right, _F_UNARY)}"
        # U W -> <-> are non-associative: both operands at the `&&` level
        return f"{print_formula(f.left, _F_AND)} {f.op} {print_formula(f.right, _F_AND)}"
    if isinstance(f, S.FQuant):
        return f"{f.kind} " + "".join(_bind(b) for b in f.binds) + " " + print_formula(f.body)
    if isinstance(f, S.FRigid):
        return "rigid " + print_expr(f.expr, _ADD)
    if isinstance(f, S.FRef):
        return f.name + "".join(_part(p) for p in f.indices)
    if isinstance(f, S.FCall):
        return f"{f.name}(" + ", ".join(print_expr(a) for a in f.args) + ")"
    if isinstance(f, S.FAction):
        return print_label(f.label)
    raise TypeError(f"not a formula: {f!r}")  # pragma: no cover


# ------------------------------------------------------------------ declarations

_SPEC_NAME_KEYS = frozenset({"safety", "assumption", "liveness", "failure", "buchi",
                             "concurrencyFluents", "activityFluents"})


def _spec_item(it: S.SpecItem) -> str:
    if it.key in _SPEC_NAME_KEYS:
        return f"{it.key} = {{{', '.join(it.names)}}}"
    if it.labels is not None:
        return f"{it.key} = {_label_set(it.labels)}"
    if len(it.ints) == 1:
        return f"{it.key} = {it.ints[0]}"
    if len(it.ints) == 2:
        return f"{it.key} = {{{it.ints[0]}, {it.ints[1]}}}"
    return it.key


def print_decl(d: S.Decl) -> str:
    """One declaration (processes and composites end with their ``.``)."""
    if isinstance(d, S.ConstDecl):
        return f"const {d.name} = {print_expr(d.value, _ADD)}"
    if isinstance(d, S.RangeDecl):
        return f"range {d.name} = {print_expr(d.low, _ADD)}..{print_expr(d.high, _ADD)}"
    if isinstance(d, S.SetDecl):
        return f"set {d.name} = {_set_lit(d.value)}"
    if isinstance(d, S.DefDecl):
        return f"def {d.name}({', '.join(d.params)}) = {print_expr(d.body)}"
    if isinstance(d, S.IncludeDecl):
        return f'include "{d.path}"'
    if isinstance(d, S.FluentDecl):
        idx = "".join(_part(p) for p in d.indices)
        text = (f"fluent {d.name}{idx} = <{print_label(d.initiating)}, "
                f"{print_label(d.terminating)}>")
        if d.initially is not None:
            text += " initially " + print_expr(d.initially, _ADD)
        return text
    if isinstance(d, S.FormulaDecl):
        text = f"{d.kind} {d.name}{_params(d.params)} = {print_formula(d.formula)}"
        if d.extension is not None:
            text += " + " + _label_set(d.extension)
        return text
    if isinstance(d, S.SpecDecl):
        body = "".join(f"\t{_spec_item(it)}\n" for it in d.items)
        return f"controllerSpec {d.name} = {{\n{body}}}"
    if isinstance(d, S.ProcessDecl):
        return _process(d)
    if isinstance(d, S.CompositeDecl):
        return _composite(d)
    if isinstance(d, S.ProgressDecl):
        head = f"progress {d.name}{''.join(_part(p) for p in d.indices)} = "
        if d.condition is not None:
            return head + f"if {_set_lit(d.condition)} then {_set_lit(d.actions)}"
        return head + _set_lit(d.actions)
    if isinstance(d, S.IgnoredDecl):
        if d.kind == "animation":
            return f'animation {d.name} = ""'
        return f"{d.kind} {d.name} = {{}}"
    raise TypeError(f"not a declaration: {d!r}")  # pragma: no cover


def print_spec(spec: S.SpecFile) -> str:
    """The whole file, declarations separated by blank lines, ending with a newline."""
    return "\n\n".join(print_decl(d) for d in spec.decls) + ("\n" if spec.decls else "")
