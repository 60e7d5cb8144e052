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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from iterplan_compiler.gr1.game import Game, prime_name
from iterplan_compiler.synthesis.fixpoint import Gr1Fixpoint as Winning

Node = Any


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
        """Nodes of ``⋁_j (goal = j) ∧ S_j`` (goal counter bits declared on demand)."""
        bdd = self.game.bdd
        width = max(1, (self.goals - 1).bit_length())
        names = [f"_goal@{k}" for k in range(width)]
        for n in names:
            if n not in bdd.vars:
                bdd.declare(n)
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


def _complete(assignment: dict[str, bool], names: tuple[str, ...]) -> dict[str, bool]:
    """Fill don't-care variables with False (deterministic)."""
    return {n: bool(assignment.get(n, False)) for n in names}


def build_strategy(game: Game, win: Winning) -> Strategy:
    """Construct the per-goal strategy relations from the iterates in ``win``."""
    bdd = game.bdd
    rho_s = game.sys_trans
    zp = game.prime(win.winning)
    not_a = [~a for a in game.env_live]
    yp = set(game.yp)
    per_goal: list[Node] = []
    for j, g in enumerate(game.sys_live):
        # Each entry carries ρs, so the ∃y' images stay restricted to legal moves.  (A variant
        # that factors ρs out and uses the partitioned image measured 2× slower on AMBA.)
        entries: list[Node] = [rho_s & g & zp]
        prev_ring = bdd.false
        for ring, xs in zip(win.y_layers[j], win.x_sets[j], strict=True):
            ring_p = game.prime(prev_ring)
            for i, x in enumerate(xs):
                entries.append(rho_s & (ring_p | (not_a[i] & game.prime(x))))
            prev_ring = ring
        s = bdd.false
        covered = bdd.false
        for t in entries:
            s |= t & ~covered
            covered |= bdd.exist(yp, t)
        per_goal.append(s & win.winning)
    return Strategy(game, win.winning, per_goal)
