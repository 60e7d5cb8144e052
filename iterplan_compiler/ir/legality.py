"""Legality of a controller with respect to a plant (MTSA ``LegalityAnalyser``, §4.2).

A controller is *legal* for a plant when, in every reachable state of ``controller || plant``
(composed as usual, optionally with further ``context`` machines), every **uncontrollable**
action that the plant enables and that belongs to the controller's alphabet is also enabled by
the controller.  In words: the controller may refuse controllable actions, but it must never
block an uncontrollable one it synchronises on.  Actions outside the controller's alphabet
cannot be blocked by it and are ignored.

Membership in ``controllable`` is exact (the front-end passes expanded label sets).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from .compose import explore_product
from .lts import ERROR, LTS

__all__ = ["LegalityResult", "LegalityWitness", "is_legal"]


@dataclass(frozen=True, slots=True)
class LegalityWitness:
    """A shortest trace to a product state where ``action`` is blocked by the controller."""

    trace: tuple[str, ...]
    action: str
    controller_state: int
    plant_state: int

    def describe(self) -> str:
        path = ", ".join(self.trace) if self.trace else "<initial state>"
        return (f"after [{path}] the plant offers uncontrollable '{self.action}' "
                f"(plant state {self.plant_state}) but the controller (state "
                f"{self.controller_state}) refuses it")


@dataclass(frozen=True, slots=True)
class LegalityResult:
    legal: bool
    witness: LegalityWitness | None = None
    product_states: int = 0

    def __bool__(self) -> bool:
        return self.legal


def _enabled(m: LTS) -> list[set[str]]:
    en: list[set[str]] = [set() for _ in range(m.num_states)]
    for s, a, _ in m.transitions:
        en[s].add(a)
    return en


def is_legal(
    controller: LTS,
    plant: LTS,
    controllable: Iterable[str],
    *,
    context: Sequence[LTS] = (),
    max_states: int | None = None,
) -> LegalityResult:
    """Check legality (module doc); the witness, if any, is the first violation in BFS order.

    Raises :class:`~iterplan_compiler.ir.compose.StateExplosion` past ``max_states``.
    """
    ctrl_set = frozenset(controllable)
    tuples, transitions, _ = explore_product(
        [controller, plant, *context], max_states=max_states, name="legality"
    )
    c_en = _enabled(controller)
    p_en = _enabled(plant)
    watched = controller.alphabet - ctrl_set
    # BFS parent = first transition that discovered the state (transitions are in BFS order).
    parent: dict[int, tuple[int, str]] = {}
    for s, a, t in transitions:
        if t != ERROR and t != 0 and t not in parent:
            parent[t] = (s, a)
    for k, tup in enumerate(tuples):
        c, p = tup[0], tup[1]
        blocked = sorted(a for a in p_en[p] & watched if a not in c_en[c])
        if blocked:
            trace: list[str] = []
            cur = k
            while cur != 0:
                cur, a = parent[cur]
                trace.append(a)
            trace.reverse()
            return LegalityResult(False, LegalityWitness(tuple(trace), blocked[0], c, p),
                                  len(tuples))
    return LegalityResult(True, None, len(tuples))
