"""Elaboration, part 2: building machines (:class:`Composition`).

Process/composite LTSs are built lazily and cached by instance name (``P``, ``P(2)``):
composition, relabel/hide/expose, priorities, operator keywords in MTSA's order (semantics doc
§2.6).  Synthesis composites are handed to the methods of :class:`~.elaborate.Elaborator`.

Codes: E0102 undefined process/composite, E0307 unbounded process instances, E0401 recursive
composition, E0402 state explosion, E0403 composite operator failed (e.g. ``property`` of a
nondeterministic machine).
"""

from __future__ import annotations

from iterplan_compiler.diagnostics import Diagnostic, Span, error, warning
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.frontend.declarations import (
    GAME_KEYWORDS,
    MAX_INSTANCE_NESTING,
    PLANT_KEYWORDS,
    Declarations,
    _instance_name,
    _max_states,
    relabel,
)
from iterplan_compiler.frontend.errors import too_deep
from iterplan_compiler.frontend.expressions import (
    Env,
    EvalError,
    Value,
    bind_all,
    evaluate,
    expand_label,
    expand_label_env,
    expand_relabels,
    expand_set,
    report,
    truth,
)
from iterplan_compiler.frontend.processes import build_process
from iterplan_compiler.ir.formulas import FormulaKind
from iterplan_compiler.ir.lts import LTS, reachable, renamed
from iterplan_compiler.ir.model import SynthesisProblem, Unrealizable


class Composition(Declarations):
    """Builds the LTSs of processes and composites on demand."""

    def build_lts(self, name: str, unrealizable: Unrealizable = Unrealizable.ERROR,
                  solve: bool = True) -> tuple[LTS | None, list[Diagnostic]]:
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
        if unrealizable is Unrealizable.PLANT and lts is None and name in self.unrealizable:
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
    def _safety_formula(self, name: str, span: Span, diags: list[Diagnostic]) -> LTS | None:
        nf = self.formulas.get(name)
        if nf is None:
            if name in self.formula_errors:
                diags.append(self.formula_errors[name])
            return None
        # a plain import (fltl pulls networkx in; most specs never need it)
        from iterplan_compiler.fltl.safety import safety_lts

        lts, ds = safety_lts(nf, self.fluents, constraint=nf.kind is FormulaKind.CONSTRAINT)
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
            synthesis = self._solver("the plant", d.name, d.span, diags)
            if synthesis is None:
                return None
            try:
                machines = list(synthesis.plant_components(problem))
            except synthesis.input_errors as e:
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


    # ------------------------------------------------------------------ defined by Elaborator
    # (synthesis composites: their problem, plant and controller; see frontend/elaborate.py)
    def _problem(self, name: str, diags: list[Diagnostic]) -> SynthesisProblem | None:
        raise NotImplementedError

    def _compatibility(self, d: S.CompositeDecl, env: Env, inst: str,
                       diags: list[Diagnostic]) -> LTS | None:
        raise NotImplementedError

    def unrealizable_plant(self, name: str) -> tuple[LTS | None, list[Diagnostic]]:
        raise NotImplementedError

    def _unsolved_plant(self, d: S.CompositeDecl, inst: str,
                        diags: list[Diagnostic]) -> LTS | None:
        raise NotImplementedError

    def _synthesised(self, d: S.CompositeDecl, inst: str, diags: list[Diagnostic]) -> LTS | None:
        raise NotImplementedError
