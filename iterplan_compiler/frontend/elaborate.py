"""Elaboration: :class:`~syntax.SpecFile` → :class:`~iterplan_compiler.ir.model.Model`.

:func:`elaborate` builds the :class:`Elaborator`, which is three layers: the declaration
tables (:mod:`.declarations`), building machines (:mod:`.composition`) and, here, the
synthesis problems of controller composites (resolving their ``controllerSpec``, the
controlled determinisation of §3.8, ``checkCompatibility``), their solving and MTSA's
legality check.

Solving is not imported: it is the injected :class:`~iterplan_compiler.ir.solving.Synthesis`
(``frontend.load(..., synthesis=...)``; the pipeline passes the real one).

Codes: E0701 undefined spec / name in a spec, E0901 synthesis failed/unrealizable, W0902
unrealizable (the plant returned instead), W0903 assumptions not compatible, E0909 no
synthesis injected.
"""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction

from iterplan_compiler.diagnostics import Diagnostic, Span, error, warning
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.frontend.composition import Composition
from iterplan_compiler.frontend.declarations import (
    GAME_KEYWORDS,
    _cb_refs,
    _fluents_in,
    _max_states,
    relabel,
)
from iterplan_compiler.frontend.errors import too_deep
from iterplan_compiler.frontend.expressions import (
    Env,
    EvalError,
    report,
)
from iterplan_compiler.ir import formulas as F
from iterplan_compiler.ir.lts import LTS, TAU, reachable, renamed
from iterplan_compiler.ir.model import (
    Model,
    ModelBackend,
    SynthesisProblem,
)
from iterplan_compiler.ir.solving import Synthesis


class Elaborator(Composition, ModelBackend):
    """Holds the declaration tables and builds LTSs on demand (the :class:`Model` backend);
    this part poses the synthesis problems of controller composites and solves them."""

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
        synthesis = self._solver("the compatibility check", d.name, d.span, diags)
        if synthesis is None:
            return None
        try:
            compatible, message = synthesis.check_compatibility(problem)
        except synthesis.input_errors as e:  # e.g. a temporal goal; a bug propagates (exit 3)
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
        synthesis = self._solver("the controller", d.name, d.span, diags)
        if synthesis is None:
            return None
        try:
            from iterplan_compiler import limits

            limits.progress(f"synthesising {d.name}", 0)
            result = synthesis.synthesize(problem)
        except synthesis.input_errors as e:  # synthesize reports these itself; a bug propagates
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



def elaborate(spec: S.SpecFile, text: str, sources: dict[str, str] | None = None,
              synthesis: Synthesis | None = None) -> tuple[Model, list[Diagnostic]]:
    """Build the :class:`Model` of a parsed file (LTSs are built lazily).  ``synthesis``
    solves the controller composites a build needs (None: such builds report E0909)."""
    diags: list[Diagnostic] = []
    el = Elaborator(spec, diags, synthesis)
    consts: dict[str, int | float | str] = {k: (float(v) if isinstance(v, Fraction) else v)
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


__all__ = ["GAME_KEYWORDS", "Elaborator", "_cb_refs", "elaborate", "relabel"]

