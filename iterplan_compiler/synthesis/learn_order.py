"""A variable order learned from a sample of the game's own states.

The BDD variable order is static (:mod:`symbolic_game`): it follows the order in which the
spec composes its machines, which FSP gives no meaning, and the solver's time depends on it
several-fold (docs/synthesis.md, "Declaration order").  Sifting the solver's own manager is
no remedy: it moves every live node — the partitioned relations, ~700 k nodes on
GyroLTLVar2_701, 25 s for one shuffle, and dynamic reordering there gave no verdict in 100 s.

A *sample* sifts cheaply.  The turn game's reachable turn starts, once they pass
:data:`turns.LEARN_NODES`, are copied alone into a scratch manager and sifted there (two
passes of CUDD's sifting; 701: 6.9 k → 3.1 k nodes in 0.2 s); the order they end in is
returned, and the caller builds the game again in it (:func:`game.solve_symbolic`) and solves
it from the start — the first pass's work is only the turns before the sample.  Measured on
the SYNTECH15 files as translated: GyroLTLVar2_701's verdict 23 → 16 s, GyroLTL_595's whole
director 71 → 33 s; files whose turn starts stay under the threshold are not touched.  It
is a heuristic: the order that suits the reachable set need not suit the relational products
(a shuffled 701 stays past 60 s, docs/synthesis.md).

Only with ``dd.cudd`` (the copy between managers and CUDD's sifting); None otherwise.
"""

from __future__ import annotations

from collections.abc import Collection
from typing import Any

from iterplan_compiler.symbolic.bdd import backend_of, new_manager

Node = Any
#: passes of CUDD's sifting over the sample (the second still shrank 701's: 13.3 k → 12.2 k)
SIFT_PASSES = 2


def sifted_order(bdd: Any, sample: Node, names: Collection[str]) -> tuple[str, ...] | None:
    """The variables ``names`` (current-state variables of ``bdd``; each with a primed copy)
    in the order sifting gives ``sample`` alone, or None without ``dd.cudd``."""
    if backend_of(bdd) != "cudd":
        return None
    scratch = new_manager(backend="cudd")  # dynamic reordering off: sifted explicitly
    scratch.declare(*sorted(bdd.vars, key=bdd.level_of_var))
    copy = bdd.copy(sample, scratch)
    for _ in range(SIFT_PASSES):
        scratch.reorder()
    wanted = set(names)
    order = tuple(sorted((v for v in scratch.vars if v in wanted), key=scratch.level_of_var))
    del copy
    return order
