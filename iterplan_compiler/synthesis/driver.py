"""Synthesis entry point: ``synthesize(problem, solver=...) -> SynthesisResult``.

Pipeline (§3.12): prepare the game components (:mod:`encode`) → solve (symbolic BDD fixpoint,
:mod:`game`, or the explicit rank solver, :mod:`explicit`) → extract MTSA's controller
(:mod:`strategy`; the symbolic path ranks only the reachable winning subgame) → minimise →
re-compose ``controller ∥ other body machines ∥ safety machines`` → or, when unrealizable,
explain (:mod:`explain`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from iterplan_compiler.diagnostics import Diagnostic, error
from iterplan_compiler.ir.compose import compose
from iterplan_compiler.ir.lts import LTS, renamed
from iterplan_compiler.ir.minimise import strong_minimise
from iterplan_compiler.ir.model import SynthesisProblem
from iterplan_compiler.synthesis import explicit as _explicit
from iterplan_compiler.synthesis.encode import (
    GameSpec,
    PreconditionFailure,
    SynthesisError,
    prepare,
)
from iterplan_compiler.synthesis.options import GameMode, MacroSteps, Solver, VariableOrder
from iterplan_compiler.synthesis.strategy import (
    StrategyKind,
    extract_controller,
    extract_director,
    nonblocking_region,
)

__all__ = ["MacroSteps", "Solver", "StrategyKind", "SynthesisResult", "SynthesisStats",
           "VariableOrder", "check_compatibility", "plant_product", "strategy_kind", "synthesize"]


SOLVERS = tuple(s.value for s in Solver)

StatValue = int | float | str


@dataclass(frozen=True)
class SynthesisStats(Mapping[str, object]):
    """Sizes and per-phase times of one :func:`synthesize` run.

    Typed fields for what every run reports (None: not measured by this solver); ``times`` are
    the phases in the order they ran (``prepare``, ``encode``/``build``, ``reach``, ``solve``,
    ``extract``), ``extra`` anything else an engine reported.  The mapping view (``st["t_solve"]``,
    ``"mode" in st``) serves the reports and benchmarks written against the former dict.
    """

    solver: Solver
    mode: GameMode | None = None
    strategy: StrategyKind | None = None
    warnings: tuple[str, ...] = ()
    precondition: str | None = None
    game_states: int | None = None
    game_transitions: int | None = None
    winning_states: int | None = None
    controller_states: int | None = None
    controller_transitions: int | None = None
    composition_states: int | None = None
    bdd_vars: int | None = None
    trans_bdd_nodes: int | None = None
    winning_bdd_nodes: int | None = None
    peak_bdd_nodes: int | None = None
    fixpoint_iterations: int | None = None
    verdict_at: float | None = None  # seconds from the start until the fixpoint decided
    bdd_backend: str | None = None
    order: VariableOrder | None = None
    times: tuple[tuple[str, float], ...] = ()
    extra: tuple[tuple[str, object], ...] = ()

    @classmethod
    def from_dict(cls, raw: Mapping[str, Any]) -> SynthesisStats:
        """The typed record of the dict the engines fill in while solving."""
        names = {f.name for f in fields(cls)} - {"times", "extra", "solver", "warnings"}
        known = {k: v for k, v in raw.items() if k in names}
        times = tuple((k[2:], float(v)) for k, v in raw.items() if k.startswith("t_"))
        extra = tuple((k, v) for k, v in raw.items()
                      if k not in names and not k.startswith("t_")
                      and k not in ("solver", "warnings"))
        return cls(Solver(raw.get("solver", Solver.SYMBOLIC)),
                   warnings=tuple(str(w) for w in raw.get("warnings", ())),
                   times=times, extra=extra, **known)

    def _items(self) -> dict[str, object]:
        out: dict[str, object] = {"solver": self.solver.value}
        for f in fields(self):
            if f.name in ("solver", "times", "extra"):
                continue
            v = getattr(self, f.name)
            if v is not None and not (f.name == "warnings" and not v and self.mode is None):
                out[f.name] = list(v) if f.name == "warnings" else v
        out.update((f"t_{k}", v) for k, v in self.times)
        out.update(self.extra)
        return out

    def __getitem__(self, key: str) -> object:
        return self._items()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._items())

    def __len__(self) -> int:
        return len(self._items())

    def seconds(self, phase: str) -> float:
        """Seconds spent in ``phase`` (0.0 when it did not run)."""
        return dict(self.times).get(phase, 0.0)


@dataclass(frozen=True)
class SynthesisResult:
    """Outcome of :func:`synthesize`.

    ``controller`` — the (minimised) controller LTS over the plant alphabet, or None
    (unrealizable, or ``realizability_only``);
    ``composition`` — ``controller ∥ other body machines ∥ safety machines`` named like the
    composite (None when unrealizable); ``explanation`` — human-readable reason when
    unrealizable (empty otherwise); ``stats`` — sizes and per-phase seconds;
    ``diagnostics`` — errors for problems that could not be posed as a game.
    """

    realizable: bool
    controller: LTS | None
    composition: LTS | None
    explanation: str
    stats: SynthesisStats = field(default_factory=lambda: SynthesisStats(Solver.SYMBOLIC))
    diagnostics: tuple[Diagnostic, ...] = ()


def _compose(components: list[LTS], name: str) -> LTS:
    return compose(components, name)


def _minimise(lts: LTS) -> LTS:
    return strong_minimise(lts, lts.name)


def synthesize(
    problem: SynthesisProblem,
    *,
    solver: Solver | str = Solver.SYMBOLIC,
    progress: Callable[[str], None] | None = None,
    explain: bool = True,
    minimise: bool = True,
    max_states: int | None = 2_000_000,
    order: VariableOrder | str = VariableOrder.CLUSTERED,
    macro: MacroSteps = MacroSteps.AUTO,
    realizability_only: bool = False,
) -> SynthesisResult:
    """Solve ``problem`` (§3) and build its controller; never raises for bad specs.

    ``solver`` — ``"symbolic"`` (BDD, default) or ``"explicit"`` (MTSA's rank solver);
    both give the same verdict and the same controller.  ``order`` selects the symbolic
    variable order (:class:`VariableOrder`, see :mod:`symbolic_game`).  Both are converted
    to their enums here; the stages below take the enums only.  ``macro``: the symbolic
    solver's macro steps (:mod:`macro`; ``MacroSteps.OFF`` solves the full game).
    ``realizability_only``: stop at the verdict — a realizable result then has no
    controller (``iterc synth --realizability-only``; an unrealizable one is explained as
    usual).  Stats
    keys: ``game_states``, ``plant_states`` (explicit) / ``bdd_nodes`` (symbolic),
    ``controller_states``, ``t_<phase>`` seconds; ``macro*`` with the macro steps.
    """
    if solver not in SOLVERS:
        raise ValueError(f"unknown solver {solver!r}; expected one of {SOLVERS}")
    stats: dict[str, Any] = {"solver": Solver(solver)}
    result = _synthesize(problem, Solver(solver), progress, explain, minimise, max_states,
                         VariableOrder(order), stats, MacroSteps(macro), realizability_only)
    return SynthesisResult(result.realizable, result.controller, result.composition,
                           result.explanation, SynthesisStats.from_dict(stats),
                           result.diagnostics)


@dataclass(frozen=True)
class _Outcome:
    realizable: bool
    controller: LTS | None
    composition: LTS | None
    explanation: str
    diagnostics: tuple[Diagnostic, ...] = ()


def _synthesize(problem: SynthesisProblem, solver: Solver,
                progress: Callable[[str], None] | None, explain: bool, minimise: bool,
                max_states: int | None, order: VariableOrder, stats: dict[str, Any],
                macro: MacroSteps = MacroSteps.AUTO, verdict_only: bool = False) -> _Outcome:
    say = progress or (lambda _msg: None)
    t0 = time.perf_counter()
    try:
        spec = prepare(problem)
    except SynthesisError as e:
        return _Outcome(False, None, None, e.message, (error(e.code, e.message, problem.span),))
    except PreconditionFailure as e:
        # MTSA prints the message and leaves no composition: the verdict is "no controller"
        stats["precondition"] = str(e)
        return _Outcome(False, None, None,
                        f"unrealizable: heuristic synthesis refused the problem: {e}")
    stats["mode"] = spec.mode
    kind = stats["strategy"] = strategy_kind(problem, spec)
    stats["warnings"] = list(spec.warnings)
    stats["t_prepare"] = time.perf_counter() - t0
    name = problem.name
    try:
        # §3.6 `permissive`: both solvers end in strategy.extract_controller
        if solver is Solver.EXPLICIT:
            result = _solve_explicit(spec, stats, say, max_states, explain, name,
                                     permissive=problem.permissive, kind=kind,
                                     verdict_only=verdict_only)
        else:
            from iterplan_compiler.synthesis.game import solve_symbolic

            result = solve_symbolic(spec, stats, say, explain=explain, name=name,
                                    order=order, permissive=problem.permissive,
                                    started=t0, kind=kind, macro=macro,
                                    verdict_only=verdict_only)
    except _explicit.StateExplosion as e:
        msg = f"the game has too many states for the explicit solver ({e})"
        return _Outcome(False, None, None, msg, (error("E0908", msg, problem.span),))
    realizable, controller, explanation = result
    if not realizable:
        return _Outcome(False, None, None, explanation)
    if controller is None:  # verdict_only
        return _Outcome(True, None, None, "")
    t1 = time.perf_counter()
    if minimise:
        controller = _minimise(controller)
    controller = renamed(controller, f"{name}:controller" if name else "controller")
    stats["controller_states"] = controller.num_states
    stats["controller_transitions"] = controller.num_transitions
    if problem.keywords & {"heuristic", "monolithicDirector"}:
        # §3.7: the DCS/director composite is the controller alone (the tests then build
        # `||Sys = (DirectedController || Plant)` themselves)
        others: list[LTS] = []
    else:
        # §3.6: the controller replaces the environment among the composite's machines
        others = list(problem.plant[problem.env_machines:]) + list(problem.safety)
    composition = _compose([controller, *others], name) if others else renamed(controller, name)
    stats["composition_states"] = composition.num_states
    stats["t_extract"] = stats.get("t_extract", 0.0) + time.perf_counter() - t1
    return _Outcome(True, controller, composition, "")


def _solve_explicit(spec: GameSpec, stats: dict[str, Any], say: Callable[[str], None],
                    max_states: int | None, explain: bool, name: str, *,
                    permissive: bool = False, kind: StrategyKind = StrategyKind.PERMISSIVE,
                    verdict_only: bool = False) -> tuple[bool, LTS | None, str]:
    t = time.perf_counter()
    game = _explicit.build_game(spec, max_states=max_states)
    stats["game_states"] = game.num_states
    stats["game_transitions"] = sum(len(e) for e in game.edges)
    stats["t_build"] = time.perf_counter() - t
    say(f"explicit game: {game.num_states} states")
    t = time.perf_counter()
    alphabet = spec.plant_alphabet | _fluent_only_actions(spec)
    if spec.mode is GameMode.NONBLOCKING:
        marked = game.guarantees[0]
        region = nonblocking_region(game, marked)
        stats["t_solve"] = time.perf_counter() - t
        stats["winning_states"] = len(region)
        if game.initial not in region:
            return False, None, _explain(spec, game, region, explain)
        if verdict_only:
            return True, None, ""
        t = time.perf_counter()
        ctrl = extract_director(game, region, marked, name, alphabet)
        stats["t_extract"] = time.perf_counter() - t
        return True, ctrl, ""
    ranks = _explicit.solve_ranks(game)
    stats["t_solve"] = time.perf_counter() - t
    win = frozenset(s for s in range(game.num_states) if ranks.winning(s))
    stats["winning_states"] = len(win)
    if not ranks.winning(game.initial):
        return False, None, _explain(spec, game, win, explain)
    if verdict_only:
        return True, None, ""
    t = time.perf_counter()
    ctrl = extract_controller(game, ranks, name, alphabet, permissive=permissive, kind=kind)
    stats["t_extract"] = time.perf_counter() - t
    return True, ctrl, ""


def strategy_kind(problem: SynthesisProblem, spec: GameSpec) -> StrategyKind:
    """The strategy a realizable ``problem`` yields (docs/semantics.md, "Synthesis").

    ``heuristic`` (MTSA's DCS, §3.9) returns a *director*: without ``nonblocking`` the GR(1)
    director of :mod:`symbolic_strategy` (one controllable move per state, the least rank
    towards the pursued guarantee), with it the non-blocking director of
    :func:`strategy.extract_director`, as ``monolithicDirector`` with ``nonblocking``.
    ``controller`` composites, ``monolithicDirector`` without ``nonblocking`` (unchanged:
    MTSA answers it with the plant, §3.10) and any composite with the ``permissive`` flag
    (whose point is the extra moves) get MTSA's controller of §3.6."""
    if spec.mode is GameMode.NONBLOCKING or ("heuristic" in problem.keywords
                                      and not problem.permissive):
        return StrategyKind.DIRECTOR
    return StrategyKind.PERMISSIVE


def _fluent_only_actions(spec: GameSpec) -> frozenset[str]:
    """Actions only fluents mention (free moves of MTSA's game; kept in the alphabet)."""
    return spec.alphabet - spec.plant_alphabet


def _explain(spec: GameSpec, game: _explicit.ExplicitGame, win: frozenset[int],
             explain: bool) -> str:
    from iterplan_compiler.synthesis.explain import explain_losing, losing_count, losing_head

    if not explain:
        return losing_head(*losing_count(game, win))

    try:
        return explain_losing(spec, game, win)
    except Exception as exc:  # noqa: BLE001 - an explanation bug must not hide the verdict
        return f"unrealizable: the initial state is not winning (no trace: {exc})"


def check_compatibility(problem: SynthesisProblem, *, solver: Solver | str = Solver.SYMBOLIC
                        ) -> tuple[bool, str]:
    """MTSA's ``checkCompatibility`` (§3.11): are the assumptions compatible with the plant?

    The actions that initiate failure fluents become controllable, the guarantees are replaced
    by FALSE, and the GR(1) game is solved: the assumptions are compatible iff **no** reachable
    state is winning, i.e. the controller can never force a violation of the assumptions.
    Returns ``(compatible, message)`` with MTSA's wording.
    """
    from dataclasses import replace

    from iterplan_compiler.ir.formulas import Const, FluentProp

    fl = {f.name: f for f in problem.fluents}
    faults: set[str] = set()
    for f in problem.failures:
        if isinstance(f, FluentProp) and f.name in fl:
            faults |= fl[f.name].initiating
    p = replace(problem, keywords=problem.keywords - {"heuristic"},
                controllable=problem.controllable | faults, guarantees=(Const(False),),
                failures=())
    spec = prepare(p, mode=GameMode.GR1)
    if Solver(solver) is Solver.EXPLICIT:
        game = _explicit.build_game(spec)
        winning = bool(_explicit.winning_region(game))
    else:
        from iterplan_compiler.synthesis.fixpoint import gr1_winning
        from iterplan_compiler.synthesis.game import SymbolicGame

        g = SymbolicGame(spec)
        reach = g.reachable()
        fp = gr1_winning(g.bdd, g.cpre, g.assumptions, g.guarantees, care=reach)
        winning = (fp.winning & reach) != g.bdd.false
    if winning:
        return False, "The assumptions are NOT compatible with the given environment."
    return True, "The assumptions are compatible with the given environment.[FSE2010]"


def plant_product(problem: SynthesisProblem) -> LTS:
    """MTSA's ``plant ||P = E~{G}``: the fluent-embedded product of §3.2 step 6."""
    spec = prepare(problem, mode=GameMode.GR1)
    return _explicit.compose_explicit(spec.components, problem.name)
