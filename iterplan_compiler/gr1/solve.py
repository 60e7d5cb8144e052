"""Realizability and strategy synthesis for slugsin GR(1) games.

Entry points:

* :func:`winning_set` — the three-nested fixpoint (Piterman–Pnueli–Sa'ar) for a
  :class:`~iterplan_compiler.gr1.game.Game`;
* :func:`solve` — parse-free driver: game → winning set → initial check → (optional)
  strategy, with phase times, BDD node counts and peak memory in ``SolveResult.stats``.

Two fixpoint forms, both for the Mealy ``cpre`` of slugs:

* *state-based* (all liveness lines are state predicates, the common case)::

      X := (G_j ∧ cpre(Z)) ∨ cpre(Y) ∨ (¬A_i ∧ cpre(X))

  where ``G_j ∧ cpre(Z)`` is computed once per goal and ``cpre(Y)`` once per ``Y`` step,
  so each ``X`` step costs one ``cpre`` of a *state* set;
* *transition-based* (some liveness line mentions primed variables; slugs' own form)::

      X := cpre((G_j ∧ Z') ∨ Y' ∨ (¬A_i ∧ X'))

Heuristics (Firman–Maoz–Ringert, Acta Inf. 2020), each switchable in
:class:`SolverOptions` so their effect can be measured:

* ``feedback`` — within a ``Z`` pass, ``Z`` is replaced by ``Y_j`` right after goal ``j``
  (``Y_j ⊆ Z``; same greatest fixpoint, faster convergence); the pass stops as soon as
  ``len(goals)`` consecutive goals left ``Z`` unchanged (early fixpoint detection);
* ``early_unrealizable`` — after each goal check ``∀x. θe → ∃y. θs ∧ Z``; ``Z`` only
  shrinks, so a failure is final;
* ``recycle`` — the ``νX`` for ``(j, r, i)`` starts from its value in the previous visit of
  goal ``j`` (∧ ``Z``) instead of from ``Z`` (sound: everything decreases with ``Z``);
* iterates are kept only when a strategy is requested, and only as *state* sets
  (transition-level strategy relations are recomputed from them afterwards).

``engine="shared"`` runs the generic fixpoint of :mod:`iterplan_compiler.synthesis.fixpoint`
instead (state-based specs only); tests check both engines agree.
"""

from __future__ import annotations

import resource
import time
from dataclasses import dataclass, field
from typing import Any

from iterplan_compiler.diagnostics import Diagnostic
from iterplan_compiler.gr1.game import Game, GameOptions, build_game
from iterplan_compiler.gr1.slugsin import SlugsSpec

Node = Any


@dataclass(frozen=True)
class SolverOptions:
    """Fixpoint heuristics; see the module docstring."""

    feedback: bool = True
    early_unrealizable: bool = True
    recycle: bool = False
    engine: str = "native"  # "native" or "shared"


@dataclass
class Winning:
    """Result of :func:`winning_set`.

    ``winning`` is ``Z`` (exact when ``complete``; when the early-unrealizability check
    fired it is a superset whose initial check already fails).  ``y_layers[j][r]`` are the
    cumulative ``μY`` iterates and ``x_sets[j][r][i]`` the ``νX`` values of the final ``Z``
    (empty unless ``keep_iterates``).
    """

    winning: Node
    complete: bool
    y_layers: list[list[Node]] = field(default_factory=list)
    x_sets: list[list[list[Node]]] = field(default_factory=list)
    iterations: dict[str, int] = field(default_factory=dict)


def winning_set(game: Game, *, keep_iterates: bool = False,
                options: SolverOptions | None = None) -> Winning:
    """GR(1) winning region of ``game`` (see the module docstring for the variants)."""
    options = options or SolverOptions()
    if options.engine == "shared" and not game.live_primed:
        return _shared_engine(game, keep_iterates)
    bdd = game.bdd
    A = game.env_live
    G = game.sys_live
    m = len(G)
    transition = game.live_primed
    stats = {"z": 0, "y": 0, "x": 0, "goals": 0}
    prev_x: list[list[list[Node]]] = [[] for _ in G]
    y_store: list[list[Node]] = [[] for _ in G]
    x_store: list[list[list[Node]]] = [[] for _ in G]
    not_a = [~a for a in A]
    memo: dict[Any, Node] = {}

    def cpre(u: Node) -> Node:
        # The first X iterate of every (Y, i) is cpre(Z), already computed for G_j ∧ cpre(Z):
        # a small memo (cleared when Z changes) avoids recomputing it.
        r = memo.get(u)
        if r is None:
            if len(memo) > 8:
                memo.clear()
            r = memo[u] = game.cpre(u)
        return r

    Z = bdd.true
    unchanged = 0
    j = 0
    cpre_false = None
    pass_start = Z
    while True:
        g = G[j]
        stats["goals"] += 1
        if transition:
            gz = g & game.prime(Z)
        else:
            gz = g & cpre(Z)
        Y = bdd.false
        layers: list[Node] = []
        x_layers: list[list[Node]] = []
        r = 0
        while True:
            stats["y"] += 1
            if transition:
                yp = game.prime(Y)
                base_t = gz | yp
                base = None
            else:
                # cpre(false) is not empty: states where the environment has no legal move
                if r == 0:
                    if cpre_false is None:
                        cpre_false = game.cpre(bdd.false)
                    base = gz | cpre_false
                else:
                    base = gz | cpre(Y)
            y_new = bdd.false
            xs: list[Node] = []
            for i in range(len(A)):
                start = Z
                if options.recycle and r < len(prev_x[j]):
                    start = prev_x[j][r][i] & Z
                X = start
                trivial = not transition and not_a[i] == bdd.false
                if trivial:
                    # assumption TRUE: νX. base ∨ (FALSE ∧ …) is just base (no cpre needed)
                    stats["x"] += 1
                    X = base & start
                while not trivial and X != bdd.false:
                    stats["x"] += 1
                    if transition:
                        x_new = game.cpre_trans(base_t | (not_a[i] & game.prime(X)))
                    else:
                        x_new = base | (not_a[i] & cpre(X))
                    x_new &= start
                    if x_new == X:
                        break
                    X = x_new
                xs.append(X)
                y_new |= X
            y_new &= Z
            if y_new == Y:
                break
            Y = y_new
            layers.append(Y)
            x_layers.append(xs)
            r += 1
            if Y == Z:
                break
        if options.recycle:
            prev_x[j] = x_layers
        if keep_iterates:
            y_store[j] = layers
            x_store[j] = x_layers
        if options.feedback:
            if Y == Z:
                unchanged += 1
            else:
                unchanged = 0
                Z = Y
            if options.early_unrealizable and unchanged == 0 and not game.initial_ok(Z):
                stats["z"] += 1
                return Winning(Z, False, [], [], stats)
            j = (j + 1) % m
            if j == 0:
                stats["z"] += 1
            if unchanged >= m:
                break
        else:
            # classic: Z_new = ∧_j Y_j with every Y_j computed from the same Z
            if j == 0:
                z_acc = Y
            else:
                z_acc &= Y
            j = (j + 1) % m
            if j == 0:
                stats["z"] += 1
                if z_acc == pass_start:
                    break
                Z = z_acc
                pass_start = Z
                if options.early_unrealizable and not game.initial_ok(Z):
                    return Winning(Z, False, [], [], stats)
    return Winning(Z, True, y_store if keep_iterates else [], x_store if keep_iterates else [],
                   stats)


def _shared_engine(game: Game, keep_iterates: bool) -> Winning:
    from iterplan_compiler.synthesis.fixpoint import gr1_winning

    res = gr1_winning(game.bdd, game.cpre, game.env_live, game.sys_live,
                      keep_iterates=keep_iterates)
    return Winning(res.winning, res.complete, res.y_layers, res.x_sets, dict(res.iterations))


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


def new_manager(reordering: bool = True) -> Any:
    """A fresh ``dd`` manager (CUDD when available) via the shared factory."""
    from iterplan_compiler.symbolic.bdd import new_manager as factory

    return factory(reordering=reordering)


def solve(spec: SlugsSpec, *, strategy: bool = True, game_options: GameOptions | None = None,
          solver_options: SolverOptions | None = None, bdd: Any = None
          ) -> tuple[SolveResult | None, list[Diagnostic]]:
    """Build the game of ``spec``, decide realizability and (optionally) extract a strategy.

    ``stats`` keys: ``build_s``, ``winning_s``, ``strategy_s``, ``total_s`` (wall) and the
    same with ``_cpu_s`` (process CPU time, robust when the machine is shared),
    ``winning_nodes``, ``strategy_nodes``, ``peak_live_nodes``, ``reordering_s``,
    ``peak_rss_mb``, ``iterations`` and the game's build statistics.
    """
    game_options = game_options or GameOptions()
    t0 = time.perf_counter()
    c0 = time.process_time()
    if bdd is None:
        bdd = new_manager(reordering=game_options.reordering)
    game, diags = build_game(spec, bdd, game_options)
    if game is None:
        return None, diags
    t1 = time.perf_counter()
    c1 = time.process_time()
    win = winning_set(game, keep_iterates=strategy, options=solver_options)
    realizable = win.complete and game.initial_ok(win.winning)
    t2 = time.perf_counter()
    c2 = time.process_time()
    strat = None
    stats: dict[str, Any] = dict(game.stats)
    if realizable and strategy:
        from iterplan_compiler.gr1.strategy import build_strategy

        strat = build_strategy(game, win)
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
