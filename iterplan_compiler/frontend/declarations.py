"""Elaboration, part 1: the declaration tables (:class:`Declarations`).

Global tables (const, range, set, def) are evaluated in source order (MTSA evaluates them at
declaration).  Processes, composites, fluents, formulas and controller specs may be used
before they are declared.  Fluents, formulas (FLTL) and controller specs are elaborated here;
building machines is :mod:`.composition`, synthesis problems :mod:`.elaborate`.

Codes: E0101 duplicate definition (with the first site), E0102 undefined process/composite,
E0103 operator keywords out of order, E0501 fluent sets not disjoint, E0601 undefined name in
a formula, E0602 recursive assert, E0701 undefined spec / name in a spec, W0151 ignored
declaration, E0909 a build needs synthesis but none was injected (:mod:`..ir.solving`).
"""

from __future__ import annotations

from collections.abc import Mapping

from iterplan_compiler.diagnostics import Diagnostic, Related, Span, error, warning
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.frontend.expressions import (
    Env,
    EvalError,
    Tables,
    Value,
    bind_all,
    evaluate,
    expand_label,
    expand_set,
    fmt,
    part_values,
    report,
    to_int,
    truth,
)
from iterplan_compiler.ir import formulas as F
from iterplan_compiler.ir.lts import LTS, TAU, make_lts
from iterplan_compiler.ir.model import (
    SYNTHESIS_KEYWORDS,
    ControllerSpec,
    SynthesisProblem,
)
from iterplan_compiler.ir.solving import Synthesis

#: a composite needs synthesis but the front-end was given none (see ir/solving.py)
E_NO_SYNTHESIS = "E0909"

OP_ORDER = ("closure", "abstract", "deterministic", "minimal", "compose", "property",
            "optimistic", "pessimistic", "component", "controller", "gr", "rtc", "rtcAnalysis",
            "starenv", "plant", "checkCompatibility", "controlled_det", "probabilistic", "mdp",
            "heuristic", "monolithicDirector")
GAME_KEYWORDS = SYNTHESIS_KEYWORDS | {"checkCompatibility"}
# Operators on a spec'd plant that do not synthesise (§3.11).
PLANT_KEYWORDS = frozenset({"plant", "controlled_det"})
# Parsed, accepted at load time, but building such a composite reports E0150 (none left).
UNSUPPORTED_AT_BUILD: frozenset[str] = frozenset()
UNSUPPORTED_KEYWORDS = frozenset({"closure", "abstract", "optimistic", "pessimistic",
                                  "component", "rtc", "rtcAnalysis", "probabilistic", "mdp"})
#: process instances spliced into one another (``P(N) = (a -> P(N+1))``) at most
MAX_INSTANCE_NESTING = 100
#: None: the --max-states limit of limits.py (tests may set a number)
MAX_STATES: int | None = None


def _max_states() -> int:
    from iterplan_compiler import limits

    return MAX_STATES if MAX_STATES is not None else limits.current().max_states


def relabel(lts: LTS, mapping: Mapping[str, list[str]]) -> LTS:
    """MTSA relabelling: a label is renamed at its longest listed dotted prefix (§2.3)."""
    if not mapping:
        return lts
    keys = sorted(mapping, key=len, reverse=True)

    def image(a: str) -> list[str]:
        if a == TAU:
            return [a]
        for k in keys:
            if a == k:
                return list(mapping[k])
            if a.startswith(k + "."):
                return [n + a[len(k):] for n in mapping[k]]
        return [a]

    trans = [(s, b, t) for s, a, t in lts.transitions for b in image(a)]
    alpha = {b for a in lts.alphabet for b in image(a)}
    return make_lts(lts.name, lts.num_states, trans, alpha, lts.initial, lts.end_states,
                    lts.state_names)


def _instance_name(name: str, args: tuple[Value, ...]) -> str:
    return f"{name}({','.join(fmt(a) for a in args)})" if args else name


def _join(first: Span, last: Span) -> Span:
    """The span from the start of ``first`` to the end of ``last`` (on one line: else ``first``)."""
    if first.line == last.line and last.end_column is not None:
        return Span(first.file, first.line, first.column, last.line, last.end_column)
    return first




class Declarations:
    """The evaluated declaration tables of one file (the base of :class:`Elaborator`)."""

    def __init__(self, spec: S.SpecFile, diags: list[Diagnostic],
                 synthesis: Synthesis | None = None):
        self.spec = spec
        # the injected synthesis stage (None: composites that need solving report E0909)
        self.synthesis = synthesis
        self.consts: dict[str, Value] = {}
        self.ranges: dict[str, tuple[int, int]] = {}
        self.sets: dict[str, tuple[str, ...]] = {}
        self.defs: dict[str, S.DefDecl] = {}
        self.failed: set[str] = set()  # const/range/set declarations that failed (reported)
        self.processes: dict[str, S.ProcessDecl] = {}
        self.composites: dict[str, S.CompositeDecl] = {}
        self.formula_decls: dict[str, S.FormulaDecl] = {}
        self.fluent_decls: dict[str, S.FluentDecl] = {}
        self.spec_decls: dict[str, S.SpecDecl] = {}
        # `progress` declarations, evaluated by `iterc check --progress` (ir/analysis.py)
        self.progress_decls: dict[str, S.ProgressDecl] = {}
        self.fluents: dict[str, F.Fluent] = {}
        self.fluent_families: dict[str, list[str]] = {}
        self.formulas: dict[str, F.NamedFormula] = {}
        self.specs: dict[str, ControllerSpec] = {}
        self.formula_errors: dict[str, Diagnostic] = {}
        self.cache: dict[str, tuple[LTS | None, list[Diagnostic]]] = {}
        # builds without solving (``solve=False``: a controller composite gives its plant)
        # keep their own cache: a composite using a controller composite differs between them
        self.solving = True
        self._unsolved_cache: dict[str, tuple[LTS | None, list[Diagnostic]]] = {}
        # synthesised composites by instance name: a controller composite built at top level
        # and again as a component of another composite is synthesised once
        self.synth_cache: dict[str, tuple[LTS | None, list[Diagnostic]]] = {}
        # the problem each synthesised instance was solved as (after §3.8), and the instances
        # found unrealizable: `build_lts(name, Unrealizable.PLANT)` returns their plant
        self.problems: dict[str, SynthesisProblem] = {}
        self.unrealizable: set[str] = set()
        self.building: list[str] = []
        self._instantiating: list[str] = []  # process instances being built (E0307)
        self._collect(diags)

    # ------------------------------------------------------------------ tables
    @property
    def tables(self) -> Tables:
        return Tables(self.consts, self.ranges, self.sets, self.defs, self.failed)

    def env(self) -> Env:
        return Env(self.tables)

    def _solver(self, what: str, name: str, span: Span,
                diags: list[Diagnostic]) -> Synthesis | None:
        """The injected synthesis stage; without one, E0909 (``what`` of composite ``name``
        needs it) and None: the front-end alone poses games but does not solve them."""
        if self.synthesis is None:
            diags.append(error(E_NO_SYNTHESIS, f"{what} of {name} needs synthesis, which is "
                               "not available in this build step (load the spec through "
                               "iterplan_compiler.pipeline, or pass synthesis= to "
                               "frontend.load)", span))
        return self.synthesis

    def _collect(self, diags: list[Diagnostic]) -> None:
        seen: dict[tuple[str, str], Span] = {}

        def dup(kind: str, name: str, span: Span) -> bool:
            key = (kind, name)
            if key in seen:
                diags.append(error("E0101", f"duplicate definition of {kind} '{name}'", span,
                                   Related(seen[key], "first definition here")))
                return True
            seen[key] = span
            return False

        for d in self.spec.decls:
            try:
                if isinstance(d, S.ConstDecl):
                    if not dup("constant", d.name, d.span):
                        self.consts[d.name] = evaluate(d.value, self.env())
                elif isinstance(d, S.RangeDecl):
                    if not dup("range", d.name, d.span):
                        lo = to_int(evaluate(d.low, self.env()), d.low.span)
                        hi = to_int(evaluate(d.high, self.env()), d.high.span)
                        if lo > hi:
                            diags.append(error("E0204", f"empty range {d.name} = {lo}..{hi}",
                                               _join(d.low.span, d.high.span)))
                        self.ranges[d.name] = (lo, hi)
                elif isinstance(d, S.SetDecl):
                    if not dup("set", d.name, d.span):
                        self.sets[d.name] = expand_set(d.value, self.env())
                elif isinstance(d, S.DefDecl):
                    if not dup("def", d.name, d.span):
                        self.defs[d.name] = d
                elif isinstance(d, S.ProcessDecl):
                    if d.name in ("STOP", "END", "ERROR"):
                        diags.append(error("E0101", f"'{d.name}' is a reserved name", d.span))
                    elif not dup("process", d.name, d.span):
                        self.processes[d.name] = d
                        self._check_keywords(d.keywords, d.span, diags)
                elif isinstance(d, S.CompositeDecl):
                    # MTSA keeps processes and composites in separate tables (`||TUNER = TUNER.`)
                    if not dup("composite", d.name, d.span):
                        self.composites[d.name] = d
                        self._check_keywords(d.keywords, d.span, diags)
                elif isinstance(d, S.FormulaDecl):
                    if not dup("assertion", d.name, d.span):
                        self.formula_decls[d.name] = d
                elif isinstance(d, S.FluentDecl):
                    if not dup("fluent", d.name, d.span):
                        self.fluent_decls[d.name] = d
                elif isinstance(d, S.SpecDecl):
                    if not dup("controllerSpec", d.name, d.span):
                        self.spec_decls[d.name] = d
                elif isinstance(d, S.ProgressDecl):
                    if not dup("progress", d.name, d.span):
                        self.progress_decls[d.name] = d
                elif isinstance(d, S.IgnoredDecl):
                    diags.append(warning("W0151", f"'{d.kind}' declaration {d.name} is ignored",
                                         d.span))
                elif isinstance(d, S.IncludeDecl):  # resolved by includes.py before us
                    pass
            except EvalError as e:
                if isinstance(d, (S.ConstDecl, S.RangeDecl, S.SetDecl)):
                    self.failed.add(d.name)
                report(diags, e)
        self._fluents(diags)
        self._formulas(diags)
        self._specs(diags)
        self._check_recursion(diags)
        self._check_composite_names(diags)

    def _check_keywords(self, kws: tuple[str, ...], span: Span, diags: list[Diagnostic]) -> None:
        pos = [OP_ORDER.index(k) for k in kws]
        if pos != sorted(pos) or len(set(pos)) != len(pos):
            diags.append(error("E0103", "operator keywords must appear in the order: "
                               + " ".join(k for k in OP_ORDER if k in kws), span))
        for k in kws:
            if k in UNSUPPORTED_KEYWORDS:
                diags.append(error("E0150", f"unsupported construct: operator '{k}'", span))

    # ------------------------------------------------------------------ fluents
    def _fluents(self, diags: list[Diagnostic]) -> None:
        for name, d in self.fluent_decls.items():
            members: list[str] = []
            try:
                keys: list[tuple[str, Env]] = [(name, self.env())]
                for part in d.indices:
                    keys = [(f"{k}.{t}", e2) for k, e in keys for t, e2 in part_values(part, e)]
                for key, env in keys:
                    ini = frozenset(expand_label(d.initiating, env))
                    ter = frozenset(expand_label(d.terminating, env))
                    both = ini & ter
                    if both:
                        diags.append(error("E0501", f"fluent {key}: initiating and terminating "
                                           f"sets share {', '.join(sorted(both))}", d.span))
                    init = bool(d.initially is not None and truth(evaluate(d.initially, env),
                                                                  d.span))
                    self.fluents[key] = F.Fluent(key, ini, ter, init, d.span)
                    members.append(key)
            except EvalError as e:
                report(diags, e)
            self.fluent_families[name] = members

    # ------------------------------------------------------------------ formulas
    def _formulas(self, diags: list[Diagnostic]) -> None:
        for name, d in self.formula_decls.items():
            try:
                env = self.env().with_params(
                    {p.name: evaluate(p.default, self.env()) for p in d.params})
                f = self.formula(d.formula, env, (name,))
                ext = frozenset(expand_set(d.extension, env)) if d.extension else frozenset()
                self.formulas[name] = F.NamedFormula(name, F.FormulaKind(d.kind), f, ext,
                                                     d.span)
            except EvalError as e:
                # MTSA compiles formulas lazily: a broken, unused formula is not an error.  We
                # warn now and report the error where the formula is used.
                self.formula_errors[name] = e.diag
                if not e.consequential:
                    diags.append(warning("W0603", f"{d.kind} {name} is not usable: "
                                         f"{e.diag.message}", e.diag.span))

    def formula(self, f: S.FNode, env: Env, stack: tuple[str, ...]) -> F.Formula:
        """Syntactic formula → IR formula (fluent families, quantifiers, asserts expanded)."""
        if isinstance(f, S.FUnary):
            a = self.formula(f.arg, env, stack)
            return {"!": F.Not, "X": F.Next, "[]": F.Always, "<>": F.Eventually}[f.op](a)
        if isinstance(f, S.FBinary):
            a = self.formula(f.left, env, stack)
            b = self.formula(f.right, env, stack)
            cls = {"&&": F.And, "||": F.Or, "->": F.Implies, "<->": F.Iff, "U": F.Until,
                   "W": F.WeakUntil}[f.op]
            return cls(a, b)
        if isinstance(f, S.FQuant):
            parts = [self.formula(f.body, e2, stack) for e2 in bind_all(f.binds, env)]
            return _fold(F.Or if f.kind == "exists" else F.And, parts, f.kind == "forall")
        if isinstance(f, S.FRigid):
            return F.Const(truth(evaluate(f.expr, env), f.span))
        if isinstance(f, S.FAction):
            return F.ActionProp(frozenset(expand_label(f.label, env)))
        if isinstance(f, S.FCall):
            return self._assert_ref(f.name, f.args, env, stack, f.span)
        assert isinstance(f, S.FRef), f
        if f.name in self.fluent_families:
            if not f.indices:
                if f.name in self.fluents:
                    return F.FluentProp(f.name)
                raise EvalError(error("E0601", f"indexed fluent family '{f.name}' used without "
                                      "an index", f.span))
            keys = [f.name]
            for part in f.indices:
                keys = [f"{k}.{t}" for k in keys for t, _ in part_values(part, env)]
            for k in keys:
                if k not in self.fluents:
                    raise EvalError(error("E0601", f"undefined fluent '{k}'", f.span))
            return _fold(F.Or, [F.FluentProp(k) for k in keys], False)
        if f.name in self.formula_decls and not f.indices:
            return self._assert_ref(f.name, (), env, stack, f.span)
        raise EvalError(error("E0601", f"'{f.name}' is neither a fluent nor an assert", f.span))

    def _assert_ref(self, name: str, args: tuple[S.Expr, ...], env: Env,
                    stack: tuple[str, ...], span: Span) -> F.Formula:
        d = self.formula_decls.get(name)
        if d is None or d.kind != "assert":
            raise EvalError(error("E0601", f"undefined assert '{name}'", span))
        if name in stack:
            raise EvalError(error("E0602", f"assert '{name}' refers to itself", span))
        vals = {p.name: evaluate(p.default, self.env()) for p in d.params}
        for p, a in zip(d.params, args, strict=False):
            vals[p.name] = evaluate(a, env)
        return self.formula(d.formula, self.env().with_params(vals), (*stack, name))

    # ------------------------------------------------------------------ controller specs
    def _specs(self, diags: list[Diagnostic]) -> None:
        for name, d in self.spec_decls.items():
            fields: dict[str, tuple[str, ...]] = {}
            controllable: frozenset[str] = frozenset()
            marking: frozenset[str] | None = None
            flags: set[str] = set()
            try:
                for it in d.items:
                    if it.key in ("safety", "assumption", "liveness", "failure", "buchi",
                                  "concurrencyFluents", "activityFluents"):
                        fields[it.key] = fields.get(it.key, ()) + it.names
                        for n in it.names:
                            if not self._spec_name_ok(it.key, n):
                                diags.append(error("E0701", f"controllerSpec {name}: '{n}' in "
                                                   f"{it.key} is not defined", it.span))
                    elif it.key == "controllable" and it.labels is not None:
                        controllable = frozenset(expand_set(it.labels, self.env()))
                    elif it.key == "marking" and it.labels is not None:
                        marking = frozenset(expand_set(it.labels, self.env()))
                    elif it.key in ("lazyness", "test_latency", "disturbances"):
                        diags.append(warning("W0702", f"controllerSpec field '{it.key}' is "
                                             "ignored", it.span))
                    else:
                        flags.add(it.key)
            except EvalError as e:
                report(diags, e)
            self.specs[name] = ControllerSpec(
                name, fields.get("safety", ()), fields.get("assumption", ()),
                fields.get("liveness", ()), fields.get("failure", ()), controllable, marking,
                frozenset(flags), d.span)

    def _spec_name_ok(self, key: str, n: str) -> bool:
        if key == "safety":
            return n in self.processes or n in self.composites or (
                n in self.formula_decls and self.formula_decls[n].kind != "assert")
        if key == "liveness" and n in self.fluents:
            return True
        return n in self.formula_decls and self.formula_decls[n].kind == "assert"

    # ------------------------------------------------------------------ names (static)
    def _check_composite_names(self, diags: list[Diagnostic]) -> None:
        """Resolve the names a composite uses without building it (so ``iterc check`` finds
        them): every component must be a process, composite or ``ltl_property``/``constraint``
        (E0102 at the reference), every ``~{G}`` a controllerSpec (E0701 at the tail)."""
        for d in self.composites.values():
            refs: list[S.CRef] = []
            _cb_crefs(d.body, refs)
            for r in refs:
                if not self._component_ok(r.name):
                    diags.append(error("E0102", f"undefined process or composite '{r.name}'",
                                       r.span))
            for t in d.tails:
                if t.kind == "spec" and t.name not in self.spec_decls:
                    diags.append(error("E0701", f"undefined controllerSpec '{t.name}'",
                                       t.span if t.span.line > 0 else d.span))

    def _component_ok(self, name: str) -> bool:
        return (name in self.processes or name in self.composites or name == "DEFAULT"
                or (name in self.formula_decls and self.formula_decls[name].kind != "assert"))

    # ------------------------------------------------------------------ recursion (static)
    def _check_recursion(self, diags: list[Diagnostic]) -> None:
        graph: dict[str, set[str]] = {}
        for name, d in self.composites.items():
            refs: set[str] = set()
            _cb_refs(d.body, refs)
            graph[name] = {r for r in refs if r in self.composites and r not in self.processes}
        reported: set[str] = set()
        for start in self.composites:
            path = _find_cycle(graph, start)
            if path and start not in reported:
                reported.update(path)
                d = self.composites[start]
                diags.append(error("E0401", "recursive expression while parallel composing: "
                                   + " -> ".join([*path, path[0]]), d.span))

    def synthesis_components(self, name: str) -> tuple[str, ...]:
        """The synthesis composites ``name`` uses, directly or through other composites (in
        first-use order; ``name`` itself excluded)."""
        seen: dict[str, None] = {}
        stack = [name]
        while stack:
            d = self.composites.get(stack.pop())
            if d is None:
                continue
            refs: list[S.CRef] = []
            _cb_crefs(d.body, refs)
            for r in refs:
                if r.name in self.composites and r.name not in self.processes \
                        and r.name not in seen and r.name != name:
                    seen[r.name] = None
                    stack.append(r.name)
        return tuple(n for n in seen if set(self.composites[n].keywords) & SYNTHESIS_KEYWORDS)



def _fold(cls: type, parts: list[F.Formula], conj: bool) -> F.Formula:
    if not parts:
        return F.Const(conj)
    out = parts[0]
    for p in parts[1:]:
        out = cls(out, p)
    return out


def _fluents_in(f: F.Formula, out: set[str]) -> None:
    if isinstance(f, F.FluentProp):
        out.add(f.name)
    for attr in ("arg", "left", "right"):
        sub = getattr(f, attr, None)
        if isinstance(sub, F.Formula):
            _fluents_in(sub, out)


def _cb_refs(b: S.CBody, out: set[str]) -> None:
    """Add the names of every component a composite body references to ``out``."""
    refs: list[S.CRef] = []
    _cb_crefs(b, refs)
    out.update(r.name for r in refs)


def _cb_crefs(b: S.CBody, out: list[S.CRef]) -> None:
    """Every component reference of a composite body, in source order."""
    if isinstance(b, S.CRef):
        out.append(b)
    elif isinstance(b, S.CPar):
        for it in b.items:
            _cb_crefs(it, out)
    elif isinstance(b, S.CForall):
        _cb_crefs(b.body, out)
    elif isinstance(b, S.CIf):
        _cb_crefs(b.then, out)
        if b.other is not None:
            _cb_crefs(b.other, out)
    elif isinstance(b, S.CItem):
        _cb_crefs(b.prim, out)


def _find_cycle(graph: dict[str, set[str]], start: str) -> list[str] | None:
    """A cycle through ``start`` (as a path starting at ``start``), or None."""
    stack = [(start, [start])]
    seen: set[str] = set()
    while stack:
        node, path = stack.pop()
        for nxt in sorted(graph.get(node, ())):
            if nxt == start:
                return path
            if nxt not in seen:
                seen.add(nxt)
                stack.append((nxt, [*path, nxt]))
    return None

