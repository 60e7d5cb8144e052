"""Python-speed state queries on a fixed handful of BDDs, and cached product moves: the inner
loop of the controller enumeration (:mod:`symbolic_strategy`).

Membership.  The enumeration asks, for every controller state and every successor, whether a
component-state tuple lies in one of a few fixed sets (the winning region, the goal, failure
and assumption sets, the rank layers).  Asked through ``dd`` (build the state's cube, then
``cube <= u``) each question costs a cube of ~50 literals and a CUDD call: ~26 µs, 56 % of
the enumeration of the explicit Fire Patrol N = 12.  :class:`CompiledSets` instead copies the
sets' BDD nodes once into flat Python lists (shared nodes once) and answers a question by
walking one root-to-terminal path, reading each bit straight from the tuple:
``(s[k] >> i) & 1`` — at most one list lookup per *current-state* bit, no BDD node made.
A node reference is ``2·index + complemented`` (CUDD's complement edges: ``dd.cudd``'s
``low``/``high`` are those of the regular node, each edge with its own ``negated`` flag, so
the walk XORs the flags it crosses); index 0 is the constant TRUE.  Measured on Fire Patrol
N = 11 (21.5 k controller states): queries 6.9 → 1.1 s (profiled).

Moves.  :class:`CachedMoves` is :class:`explicit.ProductMoves` with the synchronisation of
an action memoised per (action, local states of its owners): the product's states repeat
the same few local states of each component, so the per-state work becomes a dictionary
hit and one tuple build per move instead of a cartesian product over the owners
(Fire Patrol N = 11: 8 ``_sync`` calls per state, almost all rejected by a later owner).
An action with more than :data:`MEMO_MAX_OWNERS` owners is synchronised directly instead:
its key rarely repeats (SYNTECH15's ``tick`` has 28–49 owners; GyroLTL_637's director made
514 k memo misses for 167 k states), so the memo only cost the key, the entry and a second
pass over the owners — 637's whole synthesis 55–60 → 51 s, peak RSS 1.16 → 0.85 GB.
"""

from __future__ import annotations

from collections.abc import Sequence
from operator import itemgetter
from typing import Any

from iterplan_compiler.ir.lts import ERROR, LTS, TAU
from iterplan_compiler.symbolic.bdd import BitVec, disjoin
from iterplan_compiler.synthesis.explicit import ProductMoves, with_locals

Node = Any
State = tuple[int, ...]
#: actions with more owners are synchronised without the memo (:meth:`CachedMoves._direct`)
MEMO_MAX_OWNERS = 4
Move = tuple[str, State | None]


class CompiledSets:
    """BDDs over the current-state bits of ``vecs`` copied into flat node tables.

    ``vecs[k]`` names component ``k``'s current bits (LSB first); :meth:`add` compiles a set
    and returns its root reference; :meth:`member` tests a tuple against a root."""

    def __init__(self, bdd: Any, vecs: Sequence[BitVec]) -> None:
        self.bdd = bdd
        self.where = {name: (k, i) for k, vec in enumerate(vecs) for i, name in enumerate(vec.names)}
        # index 0: the constant TRUE (never walked through)
        self.comp: list[int] = [0]
        self.shift: list[int] = [0]
        self.lo: list[int] = [0]
        self.hi: list[int] = [0]
        # node id -> table index.  A node id is the node's address (``dd.cudd``) or its
        # slot (``dd.autoref``), which the library reuses for another node once the first
        # is freed: every compiled BDD is therefore held for the lifetime of the tables, so
        # no id in ``_ids`` can come to name a different node (a freed and reused id used to
        # hand a later set the table of an earlier one: wrong ranks in the controller).
        self._ids: dict[int, int] = {}
        self._alive: list[Node] = []

    def add(self, u: Node) -> int:
        """Compile ``u`` (a BDD over the current bits only); its root reference.  ``u`` is
        kept alive as long as these tables (see ``_ids``)."""
        self._alive.append(u)
        return self._ref(u)

    def _ref(self, f: Node) -> int:
        neg = 1 if f.negated else 0
        reg = ~f if neg else f
        if reg.var is None:
            return neg  # TRUE (0) or FALSE (1)
        key = int(reg)
        idx = self._ids.get(key)
        if idx is None:
            k, i = self.where[reg.var]  # KeyError: a next-state bit in a state set
            lo_ref = self._ref(reg.low)
            hi_ref = self._ref(reg.high)
            idx = self._ids[key] = len(self.comp)
            self.comp.append(k)
            self.shift.append(i)
            self.lo.append(lo_ref)
            self.hi.append(hi_ref)
        return 2 * idx + neg

    def add_bits(self, names: Sequence[str]) -> None:
        """Variables that are not state bits (component ``-1``, bit ``i``: see
        :class:`RankTable`)."""
        for i, name in enumerate(names):
            self.where[name] = (-1, i)

    def member(self, root: int, s: State) -> bool:
        """``s ∈ set(root)``: one path walk (module docstring)."""
        comp, shift, lo, hi = self.comp, self.shift, self.lo, self.hi
        r = root
        while r > 1:
            i = r >> 1
            r = (hi[i] if (s[comp[i]] >> shift[i]) & 1 else lo[i]) ^ (r & 1)
        return r == 0


class RankTable:
    """MTSA's rank function of one guarantee, ``rank(s)`` = the first ``k`` with
    ``s ∈ S[k]`` for the nested layers ``S[0] ⊆ … ⊆ S[L-1]`` (``inf`` outside ``S[L-1]``), in
    one path walk.

    The function is built in CUDD as its graph ``Rk(s, r) = ∨_k (S[k] \\ S[k-1])(s) ∧ r = k``
    with the bits of ``r`` declared last (at the bottom of the order), then compiled into
    ``sets``: walking ``s``'s bits reaches FALSE (``s`` outside every layer) or a node over
    the ``r`` bits alone with exactly one satisfying assignment, read off by following the
    non-FALSE branches.  Why: a binary search over the layers costs ``log2 L`` walks per
    state (6–7 on Fire Patrol, ~85 % of the enumeration's membership walks) where this costs
    one; an if-then-else over the compiled layers written in Python (the first version) built
    the same diagram with 648 k Python calls on Fire Patrol N = 13 (6.7 s profiled), the
    ``L`` CUDD operations here take ~0.1 s."""

    def __init__(self, sets: CompiledSets, layers: Sequence[Node], prefix: str,
                 inf: int) -> None:
        bdd = sets.bdd
        width = max(1, (len(layers) - 1).bit_length())
        names = [f"{prefix}_{i}" for i in range(width)]
        bdd.declare(*names)
        sets.add_bits(names)
        terms = []
        below = bdd.false
        for k, layer in enumerate(layers):
            value = bdd.cube({n: bool((k >> i) & 1) for i, n in enumerate(names)})
            terms.append((layer & ~below) & value)
            below = layer
        self.sets = sets
        self.inf = inf
        self.root = sets.add(disjoin(bdd, terms))

    def rank(self, s: State) -> int:
        sets = self.sets
        comp, shift, lo, hi = sets.comp, sets.shift, sets.lo, sets.hi
        r = self.root
        while r > 1:
            i = r >> 1
            k = comp[i]
            if k < 0:
                break
            r = (hi[i] if (s[k] >> shift[i]) & 1 else lo[i]) ^ (r & 1)
        if r == 1:
            return self.inf
        value = 0
        while r > 1:
            i = r >> 1
            up = hi[i] ^ (r & 1)
            if up != 1:
                value |= 1 << shift[i]
                r = up
            else:
                r = lo[i] ^ (r & 1)
        return value


class CachedMoves(ProductMoves):
    """The moves of a synchronous product (§2.5) from a component-state tuple, with the
    synchronisation of each action memoised per local states of its owners (module doc).
    Same moves, in the same order, as :meth:`explicit.ProductMoves.moves`."""

    def __init__(self, components: Sequence[LTS]) -> None:
        super().__init__(components)
        self._parts = {a: tuple(ks) for a, ks in self.owners.items()}
        # (component, local state) -> the non-tau actions it enables as their first owner,
        # each with its owners and a getter of their local states
        self._first: dict[tuple[int, int], list[tuple[str, tuple[int, ...], Any]]] = {}
        self._memo: dict[tuple[str, Any], list[tuple[int, ...] | None]] = {}

    def _firsts(self, k: int, s: int) -> list[tuple[str, tuple[int, ...], Any]]:
        r = self._first[(k, s)] = [
            (a, self._parts[a], itemgetter(*self._parts[a]))
            for a in self.idx[k].get(s, {}) if a != TAU and self._parts[a][0] == k]
        return r

    def _combos(self, a: str, parts: tuple[int, ...], key: tuple[str, Any]
                ) -> list[tuple[int, ...] | None]:
        local = key[1] if len(parts) > 1 else (key[1],)
        choices: list[list[int]] = []
        for k, v in zip(parts, local, strict=True):
            ts = self.idx[k].get(v, {}).get(a)
            if not ts:
                choices = []
                break
            choices.append(ts)
        r = self._memo[key] = _cartesian(choices) if choices else []
        return r

    def moves(self, cur: State) -> list[Move]:
        out: list[Move] = []
        first, sync = self._first, self._memo
        for k0 in range(self.n):
            fs = first.get((k0, cur[k0]))
            if fs is None:
                fs = self._firsts(k0, cur[k0])
            for a, parts, get in fs:
                if len(parts) > MEMO_MAX_OWNERS:
                    self._direct(cur, a, parts, out)
                    continue
                key = (a, get(cur))
                combos = sync.get(key)
                if combos is None:
                    combos = self._combos(a, parts, key)
                for combo in combos:
                    out.append((a, None if combo is None else with_locals(cur, parts, combo)))
        self._tau_moves(cur, out)
        return out


    def _direct(self, cur: State, a: str, parts: tuple[int, ...], out: list[Move]) -> None:
        """The moves of an action with many owners, without the memo: its key (the owners'
        local states) rarely repeats, so the successor is built in one pass where every
        owner has one target (else as :meth:`_combos`)."""
        idx = self.idx
        nxt = list(cur)
        for k in parts:
            ts = idx[k].get(cur[k], {}).get(a)
            if not ts:
                return
            if len(ts) != 1:
                for combo in self._combos(a, parts, (a, tuple(cur[k] for k in parts))):
                    out.append((a, None if combo is None else with_locals(cur, parts, combo)))
                return
            nxt[k] = ts[0]
        out.append((a, None if ERROR in nxt else tuple(nxt)))


def _cartesian(choices: list[list[int]]) -> list[tuple[int, ...] | None]:
    """Every combination of the owners' targets (None for one that holds ERROR), in
    ``itertools.product`` order."""
    from itertools import product

    return [None if ERROR in combo else combo for combo in product(*choices)]
