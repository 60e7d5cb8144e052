"""The GR(1) fixpoint engine: one three-nested fixpoint for every game of the project.

Equation (Piterman–Pnueli–Sa'ar VMCAI'06; Bloem et al. JCSS'12), for assumptions
``A_1..A_m`` and guarantees ``G_1..G_n``, in one of two goal kinds (:class:`GoalKind`)::

    STATE       W = νZ. ∧_j μY. ∨_i νX. (G_j ∧ CPre(Z)) ∨ CPre(Y) ∨ (¬A_i ∧ CPre(X))
    TRANSITION  W = νZ. ∧_j μY. ∨_i νX. CPreT((G_j ∧ Z') ∨ Y' ∨ (¬A_i ∧ X'))

``CPre`` — the controllable predecessor of a *state* set — is the only game-specific part
and comes from a typed predecessor object (:class:`Predecessor`): the MTSA game of
``synthesis/symbolic_game.py`` (``iterc synth``) and slugs' Mealy game of ``gr1/game.py``
(``iterc solve``) both provide ``cpre``; transition goals (slugs' liveness lines that
mention primed variables) need a :class:`TransitionPredecessor` (``prime`` + ``CPreT`` of a
transition-level target).

API::

    solve_gr1(bdd, pre, assumptions, guarantees, *, goals=GoalKind.STATE, care=None,
              keep_iterates=False, lost=None, options=EngineOptions(), progress=None)
        -> Gr1Fixpoint
    gr1_winning(bdd, cpre, assumptions, guarantees, *, care=None, keep_iterates=False,
                must_contain=None, progress=None, memo=True)        # callable-cpre form

* an empty ``assumptions``/``guarantees`` sequence means one set ``TRUE``;
* ``care`` — the universe (valid encodings ∧ reachable states): ``Z`` starts there;
* ``lost(Z)`` — early termination, must be *monotone* (true for ``Z`` ⇒ true for every
  subset): ``Z`` only shrinks, so once it holds the answer is final and the engine stops
  with ``complete = False`` (slugs: the initial condition fails; MTSA: the initial state
  left ``Z``);
* ``keep_iterates`` — also return, for the final ``Z``, the cumulative ``μY`` layers
  ``y_layers[j][r]`` and the ``νX`` sets ``x_sets[j][r][i]`` that strategy extraction needs
  (Bloem et al. 2012, §5).

Optimisations (each sound by monotonicity of the operators; switches in
:class:`EngineOptions` so they can be measured):

* *restriction to Z* — every iterate is intersected with the current ``Z``: the winning
  region is a fixpoint of the restricted operator, which is below the unrestricted one, so
  the greatest fixpoint is unchanged while the BDDs carry no junk outside ``Z``.
* *feedback with early fixpoint detection* (Firman–Maoz–Ringert 2020) — ``Z`` is replaced
  by ``Y_j`` right after goal ``j`` (``Y_j ⊆ Z``: same greatest fixpoint, faster
  convergence); goals are visited cyclically and the engine stops as soon as ``n``
  consecutive goals left ``Z`` unchanged (each then saw the final ``Z``, so their stored
  iterates are the strategy data).  ``feedback=False``: classic passes
  ``Z := ∧_j Y_j(Z)``.
* *warm start / fixpoint recycling* (slugs' ``--fixedPointRecycling``) — ``Z`` decreases
  from one visit of goal ``j`` to the next, so the ``r``-th ``μY`` iterate and every ``νX``
  value decrease too: the ``νX`` for ``(j, r, i)`` may start from its previous value
  (∧ ``Z``) instead of from ``Z``.  Fewer ``X`` steps, but every ``X`` set stays alive: on
  the slugs families it raised peak live nodes 15× (arbiter n=40) and lost, on the MTSA
  games it wins — hence a switch.
* *chained* ``μY`` (Gauss–Seidel; only without ``keep_iterates``) — inside one ``μY`` round
  the ``νX`` for assumption ``i`` already uses the ``Y`` grown by ``X_1 … X_{i-1}``.  Every
  chained iterate stays below the least fixpoint and a round without change is a fixpoint,
  so ``μY`` is the same set, in fewer rounds (DoorPatrol N=7: 831 instead of 3 612 ``νX``
  steps).  The layers strategy extraction needs exist only for the round-wise (Jacobi)
  order, so ``keep_iterates=True`` uses that order.
* *trivial assumptions* — for ``A_i = TRUE`` the ``νX`` body does not depend on ``X``:
  one evaluation, no ``CPre(X)`` (halves the ``CPre`` calls on the lift).
* *frontier νX* (only with a :class:`FrontierPredecessor`) — ``νX`` descends: ``X_{k+1} =
  X_k ∩ step(X_k)``.  A state of ``X_k`` outside ``base`` is in ``¬A_i ∩ CPre(X_{k-1})``, and
  by the definition of CPre its membership can change only if one of its successors was just
  removed (``D = X_{k-1} ∖ X_k``): an environment state leaves iff some uncontrollable
  successor is in ``D``, a controller state iff it had a controllable successor in ``D`` and
  has none left in ``X_k``.  So ``X_{k+1} = X_k ∖ cpre_lost(X_k, D, X_k ∖ base)`` — the
  same set, from preimages of the (small) ``D`` instead of a CPre of the (large) ``X_k``.
  Used once ``D`` has under ``1/frontier_ratio`` of ``X_k``'s nodes.  GyroLTL_637, first
  νX (``|X|`` ≈ 90 k nodes): with ``|X|/|D|`` = 1.0–2.4 a frontier step cost 1.8–3.7× a
  full one, at 3.6 0.8×, from 14 up 0.3× to 0.05× (the long tail of small ``D``), hence 4;
  the νX went from 26 full CPre (~35 s) to 7 full CPre and a frontier tail (~10 s).
  ``cpre_lost`` may remove more than ``X_k ∖ CPre(X_k)``, as long as it removes nothing of a
  fixpoint below ``X_k`` (Gauss–Seidel: ``SymbolicGame.cpre_lost_chained``); each iterate
  then still lies above the greatest fixpoint and below the plain one, and a step that
  removes nothing is a fixpoint.
* *frontier μY* (same predecessor) — the dual: in the chained ``μY``, ``Y`` only grows,
  and ``CPre`` is monotone, so ``CPre(Y ∪ ΔY) = CPre(Y) ∪ cpre_gained(Y, ΔY)``, where a
  state can enter only if one of its successors is in ``ΔY`` (a controller state: a
  controllable one; an environment state: an uncontrollable one, and then none may be
  outside ``Y ∪ ΔY``).  The νX base ``goal ∨ CPre(Y)`` is updated from the growth after
  every νX that grew ``Y`` (:meth:`fixpoint_ops.StateOp.grown_base`, same ratio rule)
  instead of a CPre of the whole ``Y``.  Same iterates (``tests/synthesis/test_frontier.py``).
  Measured on GyroLTL_637 (every update timed both ways in one run): the 14 updates the
  ratio admits cost 2.7 s CPU against 5.5 s for the full CPre (0.02–0.4 s against
  0.2–0.7 s each; once, at ``|Y|/|ΔY|`` = 5, 1.2 s against 1.1 s); with ``Y = ∅`` the full
  CPre is far cheaper (0.2–0.4 s against 0.3–1.7 s), which the ratio rule keeps.
* *memoised CPre* — ``CPre(Z)`` is the first ``νX`` step for every ``(r, i)`` and
  ``CPre(∅)`` the first ``Y`` base; canonical BDD nodes make a cache keyed by node exact.
  ``memo`` bounds it (least recently used out): an unbounded cache keeps every argument
  alive, which makes CUDD's sifting dearer on the slugs families.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from iterplan_compiler import limits
from iterplan_compiler.synthesis.fixpoint_ops import (
    CallableFrontierPre,
    CallablePre,
    FrontierPredecessor,
    GoalKind,
    Memo,
    Op,
    Predecessor,
    StateOp,
    TransitionOp,
    TransitionPredecessor,
)

__all__ = ["SLUGS_OPTIONS", "EngineOptions", "FrontierPredecessor", "GoalKind",
           "Gr1Fixpoint", "Predecessor", "TransitionPredecessor", "gr1_winning", "solve_gr1"]

Node = Any  # a dd BDD node (dd.cudd.Function or dd.autoref.Function)


@dataclass(frozen=True)
class EngineOptions:
    """Switches of the optimisations in the module docstring (all keep the result exact).

    ``memo``: CPre cache size (``None`` unbounded, ``0`` off); ``frontier_ratio``: frontier
    νX steps once ``|D| · ratio < |X|`` in nodes (``0`` off; needs a
    :class:`FrontierPredecessor`)."""

    feedback: bool = True
    recycle: bool = True
    chained: bool = True
    memo: int | None = None
    frontier_ratio: int = 4


#: the slugs head-to-head defaults (measured on ``benchmarks/gr1/run.py``, see docs/gr1.md)
SLUGS_OPTIONS = EngineOptions(feedback=True, recycle=False, chained=False, memo=8)


@dataclass
class Gr1Fixpoint:
    """Result of the engine.

    ``winning`` — ``Z`` (exact when ``complete``; when ``lost`` fired, a superset of the
    winning region on which ``lost`` holds); ``y_layers[j]`` — cumulative ``μY`` iterates
    of goal ``j``; ``x_sets[j][r][i]`` — the ``νX`` values (both empty unless
    ``keep_iterates``); ``iterations`` — counts of ``z`` passes, ``goals`` visits, ``y``
    and ``x`` steps.
    """

    winning: Node
    y_layers: list[list[Node]] = field(default_factory=list)
    x_sets: list[list[list[Node]]] = field(default_factory=list)
    complete: bool = True
    iterations: dict[str, int] = field(default_factory=dict)


@dataclass
class _Goal:
    """Per-goal state kept across visits: recycled ``νX`` values and the last iterates."""

    g: Node
    recycled: list[list[Node]] = field(default_factory=list)
    layers: list[Node] = field(default_factory=list)
    x_layers: list[list[Node]] = field(default_factory=list)


def solve_gr1(
    bdd: Any,
    pre: Predecessor,
    assumptions: Sequence[Node],
    guarantees: Sequence[Node],
    *,
    goals: GoalKind = GoalKind.STATE,
    care: Node | None = None,
    keep_iterates: bool = False,
    lost: Callable[[Node], bool] | None = None,
    options: EngineOptions = EngineOptions(),
    progress: Callable[[str], None] | None = None,
) -> Gr1Fixpoint:
    """Winning region of ``(∧_i GF A_i) → (∧_j GF G_j)`` for ``pre``; see the module doc."""
    top = bdd.true if care is None else care
    op = _operator(bdd, pre, goals, options)
    not_a = [~a for a in (list(assumptions) or [bdd.true])]
    states = [_Goal(g if goals is GoalKind.TRANSITION else g & top)
              for g in (list(guarantees) or [bdd.true])]
    stats = {"z": 0, "goals": 0, "y": 0, "x": 0}
    run = _feedback_passes if options.feedback else _classic_passes
    Z, complete = run(bdd, op, not_a, states, top, keep_iterates, lost, options, stats, progress)
    if not (keep_iterates and complete):
        return Gr1Fixpoint(Z, [], [], complete, stats)
    return Gr1Fixpoint(Z, [s.layers for s in states], [s.x_layers for s in states], True,
                       stats)


def _operator(bdd: Any, pre: Predecessor, goals: GoalKind, options: EngineOptions) -> Op:
    if goals is GoalKind.TRANSITION:
        if not isinstance(pre, TransitionPredecessor):
            raise TypeError("transition goals need a TransitionPredecessor (prime, cpre_trans)")
        return TransitionOp(bdd, pre)
    frontier = pre if (isinstance(pre, FrontierPredecessor)
                       and options.frontier_ratio > 0) else None
    return StateOp(bdd, Memo(pre.cpre, options.memo), frontier, options.frontier_ratio)


def _feedback_passes(bdd: Any, op: Op, not_a: list[Node], states: list[_Goal], Z: Node,
                     keep: bool, lost: Callable[[Node], bool] | None, options: EngineOptions,
                     stats: dict[str, int], progress: Callable[[str], None] | None
                     ) -> tuple[Node, bool]:
    """Goals cyclically, ``Z := Y_j`` after each; stop after ``n`` unchanged visits."""
    n = len(states)
    unchanged = 0
    j = 0
    while unchanged < n:
        limits.check_deadline()  # --time-limit inside the fixpoint
        Y = _visit(bdd, op, not_a, states[j], Z, keep, options, stats)
        if Y == Z:
            unchanged += 1
        else:
            unchanged = 0
            Z = Y
            if lost is not None and lost(Z):
                stats["z"] += 1
                if progress:
                    progress(f"gr1: early stop after {stats['goals']} goal visits")
                return Z, False
        j = (j + 1) % n
        if j == 0:
            stats["z"] += 1
            if progress:
                progress(f"gr1: Z-iteration {stats['z']}: |Z| nodes = {len(Z)}")
    if j != 0:
        stats["z"] += 1
    return Z, True


def _classic_passes(bdd: Any, op: Op, not_a: list[Node], states: list[_Goal], Z: Node,
                    keep: bool, lost: Callable[[Node], bool] | None, options: EngineOptions,
                    stats: dict[str, int], progress: Callable[[str], None] | None
                    ) -> tuple[Node, bool]:
    """``Z := ∧_j Y_j(Z)`` with every ``Y_j`` computed from the same ``Z``, until stable."""
    while True:
        limits.check_deadline()
        stats["z"] += 1
        z_new = bdd.true
        for s in states:
            z_new &= _visit(bdd, op, not_a, s, Z, keep, options, stats)
        if progress:
            progress(f"gr1: Z-iteration {stats['z']}: |Z| nodes = {len(z_new)}")
        if z_new == Z:
            return Z, True
        Z = z_new
        if lost is not None and lost(Z):
            return Z, False


def _visit(bdd: Any, op: Op, not_a: list[Node], s: _Goal, Z: Node, keep: bool,
           options: EngineOptions, stats: dict[str, int]) -> Node:
    """One ``μY`` for goal ``s`` against ``Z``; updates its recycled values / iterates."""
    stats["goals"] += 1
    if options.chained and not keep:
        x_rounds, Y = _mu_y_chained(bdd, op, not_a, s, Z, options.recycle, stats)
        layers: list[Node] = []
    else:
        layers, x_rounds, Y = _mu_y(bdd, op, not_a, s, Z, options.recycle, stats)
    if options.recycle:
        s.recycled = x_rounds
    if keep:
        s.layers, s.x_layers = layers, x_rounds
    return Y


def _start(op: Op, s: _Goal, r: int, i: int, Z: Node, base: Node, recycle: bool) -> Node:
    """Where ``νX`` for ``(r, i)`` starts: ``Z``, or its recycled value from the last visit
    (∧ ``Z``, ∨ the part of ``base`` in ``Z``, which the fixpoint contains anyway)."""
    if recycle and r < len(s.recycled) and i < len(s.recycled[r]):
        return (s.recycled[r][i] & Z) | op.floor(base, Z)
    return Z


def _mu_y(bdd: Any, op: Op, not_a: list[Node], s: _Goal, Z: Node, recycle: bool,
          stats: dict[str, int]) -> tuple[list[Node], list[list[Node]], Node]:
    """Round-wise (Jacobi) ``μY``: ``(layers, x_layers, Y)``."""
    goal = op.goal(s.g, Z)
    Y = bdd.false
    layers: list[Node] = []
    x_layers: list[list[Node]] = []
    while True:
        limits.check_deadline()
        stats["y"] += 1
        base = op.base(goal, Y, Z)
        xs = [nu_x(bdd, op, base, not_a[i],
                    _start(op, s, len(layers), i, Z, base, recycle), stats)
              for i in range(len(not_a))]
        y_new = bdd.false
        for X in xs:
            y_new |= X
        y_new &= Z
        if y_new == Y:
            return layers, x_layers, Y
        Y = y_new
        layers.append(Y)
        x_layers.append(xs)
        if Y == Z:  # cannot grow further
            return layers, x_layers, Y


def _mu_y_chained(bdd: Any, op: Op, not_a: list[Node], s: _Goal, Z: Node, recycle: bool,
                  stats: dict[str, int]) -> tuple[list[list[Node]], Node]:
    """Gauss–Seidel ``μY`` (module doc): ``Y`` grows after every ``νX``; ``(x_rounds, Y)``."""
    goal = op.goal(s.g, Z)
    Y = bdd.false
    base = op.base(goal, Y, Z)
    x_rounds: list[list[Node]] = []
    quiet = 0  # consecutive νX steps that did not grow Y
    while True:
        limits.check_deadline()
        stats["y"] += 1
        xs: list[Node] = []
        x_rounds.append(xs)
        for i in range(len(not_a)):
            X = nu_x(bdd, op, base, not_a[i],
                      _start(op, s, len(x_rounds) - 1, i, Z, base, recycle), stats)
            xs.append(X)
            y_new = (Y | X) & Z
            if y_new == Y:
                quiet += 1
            else:  # Y only grows: the base from its CPre on the growth (frontier μY)
                quiet = 0
                base = op.grown_base(goal, base, Y, y_new & ~Y, Z)
            Y = y_new
            # Y == Z cannot grow; after len(not_a) quiet steps every νX was evaluated against
            # the current Y and stayed inside it: Y is the fixpoint.
            if Y == Z or quiet == len(not_a):
                return x_rounds, Y


def nu_x(bdd: Any, op: Op, base: Node, not_a: Node, start: Node,
         stats: dict[str, int] | None = None, *, first: Node | None = None) -> Node:
    """``νX. step(X)`` from ``start`` (an over-approximation), descending inside ``start``.

    ``X_{k+1} = step(X_k) ∧ start ⊆ X_k`` by monotonicity, so the first repetition (or
    ``∅``) is the fixpoint; for ``¬A_i = ∅`` the step ignores ``X``: one evaluation.
    ``stats["x"]`` counts the steps.  ``first``: ``step(start) ∧ start`` when the caller
    knows it without a CPre.  Also the νX of MTSA's rank layers
    (``symbolic_strategy.rank_layers``).
    """
    stats = {"x": 0} if stats is None else stats
    stats["x"] += 1
    X = op.x_step(base, not_a, start) & start if first is None else first
    if not_a == bdd.false:
        return X
    prev = start
    while X != bdd.false:
        limits.check_deadline()
        stats["x"] += 1
        x_new = op.x_next(base, not_a, X, prev, start)
        if x_new == X:
            break
        prev, X = X, x_new
    return X


def gr1_winning(
    bdd: Any,
    cpre: Callable[[Node], Node],
    assumptions: Sequence[Node],
    guarantees: Sequence[Node],
    *,
    care: Node | None = None,
    keep_iterates: bool = False,
    must_contain: Node | None = None,
    progress: Callable[[str], None] | None = None,
    memo: bool = True,
    cpre_lost: Callable[[Node, Node, Node], Node] | None = None,
    cpre_gained: Callable[[Node, Node, Node], Node] | None = None,
    frontier_ratio: int = EngineOptions.frontier_ratio,
) -> Gr1Fixpoint:
    """:func:`solve_gr1` with a ``cpre`` function, state goals and the MTSA defaults
    (recycling, chained ``μY``, unbounded memo); ``must_contain`` — stop once
    ``Z ∧ must_contain = ∅``.  ``memo=False`` if ``cpre`` is not a pure function;
    ``cpre_lost`` (see :class:`FrontierPredecessor`) enables the frontier νX, and with it
    ``cpre_gained`` the frontier μY."""
    lost = None
    if must_contain is not None:
        mc = must_contain

        def lost(Z: Node) -> bool:
            return bool((Z & mc) == bdd.false)

    pre = (CallablePre(cpre) if cpre_lost is None
           else CallableFrontierPre(cpre, cpre_lost, cpre_gained))
    return solve_gr1(bdd, pre, assumptions, guarantees, care=care,
                     keep_iterates=keep_iterates, lost=lost, progress=progress,
                     options=EngineOptions(memo=None if memo else 0,
                                           frontier_ratio=frontier_ratio))
