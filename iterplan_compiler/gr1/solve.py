"""Realizability and strategy synthesis for slugsin GR(1) games (``iterc solve``).

A thin adapter over the project's one GR(1) engine, :func:`iterplan_compiler.synthesis.
fixpoint.solve_gr1`: the slugs :class:`~iterplan_compiler.gr1.game.Game` is the
predecessor object (Mealy ``CPre``; ``CPreT`` for transition goals), liveness lines that
mention primed variables select ``GoalKind.TRANSITION``, and slugs' initial condition is
the engine's monotone ``lost`` test (early unrealizability: ``Z`` only shrinks, so once
``∀x. θe → ∃y. θs ∧ Z`` fails it fails for good).

* :func:`winning_set` — game → :class:`Winning` (the engine's result);
* :func:`solve` — game → winning set → initial check → (optional) strategy, with phase
  times, BDD node counts and peak memory in ``SolveResult.stats``.

:class:`SolverOptions` maps the CLI switches onto :class:`~iterplan_compiler.synthesis.
fixpoint.EngineOptions`; the defaults are :data:`~iterplan_compiler.synthesis.fixpoint.
SLUGS_OPTIONS` (feedback on, recycling off, round-wise ``μY``, small CPre memo — the
measured best on the slugs families, docs/gr1.md).
"""

from __future__ import annotations

import resource
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from iterplan_compiler.diagnostics import Diagnostic
from iterplan_compiler.gr1.game import Game, GameOptions, build_game
from iterplan_compiler.gr1.slugsin import SlugsSpec
from iterplan_compiler.gr1.strategy import StrategyOptions, build_strategy
from iterplan_compiler.symbolic.bdd import new_manager
from iterplan_compiler.synthesis.fixpoint import (
    SLUGS_OPTIONS,
    EngineOptions,
    GoalKind,
    Gr1Fixpoint,
    solve_gr1,
)

Node = Any

#: the result of :func:`winning_set` (``winning``, ``complete``, ``y_layers``, ``x_sets``)
Winning = Gr1Fixpoint


@dataclass(frozen=True)
class SolverOptions:
    """Fixpoint switches (see :mod:`iterplan_compiler.synthesis.fixpoint`)."""

    feedback: bool = SLUGS_OPTIONS.feedback
    early_unrealizable: bool = True
    recycle: bool = SLUGS_OPTIONS.recycle
    chained: bool = SLUGS_OPTIONS.chained

    def engine(self) -> EngineOptions:
        return replace(SLUGS_OPTIONS, feedback=self.feedback, recycle=self.recycle,
                       chained=self.chained)


def winning_set(game: Game, *, keep_iterates: bool = False,
                options: SolverOptions | None = None,
                progress: Callable[[str], None] | None = None) -> Winning:
    """GR(1) winning region of ``game`` (slugs semantics, see the module docstring);
    ``progress`` gets the fixpoint's Z iterations."""
    options = options or SolverOptions()
    kind = GoalKind.TRANSITION if game.live_primed else GoalKind.STATE

    def lost(Z: Node) -> bool:
        return not game.initial_ok(Z)

    return solve_gr1(game.bdd, game, game.env_live, game.sys_live, goals=kind,
                     keep_iterates=keep_iterates,
                     lost=lost if options.early_unrealizable else None,
                     options=options.engine(), progress=progress)


@dataclass
class SolveResult:
    """Outcome of :func:`solve`: verdict, the game, winning set, strategy and statistics."""

    realizable: bool
    game: Game
    winning: Node
    strategy: Any = None  # iterplan_compiler.gr1.strategy.Strategy
    stats: dict[str, Any] = field(default_factory=dict)


def peak_rss_mb() -> float:
    """Peak resident set size of this process in MB (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def solve(spec: SlugsSpec, *, strategy: bool = True, game_options: GameOptions | None = None,
          solver_options: SolverOptions | None = None, bdd: Any = None,
          strategy_options: StrategyOptions | None = None,
          progress: Callable[[str], None] | None = None
          ) -> tuple[SolveResult | None, list[Diagnostic]]:
    """Build the game of ``spec``, decide realizability and (optionally) extract a strategy.

    ``stats`` keys: ``build_s``, ``winning_s``, ``strategy_s``, ``total_s`` (wall) and the
    same with ``_cpu_s`` (process CPU time, robust when the machine is shared),
    ``winning_nodes``, ``strategy_nodes``, ``peak_live_nodes``, ``reordering_s``,
    ``peak_rss_mb``, ``iterations``, ``trigger_raises`` (reorderings whose next trigger the
    restart back-off raised) and the game's build statistics.

    ``progress`` (e.g. ``iterc solve -v``) hears of the phases, the fixpoint's Z iterations,
    the verdict as soon as it is known and each goal's strategy relation.
    """
    game_options = game_options or GameOptions()
    t0 = time.perf_counter()
    c0 = time.process_time()
    if bdd is None:
        bdd = new_manager(reordering=game_options.reordering)  # symbolic/bdd.py
    say = progress or (lambda _msg: None)
    say(f"building the game ({len(spec.inputs)} inputs, {len(spec.outputs)} outputs)")
    game, diags = build_game(spec, bdd, game_options)
    if game is None:
        return None, diags
    t1 = time.perf_counter()
    c1 = time.process_time()
    say(f"game built: ρe {game.stats.get('env_trans_nodes')} nodes, "
        f"ρs {game.stats.get('sys_trans_nodes')} nodes; winning set ...")
    win = winning_set(game, keep_iterates=strategy, options=solver_options, progress=progress)
    realizable = win.complete and game.initial_ok(win.winning)
    say(f"verdict: {'realizable' if realizable else 'unrealizable'}")
    t2 = time.perf_counter()
    c2 = time.process_time()
    strat = None
    stats: dict[str, Any] = dict(game.stats)
    if realizable and strategy:
        strat = build_strategy(game, win, strategy_options, progress=progress)
        stats["strategy_nodes"] = strat.node_count()
    t3 = time.perf_counter()
    c3 = time.process_time()
    stats.update(
        build_cpu_s=c1 - c0,
        winning_cpu_s=c2 - c1,
        strategy_cpu_s=c3 - c2 if strat is not None else 0.0,
        total_cpu_s=c3 - c0,
        build_s=t1 - t0,
        winning_s=t2 - t1,
        strategy_s=t3 - t2 if strat is not None else 0.0,
        total_s=t3 - t0,
        winning_nodes=len(win.winning),
        iterations=win.iterations,
        early_stop=not win.complete,
        peak_rss_mb=peak_rss_mb(),
    )
    stats.update(_manager_stats(bdd))
    stats["trigger_raises"] = game.backoff.raised if game.backoff is not None else 0
    return SolveResult(realizable, game, win.winning, strat, stats), diags


def _manager_stats(bdd: Any) -> dict[str, Any]:
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            s = bdd.statistics()
    except Exception:  # autoref has a different statistics() shape
        return {}
    return {
        "peak_live_nodes": s.get("peak_live_nodes"),
        "reordering_s": s.get("reordering_time"),
        "reorderings": s.get("n_reorderings"),
    }
