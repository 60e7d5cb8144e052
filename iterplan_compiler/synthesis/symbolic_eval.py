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
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from iterplan_compiler.ir.lts import ERROR, LTS, TAU
from iterplan_compiler.symbolic.bdd import BitVec

Node = Any
State = tuple[int, ...]
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
        self.level: list[int] = [1 << 30]  # the terminal sits below every variable
        self._ids: dict[int, int] = {}
        self._level_of = {name: bdd.level_of_var(name) for name in self.where}
        self.bit_at = {lvl: self.where[name] for name, lvl in self._level_of.items()}

    def add(self, u: Node) -> int:
        """Compile ``u`` (a BDD over the current bits only); its root reference."""
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
            self.level.append(self._level_of[reg.var])
        return 2 * idx + neg

    def cofactors(self, ref: int, level: int) -> tuple[int, int]:
        """(low, high) cofactors of ``ref`` on the variable at ``level`` (at or above the
        top variable of ``ref``)."""
        i = ref >> 1
        if self.level[i] != level:
            return ref, ref
        neg = ref & 1
        return self.lo[i] ^ neg, self.hi[i] ^ neg

    def member(self, root: int, s: State) -> bool:
        """``s ∈ set(root)``: one path walk (module docstring)."""
        comp, shift, lo, hi = self.comp, self.shift, self.lo, self.hi
        r = root
        while r > 1:
            i = r >> 1
            r = (hi[i] if (s[comp[i]] >> shift[i]) & 1 else lo[i]) ^ (r & 1)
        return r == 0


class RankTable:
    """MTSA's rank function of one guarantee as one multi-terminal decision diagram over the
    compiled nested layers ``S[0] ⊆ … ⊆ S[L-1]``: ``rank(s)`` = the first ``k`` with
    ``s ∈ S[k]``, ``inf`` outside ``S[L-1]``, in one path walk.

    Built by halving: ``R[lo..hi] = S[mid] ? R[lo..mid] : R[mid+1..hi]`` (``s ∈ S[mid]``
    iff its rank is ``≤ mid``; each half is only asked about its own states, the rest is
    filled with a constant), with a memoised if-then-else on the compiled tables.  A
    reference ``>= 0`` is a node, ``-1 - r`` the terminal of rank ``r``.  Why: a binary
    search costs ``log2 L`` walks per state (6–7 on Fire Patrol, ~85 % of the enumeration's
    membership walks); the diagram costs one."""

    def __init__(self, sets: CompiledSets, roots: Sequence[int], inf: int) -> None:
        self.sets = sets
        self.comp: list[int] = []
        self.shift: list[int] = []
        self.lo: list[int] = []
        self.hi: list[int] = []
        self.level: list[int] = []
        self._unique: dict[tuple[int, int, int], int] = {}
        self._memo: dict[tuple[int, int, int], int] = {}
        self.root = self._range(list(roots), 0, len(roots) - 1, -1 - inf)

    def _range(self, roots: list[int], lo: int, hi: int, outside: int) -> int:
        """Right on the states of rank ``lo..hi``, ``outside`` off ``S[hi]``."""
        if lo == hi:
            return self._ite(roots[hi], -1 - hi, outside)
        mid = (lo + hi) // 2
        inner = self._range(roots, lo, mid, -1 - mid)  # off S[mid]: never asked
        outer = self._range(roots, mid + 1, hi, outside)
        return self._ite(roots[mid], inner, outer)

    def _top(self, m: int) -> int:
        return self.level[m] if m >= 0 else 1 << 30

    def _ite(self, f: int, g: int, h: int) -> int:
        """``f ? g : h`` — ``f`` a compiled BDD reference, ``g``/``h`` rank diagrams."""
        if f == 0 or g == h:
            return g
        if f == 1:
            return h
        key = (f, g, h)
        r = self._memo.get(key)
        if r is None:
            sets = self.sets
            lvl = min(sets.level[f >> 1], self._top(g), self._top(h))
            f0, f1 = sets.cofactors(f, lvl)
            g0, g1 = self._cofactors(g, lvl)
            h0, h1 = self._cofactors(h, lvl)
            r = self._memo[key] = self._node(lvl, self._ite(f0, g0, h0),
                                             self._ite(f1, g1, h1))
        return r

    def _cofactors(self, m: int, level: int) -> tuple[int, int]:
        if m < 0 or self.level[m] != level:
            return m, m
        return self.lo[m], self.hi[m]

    def _node(self, level: int, lo_ref: int, hi_ref: int) -> int:
        if lo_ref == hi_ref:
            return lo_ref
        key = (level, lo_ref, hi_ref)
        r = self._unique.get(key)
        if r is None:
            k, i = self.sets.bit_at[level]
            r = self._unique[key] = len(self.comp)
            self.comp.append(k)
            self.shift.append(i)
            self.lo.append(lo_ref)
            self.hi.append(hi_ref)
            self.level.append(level)
        return r

    def rank(self, s: State) -> int:
        comp, shift, lo, hi = self.comp, self.shift, self.lo, self.hi
        r = self.root
        while r >= 0:
            r = hi[r] if (s[comp[r]] >> shift[r]) & 1 else lo[r]
        return -1 - r


class CachedMoves:
    """The moves of a synchronous product (§2.5) from a component-state tuple, with the
    synchronisation of each action memoised per local states of its owners (module doc).
    Same moves, in the same order, as :meth:`explicit.ProductMoves.moves`."""

    def __init__(self, components: Sequence[LTS]) -> None:
        self.n = len(components)
        self.start: State = tuple(c.initial for c in components)
        owners: dict[str, list[int]] = {}
        for k, c in enumerate(components):
            for a in c.alphabet:
                owners.setdefault(a, []).append(k)
        self.owners = {a: tuple(ks) for a, ks in owners.items()}
        self.idx: list[dict[int, dict[str, list[int]]]] = []
        for c in components:
            out: dict[int, dict[str, list[int]]] = {}
            for s, a, t in c.transitions:
                out.setdefault(s, {}).setdefault(a, []).append(t)
            self.idx.append(out)
        # (component, local state) -> the non-tau actions it enables as their first owner
        self._first: dict[tuple[int, int], list[tuple[str, tuple[int, ...]]]] = {}
        self._sync: dict[tuple[str, tuple[int, ...]], list[tuple[int, ...] | None]] = {}

    def _firsts(self, k: int, s: int) -> list[tuple[str, tuple[int, ...]]]:
        key = (k, s)
        r = self._first.get(key)
        if r is None:
            r = self._first[key] = [(a, self.owners[a]) for a in self.idx[k].get(s, {})
                                    if a != TAU and self.owners[a][0] == k]
        return r

    def _combos(self, a: str, parts: tuple[int, ...], cur: State) -> list[tuple[int, ...] | None]:
        local = tuple(cur[k] for k in parts)
        key = (a, local)
        r = self._sync.get(key)
        if r is None:
            choices: list[list[int]] = []
            for k, v in zip(parts, local, strict=True):
                ts = self.idx[k].get(v, {}).get(a)
                if not ts:
                    choices = []
                    break
                choices.append(ts)
            r = self._sync[key] = _cartesian(choices) if choices else []
        return r

    def moves(self, cur: State) -> list[Move]:
        out: list[Move] = []
        for k0 in range(self.n):
            for a, parts in self._firsts(k0, cur[k0]):
                for combo in self._combos(a, parts, cur):
                    if combo is None:
                        out.append((a, None))
                        continue
                    nxt = list(cur)
                    for k, t in zip(parts, combo, strict=True):
                        nxt[k] = t
                    out.append((a, tuple(nxt)))
        for k in range(self.n):
            for t in self.idx[k].get(cur[k], {}).get(TAU, ()):
                if t == ERROR:
                    out.append((TAU, None))
                else:
                    nxt = list(cur)
                    nxt[k] = t
                    out.append((TAU, tuple(nxt)))
        return out


def _cartesian(choices: list[list[int]]) -> list[tuple[int, ...] | None]:
    """Every combination of the owners' targets (None for one that holds ERROR), in
    ``itertools.product`` order."""
    from itertools import product

    return [None if ERROR in combo else combo for combo in product(*choices)]
