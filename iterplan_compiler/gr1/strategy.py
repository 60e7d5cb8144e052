"""Mealy strategies for slugsin GR(1) games (Bloem et al., JCSS 2012, §5; slugs' variant).

For every goal ``j`` the strategy is a transition relation ``S_j(x, y, x', y')`` built from
the state-level iterates of the final ``Z`` pass, in priority order:

1. ``ρs ∧ G_j ∧ Z'`` — reach the goal (then the goal counter advances to ``j+1``);
2. for ring ``r = 1, 2, ...`` and assumption ``i``: ``ρs ∧ (Y_{r-1}' ∨ (¬A_i ∧ X_{r,i}'))`` —
   get one ring closer to the goal, or stay in ``X_{r,i}`` while assumption ``i`` is violated.

For each ``(x, y, x')`` only the transitions of the first applicable entry are kept
(``S_j |= T_k ∧ ¬covered``, ``covered |= ∃y'. T_k``).  Why this is winning: a state in
``X_{r,i}`` has, for every legal ``x'``, a successor of priority ``≤ (r, i)``; hence along a
play the pair ``(r, i)`` never increases while the goal is pending, so either the ring
strictly decreases until the goal is hit, or the play eventually stays in one ``X_{r,i}``
violating ``A_i`` forever.

The symbolic strategy is also reported as one BDD ``⋁_j (goal = j) ∧ S_j`` with a binary
goal counter (``strategy_nodes``), comparable to slugs' ``--symbolicStrategy`` and omega's
transducer.  :meth:`Strategy.step` executes it (used by the simulation tests).

Extraction controls (:class:`StrategyOptions`, measured in docs/gr1.md):

* **reordering** (:class:`StrategyReordering`): ``DYNAMIC`` (default) leaves CUDD's
  automatic sifting on while the relations are built; ``GUARDED`` switches it off and
  sifts explicitly only when the manager has grown ``guard_growth``-fold since the last
  sift (faster on GenBuf, 4× slower on the lift: the order left by the fixpoint does not
  suit ``ρs ∧ …``); ``OFF`` never sifts.  A manager built with reordering off
  (``--no-reorder``) is never sifted here.  Goal ``j``'s iterates are released as soon as
  ``S_j`` exists, so every sift sees fewer live nodes.
* **final_sift**: one explicit sifting pass once the strategy relations exist.  The goal
  counter bits are declared *on top* of the order (:meth:`Strategy.node_count`), so
  ``⋁_j (goal = j) ∧ S_j`` is one decision on the counter above the shared ``S_j`` (at the
  bottom, after restrict, genbuf n=17 measured 7 M nodes instead of 3 k).
* **restrict**: each ``S_j`` is also simplified by CUDD's ``restrict`` (Coudert–Madre) to
  the care set ``Win ∧ ρe`` — the only ``(x, y, x')`` at which :meth:`Strategy.step` is
  asked (a winning state and a legal input); outside it the relation is unspecified,
  inside it unchanged (:meth:`Strategy.violations` checks this).  Restricted relations are
  smaller one by one but may share less, so of the plain family ``S_j ∧ Win``, the
  restricted one and their per-goal minimum the one with the fewest shared nodes is kept.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from enum import Enum
from typing import Any

from iterplan_compiler.gr1.game import Game, prime_name
from iterplan_compiler.symbolic import bdd as _bdd
from iterplan_compiler.synthesis.fixpoint import Gr1Fixpoint as Winning

Node = Any


class StrategyReordering(Enum):
    """CUDD reordering while the strategy relations are built (``--strategy-reordering``)."""

    GUARDED = "guarded"
    DYNAMIC = "dynamic"
    OFF = "off"


@dataclass(frozen=True)
class StrategyOptions:
    """How :func:`build_strategy` runs (module docstring)."""

    reordering: StrategyReordering = StrategyReordering.DYNAMIC
    final_sift: bool = True
    restrict: bool = True
    guard_growth: float = 2.0


@dataclass
class Strategy:
    """A goal-counter Mealy strategy: ``per_goal[j]`` is ``S_j`` over ``x, y, x', y'``."""

    game: Game
    winning: Node
    per_goal: list[Node]

    @property
    def goals(self) -> int:
        return len(self.per_goal)

    def node_count(self) -> int:
        """Nodes of ``⋁_j (goal = j) ∧ S_j`` (goal counter bits declared on demand, on top
        of the order when the backend can insert a variable at a level)."""
        bdd = self.game.bdd
        width = max(1, (self.goals - 1).bit_length())
        names = [f"_goal@{k}" for k in range(width)]
        for k, n in enumerate(names):
            if n not in bdd.vars:
                if hasattr(bdd, "insert_var"):
                    bdd.insert_var(n, k)
                else:
                    bdd.declare(n)
        with _reordering(bdd, False):  # sifting here would move the counter bits
            total = bdd.false
            for j, s in enumerate(self.per_goal):
                enc = bdd.true
                for k, n in enumerate(names):
                    enc &= bdd.var(n) if (j >> k) & 1 else ~bdd.var(n)
                total |= enc & s
            return len(total)

    def initial(self, inputs: dict[str, bool]) -> dict[str, bool] | None:
        """Initial outputs for initial ``inputs`` (``None`` if ``θe`` rejects them)."""
        bdd, g = self.game.bdd, self.game
        u = bdd.let(dict(inputs), g.sys_init & self.winning)
        if u == bdd.false:
            return None
        return _complete(bdd.pick(u, care_vars=set(g.outputs)) or {}, g.outputs)

    def step(self, state: dict[str, bool], goal: int, next_inputs: dict[str, bool]
             ) -> tuple[dict[str, bool], int] | None:
        """Outputs ``y'`` and the next goal for ``next_inputs`` in ``state`` (x and y values).

        Returns ``None`` when no move exists (only possible for illegal environment moves).
        """
        g = self.game
        bdd = g.bdd
        values = dict(state)
        values.update({prime_name(k): v for k, v in next_inputs.items()})
        u = bdd.let(values, self.per_goal[goal])
        if u == bdd.false:
            return None
        pick = bdd.pick(u, care_vars=set(g.yp)) or {}
        nxt = _complete({k[:-1]: v for k, v in pick.items()}, g.outputs)
        full = dict(values)
        full.update({prime_name(k): v for k, v in nxt.items()})
        reached = bdd.let(full, g.sys_live[goal]) == bdd.true
        return nxt, (goal + 1) % self.goals if reached else goal


    def violations(self) -> list[str]:
        """Problems of the strategy on the care set ``Win ∧ ρe`` (empty = winning-safe).

        For every goal ``j``: each move of ``S_j`` from a winning state under a legal input
        must satisfy ``ρs`` and stay in ``Win``, and every winning state must have a move
        for every legal input.  (That the moves reach the goals is the ranking argument of
        the module docstring; tests check it exhaustively on small games.)  Monolithic
        relations: meant for tests and small games.
        """
        g = self.game
        bdd = g.bdd
        care = self.winning & g.env_trans
        safe = g.sys_trans & g.prime(self.winning)
        problems: list[str] = []
        for j, s in enumerate(self.per_goal):
            moves = care & s
            bad = moves & ~safe
            if bad != bdd.false:
                problems.append(f"goal {j}: a move violates ρs or leaves the winning region: "
                                f"{bdd.pick(bad)}")
            stuck = care & ~bdd.exist(set(g.yp), moves)
            if stuck != bdd.false:
                problems.append(f"goal {j}: no move in a winning state: {bdd.pick(stuck)}")
        return problems


def _complete(assignment: dict[str, bool], names: tuple[str, ...]) -> dict[str, bool]:
    """Fill don't-care variables with False (deterministic)."""
    return {n: bool(assignment.get(n, False)) for n in names}


def _dynamic_reordering(bdd: Any) -> bool:
    try:
        return bool(bdd.configure()["reordering"])
    except (KeyError, TypeError):  # a backend without the setting
        return False


@contextmanager
def _reordering(bdd: Any, on: bool) -> Iterator[None]:
    """Dynamic reordering ``on``/off inside the block, the previous setting restored after."""
    before = _dynamic_reordering(bdd)
    if before != on:
        bdd.configure(reordering=on)
    try:
        yield
    finally:
        if before != on:
            bdd.configure(reordering=before)


class _Guard:
    """``GUARDED`` reordering: sift explicitly once the manager grew ``growth``-fold."""

    def __init__(self, bdd: Any, enabled: bool, growth: float) -> None:
        self.bdd, self.enabled, self.growth = bdd, enabled, growth
        self.base = max(len(bdd), 1)

    def check(self) -> None:
        if self.enabled and len(self.bdd) > self.growth * self.base:
            self.bdd.reorder()
            self.base = max(len(self.bdd), 1)


def _goal_relation(game: Game, win: Winning, j: int, zp: Node, guard: _Guard) -> Node:
    """``S_j`` (module docstring): the first applicable entry per ``(x, y, x')``."""
    bdd = game.bdd
    rho_s = game.sys_trans
    yp = set(game.yp)
    # Each entry carries ρs, so the ∃y' images stay restricted to legal moves.  (A variant
    # that factors ρs out and uses the partitioned image measured 2× slower on AMBA.)
    s = rho_s & game.sys_live[j] & zp
    covered = bdd.exist(yp, s)
    prev_ring = bdd.false
    for ring, xs in zip(win.y_layers[j], win.x_sets[j], strict=True):
        ring_p = game.prime(prev_ring)
        for i, x in enumerate(xs):
            t = rho_s & (ring_p | (~game.env_live[i] & game.prime(x)))
            s |= t & ~covered
            covered |= bdd.exist(yp, t)
            guard.check()
        prev_ring = ring
    return s


def _smallest(game: Game, plain: list[Node], restricted: list[Node]) -> list[Node]:
    """The family with the fewest shared nodes among ``plain``, ``restricted`` and their
    per-goal minimum (restrict shrinks each ``S_j``, but the results may share less)."""
    if not restricted:
        return plain
    mixed = [r if len(r) < len(u) else u for u, r in zip(plain, restricted, strict=True)]
    return min((plain, restricted, mixed), key=game.node_count)


def build_strategy(game: Game, win: Winning, options: StrategyOptions | None = None,
                   progress: Callable[[str], None] | None = None) -> Strategy:
    """Construct the per-goal strategy relations from the iterates in ``win`` (``progress``
    hears of each goal's).

    The iterates are *consumed*: ``win.y_layers[j]`` and ``win.x_sets[j]`` are emptied once
    goal ``j``'s relation exists (fewer live nodes for sifting; nothing reads them later).
    """
    options = options or StrategyOptions()
    bdd = game.bdd
    can_sift = _dynamic_reordering(bdd)
    mode = options.reordering if can_sift else StrategyReordering.OFF
    zp = game.prime(win.winning)
    # the monolithic relations are built (once) under the manager's own reordering setting
    care = win.winning & game.env_trans if options.restrict else None
    _ = game.sys_trans
    plain: list[Node] = []
    restricted: list[Node] = []
    with _reordering(bdd, mode is StrategyReordering.DYNAMIC and can_sift):
        guard = _Guard(bdd, mode is StrategyReordering.GUARDED, options.guard_growth)
        for j in range(len(game.sys_live)):
            s = _goal_relation(game, win, j, zp, guard)
            plain.append(s & win.winning)
            if care is not None:
                restricted.append(_bdd.cofactor(bdd, s, care))
            # goal j's iterates are consumed: releasing them keeps sifting cheap
            win.y_layers[j], win.x_sets[j] = [], []
            if progress:
                progress(f"strategy: goal {j + 1}/{len(game.sys_live)}, {len(bdd)} live nodes")
        per_goal = _smallest(game, plain, restricted)
        del plain, restricted, care
        if options.final_sift and can_sift:
            if progress:
                progress("strategy: final sifting")
            bdd.reorder()
    return Strategy(game, win.winning, per_goal)
