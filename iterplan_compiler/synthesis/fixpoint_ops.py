"""The operators of the GR(1) engine (:mod:`fixpoint`): what one step of ``νX``/``μY``
computes, for each goal kind, and the CPre cache.  :mod:`fixpoint` holds the equation and
the iteration; every optimisation used here is justified in its module docstring.

* :class:`Predecessor` (and its transition/frontier refinements) — the game as the engine
  sees it;
* :class:`StateOp` / :class:`TransitionOp` — ``goal``, ``base``, ``x_step``, ``floor`` and
  ``x_next`` of the two equations (state goals: ``νX. goal ∨ CPre(Y) ∨ (¬A_i ∧ CPre(X))``;
  transition goals: ``νX. CPreT((G ∧ Z') ∨ Y' ∨ (¬A_i ∧ X'))``);
* :class:`Memo` — ``CPre`` cached by BDD node (canonical nodes make it exact);
* :class:`CallablePre` / :class:`CallableFrontierPre` — plain functions as predecessors.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from enum import Enum
from typing import Any, Protocol, runtime_checkable

Node = Any  # a dd BDD node (dd.cudd.Function or dd.autoref.Function)


class GoalKind(Enum):
    """Whether assumptions/guarantees are state predicates or may mention next-state
    variables (slugs' primed liveness lines)."""

    STATE = "state"
    TRANSITION = "transition"


@runtime_checkable
class Predecessor(Protocol):
    """A game, seen by the engine: the controllable predecessor of a state set."""

    def cpre(self, states: Node) -> Node:
        """States from which the controller can force the next state into ``states``."""
        ...


@runtime_checkable
class TransitionPredecessor(Predecessor, Protocol):
    """A game that also supports transition-level targets (needed by ``GoalKind.TRANSITION``)."""

    def prime(self, states: Node) -> Node:
        """The next-state copy of a state set."""
        ...

    def cpre_trans(self, target: Node) -> Node:
        """States from which the controller can force the next *transition* into ``target``."""
        ...


@runtime_checkable
class FrontierPredecessor(Predecessor, Protocol):
    """A game that can update CPre after its argument shrank (:mod:`fixpoint` doc: frontier νX)."""

    def cpre_lost(self, states: Node, removed: Node, within: Node) -> Node:
        """The states of ``within`` (a subset of ``CPre(states ∪ removed)``) that are not in
        ``CPre(states)`` — or a superset of them inside ``within`` that is disjoint from
        every fixpoint of the νX below ``states`` (a Gauss–Seidel update such as
        ``SymbolicGame.cpre_lost_chained``: the νX then reaches the same value in fewer
        steps)."""
        ...

    def cpre_gained(self, states: Node, added: Node, within: Node) -> Node:
        """A subset of ``within ∩ CPre(states ∪ added)`` holding every state of ``within``
        that is not in ``CPre(states)``."""
        ...


class Memo:
    """``CPre`` with a cache keyed by BDD node (LRU-bounded unless ``size`` is None)."""

    def __init__(self, cpre: Callable[[Node], Node], size: int | None) -> None:
        self.raw = cpre
        self.size = size
        self.cache: OrderedDict[Node, Node] = OrderedDict()

    def __call__(self, u: Node) -> Node:
        if self.size == 0:
            return self.raw(u)
        r = self.cache.get(u)
        if r is not None:
            self.cache.move_to_end(u)
            return r
        r = self.cache[u] = self.raw(u)
        if self.size is not None and len(self.cache) > self.size:
            self.cache.popitem(last=False)
        return r


class StateOp:
    """The STATE-kind operator: ``νX. goal ∨ CPre(Y) ∨ (¬A_i ∧ CPre(X))``, inside ``Z``."""

    def __init__(self, bdd: Any, cpre: Callable[[Node], Node],
                 frontier: FrontierPredecessor | None = None, ratio: int = 0) -> None:
        self.bdd, self.cpre, self.frontier, self.ratio = bdd, cpre, frontier, ratio

    def goal(self, g: Node, Z: Node) -> Node:
        return g & self.cpre(Z)

    def base(self, goal: Node, Y: Node, Z: Node) -> Node:
        # not restricted to Z: every νX step is intersected with its start ⊆ Z anyway
        return goal | self.cpre(Y)

    def grown_base(self, goal: Node, base: Node, Y: Node, added: Node, Z: Node) -> Node:
        """``base(goal, Y ∪ added, Z)`` inside ``Z``, from ``base = base(goal, Y, Z)``:
        ``CPre`` is monotone, so ``CPre(Y ∪ added) = CPre(Y) ∪ gained`` (frontier μY)."""
        if self.frontier is not None and len(added) * self.ratio < len(Y):
            return base | self.frontier.cpre_gained(Y, added, Z)
        return self.base(goal, Y | added, Z)

    def x_step(self, base: Node, not_a: Node, X: Node) -> Node:
        if not_a == self.bdd.false:
            return base
        return base | (not_a & self.cpre(X))

    def floor(self, base: Node, Z: Node) -> Node:
        """A state set inside ``Z`` that every ``νX`` value contains."""
        return base & Z

    def x_next(self, base: Node, not_a: Node, X: Node, prev: Node, start: Node) -> Node:
        """``step(X) ∧ start`` for ``X = step(prev) ∧ start ⊆ prev`` (frontier νX)."""
        if self.frontier is not None:
            removed = prev & ~X
            if len(removed) * self.ratio < len(X):
                return X & ~self.frontier.cpre_lost(X, removed, X & ~base)
        return self.x_step(base, not_a, X) & start


class TransitionOp:
    """The TRANSITION-kind operator: ``νX. CPreT((G ∧ Z') ∨ Y' ∨ (¬A_i ∧ X'))``."""

    def __init__(self, bdd: Any, pre: TransitionPredecessor) -> None:
        self.bdd, self.pre = bdd, pre

    def goal(self, g: Node, Z: Node) -> Node:
        return g & self.pre.prime(Z)

    def base(self, goal: Node, Y: Node, Z: Node) -> Node:
        return goal | self.pre.prime(Y)

    def x_step(self, base: Node, not_a: Node, X: Node) -> Node:
        if not_a == self.bdd.false:
            return self.pre.cpre_trans(base)
        return self.pre.cpre_trans(base | (not_a & self.pre.prime(X)))

    def floor(self, base: Node, Z: Node) -> Node:
        """A state set inside ``Z`` that every ``νX`` value contains (``base`` is
        transition-level here, so: none)."""
        return self.bdd.false

    def grown_base(self, goal: Node, base: Node, Y: Node, added: Node, Z: Node) -> Node:
        return self.base(goal, Y | added, Z)

    def x_next(self, base: Node, not_a: Node, X: Node, prev: Node, start: Node) -> Node:
        return self.x_step(base, not_a, X) & start


Op = StateOp | TransitionOp


class CallablePre:
    """A plain ``cpre`` function as a :class:`Predecessor`."""

    def __init__(self, cpre: Callable[[Node], Node]) -> None:
        self._cpre = cpre

    def cpre(self, states: Node) -> Node:
        return self._cpre(states)


class CallableFrontierPre(CallablePre):
    """``cpre``, ``cpre_lost`` and (optional) ``cpre_gained`` functions as a
    :class:`FrontierPredecessor`; without ``cpre_gained``, ``CPre(states ∪ added)``."""

    def __init__(self, cpre: Callable[[Node], Node],
                 lost: Callable[[Node, Node, Node], Node],
                 gained: Callable[[Node, Node, Node], Node] | None = None) -> None:
        super().__init__(cpre)
        self._lost = lost
        self._gained = gained

    def cpre_lost(self, states: Node, removed: Node, within: Node) -> Node:
        return self._lost(states, removed, within)

    def cpre_gained(self, states: Node, added: Node, within: Node) -> Node:
        if self._gained is None:
            return within & self._cpre(states | added)
        return self._gained(states, added, within)
