"""The partitioned transition relation of the symbolic game (:mod:`symbolic_game`).

    T = ∨_g R_g,   R_g = ∨_{a ∈ g} ∧_{k owns a} R_k^a      (over the owners' variables only)

A *group* ``g`` holds the actions with one owner set and one controllability; an image over
``R_g`` renames and quantifies only the owners' variables (early quantification: the frame
``x' = x`` of every other variable is implicit).  A group whose owners are all components is
*framed*: its relation mentions every variable, and all such groups share one rename per
CPre.  This module builds the groups (:func:`owner_groups`) and merges them
(:func:`cluster`); :class:`Vars` is the game's variable naming it needs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from iterplan_compiler.ir.lts import LTS, TAU
from iterplan_compiler.symbolic.bdd import BitVec, disjoin

Node = Any


@dataclass(frozen=True)
class Vars:
    """The game's variables: per component its current and next bit vectors (shared fluent
    variables appear in several components' vectors), and the renamings."""

    cur: Sequence[BitVec]
    nxt: Sequence[BitVec]
    prime: dict[str, str]          # current var -> next var (names)
    prime_f: dict[str, Node]       # current var -> next var node (for ``let``)
    unprime_f: dict[str, Node]     # next var -> current var node

    @property
    def cur_vars(self) -> frozenset[str]:
        return frozenset(self.prime)

    @property
    def nxt_vars(self) -> frozenset[str]:
        return frozenset(self.prime.values())


#: an action's relation (its owners' relations conjoined in component order) is *deferred* —
#: kept as its factors and built only when first read — once it passes this many nodes while
#: being built.  GyroLTLVar2_701's ``tick`` (49 owners) has 5.5 M nodes and took 19 s of the
#: encoding; the turn game (:mod:`turns`) images it through clusters of its owners' relations
#: and never reads it, so its verdict no longer waits for it.  Above
#: :data:`symbolic_game.CLUSTER_MAX_NODES`, so a deferred group is never worth merging.
DEFER_NODES = 500_000


@dataclass
class Group:
    """Actions sharing owners and controllability: ``rel`` over the owners' cur/next bits.

    ``rel`` is ``built`` (the actions built at once) or'ed with, per *deferred* action
    (:data:`DEFER_NODES`), the conjunction of its ``factors``, computed on first read."""

    owners: tuple[int, ...]
    controllable: bool
    actions: tuple[str, ...]
    built: Node
    nxt_vars: frozenset[str]
    cur_vars: frozenset[str]
    prime: dict[str, Node]     # owner cur var -> next var node (for ``let``)
    unprime: dict[str, Node]   # owner next var -> cur var node
    factors: tuple[tuple[Node, ...], ...] = ()

    @property
    def deferred(self) -> bool:
        return bool(self.factors)

    @property
    def rel(self) -> Node:
        if self.factors:
            self.built = self.within()
            self.factors = ()
        return self.built

    @rel.setter
    def rel(self, value: Node) -> None:
        self.built, self.factors = value, ()

    def within(self, *cares: Node) -> Node:
        """``rel ∧ cares…``, conjoined one by one (a set and its primed copy conjoined
        first can be far larger than either: interleaved variables); a deferred action is
        built from the first care set on, its factors next, the other care sets last (so
        every intermediate product is already restricted)."""
        out = self.built
        for c in cares:
            out &= c
        for fs in self.factors:
            r = self.built.bdd.true
            for f in (*cares[:1], *fs, *cares[1:]):
                r &= f
            out |= r
        return out


def group_over(v: Vars, owners: tuple[int, ...], controllable: bool,
               actions: tuple[str, ...], rel: Node,
               factors: tuple[tuple[Node, ...], ...] = ()) -> Group:
    """A :class:`Group` of ``owners`` (their variables, shared ones included)."""
    cv = [x for k in owners for x in v.cur[k].names]
    nv = [x for k in owners for x in v.nxt[k].names]
    return Group(owners, controllable, actions, rel, frozenset(nv), frozenset(cv),
                 {c: v.prime_f[c] for c in cv}, {n: v.unprime_f[n] for n in nv}, factors)


def owner_groups(bdd: Any, v: Vars, comps: Sequence[LTS], controllable: frozenset[str],
                 rels: list[dict[str, Node]]) -> list[Group]:
    """One :class:`Group` per (owner set, controllability) from the components' relations
    ``rels[k][a] = R_k^a``; ``tau`` of component ``k`` is an uncontrollable action owned by
    ``k`` alone."""
    owner_lists: dict[str, list[int]] = {}
    for k, c in enumerate(comps):
        for a in sorted(c.alphabet - {TAU}):
            owner_lists.setdefault(a, []).append(k)
    parts: dict[tuple[tuple[int, ...], bool], list[tuple[str, Node]]] = {}
    later: dict[tuple[tuple[int, ...], bool], list[tuple[Node, ...]]] = {}
    for a, ks_list in sorted(owner_lists.items()):
        key = (tuple(ks_list), a in controllable)
        fs = [rels[k].get(a, bdd.false) for k in ks_list]
        r = bdd.true
        for i, f in enumerate(fs):
            r &= f
            if r == bdd.false:
                break
            if len(r) > DEFER_NODES and i + 1 < len(fs):
                later.setdefault(key, []).append((r, *fs[i + 1:]))
                r = None
                break
        parts.setdefault(key, []).append((a, bdd.false if r is None else r))
    for k, comp_rel in enumerate(rels):
        if TAU in comp_rel:
            parts.setdefault(((k,), False), []).append((TAU, comp_rel[TAU]))
    out: list[Group] = []
    for (ks, is_ctrl), acts in parts.items():
        rel = disjoin(bdd, [r for _, r in acts])
        factors = tuple(later.get((ks, is_ctrl), ()))
        if rel != bdd.false or factors:
            out.append(group_over(v, ks, is_ctrl, tuple(a for a, _ in acts), rel, factors))
    return out


def framed_to(bdd: Any, v: Vars, moved: frozenset[str]) -> Node:
    """The frame ``∧_{x ∉ moved} x' = x``: every current variable *outside* ``moved`` (a
    group's ``cur_vars``) keeps its value.

    Framed per *variable*, not per machine: with shared fluent variables
    (``SymbolicGame._declare_by_keys``) a machine outside the group may read a variable that
    an owner writes.  Sharers agree on the fluent's own moves (its actions are in both
    alphabets), but an owner's ERROR move clears its feature bits (ERROR is the error bit
    alone, :mod:`recode`); framing the non-owner's bits then demanded ``f' = f`` and dropped
    that move — on GyroLTL_637, and on the spec of ``tests/synthesis/test_framing.py``, an
    uncontrollable move to ERROR vanished and the symbolic game called a losing state
    winning."""
    u = bdd.true
    for x in sorted(v.cur_vars - moved):
        u &= bdd.var(x).equiv(bdd.var(v.prime[x]))
    return u


def is_framed(v: Vars, g: Group) -> bool:
    """``g`` is owned by every component (its relation mentions every variable)."""
    return len(g.owners) == len(v.cur)


def cluster(bdd: Any, v: Vars, groups: list[Group], max_nodes: int) -> list[Group]:
    """Merge the groups of each controllability into one *framed* relation over all
    variables when it stays below ``max_nodes`` nodes.

    Trade-off, measured on SYNTECH15 GyroLTL_486 (7 groups of 18/13/... owners): renaming
    ``X`` once per group cost 4.7 s of fixpoint against 0.7 s with one framed relation per
    controllability (one shared rename per CPre); on GyroLTL_637 the framed controllable
    relation has 550 k nodes, so there the groups stay partitioned.  The bound was 100 k
    until Fire Patrol N = 14, whose framed controllable relation has ~100 k nodes: kept
    partitioned (4 groups) its fixpoint took 13.1 s CPU, framed (2 groups) 3.2 s (N = 13,
    52 k nodes framed: 1.1 s).  At 250 k no SYNTECH15 file changes grouping (their
    framed relations are under 70 k nodes or over 250 k)."""
    out: list[Group] = []
    everyone = tuple(range(len(v.cur)))
    for is_ctrl in (True, False):
        part = [g for g in groups if g.controllable == is_ctrl]
        if len(part) <= 1:
            out.extend(part)
            continue
        rel = bdd.false
        for g in part:
            if g.deferred:  # over DEFER_NODES ≥ max_nodes: not built for this
                break
            rel |= g.rel & framed_to(bdd, v, g.cur_vars)
            if len(rel) > max_nodes:
                break
        else:
            acts = tuple(a for g in part for a in g.actions)
            out.append(group_over(v, everyone, is_ctrl, acts, rel))
            continue
        out.extend(part)
    return out

