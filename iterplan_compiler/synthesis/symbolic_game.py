"""The MTSA game (§3.2–3.4) over BDDs, composed symbolically from its leaf machines.

Encoding.  Component *k* (a plant leaf, a safety machine, a fluent monitor — see
:mod:`encode`) gets ``bits_for(n_k + e_k)`` current/next variable pairs, where ``e_k = 1`` if it
has ERROR moves: code ``n_k`` then stands for its ERROR state (a machine recoded by
:mod:`recode` instead has fluent-aligned codes: its feature bits are variables *shared* with
every machine tracking the same fluent, and its top bit is an error bit — every code with it
set is ERROR; see :meth:`SymbolicGame._declare_by_keys`).  No product is ever built
explicitly, and neither is a monolithic transition relation: the relation is kept
*partitioned by action* —

    T = ∨_a T_a,   T_a = ∧_{k owns a} R_k^a(s_k, s_k') ∧ ∧_{k does not own a} (s_k' = s_k)

(§2.5: an action moves every component whose alphabet holds it, the others stay; ``tau`` of a
component interleaves, i.e. is an action owned by that component alone).  Actions with the same
owner set and the same controllability are merged into one *group* ``R_g = ∨_a ∧_k R_k^a``;
the frame conjuncts are never built: an image over a group renames and quantifies only the
owners' variables (early quantification — everything outside the owners passes through the
relational product untouched; the groups are built and merged in :mod:`partition`).  Measured on SYNTECH15 GyroLTL_637 (29 leaves, 17+5 actions):
the monolithic action-quantified relation had 550 k nodes, the groups together a few
thousand, so one CPre costs a few dozen small relational products instead of two huge ones.

Any state in which some component is at its ERROR code has no successors (ERROR is a losing
sink); all operators keep their results inside ``live = valid ∧ ¬error``.

Game (§3.3): ``Env(s) = ∨_{g unc} ∃s'. R_g``;
``CPre(X) = (Env ∧ ¬∨_{g unc} ∃s'. R_g ∧ ¬X') ∨ (¬Env ∧ ∨_{g ctrl} ∃s'. R_g ∧ X')``
restricted to ``live``; dead ends satisfy neither disjunct, so they lose.

Variable orders (``order``, :class:`options.VariableOrder`; docs/synthesis.md): ``CLUSTERED``
(default: components' bits in composition order, current/next interleaved, each fluent
monitor's bit after the machine sharing most actions with it), ``ACTION_FIRST`` = ``LAST``
(fluents last), ``BLOCKED`` (all current bits, then all next bits); or ``names`` (learned).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from iterplan_compiler.ir.lts import ERROR, LTS
from iterplan_compiler.ir.minimise import strong_minimise
from iterplan_compiler.symbolic.bdd import (
    BitVec,
    and_exists,
    bits_for,
    cofactor,
    disjoin,
    new_manager,
    value_cubes,
)
from iterplan_compiler.synthesis.encode import GameSpec, evaluate
from iterplan_compiler.synthesis.options import VariableOrder
from iterplan_compiler.synthesis.partition import Group, Vars, cluster, owner_groups
from iterplan_compiler.synthesis.recode import ERROR_BIT

#: see :func:`partition.cluster`
CLUSTER_MAX_NODES = 250_000
#: see :meth:`SymbolicGame.restrict`
KEEP_SMALLER_RELATION = True
#: see :func:`quotient_leaves`
QUOTIENT_MAX_STATES = 1_000
#: components per cached partial cube in :meth:`SymbolicGame.state_cube`
CUBE_BLOCK = 4
Node = Any


def quotient_leaves(spec: GameSpec) -> GameSpec:
    """``spec`` with every body machine (plant and safety, not the fluent monitors) replaced
    by its strong-bisimulation quotient when that is smaller.

    Sound: the product of the quotients is strongly bisimilar to the product of the
    originals, and the fluent monitors (whose states *are* the labelling: two monitor states
    are bisimilar as machines but differ in value) stay as they are, so bisimilar game states
    carry the same fluent values.  The winning region, CPre and MTSA's rank layers are
    computed from CPre and the labelling only, so they are unions of bisimulation classes;
    the enumerated controller is then the image of the original one under the functional
    bisimulation ``(s, j) ↦ ([s], j)``, and after the driver's strong minimisation the two
    are the same machine (the minimal quotient is unique up to isomorphism).

    Why: machines written in FSP often distinguish states that behave alike — the explicit
    Fire Patrol's ``At[i] = (go[j] -> arrived[j] -> At[j])`` has N + N² states whose
    quotient has 1 + N (every ``At[i]`` behaves alike).  The product, and with it the
    enumerated controller (before the driver minimises it), shrinks by that factor:
    Fire Patrol N = 9, game 106 k → 23.6 k states, controller before minimisation
    21.1 k → 4.9 k states (4.4 k after), extraction 5.1 → 1.1 s.

    Machines over :data:`QUOTIENT_MAX_STATES` states are left alone: the big leaves are the
    front-end's safety automata, which it already minimises (Fire Patrol's ``RoundComplete``,
    2^N + 1 states, is its own quotient; minimising it again cost 0.27 s at N = 11 and
    doubles with every N)."""
    nbody = spec.num_plant + spec.num_safety
    comps = list(spec.components)
    changed = False
    for k in range(nbody):
        if comps[k].num_states > QUOTIENT_MAX_STATES:
            continue
        q = strong_minimise(comps[k], comps[k].name)
        if q.num_states < comps[k].num_states:
            comps[k] = q
            changed = True
    return replace(spec, components=tuple(comps)) if changed else spec


class SymbolicGame:
    """Partitioned BDD encoding of a :class:`GameSpec` (see the module docstring)."""

    def __init__(self, spec: GameSpec, *, bdd: Any = None,
                 order: VariableOrder = VariableOrder.CLUSTERED,
                 names: tuple[str, ...] | None = None) -> None:  # names: learn_order.py
        if not isinstance(order, VariableOrder):
            raise TypeError(f"order must be a VariableOrder, not {order!r}")
        self.spec = spec
        self.bdd = bdd if bdd is not None else new_manager()
        comps = spec.components
        self.err_code = [c.num_states if c.has_error else None for c in comps]
        self._declare(order, names)
        self.cur_vars = {v for vec in self.cur for v in vec.names}
        self.nxt_vars = {v for vec in self.nxt for v in vec.names}
        self.prime = {c: n for cv, nv in zip(self.cur, self.nxt, strict=True)
                      for c, n in zip(cv.names, nv.names, strict=True)}
        self._prime_f = {c: self.bdd.var(n) for c, n in self.prime.items()}
        self._unprime_f = {n: self.bdd.var(c) for c, n in self.prime.items()}
        self.vars = Vars(self.cur, self.nxt, self.prime, self._prime_f, self._unprime_f)
        self.reach: Any = None  # set by reachable()
        self._parts: dict[str, list[tuple[Node, frozenset[str]]]] = {}  # action_parts
        self._block_cubes: list[dict[tuple[int, ...], Node]] = [
            {} for _ in range(0, len(spec.components), CUBE_BLOCK)]
        self._build()

    # -- variables ----------------------------------------------------------------------

    def _declare(self, order: VariableOrder, given: tuple[str, ...] | None) -> None:
        b = self.bdd
        comps = self.spec.components
        widths = [bits_for(c.num_states + (1 if c.has_error else 0)) for c in comps]
        self.cur: list[BitVec] = []
        self.nxt: list[BitVec] = []
        if order is VariableOrder.BLOCKED:
            self.cur = [BitVec(tuple(f"s{k}_{i}" for i in range(w))) for k, w in enumerate(widths)]
            self.nxt = [BitVec(tuple(n + "'" for n in vec.names)) for vec in self.cur]
            for vec in (*self.cur, *self.nxt):
                b.declare(*vec.names)
            return
        if self.spec.bit_keys and order is VariableOrder.CLUSTERED:
            self._declare_by_keys(widths, given)
            return
        ks = self._declaration_order(order)
        cur = {k: tuple(f"s{k}_{i}" for i in range(widths[k])) for k in ks}
        self._declare_pairs([n for k in ks for n in cur[k]], given)
        self.cur = [BitVec(cur[k]) for k in range(len(widths))]
        self.nxt = [BitVec(tuple(n + "'" for n in cur[k])) for k in range(len(widths))]

    def _declare_pairs(self, names: list[str], given: tuple[str, ...] | None) -> None:
        """Each current-state variable and its primed copy, interleaved, in the order
        ``names`` or in the ``given`` one (a permutation of it: the constructor's ``names``)."""
        if given is not None and sorted(given) != sorted(names):
            raise ValueError("the variable order given is not one of this game's variables")
        for n in names if given is None else given:
            self.bdd.declare(n, n + "'")

    def _declare_by_keys(self, widths: list[int], given: tuple[str, ...] | None) -> None:
        """Variables of recoded machines (:mod:`recode`): a feature bit is the *shared*
        variable of its fluent (every machine tracking the same fluent, same initial value,
        reads the same variable — their copies agree on every reachable state, so only
        unreachable states are dropped); residual and error bits are the machine's own.
        Declared component by component (``clustered`` order), each shared variable where
        it is first used; current/next interleaved."""
        keys = self.spec.bit_keys
        shared: dict[str, str] = {}
        cur: dict[int, list[str]] = {k: [] for k in range(len(widths))}
        order: list[str] = []
        for k in self._declaration_order(VariableOrder.CLUSTERED):
            for i, key in enumerate(keys[k]):
                if key is None or key == ERROR_BIT:
                    name = f"s{k}_{i}"
                elif key in shared:
                    cur[k].append(shared[key])
                    continue
                else:
                    name = shared[key] = f"f{len(shared)}"
                order.append(name)
                cur[k].append(name)
        self._declare_pairs(order, given)
        self.cur = [BitVec(tuple(cur[k])) for k in range(len(widths))]
        self.nxt = [BitVec(tuple(n + "'" for n in cur[k])) for k in range(len(widths))]

    def _declaration_order(self, order: VariableOrder) -> list[int]:
        """Component order in the BDD: given order, or (``clustered``) each fluent monitor
        placed right after the body component sharing most actions with it, so a fluent's bit
        sits next to the state bits it is correlated with."""
        spec = self.spec
        nbody = spec.num_plant + spec.num_safety
        ks = list(range(len(spec.components)))
        if order is not VariableOrder.CLUSTERED or nbody == 0:
            return ks
        after: dict[int, list[int]] = {k: [] for k in range(nbody)}
        for f in range(nbody, len(ks)):
            alpha = spec.components[f].alphabet
            best = max(range(nbody), key=lambda k: (len(alpha & spec.components[k].alphabet),
                                                    -len(spec.components[k].alphabet), -k))
            after[best].append(f)
        out: list[int] = []
        for k in range(nbody):
            out.append(k)
            out.extend(after[k])
        return out

    # -- construction -------------------------------------------------------------------

    def _error_bit(self, k: int) -> bool:
        """Component ``k`` was recoded with a top error bit (:mod:`recode`)."""
        keys = self.spec.bit_keys
        return bool(keys) and keys[k][-1:] == (ERROR_BIT,)

    def _component_relation(self, k: int, c: LTS) -> dict[str, Node]:
        """``{label: R(s_k, s_k')}`` for every label component ``k`` moves on."""
        b = self.bdd
        terms: dict[str, list[Node]] = {}
        err = self.err_code[k]
        codes = c.num_states + (1 if err is not None else 0)
        src = value_cubes(b, self.cur[k], codes)
        dst = value_cubes(b, self.nxt[k], codes)
        for s, a, t in c.transitions:
            code = t if t != ERROR else err
            assert code is not None  # an ERROR move means the component has an ERROR code
            terms.setdefault(a, []).append(src[s] & dst[code])
        return {a: disjoin(b, ts) for a, ts in terms.items()}

    def _build(self) -> None:
        b = self.bdd
        spec = self.spec
        comps = spec.components
        valid, err, init = b.true, b.false, b.true
        rels = []
        #: per component, its codes that are neither ERROR nor unused (``live`` is their
        #: conjunction)
        self.live_parts: list[Node] = []
        for k, c in enumerate(comps):
            init &= self.cur[k].eq(b, c.initial)
            code = self.err_code[k]
            if self._error_bit(k):  # recoded: every code with the error bit set is ERROR
                err_k, valid_k = b.var(self.cur[k].names[-1]), b.true
            else:
                valid_k = self.cur[k].less_than(b, c.num_states + (1 if c.has_error else 0))
                err_k = self.cur[k].eq(b, code) if code is not None else b.false
            valid &= valid_k
            err |= err_k
            self.live_parts.append(valid_k & ~err_k)
            rels.append(self._component_relation(k, c))
        self.valid, self.error, self.init = valid, err & valid, init
        self.live = valid & ~err
        #: per component ``{label: R_k^a}`` (:meth:`action_parts` reads them again)
        self.component_rels: tuple[dict[str, Node], ...] = tuple(rels)
        self.groups = self._groups(rels)
        self.env = self.live & disjoin(b, [b.exist(g.nxt_vars, g.rel)
                                           for g in self.groups if not g.controllable])
        self.ctrl_owned = self.live & ~self.env
        nbody = spec.num_plant + spec.num_safety
        val = {name: b.var(self.cur[nbody + i].names[0])
               for i, name in enumerate(spec.fluent_names)}

        def sets(formulas: tuple) -> list[Node]:
            return [evaluate(f, val, true=b.true, false=b.false, neg=lambda x: ~x) & self.live
                    for f in formulas]

        self.assumptions = sets(spec.assumptions)
        self.guarantees = sets(spec.guarantees)
        self.failures = disjoin(b, sets(spec.failures))

    def action_parts(self, action: str) -> list[tuple[Node, frozenset[str]]]:
        """``action``'s relation as its owners' relations ``R_k^a`` with their variables
        (current ones; the conjunction is what :func:`partition.owner_groups` builds), in
        component order, each *into live codes only* (``R_k^a ∧ live_k'``) — for images with
        early quantification (:mod:`turns`), exact for images of live sets that are then
        kept to ``live`` (and preimages of live sets).  Why the targets: GyroLTLVar2_701's
        ``tick`` images had up to 2.3 M nodes of which 13 k were live (moves into ERROR
        of every property at once)."""
        if action not in self._parts:
            comps = self.spec.components
            self._parts[action] = [
                (self.component_rels[k].get(action, self.bdd.false)
                 & self.to_next(self.live_parts[k]), frozenset(self.cur[k].names))
                for k, c in enumerate(comps) if action in c.alphabet]
        return self._parts[action]

    def _groups(self, rels: list[dict[str, Node]]) -> list[Group]:
        """The partitioned relation (:func:`partition.owner_groups`), merged per
        controllability where that stays small (:func:`partition.cluster`)."""
        groups = owner_groups(self.bdd, self.vars, self.spec.components,
                              self.spec.controllable, rels)
        #: the groups before merging: one owner set and controllability each (:mod:`turns`
        #: needs its turn's chain and exit moves apart)
        self.owner_groups: tuple[Group, ...] = tuple(groups)
        return cluster(self.bdd, self.vars, groups, CLUSTER_MAX_NODES)

    # -- operators ----------------------------------------------------------------------

    def to_next(self, u: Node) -> Node:
        return self.bdd.let(self._prime_f, u)

    def to_cur(self, u: Node) -> Node:
        return self.bdd.let(self._unprime_f, u)

    def _pre(self, g: Group, X: Node, xn: list[Node]) -> Node:
        """``∃s'. T_g ∧ X'``: rename only the owners' bits, quantify only them (a framed
        group owns everything and shares the one full rename ``xn``)."""
        if len(g.owners) == len(self.cur):
            if not xn:
                xn.append(self.to_next(X))
            return and_exists(self.bdd, g.rel, xn[0], g.nxt_vars)
        return and_exists(self.bdd, g.rel, self.bdd.let(g.prime, X), g.nxt_vars)

    def cpre(self, X: Node) -> Node:
        """Controllable predecessor of §3.4 (dead ends never belong to it)."""
        b = self.bdd
        X = X & self.live
        bad = ~X
        xb: list[Node] = []
        env_bad = disjoin(b, [self._pre(g, bad, xb) for g in self.groups
                              if not g.controllable])
        xg: list[Node] = []
        good = disjoin(b, [self._pre(g, X, xg) for g in self.groups if g.controllable])
        return (self.env & ~env_bad) | (self.ctrl_owned & good)

    def pre_of(self, controllable: bool, X: Node) -> Node:
        """``∃s'. T ∧ X'`` over the groups of one controllability."""
        xn: list[Node] = []
        return disjoin(self.bdd, [self._pre(g, X, xn) for g in self.groups
                                  if g.controllable == controllable])

    def cpre_lost(self, X: Node, removed: Node, within: Node) -> Node:
        """States of ``within`` ⊆ ``CPre(X ∪ removed)`` outside ``CPre(X)``
        (:class:`fixpoint.FrontierPredecessor`).

        By the definition of :meth:`cpre`: an environment state of ``within`` had all its
        uncontrollable successors in ``X ∪ removed``, so it leaves iff one is in ``removed``;
        a controller state had a controllable successor in ``X ∪ removed``, so only those
        with one in ``removed`` (``cand``) need the check "some controllable successor in
        ``X``", which looks at successors of ``cand`` only — hence ``X`` may be replaced by
        its generalised cofactor on them (smaller, equal where it is read)."""
        env_lost = within & self.env & self.pre_of(False, removed)
        return env_lost | self._ctrl_lost(X, removed, within)

    def _ctrl_lost(self, X: Node, removed: Node, within: Node) -> Node:
        """The controller states of :meth:`cpre_lost`."""
        b = self.bdd
        cand = within & self.ctrl_owned & self.pre_of(True, removed)
        if cand == b.false:
            return b.false
        succ = self.post_of(True, cand)
        keep = cand & self.pre_of(True, cofactor(b, X & self.live, succ))
        return cand & ~keep

    def cpre_lost_chained(self, X: Node, removed: Node, within: Node) -> Node:
        """:meth:`cpre_lost` in Gauss–Seidel order, for a descending ``νX``: the environment
        states lost (``E``, outside ``CPre(X)``) are removed before the controller states
        are checked, against ``X ∖ E`` with ``removed ∪ E``.  A superset of
        ``within ∖ CPre(X)`` (``E`` ∪ the controller states of ``within ∖ CPre(X ∖ E)``),
        and still disjoint from every fixpoint below ``X``: ``E`` is, so such a fixpoint
        lies in ``X ∖ E``, and a controller state without a controllable successor there is
        outside its CPre.  The νX then reaches the same fixpoint in
        fewer steps (a step removing nothing is still a fixpoint).  GyroLTL_637's fixpoint:
        638 → 620 νX steps, CUDD cache insertions 28.4 M → 25.6 M (−10 %), peak live nodes
        1.19 M → 0.99 M (docs/synthesis.md)."""
        env_lost = within & self.env & self.pre_of(False, removed)
        return env_lost | self._ctrl_lost(X & ~env_lost, removed | env_lost, within)

    def cpre_gained(self, X: Node, added: Node, within: Node) -> Node:
        """States of ``within`` in ``CPre(X ∪ added)``, at least those outside ``CPre(X)``
        (:class:`fixpoint_ops.FrontierPredecessor`; the μY direction: ``Y`` grows).

        The dual of :meth:`cpre_lost`: a controller state enters iff it has a controllable
        successor in ``added`` (it had none in ``X``); an environment state can enter only
        if one of its uncontrollable successors is in ``added`` (``cand``; otherwise all are
        in ``X`` and it was in ``CPre(X)`` already), and it is in iff none is outside
        ``X ∪ added`` — a check that reads successors of ``cand`` only, so the complement
        may be replaced by its generalised cofactor on them."""
        b = self.bdd
        added = added & self.live
        gained = within & self.ctrl_owned & self.pre_of(True, added)
        cand = within & self.env & self.pre_of(False, added)
        if cand == b.false:
            return gained
        bad = cofactor(b, ~((X | added) & self.live), self.post_of(False, cand))
        return gained | (cand & ~self.pre_of(False, bad))

    def post_of(self, controllable: bool, X: Node) -> Node:
        """Successors of ``X`` (current variables) over the groups of one controllability."""
        b = self.bdd
        return disjoin(b, [b.let(g.unprime, and_exists(b, g.rel, X, g.cur_vars))
                           for g in self.groups if g.controllable == controllable])

    def restrict(self, care: Node) -> None:
        """Restrict the relations to ``care`` (e.g. the reachable states) at both ends: a
        framed group to ``care`` itself, a partitioned group to ``care``'s projection on its
        owners' variables.

        Only sound for a forward-closed ``care``: then no relevant edge is lost — for a
        partitioned group, a state ``s`` of ``care`` satisfies the projection and so does
        each of its successors (they are in ``care`` too), so every image and preimage read
        on ``care`` is unchanged.  Measured on
        GyroLTLVar3_702 (31 k reachable states, 68 k-node framed controllable relation): the
        fixpoint took 60 s unrestricted and 8 s restricted — the relational products then
        never touch unreachable junk.  With :data:`KEEP_SMALLER_RELATION` a restriction that
        *grows* the relation is not kept (either relation is exact on ``care``): with
        recoded machines GyroLTL_637's framed uncontrollable relation has 16.8 k nodes and
        51 k restricted, and its first 35 CPre took 42.6 s CPU instead of 47.1 s; neutral on
        GyroLTLVar3_702 and GyroLTL_486/_588/_590.  The projection (0.2 s) shrinks
        GyroLTL_637's 28-owner ``tick`` group from 206 k to 61 k nodes (the small groups
        would grow and are kept as they are); its fixpoint then computes 8 % fewer CUDD
        cache insertions (30.8 M → 28.4 M) and peaks at 1.19 M instead of 1.29 M live
        nodes, same iterates — small, since the iterates dominate (docs/synthesis.md).
        A deferred action (:data:`partition.DEFER_NODES`) is built here for the first time,
        restricted as it is built (:meth:`partition.Group.within`), and always kept."""
        b = self.bdd
        cn = self.to_next(care)
        for g in self.groups:
            if len(g.owners) == len(self.cur):
                r = g.within(care, cn)
            else:
                p = b.exist(self.cur_vars - g.cur_vars, care)
                r = g.within(p, b.let(g.prime, p))
            if g.deferred or len(r) <= len(g.rel) or not KEEP_SMALLER_RELATION:
                g.rel = r

    def post(self, X: Node) -> Node:
        b = self.bdd
        X = X & self.live
        imgs = [b.let(g.unprime, and_exists(b, g.rel, X, g.cur_vars)) for g in self.groups]
        return disjoin(b, imgs)

    def pre_any(self, X: Node) -> Node:
        X = X & self.live
        xn: list[Node] = []
        return self.live & disjoin(self.bdd, [self._pre(g, X, xn) for g in self.groups])

    def reachable(self, *, max_nodes: int | None = None) -> Node:
        """Forward-reachable states from ``init`` (also cached as ``self.reach``).

        With ``max_nodes``, give up (return None, ``self.reach`` stays None) as soon as the
        reached set's BDD exceeds that many nodes: some products (SYNTECH15) have reachable
        sets without BDD structure, and the fixpoint does not need them (it runs over
        ``live`` instead; unreachable states do not change the ranks of reachable ones)."""
        from iterplan_compiler import limits

        R = self.init
        frontier = self.init
        while frontier != self.bdd.false:
            limits.check_deadline()  # --time-limit between image steps
            img = self.post(frontier)
            frontier = img & ~R
            R |= frontier
            if max_nodes is not None and len(R) > max_nodes:
                return None
        self.reach = R
        return R

    def relation_nodes(self) -> int:
        return sum(len(g.rel) for g in self.groups)

    def count(self, u: Node) -> int:
        return int(self.bdd.count(u, nvars=len(self.cur_vars))) if u != self.bdd.false else 0

    def decode(self, assignment: dict[str, bool], vecs: list[BitVec]) -> tuple[int, ...]:
        return tuple(v.decode(assignment) for v in vecs)

    def state_cube(self, tup: tuple[int, ...]) -> Node:
        """The cube of one state: a conjunction of cached cubes of blocks of
        :data:`CUBE_BLOCK` components (explored states share most blocks, so a cube costs a
        few conjunctions instead of one per component)."""
        u = self.bdd.true
        for lo in range(0, len(tup), CUBE_BLOCK):
            part = tup[lo:lo + CUBE_BLOCK]
            cache = self._block_cubes[lo // CUBE_BLOCK]
            c = cache.get(part)
            if c is None:
                c = self.bdd.true
                for k, val in enumerate(part, start=lo):
                    c &= self.cur[k].eq(self.bdd, val)
                cache[part] = c
            u &= c
        return u

    def contains(self, u: Node, tup: tuple[int, ...]) -> bool:
        """Is the state ``tup`` in the set ``u``?  (One cofactor walk, no new nodes kept.)"""
        return self.bdd.let(self.assignment(tup), u) == self.bdd.true

    def assignment(self, tup: tuple[int, ...]) -> dict[str, bool]:
        out: dict[str, bool] = {}
        for vec, val in zip(self.cur, tup, strict=True):
            out.update(vec.assign(val))
        return out

    def fluent_values(self, tup: tuple[int, ...]) -> dict[str, bool]:
        nbody = self.spec.num_plant + self.spec.num_safety
        return {name: tup[nbody + i] == 1 for i, name in enumerate(self.spec.fluent_names)}
