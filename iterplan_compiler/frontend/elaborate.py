"""Elaboration: :class:`~syntax.SpecFile` → :class:`~iterplan_compiler.ir.model.Model`.

Global tables (const, range, set, def) are evaluated in source order (MTSA evaluates them at
declaration).  Processes, composites, fluents, formulas and controller specs may be used
before they are declared.  Process/composite LTSs are built lazily by :class:`Elaborator`
(the model's backend) and cached by instance name (``P``, ``P(2)``).

Codes: E0101 duplicate definition (with the first site), E0102 undefined process/composite,
E0103 operator keywords out of order, E0401 recursive composition, E0402 state explosion,
E0403 composite operator failed (e.g. ``property`` of a nondeterministic machine),
E0501 fluent sets not disjoint, E0601 undefined name in a formula, E0602 recursive assert,
E0701 undefined spec / name in a spec,
E0901 synthesis failed/unrealizable, W0151 ignored declaration.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from fractions import Fraction

from iterplan_compiler.diagnostics import Diagnostic, Related, Span, error, warning
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.frontend.errors import too_deep
from iterplan_compiler.frontend.expressions import (
    Env,
    EvalError,
    Tables,
    Value,
    bind_all,
    evaluate,
    expand_label,
    expand_label_env,
    expand_relabels,
    expand_set,
    fmt,
    part_values,
    report,
    to_int,
    truth,
)
from iterplan_compiler.frontend.processes import build_process
from iterplan_compiler.ir import formulas as F
from iterplan_compiler.ir.lts import LTS, TAU, make_lts, reachable, renamed
from iterplan_compiler.ir.model import (
    SYNTHESIS_KEYWORDS,
    ControllerSpec,
    Model,
    ModelBackend,
    SynthesisProblem,
)
from iterplan_compiler.synthesis import driver as synthesis_driver
from iterplan_compiler.synthesis.encode import prepare as prepare_game

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


def _synthesis_errors() -> tuple[type[BaseException], ...]:
    """The exceptions of the synthesis stage that are about the *input* (a diagnostic, exit 1);
    every other exception is a compiler bug and must reach the CLI's exit 3 handler."""
    from iterplan_compiler.synthesis import encode

    return (encode.SynthesisError, encode.PreconditionFailure)


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


class Elaborator(ModelBackend):
    """Holds the declaration tables and builds LTSs on demand (the :class:`Model` backend)."""

    def __init__(self, spec: S.SpecFile, diags: list[Diagnostic]):
        self.spec = spec
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
        # found unrealizable: `build_lts(name, unrealizable="plant")` returns their plant
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
                self.formulas[name] = F.NamedFormula(name, d.kind, f, ext, d.span)
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

    # ------------------------------------------------------------------ building
    def build_lts(self, name: str, unrealizable: str = "error", solve: bool = True
                  ) -> tuple[LTS | None, list[Diagnostic]]:
        """See :meth:`Model.build_lts`."""
        if not solve and self.solving:
            saved = self.cache
            self.cache, self.solving = self._unsolved_cache, False
            try:
                return self.build_lts(name, unrealizable)
            finally:
                self.cache, self.solving = saved, True
        from iterplan_compiler import limits

        limits.progress(f"building {name}", 0)
        try:
            lts, diags = self._build_top(name)
        except RecursionError:
            self.building.clear()
            return None, [too_deep(self.spec.path)]
        except limits.LimitReached as e:  # e.g. the winning region of a game: a diagnostic
            self.building.clear()
            d = self.composites.get(name) or self.processes.get(name)
            span = d.span if d is not None else Span(self.spec.path, 0, 0)
            return None, [error(e.code, f"building {name}: {e.message}", span)]
        if unrealizable == "plant" and lts is None and name in self.unrealizable:
            plant, ds = self.unrealizable_plant(name)
            if plant is not None:
                # the verdict stays visible, as a warning: the caller asked for the plant
                kept = [x for x in diags if not (x.code == "E0901" and x.is_error)]
                note = warning("W0902", f"{name}: no controller exists (unrealizable); this "
                               f"is the plant {plant.name}", self.composites[name].span)
                return plant, [*kept, note, *ds]
        return lts, diags

    def _build_top(self, name: str) -> tuple[LTS | None, list[Diagnostic]]:
        key = "<top>" + name  # top-level names prefer composites; `get` prefers processes
        if key in self.cache:
            return self.cache[key]
        diags: list[Diagnostic] = []
        try:
            lts = self._build(name, (), Span("<command line>", 0, 0), diags,
                              prefer_composite=True)
        except EvalError as e:
            report(diags, e)
            lts = None
        result = (lts, diags)
        self.cache[key] = result
        return result

    def get(self, name: str, args: tuple[Value, ...], span: Span,
            diags: list[Diagnostic]) -> LTS | None:
        """Instance of a process/composite/safety formula by name (cached)."""
        key = _instance_name(name, args)
        if key in self.cache:
            lts, ds = self.cache[key]
            diags.extend(d for d in ds if d not in diags)
            return lts
        local: list[Diagnostic] = []
        stack = self._instantiating
        if key in stack or len(stack) >= MAX_INSTANCE_NESTING:
            # `P(N=1) = (a -> P(N+1))`: each instance splices in the next one, forever
            chain = " -> ".join([*stack[:3], "...", *stack[-2:], key] if len(stack) > 6
                                else [*stack, key])
            why = ("includes itself" if key in stack else
                   f"needs more than {MAX_INSTANCE_NESTING} nested process instances "
                   "(parameters that grow without bound?)")
            raise EvalError(error("E0307", f"process instance {stack[0]} {why}: {chain}",
                                  span))
        stack.append(key)
        try:
            lts = self._build(name, args, span, local)
        except EvalError as e:
            report(local, e)
            lts = None
        finally:
            stack.pop()
        self.cache[key] = (lts, local)
        diags.extend(local)
        return lts

    def _params(self, params: tuple[S.Param, ...], args: tuple[Value, ...], name: str,
                span: Span) -> dict[str, Value]:
        if len(args) > len(params):
            raise EvalError(error("E0102", f"'{name}' takes {len(params)} parameters, "
                                  f"{len(args)} given", span))
        vals = {p.name: evaluate(p.default, self.env()) for p in params}
        for p, a in zip(params, args, strict=False):
            vals[p.name] = a
        return vals

    def _build(self, name: str, args: tuple[Value, ...], span: Span,
               diags: list[Diagnostic], prefer_composite: bool = False) -> LTS | None:
        inst = _instance_name(name, args)
        if name in self.processes and not (prefer_composite and name in self.composites):
            d = self.processes[name]
            env = self.env().with_params(self._params(d.params, args, name, span))
            raw = build_process(d, env, inst, lambda n, a, sp: self.get(n, a, sp, diags), diags)
            if raw is None:
                return None
            return self._apply_tails(raw, d.tails, d.keywords, env, diags, d.span, process=True)
        if name in self.composites:
            if name in self.building:
                raise EvalError(error("E0401", "recursive expression while parallel composing: "
                                      + " -> ".join([*self.building, name]), span))
            self.building.append(name)
            try:
                return self._composite(self.composites[name], args, inst, diags)
            finally:
                self.building.pop()
        if name in self.formula_decls and self.formula_decls[name].kind != "assert":
            return self._safety_formula(name, span, diags)
        if name == "DEFAULT":
            machines = self._default_machines(span, diags)
            if machines is None:
                return None
            from iterplan_compiler.ir.compose import StateExplosion, compose

            try:
                return compose(machines, "DEFAULT", max_states=_max_states())
            except StateExplosion as e:
                diags.append(error("E0402", f"composing DEFAULT: {e}", span))
                return None
        raise EvalError(error("E0102", f"undefined process or composite '{name}'", span))

    def _default_machines(self, span: Span, diags: list[Diagnostic]) -> list[LTS] | None:
        """MTSA's ``DEFAULT`` composite (§4.1): every process (at its default parameters) and
        every ``ltl_property``/``constraint``, in declaration order."""
        names = [*self.processes,
                 *(n for n, f in self.formula_decls.items() if f.kind != "assert")]
        out = []
        for n in names:
            lts = self.get(n, (), span, diags)
            if lts is None:
                return None
            out.append(lts)
        return out

    # ------------------------------------------------------------------ legality
    def legality(self, name: str) -> tuple[bool, str]:
        """MTSA's ``LegalityAnalyser`` over a composite's first two machines (§4.2).

        The composite ``name`` (else the first composite, else ``DEFAULT``: MTSA's fallback)
        is instantiated; its machine 0 is the *controller*, machine 1 the *plant*, the others
        are context.  Controllable actions: the controllerSpec attached with ``~{G}``, else the
        file's only controllerSpec, else a declared set whose name contains "control"
        (case-insensitive), else the only declared set.  (MTSA's test passes the machines and the set explicitly; this rule reproduces
        the corpus' choices.)  Returns ``(legal, detail)``; a problem building the machines is
        reported as ``(False, "error: ...")``.
        """
        from iterplan_compiler.ir.legality import is_legal

        diags: list[Diagnostic] = []
        span = Span("<legality>", 0, 0)
        d = self.composites.get(name) or next(iter(self.composites.values()), None)
        try:
            if d is not None:
                env = self.env().with_params(self._params(d.params, (), d.name, d.span))
                machines = self._cbody(d.body, env, diags)
                spec = self._spec_of(d)
            else:
                machines = self._default_machines(span, diags)
                spec = None
        except EvalError as e:
            return False, f"error: {e.diag.message}"
        if machines is None or len(machines) < 2:
            msg = "; ".join(x.message for x in diags if x.is_error) or "fewer than two machines"
            return False, f"error: {msg}"
        if spec is None and len(self.specs) == 1:
            spec = next(iter(self.specs))  # `||Sys = (C || Plant)`: the file's only spec
        if spec is not None and spec in self.specs:
            controllable = self.specs[spec].controllable
            source = f"controllerSpec {spec}"
        else:
            named = [n for n in self.sets if "control" in n.lower()]
            if not named and len(self.sets) == 1:
                named = list(self.sets)
            if not named:
                return False, "error: no controllable set (no ~{G} and no set named *Control*)"
            controllable = frozenset(self.sets[named[0]])
            source = f"set {named[0]}"
        res = is_legal(machines[0], machines[1], controllable, context=machines[2:],
                       max_states=_max_states())
        pair = f"controller {machines[0].name}, plant {machines[1].name}, controllable = {source}"
        if res.legal:
            return True, f"legal ({pair}; {res.product_states} states)"
        why = res.witness.describe() if res.witness is not None else ""
        return False, f"not legal ({pair}): {why}"

    def _safety_formula(self, name: str, span: Span, diags: list[Diagnostic]) -> LTS | None:
        nf = self.formulas.get(name)
        if nf is None:
            if name in self.formula_errors:
                diags.append(self.formula_errors[name])
            return None
        # a plain import (fltl pulls networkx in; most specs never need it)
        from iterplan_compiler.fltl.safety import safety_lts

        lts, ds = safety_lts(nf, self.fluents, constraint=nf.kind == "constraint")
        diags.extend(ds)
        return None if lts is None else renamed(lts, name)

    def _composite(self, d: S.CompositeDecl, args: tuple[Value, ...], inst: str,
                   diags: list[Diagnostic]) -> LTS | None:
        """Build a composite in MTSA's operator order (semantics doc §2.6):

        compose → relabel/hide/expose → ``deterministic`` → ``minimal`` → synthesis
        (``controller``, ``heuristic``, ...) → ``plant`` → ``controlled_det`` → ``property`` →
        final hide/expose.  Synthesis composites and ``plant``/``controlled_det`` also compose
        the machines of their spec's ``safety`` list (§3.2).
        """
        env = self.env().with_params(self._params(d.params, args, d.name, d.span))
        kws = set(d.keywords)
        if "checkCompatibility" in kws and not kws & (GAME_KEYWORDS
                                                      - {"checkCompatibility"}):
            lts = self._compatibility(d, env, inst, diags)
        elif kws & GAME_KEYWORDS:
            lts = (self._synthesised(d, inst, diags) if self.solving
                   else self._unsolved_plant(d, inst, diags))
        elif kws & PLANT_KEYWORDS:
            lts = self._plant_operators(d, env, inst, diags)
        else:
            machines = self._cbody(d.body, env, diags)
            if machines is None:
                return None
            return self._compose_and_finish(machines, d, env, inst, diags)
        if lts is None:
            return None
        return self._post_synthesis(lts, d, env, diags)

    def _priority(self, d: S.CompositeDecl, env: Env) -> tuple[tuple[str, ...], bool] | None:
        prio = None
        for t in d.tails:
            if t.kind in ("high", "low") and t.labels is not None:
                prio = (expand_set(t.labels, env), t.kind == "high")
        return prio

    def _compose(self, machines: list[LTS], d: S.CompositeDecl, env: Env, inst: str,
                 diags: list[Diagnostic]) -> LTS | None:
        from iterplan_compiler.ir.compose import StateExplosion, compose

        try:
            return compose(machines, inst, self._priority(d, env), max_states=_max_states())
        except StateExplosion as e:
            diags.append(error("E0402", f"composing {inst}: {e}", d.span))
            return None

    def _compose_and_finish(self, machines: list[LTS], d: S.CompositeDecl, env: Env, inst: str,
                            diags: list[Diagnostic]) -> LTS | None:
        lts = self._compose(machines, d, env, inst, diags)
        if lts is None:
            return None
        return self._apply_tails(lts, d.tails, d.keywords, env, diags, d.span, process=False)

    def _plant_operators(self, d: S.CompositeDecl, env: Env, inst: str,
                         diags: list[Diagnostic]) -> LTS | None:
        """``plant ||P = E~{G}`` (the product with the goal's fluent monitors, §3.11) and
        ``controlled_det ||D = E~{G}`` (controllable determinisation, §3.8)."""
        from iterplan_compiler.frontend.operators import controlled_determinisation
        from iterplan_compiler.ir import alphabet_ops as ops

        problem = self._problem(d.name, diags)
        if problem is None:
            return None
        machines = [*problem.plant, *problem.safety]
        if "plant" in d.keywords:
            try:
                machines = list(prepare_game(problem).components)
            except _synthesis_errors() as e:
                # an unsupported goal; any other exception is a bug and propagates (exit 3)
                diags.append(error("E0901", f"{d.name}: {getattr(e, 'message', e)}", d.span))
                return None
        lts = self._compose(machines, d, env, inst, diags)
        if lts is None:
            return None
        lts = self._alphabet_tails(lts, d.tails, env)
        if "plant" in d.keywords:
            # the fluent monitors' states are internal bookkeeping, the product is the plant
            lts = renamed(lts, inst)
        if "controlled_det" in d.keywords and not ops.is_deterministic(lts):
            lts = reachable(controlled_determinisation(lts, problem.controllable, inst))
        return lts

    def _post_synthesis(self, lts: LTS, d: S.CompositeDecl, env: Env,
                        diags: list[Diagnostic]) -> LTS | None:
        """``property`` and the final hide/expose after synthesis / plant operators."""
        return self._keyword_ops(lts, tuple(k for k in d.keywords
                                            if k in ("starenv", "property")),
                                 d.tails, env, diags, d.span, process=False,
                                 hide_after=True)

    def _alphabet_tails(self, lts: LTS, tails: tuple[S.Tail, ...], env: Env) -> LTS:
        """``+S``, ``/{relabels}``, then ``\\S`` / ``@S`` (MTSA applies them in this order)."""
        from iterplan_compiler.ir import alphabet_ops as ops

        for t in tails:
            if t.kind == "extend" and t.labels is not None:
                lts = ops.extend_alphabet(lts, expand_set(t.labels, env))
        for t in tails:
            if t.kind == "relabel":
                lts = relabel(lts, expand_relabels(t.relabels, env))
        return self._hide_tails(lts, tails, env)

    def _hide_tails(self, lts: LTS, tails: tuple[S.Tail, ...], env: Env) -> LTS:
        from iterplan_compiler.ir import alphabet_ops as ops

        for t in tails:
            if t.kind == "hide" and t.labels is not None:
                lts = ops.hide(lts, expand_set(t.labels, env))
            elif t.kind == "expose" and t.labels is not None:
                lts = ops.expose(lts, expand_set(t.labels, env))
        return lts

    def _apply_tails(self, lts: LTS, tails: tuple[S.Tail, ...], keywords: tuple[str, ...],
                     env: Env, diags: list[Diagnostic], span: Span, *, process: bool) -> LTS | None:
        lts = self._alphabet_tails(lts, tails, env)
        return self._keyword_ops(lts, keywords, tails, env, diags, span, process=process)

    def _keyword_ops(self, lts: LTS, keywords: tuple[str, ...], tails: tuple[S.Tail, ...],
                     env: Env, diags: list[Diagnostic], span: Span, *, process: bool,
                     hide_after: bool = False) -> LTS | None:
        """``deterministic`` → ``minimal`` → ``starenv`` → ``property`` (§2.6), then (``hide_after``) the
        hide/expose tails once more, as MTSA re-applies hiding after every operator."""
        from iterplan_compiler.ir import alphabet_ops as ops
        from iterplan_compiler.ir import minimise as mn

        kws = set(keywords)
        name = lts.name
        try:
            if "deterministic" in kws:
                lts = mn.deterministic(lts, name)
            if "minimal" in kws:
                lts = mn.weak_minimise(lts, name)
            if "starenv" in kws:
                from iterplan_compiler.frontend.operators import star_environment

                lts = star_environment(lts, name)
            if "property" in kws:
                if not process:
                    # a property composite is determinised first (§2.4); a property process
                    # must already be deterministic (property_complete reports it)
                    lts = mn.deterministic(lts, name)
                err = None
                for t in tails:
                    if t.kind == "error_set" and t.labels is not None:
                        err = expand_set(t.labels, env)
                lts = ops.property_complete(lts, err)
            lts = reachable(lts)
        except ValueError as e:  # NotDeterministic and friends
            diags.append(error("E0403", str(e), span))
            return None
        if hide_after:
            lts = self._hide_tails(lts, tails, env)
        return lts

    def _plain_composite(self, name: str) -> S.CompositeDecl | None:
        """The declaration of ``name`` if it is a composite that is nothing but a parallel
        composition (no operator keyword, no tail): its product is the product of its leaves,
        so synthesis may take the leaves instead of the flattened machine."""
        if name in self.processes or name not in self.composites:
            return None
        d = self.composites[name]
        return None if d.keywords or d.tails else d

    def _cbody(self, b: S.CBody, env: Env, diags: list[Diagnostic], *,
               leaves: bool = False) -> list[LTS] | None:
        """The machines of a composite body.  With ``leaves``, references to plain composites
        (:meth:`_plain_composite`) are expanded into their own machines instead of being
        composed explicitly (synthesis composes them symbolically); prefixes distribute over
        the product, a relabelling does not (it may merge labels), so a relabelled item is
        built as one machine."""
        if isinstance(b, S.CRef):
            args = tuple(evaluate(a, env) for a in b.args)
            d = self._plain_composite(b.name) if leaves else None
            if d is not None:
                if b.name in self.building:
                    raise EvalError(error(
                        "E0401", "recursive expression while parallel composing: "
                        + " -> ".join([*self.building, b.name]), b.span))
                self.building.append(b.name)
                try:
                    inner = self.env().with_params(self._params(d.params, args, d.name, b.span))
                    return self._cbody(d.body, inner, diags, leaves=True)
                finally:
                    self.building.pop()
            lts = self.get(b.name, args, b.span, diags)
            return None if lts is None else [lts]
        if isinstance(b, S.CPar):
            out: list[LTS] = []
            for it in b.items:
                sub = self._cbody(it, env, diags, leaves=leaves)
                if sub is None:
                    return None
                out.extend(sub)
            return out
        if isinstance(b, S.CForall):
            out = []
            for e2 in bind_all(b.binds, env):
                sub = self._cbody(b.body, e2, diags, leaves=leaves)
                if sub is None:
                    return None
                out.extend(sub)
            return out
        if isinstance(b, S.CIf):
            if truth(evaluate(b.cond, env), b.span):
                return self._cbody(b.then, env, diags, leaves=leaves)
            return [] if b.other is None else self._cbody(b.other, env, diags, leaves=leaves)
        # CItem: `p1:p2::...:prim / {relabels}`.  A prefix may bind variables (`[i:R]:P(i)`),
        # which scope over the rest of the item, so each non-sharing prefix value gives its own
        # environment; prefixes are applied innermost first, the relabelling last.
        from iterplan_compiler.ir import alphabet_ops as ops

        out = []
        for leaf_env, chain in self._prefix_chains(b.prefixes, env):
            base = self._cbody(b.prim, leaf_env, diags,
                               leaves=leaves and b.relabels is None)
            if base is None:
                return None
            machines = base
            for share, labels in reversed(chain):
                if share:
                    machines = [ops.share_labels(m, labels) for m in machines]
                else:
                    lab = labels[0]
                    machines = [renamed(ops.prefix_labels(m, lab), f"{lab}:{m.name}")
                                for m in machines]
            if b.relabels is not None:
                mapping = expand_relabels(b.relabels, leaf_env)
                machines = [relabel(m, mapping) for m in machines]
            out.extend(machines)
        return out

    def _prefix_chains(self, prefixes: tuple[S.Prefix, ...], env: Env
                       ) -> list[tuple[Env, list[tuple[bool, list[str]]]]]:
        """Every combination of the prefixes' values: ``(env at the item, [(share, labels)])``
        outermost first; a sharing prefix keeps all its labels in one entry."""
        chains: list[tuple[Env, list[tuple[bool, list[str]]]]] = [(env, [])]
        for pre in prefixes:
            nxt: list[tuple[Env, list[tuple[bool, list[str]]]]] = []
            for e, chain in chains:
                if pre.share:
                    nxt.append((e, [*chain, (True, expand_label(pre.label, e))]))
                else:
                    nxt.extend((e2, [*chain, (False, [lab])])
                               for lab, e2 in expand_label_env(pre.label, e))
            chains = nxt
        return chains

    # ------------------------------------------------------------------ synthesis
    def _spec_of(self, d: S.CompositeDecl) -> str | None:
        for t in d.tails:
            if t.kind == "spec":
                return t.name
        return None

    def controllable(self, name: str) -> frozenset[str]:
        d = self.composites.get(name)
        spec = self._spec_of(d) if d else None
        if spec and spec in self.specs:
            return self.specs[spec].controllable
        return frozenset()

    def synthesis_problem(self, name: str) -> tuple[SynthesisProblem | None, list[Diagnostic]]:
        """The problem synthesis solves for composite ``name`` -- the same one ``build_lts``
        solves, so ``iterc synth``/``compile`` and ``iterc lts`` agree: a nondeterministic or
        tau plant is already controlled-determinised (§3.8, :meth:`_controlled_det_problem`)."""
        diags: list[Diagnostic] = []
        try:
            problem = self._problem(name, diags)
            d = self.composites.get(name)
            if problem is not None and d is not None:
                problem = self._controlled_det_problem(problem, d, diags)
            return problem, diags
        except EvalError as e:
            report(diags, e)
            return None, diags
        except RecursionError:
            self.building.clear()
            return None, [*diags, too_deep(self.spec.path)]

    def _problem(self, name: str, diags: list[Diagnostic]) -> SynthesisProblem | None:
        d = self.composites.get(name)
        if d is None:
            diags.append(error("E0102", f"undefined composite '{name}'",
                               Span(self.spec.path, 0, 0)))
            return None
        spec_name = self._spec_of(d)
        if spec_name is None or spec_name not in self.specs:
            diags.append(error("E0701", f"composite {name} has no controllerSpec "
                               f"(~{{{spec_name or 'G'}}})", d.span))
            return None
        spec = self.specs[spec_name]
        env = self.env()
        # §3.2: the body's machines, plain sub-composites as their leaves (composed
        # symbolically by synthesis); the first body item is MTSA's "environment" machine
        items = d.body.items if isinstance(d.body, S.CPar) else (d.body,)
        plant: list[LTS] = []
        env_machines = 0
        for k, item in enumerate(items):
            part = self._cbody(item, env, diags, leaves=True)
            if part is None:
                return None
            plant.extend(part)
            if k == 0:
                env_machines = len(part)
        safety: list[LTS] = []
        for n in spec.safety:
            lts = self.get(n, (), spec.span, diags)
            if lts is None:
                return None
            from iterplan_compiler.ir import alphabet_ops as ops
            acc = [a for a in lts.alphabet if a.startswith("@")]
            safety.append(ops.hide(lts, acc) if acc else lts)

        def goal(n: str, allow_fluent: bool) -> F.Formula:
            if allow_fluent and n in self.fluents:
                return F.FluentProp(n)
            if n in self.formulas:
                return self.formulas[n].formula
            if n in self.formula_errors:
                raise EvalError(self.formula_errors[n])
            raise EvalError(error("E0701", f"controllerSpec {spec.name}: undefined '{n}'",
                                  spec.span))

        assumptions = tuple(goal(n, False) for n in spec.assumptions)
        guarantees = tuple(goal(n, True) for n in spec.liveness)
        failures = tuple(goal(n, False) for n in spec.failures)
        used: set[str] = set()
        for f in (*assumptions, *guarantees, *failures):
            _fluents_in(f, used)
        return SynthesisProblem(
            name=name, keywords=frozenset(d.keywords), plant=tuple(plant),
            safety=tuple(safety), assumptions=assumptions, guarantees=guarantees,
            failures=failures, fluents=tuple(self.fluents[u] for u in sorted(used)),
            controllable=spec.controllable, marking=spec.marking, nonblocking=spec.nonblocking,
            spec_name=spec.name, span=d.span, permissive="permissive" in spec.flags,
            env_machines=env_machines)

    def _controlled_det_problem(self, problem: SynthesisProblem, d: S.CompositeDecl,
                                diags: list[Diagnostic]) -> SynthesisProblem | None:
        """MTSA §3.8 for ``controller``/``gr`` without ``nonblocking``: when the plant product
        ``P = body ∥ safety machines`` has tau moves or is nondeterministic, the game is played
        on the *controlled determinisation* of ``P`` (tau moves removed first: hidden actions
        are unobservable), whose extra action ``-1`` is uncontrollable.  Otherwise (the normal
        case) the problem is returned unchanged, its components not composed here."""
        from iterplan_compiler.frontend.operators import (
            controlled_determinisation,
            eliminate_tau,
        )
        from iterplan_compiler.ir import alphabet_ops as ops
        from iterplan_compiler.ir.compose import StateExplosion, compose

        kws = problem.keywords
        if (not kws & {"controller", "gr"} or problem.nonblocking
                or kws & {"heuristic", "monolithicDirector", "checkCompatibility"}):
            return problem
        machines = [*problem.plant, *problem.safety]
        # a product of deterministic tau-free machines is deterministic: compose only if needed
        if all(ops.is_deterministic(m) for m in machines):
            return problem
        try:
            plant = compose(machines, problem.name, max_states=_max_states())
        except StateExplosion as e:
            diags.append(error("E0402", f"composing the plant of {problem.name}: {e}", d.span))
            return None
        if ops.is_deterministic(plant):
            return problem
        if any(a == TAU for _, a, _ in plant.transitions):
            plant = eliminate_tau(plant)
        det = reachable(controlled_determinisation(plant, problem.controllable, problem.name))
        return replace(problem, plant=(det,), safety=(), env_machines=1)

    def _compatibility(self, d: S.CompositeDecl, env: Env, inst: str,
                       diags: list[Diagnostic]) -> LTS | None:
        """``checkCompatibility ||C = E~{G}`` (§3.11): MTSA only prints whether the spec's
        assumptions are compatible with the plant.  We report "NOT compatible" as warning
        W0903 and build the plant product (body ∥ safety machines) as the composite."""
        problem = self._problem(d.name, diags)
        if problem is None:
            return None
        try:
            compatible, message = synthesis_driver.check_compatibility(problem)
        except _synthesis_errors() as e:  # e.g. a temporal goal; a bug propagates (exit 3)
            diags.append(error("E0901", f"compatibility check of {d.name} failed: "
                               f"{getattr(e, 'message', e)}", d.span))
            return None
        if not compatible:
            diags.append(warning("W0903", f"{d.name}: {message}", d.span))
        return self._compose([*problem.plant, *problem.safety], d, env, inst, diags)

    def unrealizable_plant(self, name: str) -> tuple[LTS | None, list[Diagnostic]]:
        """MTSA's composition of an unrealizable ``controller`` composite (§3.7): the plant
        the game was played on (after §3.8), operators and hiding applied, named
        ``name_#NC#``.  ``(None, [])`` when ``name`` was not built or is not unrealizable."""
        from iterplan_compiler.ir.compose import StateExplosion, compose

        d = self.composites.get(name)
        problem = self.problems.get(name)
        if d is None or problem is None or name not in self.unrealizable:
            return None, []
        diags: list[Diagnostic] = []
        try:
            plant = compose([*problem.plant, *problem.safety], f"{name}_#NC#",
                            max_states=_max_states())
        except StateExplosion as e:
            return None, [error("E0402", f"composing the plant of {name}: {e}", d.span)]
        env = self.env().with_params(self._params(d.params, (), d.name, d.span))
        lts = self._post_synthesis(plant, d, env, diags)
        return lts, diags

    def _unsolved_plant(self, d: S.CompositeDecl, inst: str,
                        diags: list[Diagnostic]) -> LTS | None:
        """A synthesis composite built without solving: the plant its game is played on
        (body machines ∥ safety machines, after §3.8), named like the composite."""
        from iterplan_compiler.ir.compose import StateExplosion, compose

        problem = self._problem(d.name, diags)
        if problem is None:
            return None
        problem = self._controlled_det_problem(problem, d, diags)
        if problem is None:
            return None
        try:
            return compose([*problem.plant, *problem.safety], inst, max_states=_max_states())
        except StateExplosion as e:
            diags.append(error("E0402", f"composing the plant of {d.name}: {e}", d.span))
            return None

    def _synthesised(self, d: S.CompositeDecl, inst: str, diags: list[Diagnostic]) -> LTS | None:
        if inst not in self.synth_cache:
            local: list[Diagnostic] = []
            self.synth_cache[inst] = (self._synthesise(d, inst, local), local)
        lts, ds = self.synth_cache[inst]
        diags.extend(x for x in ds if x not in diags)
        return lts

    def _synthesise(self, d: S.CompositeDecl, inst: str, diags: list[Diagnostic]) -> LTS | None:
        problem = self._problem(d.name, diags)
        if problem is None:
            return None
        problem = self._controlled_det_problem(problem, d, diags)
        if problem is None:
            return None
        self.problems[inst] = problem
        try:
            from iterplan_compiler import limits

            limits.progress(f"synthesising {d.name}", 0)
            result = synthesis_driver.synthesize(problem)
        except _synthesis_errors() as e:  # synthesize reports these itself; a bug propagates
            diags.append(error("E0901", f"synthesis of {d.name} failed: "
                               f"{getattr(e, 'message', e)}", d.span))
            return None
        if not result.realizable:
            self.unrealizable.add(inst)
            diags.append(error("E0901", f"{d.name}: no controller exists (unrealizable)"
                               + (f": {result.explanation}" if result.explanation else ""),
                               d.span))
            return None
        lts = result.composition if result.composition is not None else result.controller
        if lts is None:
            return None
        return renamed(lts, inst)


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


def elaborate(spec: S.SpecFile, text: str, sources: dict[str, str] | None = None
              ) -> tuple[Model, list[Diagnostic]]:
    """Build the :class:`Model` of a parsed file (LTSs are built lazily)."""
    diags: list[Diagnostic] = []
    el = Elaborator(spec, diags)
    consts: dict[str, object] = {k: (float(v) if isinstance(v, Fraction) else v)
                                 for k, v in el.consts.items()}
    model = Model(
        source_path=spec.path, source_text=text,
        processes=tuple(el.processes), composites=tuple(el.composites),
        composite_keywords={n: frozenset(d.keywords) for n, d in el.composites.items()},
        fluents=el.fluents, formulas=el.formulas, controller_specs=el.specs,
        constants=consts, ranges=el.ranges, sets=el.sets, backend=el,
        sources=dict(sources or {spec.path: text}),
        origins={n: d.span.file for table in (el.processes, el.composites, el.formula_decls)
                 for n, d in table.items()})
    return model, diags


__all__ = ["Elaborator", "elaborate", "relabel", "expand_label_env"]
