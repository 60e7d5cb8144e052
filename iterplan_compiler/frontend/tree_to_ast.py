"""Parsing, part 2: the Lark parse tree → :mod:`syntax` nodes (:class:`TreeToAst`).

The grammar is permissive; constructs it accepts that are not valid FSP raise
:class:`Malformed` (E0004; E0208 for a literal past ``--max-int-bits``, E0150 for MTS maybe
actions), which :func:`~.parse.parse_text` reports, dropping that declaration only.
"""


from __future__ import annotations

from fractions import Fraction

from lark import Token, Tree

from iterplan_compiler import limits
from iterplan_compiler.diagnostics import Diagnostic, Span, error
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.frontend.errors import Malformed, tok_span


def parse_int(text: str) -> int:
    """MTSA integer literal: ``0x..`` hex, a leading ``0`` means octal, else decimal."""
    if text[:2] in ("0x", "0X"):
        return int(text, 16)
    if len(text) > 1 and text[0] == "0" and all(c in "01234567" for c in text):
        return int(text, 8)
    return int(text)


class TreeToAst:
    """Converts the Lark tree into :mod:`syntax` nodes."""

    def __init__(self, path: str, diags: list[Diagnostic], *, allow_mts: bool = False):
        self.path = path
        self.diags = diags
        self.allow_mts = allow_mts

    # -- helpers
    def span(self, node: Tree | Token) -> Span:
        if isinstance(node, Token):
            return tok_span(self.path, node)
        meta = node.meta
        if getattr(meta, "empty", True):
            return Span(self.path, 0, 0)
        end_col = meta.end_column if meta.end_line == meta.line else None
        return Span(self.path, meta.line, meta.column, meta.end_line, end_col)

    def int_lit(self, tok: Token | Tree) -> int:
        """An integer literal; E0208 (not a crash) past ``--max-int-bits``."""
        msg = limits.literal_too_large(str(tok))
        if msg is not None:
            raise self.bad(tok, msg, "E0208")
        return parse_int(str(tok))

    def bad(self, node: Tree | Token, message: str, code: str = "E0004") -> Malformed:
        return Malformed(error(code, message, self.span(node)))

    @staticmethod
    def trees(node: Tree, name: str | None = None) -> list[Tree]:
        return [c for c in node.children if isinstance(c, Tree) and (name is None or c.data == name)]

    # -- declarations
    def decl(self, t: Tree) -> S.Decl | None:
        method = getattr(self, "d_" + t.data, None)
        if method is None:  # pragma: no cover - grammar and builder are kept in sync
            raise self.bad(t, f"internal: unknown declaration {t.data}")
        return method(t)

    def d_const_decl(self, t: Tree) -> S.ConstDecl:
        name, value = t.children
        return S.ConstDecl(str(name), self.expr(value), self.span(name))

    def d_range_decl(self, t: Tree) -> S.RangeDecl:
        name, lo, hi = t.children
        return S.RangeDecl(str(name), self.expr(lo), self.expr(hi), self.span(name))

    def d_set_decl(self, t: Tree) -> S.SetDecl:
        name, value = t.children
        return S.SetDecl(str(name), self.set_lit(value), self.span(name))

    def d_def_decl(self, t: Tree) -> S.DefDecl:
        name = t.children[0]
        params = tuple(str(c) for c in t.children[1:-1] if c is not None)
        return S.DefDecl(str(name), params, self.expr(t.children[-1]), self.span(name))

    def d_include_decl(self, t: Tree) -> S.IncludeDecl:
        tok = t.children[0]
        return S.IncludeDecl(str(tok)[1:-1], self.span(tok))

    def d_progress_decl(self, t: Tree) -> S.ProgressDecl:
        name = t.children[0]
        rest = [c for c in t.children[1:] if isinstance(c, Tree)]
        sets = [self.set_lit(c) for c in rest if c.data == "set_lit"]
        idx = tuple(self.bracket(c) for c in rest if c.data != "set_lit")
        cond = sets[0] if len(sets) == 2 else None
        return S.ProgressDecl(str(name), idx, cond, sets[-1], self.span(name))

    def d_menu_decl(self, t: Tree) -> S.IgnoredDecl:
        return S.IgnoredDecl("menu", str(t.children[0]), self.span(t))

    def d_animation_decl(self, t: Tree) -> S.IgnoredDecl:
        return S.IgnoredDecl("animation", str(t.children[0]), self.span(t))

    def d_fluent_decl(self, t: Tree) -> S.FluentDecl:
        name = t.children[0]
        rest = t.children[1:]
        init = rest[-1]
        labels = [c for c in rest[:-1] if isinstance(c, Tree) and c.data == "label"]
        idx = tuple(self.bracket(c) for c in rest[:-1]
                    if isinstance(c, Tree) and c.data != "label")
        return S.FluentDecl(str(name), idx, self.label(labels[0]), self.label(labels[1]),
                            None if init is None else self.expr(init), self.span(name))

    def params(self, t: Tree | None) -> tuple[S.Param, ...]:
        if t is None:
            return ()
        out = []
        for p in self.trees(t, "formal_param"):
            name, default = p.children
            out.append(S.Param(str(name), self.expr(default), self.span(name)))
        return tuple(out)

    def d_formula_decl(self, t: Tree) -> S.FormulaDecl:
        kind_t, name, params, formula, ext = t.children
        kind = str(kind_t.children[0])
        return S.FormulaDecl(kind, str(name), self.params(params), self.formula(formula),
                             None if ext is None else self.label_set(ext), self.span(name))

    def d_spec_decl(self, t: Tree) -> S.SpecDecl:
        name = t.children[0]
        items = []
        for it in t.children[1:]:
            key_tok = it.children[0].children[0]
            key = str(key_tok)
            sp = self.span(key_tok)
            if it.data == "spec_names":
                names = tuple(str(c) for c in it.children[1:] if c is not None)
                items.append(S.SpecItem(key, names=names, span=sp))
            elif it.data == "spec_labels":
                items.append(S.SpecItem(key, labels=self.label_set(it.children[1]), span=sp))
            elif it.data in ("spec_int", "spec_pair"):
                ints = tuple(self.int_lit(c) for c in it.children[1:])
                items.append(S.SpecItem(key, ints=ints, span=sp))
            else:
                items.append(S.SpecItem(key, span=sp))
        return S.SpecDecl(str(name), tuple(items), self.span(name))

    def keywords(self, t: Tree) -> tuple[str, ...]:
        return tuple(str(k.children[0]) for k in t.children)

    def tail(self, t: Tree) -> S.Tail:
        kind = t.data[len("tail_"):]
        sp = self.span(t)
        if kind == "relabel":
            return S.Tail("relabel", relabels=self.relabel_set(t.children[0]), span=sp)
        if kind == "spec":
            return S.Tail("spec", name=str(t.children[0]), span=sp)
        return S.Tail(kind, labels=self.label_set(t.children[0]), span=sp)

    def d_process_decl(self, t: Tree) -> S.ProcessDecl:
        kws, name, params, accept, body = t.children[:5]
        locals_: list[S.LocalDef] = []
        tails: list[S.Tail] = []
        for c in t.children[5:]:
            if c.data == "local_def":
                lname, *mid = c.children
                lbody = mid[-1]
                laccept = mid[-2] is not None
                idx = tuple(self.bracket(b) for b in mid[:-2])
                locals_.append(S.LocalDef(str(lname), idx, self.state(lbody), laccept,
                                          self.span(lname)))
            else:
                tails.append(self.tail(c))
        body_node = self.top_state(body, tails)
        return S.ProcessDecl(str(name), self.params(params), self.keywords(kws), body_node,
                             tuple(locals_), tuple(tails), accept is not None, self.span(name))

    def top_state(self, body: Tree, tails: list[S.Tail]) -> S.StateExpr:
        # `P = Q \ {a}.` parses as a set difference; it means hiding (see grammar header).
        lab = body.children[0] if body.data == "t_label" else body
        if isinstance(lab, Tree) and lab.data == "label" and len(lab.children) > 1:
            first = self.label_cat(lab.children[0])
            if self._as_state_ref(first) is not None:
                for extra in lab.children[1:]:
                    parts = self.label_cat(extra).parts
                    if len(parts) == 1 and isinstance(parts[0], (S.SetLit, S.SetName)):
                        tails.insert(0, S.Tail("hide", labels=parts[0], span=self.span(extra)))
                    else:
                        raise self.bad(extra, "expected a label set after '\\'")
                return self._as_state_ref(first)  # type: ignore[return-value]
        return self.state(body)

    def d_composite_decl(self, t: Tree) -> S.CompositeDecl:
        kws, name, params, body = t.children[:4]
        tails = tuple(self.tail(c) for c in t.children[4:])
        return S.CompositeDecl(str(name), self.params(params), self.keywords(kws),
                               self.cbody(body), tails, self.span(name))

    # -- state expressions
    def _as_state_ref(self, lab: S.Label) -> S.StateRef | None:
        parts = lab.parts
        if not parts or not isinstance(parts[0], S.SetName):
            return None
        idx = []
        for p in parts[1:]:
            if isinstance(p, S.Index):
                idx.append(p.expr)
            else:
                return None
        return S.StateRef(parts[0].name, None, tuple(idx), lab.span)

    def state(self, t: Tree) -> S.StateExpr:
        d = t.data
        if d == "t_label":
            return self.state(t.children[0])
        if d == "label":
            lab = self.label(t)
            if isinstance(lab, S.Label):
                ref = self._as_state_ref(lab)
                if ref is not None:
                    return ref
            raise self.bad(t, "expected a state (a local process name such as P or P[i]), "
                           "found an action label; is a '->' missing?")
        if d == "proc_call":
            name, *rest = t.children
            brackets = [c for c in rest if isinstance(c, Tree) and c.data == "bracket"]
            # Arguments and trailing indices are both trees; indices come after ')'.
            n_idx = len(brackets)
            args = tuple(self.expr(c) for c in rest[: len(rest) - n_idx] if c is not None)
            idx = []
            for b in brackets:
                part = self.bracket(b)
                if not isinstance(part, S.Index):
                    raise self.bad(b, "a process index must be an expression")
                idx.append(part.expr)
            return S.StateRef(str(name), args, tuple(idx), self.span(name))
        if d == "seq_ref":
            items = []
            for c in t.children:
                st = self.state(c)
                if not isinstance(st, S.StateRef):
                    raise self.bad(c, "sequential composition items must be process names")
                items.append(st)
            return S.SeqComp(tuple(items), self.span(t))
        if d in ("t_choices", "choices"):
            node = t.children[0] if d == "t_choices" else t
            return self.choices(node)
        if d == "t_if":
            cond, then, other = t.children
            return S.IfState(self.expr(cond), self.state(then),
                             None if other is None else self.state(other), self.span(t))
        raise self.bad(t, f"internal: unexpected state node {d}")  # pragma: no cover

    def choices(self, t: Tree) -> S.Choices:
        foreach: tuple[S.Bind, ...] = ()
        out = []
        children = list(t.children)
        if children and (children[0] is None or children[0].data == "foreach"):
            if children[0] is not None:
                foreach = tuple(self.bind(b) for b in children[0].children[1:])
            children = children[1:]
        for c in children:
            if c is None:
                continue
            guard_t, *seq = c.children
            labels_t = [seq[0], *seq[1:-1]]
            labels = []
            for lt in labels_t:
                node = lt.children[0] if lt.data == "t_label" else lt
                if node.data != "label":
                    raise self.bad(lt, "only the last element of a prefix chain may be a "
                                   "process; expected an action label")
                labels.append(self.label(node))
            out.append(S.Choice(None if guard_t is None else self.expr(guard_t), tuple(labels),
                                self.state(seq[-1]), self.span(c)))
        return S.Choices(tuple(out), foreach, self.span(t))

    # -- composites
    def cbody(self, t: Tree) -> S.CBody:
        d = t.data
        if d == "cb_if":
            cond, then, other = t.children
            return S.CIf(self.expr(cond), self.cbody(then),
                         None if other is None else self.cbody(other), self.span(t))
        if d == "cb_forall":
            *binds, body = t.children
            return S.CForall(tuple(self.bind(b) for b in binds), self.cbody(body), self.span(t))
        if d == "cb_item":
            *pre, prim, rel = t.children
            prefixes = tuple(
                S.Prefix(self.label_cat(p.children[0]), p.data == "share_prefix", self.span(p))
                for p in pre)
            prim_node = self.cprim(prim)
            relabels = None if rel is None else self.relabel_set(rel)
            if not prefixes and relabels is None:
                return prim_node
            return S.CItem(prefixes, prim_node, relabels, self.span(t))
        raise self.bad(t, f"internal: unexpected composite node {d}")  # pragma: no cover

    def cprim(self, t: Tree) -> S.CRef | S.CPar:
        if t.data == "cb_par":
            return S.CPar(tuple(self.cbody(c) for c in t.children if c is not None), self.span(t))
        name, *args = t.children
        return S.CRef(str(name), tuple(self.expr(a) for a in args if a is not None),
                      self.span(name))

    # -- labels
    def label(self, t: Tree) -> S.LabelExpr:
        cats = [self.label_cat(c) for c in t.children]
        if len(cats) == 1:
            return cats[0]
        return S.SetDiff(cats[0], tuple(cats[1:]), self.span(t))

    def label_cat(self, t: Tree | Token) -> S.Label:
        if isinstance(t, Token) or t.data not in ("label_cat", "lower_label", "clabel"):
            return S.Label((self.part(t),), self.span(t))
        parts = []
        for c in t.children:
            if isinstance(c, Tree) and c.data == "lpart_rest":
                c = c.children[-1]
            if isinstance(c, Token) and c.type == "LDOT":
                continue
            parts.append(self.part(c))
        return S.Label(tuple(parts), self.span(t))

    def part(self, t: Tree | Token) -> S.Part:
        if isinstance(t, Token):
            if t.type == "LOWER_ID":
                if "?" in t.value and not self.allow_mts:
                    raise self.bad(t, f"unsupported construct: MTS maybe action '{t.value}'",
                                   "E0150")
                return S.Ident(str(t), self.span(t))
            if t.type == "UPPER_ID":
                return S.SetName(str(t), self.span(t))
            if t.type == "INT":  # `a.1`: kept literally (the label is "a.1")
                return S.Ident(str(t), self.span(t))
            raise self.bad(t, f"internal: unexpected token {t.type}")  # pragma: no cover
        if t.data == "set_lit":
            return self.set_lit(t)
        return self.bracket(t)

    def bracket(self, t: Tree) -> S.Part:
        if t.data == "bracket":
            t = t.children[0]
        d = t.data
        if d in ("b_expr", "cbracket"):
            return S.Index(self.expr(t.children[0]), self.span(t))
        if d == "b_range":
            return S.RangeIndex(self.expr(t.children[0]), self.expr(t.children[1]), self.span(t))
        if d in ("fbind", "cbind", "febind"):
            return self.bind(t)
        raise self.bad(t, f"internal: unexpected bracket {d}")  # pragma: no cover

    def bind(self, t: Tree) -> S.Bind:
        var, spec = t.children
        sd = spec.data
        rng: S.RangeName | S.RangeLit | S.SetLit
        if sd == "rs_name":
            rng = S.RangeName(str(spec.children[0]), self.span(spec))
        elif sd == "rs_range":
            rng = S.RangeLit(self.expr(spec.children[0]), self.expr(spec.children[1]),
                             self.span(spec))
        else:
            rng = self.set_lit(spec.children[0])
        return S.Bind(str(var), rng, self.span(t))

    def set_lit(self, t: Tree) -> S.SetLit:
        return S.SetLit(tuple(self.label(c) for c in t.children if c is not None), self.span(t))

    def label_set(self, t: Tree) -> S.LabelSetRef:
        c = t.children[0]
        if isinstance(c, Token):
            return S.SetName(str(c), self.span(c))
        return self.set_lit(c)

    def relabel_set(self, t: Tree) -> tuple[S.RelabelItem, ...]:
        out: list[S.RelabelItem] = []
        for c in t.children:
            if c is None:
                continue
            if c.data == "relabel_pair":
                out.append(S.RelabelPair(self.label(c.children[0]), self.label(c.children[1]),
                                         self.span(c)))
            else:
                *brackets, inner = c.children
                binds = []
                for b in brackets:
                    part = self.bracket(b)
                    if not isinstance(part, S.Bind):
                        raise self.bad(b, "'forall' in a relabelling needs bindings [i:R]")
                    binds.append(part)
                out.append(S.RelabelForall(tuple(binds), self.relabel_set(inner), self.span(c)))
        return tuple(out)

    # -- formulas
    def formula(self, t: Tree | Token) -> S.FNode:
        if isinstance(t, Token):  # pragma: no cover - grammar wraps atoms in trees
            raise self.bad(t, "internal: bare token in formula")
        d = t.data
        sp = self.span(t)
        if d == "f_not":
            return S.FUnary("!", self.formula(t.children[0]), sp)
        if d == "f_next":
            return S.FUnary("X", self.formula(t.children[1]), sp)
        if d == "f_always":
            return S.FUnary("[]", self.formula(t.children[0]), sp)
        if d == "f_eventually":
            return S.FUnary("<>", self.formula(t.children[0]), sp)
        if d in ("f_exists", "f_forall"):
            binds_t, body = t.children
            return S.FQuant("exists" if d == "f_exists" else "forall",
                            self.fbinds(binds_t), self.formula(body), sp)
        if d == "f_rigid":
            return S.FRigid(self.expr(t.children[0]), sp)
        if d == "f_ref":
            name, *idx = t.children
            return S.FRef(str(name), tuple(self.bracket(b) for b in idx), sp)
        if d == "f_call":
            name, *args = t.children
            return S.FCall(str(name), tuple(self.expr(a) for a in args if a is not None), sp)
        if d == "f_action":
            lab = self.label_cat(t.children[0])
            return S.FAction(lab, sp)
        if d == "f_or":
            items = [self.formula(c) for c in t.children]
            out = items[0]
            for it in items[1:]:
                out = S.FBinary("||", out, it, sp)
            return out
        if d == "f_and":
            items = [self.formula(c) for c in t.children]
            out = items[0]
            for it in items[1:]:
                out = S.FBinary("&&", out, it, sp)
            return out
        if d == "f_bin":
            if len(t.children) == 1 or t.children[1] is None:
                return self.formula(t.children[0])
            left, op, right = t.children
            return S.FBinary(str(op.children[0]), self.formula(left), self.formula(right), sp)
        raise self.bad(t, f"internal: unexpected formula node {d}")  # pragma: no cover

    def fbinds(self, t: Tree) -> tuple[S.Bind, ...]:
        out: list[S.Bind] = []
        for c in t.children:
            if c.data == "fbinds":
                out.extend(self.fbinds(c))
            else:
                out.append(self.bind(c))
        return tuple(out)

    # -- expressions
    def expr(self, t: Tree | Token) -> S.Expr:
        if isinstance(t, Token):  # pragma: no cover
            raise self.bad(t, "internal: bare token in expression")
        d = t.data
        sp = self.span(t)
        c = t.children
        if d == "e_int":
            return S.Num(self.int_lit(c[0]), sp)
        if d == "e_real":
            text = str(c[0])
            msg = limits.literal_too_large(text.replace(".", "").lstrip("0") or "0")
            if msg is not None:
                raise self.bad(c[0], msg.replace("integer literal", "number literal"), "E0208")
            return S.Num(Fraction(text), sp)
        if d == "e_var":
            return S.Var(str(c[0]), sp)
        if d == "e_name":
            return S.Name(str(c[0]), sp)
        if d == "e_call":
            return S.Call(str(c[0]), tuple(self.expr(a) for a in c[1:] if a is not None), sp)
        if d == "e_label":
            parts: list[S.Part] = [S.Ident(str(c[0]), self.span(c[0]))]
            for p in c[1:]:
                if isinstance(p, Tree) and p.data == "lpart_rest":
                    p = p.children[-1]
                if isinstance(p, Token) and p.type == "LDOT":
                    continue
                parts.append(self.part(p))
            return S.LabelConst(S.Label(tuple(parts), sp), sp)
        if d == "e_card":
            return S.Card(self.label_set(c[0]), sp)
        if d == "e_at":
            return S.At(self.label_set(c[0]), self.expr(c[1]), sp)
        if d == "e_unary":
            return S.Unary(str(c[0].children[0]), self.expr(c[1]), sp)
        if d == "e_bin2":
            return S.Binary(str(c[1].children[0]), self.expr(c[0]), self.expr(c[2]), sp)
        if d == "e_pow":
            return S.Binary("**", self.expr(c[0]), self.expr(c[1]), sp)
        ops = {"e_or": "||", "e_and": "&&", "e_bor": "|", "e_bxor": "^", "e_band": "&"}
        if d in ops:
            return S.Binary(ops[d], self.expr(c[0]), self.expr(c[1]), sp)
        if d == "e_cond":
            return S.Cond(self.expr(c[0]), self.expr(c[1]), self.expr(c[2]), sp)
        raise self.bad(t, f"internal: unexpected expression node {d}")  # pragma: no cover
