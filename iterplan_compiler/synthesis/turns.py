"""Turn steps: the MTSA game of a turn-based translation solved one whole turn at a time.

MTSA's Spectra translation (the SYNTECH15 specs) makes a synchronous game asynchronous: a
``Clock`` lets the environment move (``Env_turn``: any uncontrolled actions, then ``tock``)
and then the controller (``Sys_turn``: controlled actions, then ``tick``), and ``Turns(N)``
bounds a system turn to ``N`` moves.  Every action sets one variable, so the states *inside*
a turn are all the orders and partial assignments of that turn: GyroLTL_595 has 1,851,800
reachable states of which 12,938 start a turn.  This module solves the game on the turn
starts only, with a whole turn as one move, and proves that this is the same game.

Equation.  ``B`` = the reachable turn starts (the initial state and every target of a turn
exit); ``E`` / ``S`` = the states whose clock is in an environment / system turn state;
chain groups ``h_1 … h_m`` of one side (moves that stay in the turn) in a fixed canonical
order, exit groups ``x`` (moves that end it); ``Pre_h(Z) = ∃s'. R_h ∧ Z'``::

    Esc(X)  = S ∧ B_1(B_2(… B_m(Pre_x(X)) …))          B_i(Z) = Z ∨ (S ∧ Pre_{h_i}(Z))
    Bad(X)  = E ∧ D_1(… D_k(Pre_x(¬X) ∨ Pre_h(¬live) ∨ ¬Env) …)   D_i likewise over E
    CPre_B(X) = B ∧ ((S ∧ Esc(X)) ∨ (E ∧ Env ∧ ¬Bad(X)))
    W_B = the GR(1) fixpoint (fixpoint.gr1_winning) over B with CPre_B

(``Esc``: the system turns the controller can finish in ``X``; ``Bad``: the environment
turns that can end outside ``X``, in ERROR or in a dead end.)  The verdict is
``init ∈ W_B``.  For MTSA's controller the winning region of every state is then rebuilt
from ``W_B`` with the *exact* relations (:meth:`TurnGame.full_winning`).

Why it is the same game — conditions, each checked (:func:`turn_shape.find_turns`):

1. *A turn component* (the ``Clock``): one machine owns every action; each of its states
   has only uncontrolled (``E``) or only controlled (``S``) moves; every action either
   always stays on its side (chain) or always crosses (exit), and every partition group
   is one kind.  So a turn is: chain moves of one player, then one exit move.
2. *Chain moves commute and the last one wins* (checked machine by machine on the
   explicit LTSs, ERROR moves left out, every chain action deterministic): the turn
   groups of a side are the partition groups, those with two actions that do not commute
   merged (``x0 ; x1`` ≠ ``x1 ; x0`` for two values of one variable whose setters sit in
   different groups); for chain actions ``a, b`` of different turn groups, ``a;b`` and
   ``b;a`` reach the same states of every machine; for ``a, a'`` of one system turn group
   ``a;a'`` reaches only states ``a'`` reaches ("last wins"; an environment group where
   it does not hold, e.g. a property that fails on ``d1`` unless ``e1`` came first, is
   iterated to its fixpoint instead of taken once).  The product moves every machine on its own, and a shared (recoded) fluent
   bit takes the value the action gives it in every machine, so the same holds for live
   game states.  Hence every live path inside a turn can be reordered into the canonical
   order of the groups, with at most one move per system group, to the same end state:
   the states a turn can reach are exactly those of the ``B_i`` / ``D_i`` compositions.
3. *A turn budget* (``Turns(N)``): a machine that owns every system chain and exit action
   and no uncontrolled one, moves the same way on every chain action, has no chain cycle
   from its initial state, but a chain path of length ``m`` (the number of system
   groups), and returns to its initial state on every exit.  It is at its initial state
   at every turn start, so the ``≤ m`` canonical moves always fit, and its variables can
   be left out of the turn's states (they are projected away: states the same but for the
   budget are one); no system turn is endless, so the controller must exit.
4. *The goals see the same*: every assumption and goal is, on the states inside the turns
   of one side (after ≥ 1 chain move), either false or true together with every turn
   start of that side (absorbed, e.g. ``Tock`` inside system turns, or a goal ``TRUE``);
   and some assumption is false inside environment turns, so an environment that never
   ends its turn loses — which is why the compressed game may leave that choice out.

Then a play of the full game is a sequence of turns, a strategy of either game translates
to the other turn by turn (follow the canonical path the compressed strategy picks;
conversely the end state of any turn is the end of a canonical path), and the GR(1)
condition sees the same propositions infinitely often, so ``W_B = W ∧ B``.

Optimisations (each exact; measured in docs/synthesis.md, "Turn steps"): the budget's
variables projected out of the turn positions (condition 3; GyroLTL_595's fixpoint 61 → 20 s
CPU); one backward step per group where the last move wins (condition 2); every backward
step simplified to the positions the reachable turns have at that stage (:meth:`TurnGame.esc`:
a position of stage ``j`` moves by group ``j`` into stage ``j + 1``; GyroLTLVar2_701's ``Esc``
16.7 → 1.2 s); the system exit imaged through clusters of its owners' relations
(:func:`exit_clusters`; 701's turn starts 41 → 19 s), each into live codes only
(:meth:`SymbolicGame.action_parts`: its images had up to 2.3 M nodes, 13 k of them live;
then 26 → 6 s on a slower machine); condition 4 checked on the positions the turn images
reached (not imaged again: 5.6 s).  The exit's monolithic relation is never read here (it is
deferred, :data:`partition.DEFER_NODES`: 701's 5.5 M-node ``tick`` cost 19 s to build).

When it does not apply (``solve_turns`` returns None; the caller solves the full game as
before): :class:`options.MacroSteps` ``CHAINS`` or ``OFF``; any condition above fails; the
turn starts pass :data:`MAX_BOUNDARY_NODES`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

from iterplan_compiler import limits
from iterplan_compiler.symbolic.bdd import and_exists, cofactor, disjoin
from iterplan_compiler.synthesis.fixpoint import Gr1Fixpoint, gr1_winning
from iterplan_compiler.synthesis.learn_order import sifted_order
from iterplan_compiler.synthesis.partition import Group
from iterplan_compiler.synthesis.symbolic_game import SymbolicGame
from iterplan_compiler.synthesis.turn_shape import TurnShape, find_turns

__all__ = ["MAX_BOUNDARY_NODES", "TurnGame", "TurnSolution", "find_turns", "solve_turns"]

Node = Any
#: ``(relation, current variables no later cluster mentions, next ones likewise)``
Clusters = tuple[tuple[Node, frozenset[str], frozenset[str]], ...]
#: a system exit's relation is kept as the conjunction of clusters of its owners'
#: relations, each cluster grown up to this many nodes, and imaged cluster by cluster with
#: early quantification.  GyroLTLVar2_701's ``tick``: 5.5 M nodes monolithic, 3 clusters
#: of 25 k / 31 k / 0.7 k nodes at 50 k; its turn starts' search 41 → 19 s CPU (200 k:
#: 27 s, 600 k: 24 s; one cluster per owner, no merging: 57 s; measured before the
#: clusters moved into live codes only; docs/synthesis.md)
EXIT_CLUSTER_NODES = 50_000
#: give up (full game instead) once the reachable turn starts pass this many nodes
#: (GyroLTL_595: 20.8 k, GyroLTLVar2_701: 60.9 k)
MAX_BOUNDARY_NODES = 1_000_000
#: once the reachable turn starts pass this many nodes, learn the variable order from them
#: (:mod:`learn_order`; 701 learns at 6.9 k, 595 at 8.5 k; 637's 3.8 k stay as they are).
#: At 40 k instead: 701's verdict 18.5 s instead of 15.8 s.  None: never
LEARN_NODES: int | None = 5_000


@dataclass(frozen=True)
class Reorder:
    """The turn starts passed :data:`LEARN_NODES`: build the game again with its
    current-state variables in ``names`` and solve it from the start (:mod:`learn_order`)."""

    names: tuple[str, ...]
    nodes: int  # the turn starts' nodes when learned


@dataclass(frozen=True)
class TurnGame:
    """The game on the turn starts ``B`` (module doc); ``budget`` are the projected
    variables, ``sys_rel`` the system groups' relations without them."""

    g: SymbolicGame
    shape: TurnShape
    env_side: Node
    sys_side: Node
    budget: frozenset[str]
    sys_rel: tuple[Node, ...]     # sys_chain's relations, budget projected
    boundary: Node
    #: the positions of the reachable turns after groups ``1..j`` of the canonical order
    #: (``[0]``: the turn starts; budget projected on the system side), see :meth:`esc`
    sys_stages: tuple[Node, ...] = ()
    env_stages: tuple[Node, ...] = ()
    #: per system exit group (its actions), per action: the clusters of its relation
    exit_clusters: dict[tuple[str, ...], tuple[Clusters, ...]] = field(default_factory=dict)

    # -- images ------------------------------------------------------------------------

    def _env_close(self, grp: Group, once: bool, Y: Node, *, forward: bool) -> Node:
        """``Y`` and the environment positions one move of ``grp`` away from it (after it
        when ``forward``, before it else) — once where the last move wins, else iterated
        to the fixpoint (no budget bounds an environment group)."""
        return self._env_steps(grp, once, Y, forward=forward)[0]

    def _env_steps(self, grp: Group, once: bool, Y: Node, *, forward: bool
                   ) -> tuple[Node, Node]:
        """:meth:`_env_close` and the positions its moves reached (the union of its
        steps)."""
        moved = self.g.bdd.false
        while True:
            step = (self._post(grp, grp.rel, Y) & self.g.live if forward
                    else self.env_side & self._pre(grp, grp.rel, Y))
            moved |= step
            nxt = Y | step
            if once or nxt == Y:
                return nxt, moved
            limits.check_deadline()
            Y = nxt

    def _post(self, grp: Group, rel: Node, Y: Node) -> Node:
        b = self.g.bdd
        return b.let(grp.unprime, and_exists(b, rel, Y, grp.cur_vars))

    def _pre(self, grp: Group, rel: Node, Z: Node) -> Node:
        b = self.g.bdd
        return and_exists(b, rel, b.let(grp.prime, Z), grp.nxt_vars)

    def _sys_groups(self) -> list[tuple[Group, Node]]:
        """The system chain groups with their relations, budget projected."""
        return list(zip(self.shape.sys_chain, self.sys_rel, strict=True))

    def turn_image(self, S: Node) -> tuple[Node, Node]:
        """The turn starts that whole turns from ``S`` reach, and the positions inside
        those turns after at least one chain move (budget projected; in the canonical order,
        which reaches every such position by condition 2)."""
        g, b, s = self.g, self.g.bdd, self.shape
        live = g.live
        P = S & self.env_side
        moved = b.false
        for grp, once in zip(s.env_chain, s.env_once, strict=True):
            P, step = self._env_steps(grp, once, P, forward=True)
            moved |= step
        Q = b.exist(self.budget, S & self.sys_side)
        sys = self._sys_groups()
        for grp, rel in sys:
            step = self._post(grp, rel, Q) & live
            moved |= step
            Q |= step
        out = disjoin(b, [self._post(grp, grp.rel, P) for grp in s.env_exit]
                      + [self._exit_post(grp, Q) for grp in s.sys_exit])
        return out & live, moved

    def _exit_post(self, grp: Group, Q: Node) -> Node:
        """The image of ``Q`` (budget projected) by a system exit group."""
        return self.g.bdd.let(grp.unprime, self._through_exit(grp, Q, forward=True))

    def _exit_pre(self, grp: Group, X: Node) -> Node:
        """The states with a move of a system exit group into ``X``, budget projected."""
        b = self.g.bdd
        Y = self._through_exit(grp, b.let(grp.prime, X), forward=False)
        return b.exist(self.budget, Y)

    def _through_exit(self, grp: Group, Y: Node, *, forward: bool) -> Node:
        """``Y`` conjoined with each action's clusters (:func:`exit_clusters`) in turn,
        each cluster's last current (``forward``) or next variables quantified right after
        it; the union over the group's actions."""
        b = self.g.bdd
        outs = []
        for clusters in self.exit_clusters[grp.actions]:
            Z = Y
            for rel, cur_done, nxt_done in clusters:
                Z = and_exists(b, Z, rel, cur_done if forward else nxt_done)
            outs.append(Z)
        return disjoin(b, outs)

    # -- the compressed game -------------------------------------------------------------

    def stages(self) -> tuple[tuple[Node, ...], tuple[Node, ...]]:
        """``sys_stages`` and ``env_stages`` for the turn starts ``boundary``."""
        g, b, s = self.g, self.g.bdd, self.shape
        Q = [b.exist(self.budget, self.boundary & self.sys_side)]
        for grp, rel in self._sys_groups():
            Q.append(Q[-1] | (self._post(grp, rel, Q[-1]) & g.live))
        P = [self.boundary & self.env_side]
        for grp, once in zip(s.env_chain, s.env_once, strict=True):
            P.append(self._env_close(grp, once, P[-1], forward=True))
        return tuple(Q), tuple(P)

    def esc(self, X: Node) -> Node:
        """System turn positions from which the controller can end the turn in ``X``.

        Each backward step only needs its set on the positions the turns reach at that
        stage (``sys_stages[j + 1]``: a position there moves by group ``j`` to one there),
        so the set is first simplified there (CUDD's generalised cofactor): exact on the
        turn starts, and far smaller — GyroLTLVar2_701's first ``Esc`` 16.7 → 1.2 s CPU,
        its largest intermediate 3.4 M → 95 k nodes (docs/synthesis.md)."""
        b, s = self.g.bdd, self.shape
        sys = self._sys_groups()
        m = len(s.sys_chain)
        Z = disjoin(b, [self._exit_pre(grp, X) for grp in s.sys_exit])
        Z &= self.sys_side
        for j in reversed(range(m)):
            grp, rel = sys[j]
            if self.sys_stages:
                Z = cofactor(b, Z, self.sys_stages[j + 1])
            Z |= self.sys_side & self._pre(grp, rel, Z)
        return Z

    def bad(self, X: Node) -> Node:
        """Environment turn positions from which the environment can end the turn outside
        ``X``, in ERROR or in a dead end (simplified stage by stage as in :meth:`esc`)."""
        g, b, s = self.g, self.g.bdd, self.shape
        dead = ~g.live
        Z = disjoin(b, [self._pre(grp, grp.rel, ~X) for grp in s.env_exit]
                    + [self._pre(grp, grp.rel, dead) for grp in s.env_chain])
        Z = self.env_side & (Z | ~g.env)
        for j in reversed(range(len(s.env_chain))):
            if self.env_stages:
                Z = cofactor(b, Z, self.env_stages[j + 1])
            Z = self._env_close(s.env_chain[j], s.env_once[j], Z, forward=False)
        return Z

    def cpre(self, X: Node) -> Node:
        X &= self.boundary
        win = (self.sys_side & self.esc(X)) | (self.env_side & self.g.env & ~self.bad(X))
        return self.boundary & win

    def _closed(self, grp: Group, Y: Node, *, forward: bool, within: Node) -> Node:
        """``Y`` and every state of ``within`` some moves of ``grp`` after (before) it,
        exact relations (budget included)."""
        while True:
            limits.check_deadline()
            step = (self._post(grp, grp.rel, Y) if forward
                    else self._pre(grp, grp.rel, Y))
            nxt = Y | (within & step)
            if nxt == Y:
                return Y
            Y = nxt

    def reachable(self) -> Node:
        """Every reachable state of the full game: the turn starts, the states inside their
        turns — each chain group iterated to its fixpoint in the canonical order, exact
        relations (exact: a path inside a turn reorders into the canonical order with the
        same moves, condition 2, and the budget moves alike on each) — and the ERROR
        states their moves reach (ERROR has no moves), so the set is forward closed."""
        g, s = self.g, self.shape
        P = self.boundary & self.env_side
        for grp in s.env_chain:
            P = self._closed(grp, P, forward=True, within=g.live)
        Q = self.boundary & self.sys_side
        for grp in s.sys_chain:
            Q = self._closed(grp, Q, forward=True, within=g.live)
        R = self.boundary | P | Q
        return R | (g.post(R) & g.error)

    def full_winning(self, WB: Node, care: Node) -> Node:
        """The winning region of every state of ``care`` (forward closed, e.g.
        :meth:`reachable`) from ``W_B``: a system turn position wins iff some path of the
        turn ends in ``W_B``, an environment one iff none ends outside it, in ERROR or in a
        dead end.  Exact relations, each group iterated to its fixpoint, backwards through
        the canonical order (exact as in :meth:`reachable`)."""
        g, b, s = self.g, self.g.bdd, self.shape
        sys_in, env_in = care & self.sys_side, care & self.env_side
        Z = sys_in & g.pre_of(True, WB & self.env_side)
        for grp in reversed(s.sys_chain):
            Z = self._closed(grp, Z, forward=False, within=sys_in)
        bad = env_in & (~g.env | disjoin(
            b, [self._pre(grp, grp.rel, ~WB) for grp in s.env_exit]
            + [self._pre(grp, grp.rel, ~g.live) for grp in s.env_chain]))
        for grp in reversed(s.env_chain):
            bad = self._closed(grp, bad, forward=False, within=env_in)
        return g.live & care & (Z | (env_in & g.env & ~bad))


def exit_clusters(g: SymbolicGame, action: str, limit: int = EXIT_CLUSTER_NODES
                  ) -> Clusters:
    """``action``'s relation as clusters: its owners' relations conjoined in component
    order while the product stays under ``limit`` nodes; each with the current and next
    variables that no later cluster mentions (quantified right after it)."""
    groups: list[tuple[Node, set[str]]] = []
    for rel, cur in g.action_parts(action):
        if groups and len(prod := groups[-1][0] & rel) <= limit:
            groups[-1] = (prod, groups[-1][1] | cur)
        else:
            groups.append((rel, set(cur)))
    last = {v: i for i, (_, vs) in enumerate(groups) for v in vs}
    out = []
    for i, (rel, vs) in enumerate(groups):
        done = frozenset(v for v in vs if last[v] == i)
        out.append((rel, done, frozenset(g.prime[v] for v in done)))
    return tuple(out)


def _turn_game(g: SymbolicGame, shape: TurnShape) -> TurnGame:
    b = g.bdd
    vec = g.cur[shape.clock]
    env_codes = [vec.eq(b, s) for s in sorted(shape.env_states)]
    env_side = g.live & disjoin(b, env_codes)
    budget = frozenset(v for k in shape.budget for v in g.cur[k].names)
    nbudget = frozenset(g.prime[v] for v in budget)
    rels = tuple(b.exist(budget | nbudget, grp.rel) for grp in shape.sys_chain)
    clusters = {grp.actions: tuple(exit_clusters(g, a) for a in grp.actions)
                for grp in shape.sys_exit}
    return TurnGame(g, shape, env_side, g.live & ~env_side, budget, rels, b.false,
                    exit_clusters=clusters)


def _boundary(tg: TurnGame, say: Callable[[str], None], max_nodes: int, learn: bool
              ) -> tuple[Node, Node, int] | Reorder | None:
    """The reachable turn starts, the positions inside their turns after at least one chain
    move (:meth:`TurnGame.turn_image`), the number of turns; with ``learn``, a
    :class:`Reorder` instead once they pass :data:`LEARN_NODES` (and are not complete)."""
    g, b = tg.g, tg.g.bdd
    R = frontier = g.init
    inside = b.false
    steps = 0
    while frontier != b.false:
        limits.check_deadline()
        img, moved = tg.turn_image(frontier)
        inside |= moved
        frontier = img & ~R
        R |= frontier
        steps += 1
        say(f"turn steps: {steps} turns from the start, turn starts {len(R)} nodes")
        if learn and LEARN_NODES is not None and len(R) > LEARN_NODES and frontier != b.false:
            names = sifted_order(b, R, g.cur_vars)
            if names is not None:
                return Reorder(names, len(R))
        if len(R) > max_nodes:
            say(f"turn steps: not applied (turn starts past {max_nodes} nodes)")
            return None
    return R, inside, steps


def _props_ok(tg: TurnGame, R: Node, inside: Node, assumptions: Sequence[Node],
              goals: Sequence[Node]) -> str | None:
    """Condition 4 of the module doc, on the positions ``inside`` the reachable turns after
    at least one chain move (collected while the turns were imaged: GyroLTLVar2_701's
    check took 5.6 s CPU when it imaged them again)."""
    g, b = tg.g, tg.g.bdd
    env_in, sys_in = inside & tg.env_side, inside & tg.sys_side
    sides = ((env_in, R & tg.env_side), (sys_in, R & tg.sys_side))
    for P in (*assumptions, *goals):
        for inside_, starts in sides:
            if P & inside_ != b.false and (inside_ & ~P != b.false or starts & ~P != b.false):
                return "a GR(1) proposition holds on part of a turn only"
    if env_in != b.false and all(A & env_in != b.false for A in assumptions or [g.live]):
        return "an environment that never ends its turn would not lose"
    return None


@dataclass(frozen=True)
class TurnSolution:
    """The fixpoint over the turn starts and the game that gives the full region."""

    game: TurnGame
    fixpoint: Gr1Fixpoint
    assumptions: tuple[Node, ...]
    goals: tuple[Node, ...]

    @property
    def realizable(self) -> bool:
        g = self.game.g
        return (g.init & self.fixpoint.winning) != g.bdd.false

    @property
    def iterations(self) -> dict[str, int]:
        return self.fixpoint.iterations

    def reachable(self) -> Node:
        """The full game's reachable set (:meth:`TurnGame.reachable`)."""
        return self.game.reachable()

    def full_winning(self, care: Node, *, exact: bool) -> Node:
        """The full game's winning region on ``care`` (:meth:`TurnGame.full_winning`); for
        a fixpoint stopped early (the initial state lost) only with ``exact`` (the fixpoint
        is then run to its end first), else just ``W_B``'s superset on the turn starts,
        enough for the verdict."""
        fp = self.fixpoint
        tg = self.game
        if not fp.complete:
            if not exact:
                return fp.winning & care
            fp = gr1_winning(tg.g.bdd, tg.cpre, self.assumptions, self.goals,
                             care=tg.boundary)
        return tg.full_winning(fp.winning, care)


def solve_turns(g: SymbolicGame, assumptions: Sequence[Node], goals: Sequence[Node], *,
                say: Callable[[str], None], stats: dict[str, Any],
                max_nodes: int = MAX_BOUNDARY_NODES, learn: bool = False
                ) -> TurnSolution | Reorder | None:
    """The GR(1) fixpoint over the turn starts (module doc), or None where the transform
    does not apply; ``stats["turns"]`` says which, with the sizes.  With ``learn``, a
    :class:`Reorder` when the turn starts grow past :data:`LEARN_NODES`."""
    shape = find_turns(g)
    if isinstance(shape, str):
        stats["turns"] = f"off: {shape}"
        return None
    tg = _turn_game(g, shape)
    found = _boundary(tg, say, max_nodes, learn)
    if isinstance(found, Reorder):
        return found
    if found is None:
        stats["turns"] = f"off: turn starts past {max_nodes} nodes"
        return None
    R, inside, steps = found
    R &= g.live
    why = _props_ok(tg, R, inside, assumptions, goals)
    if why is not None:
        stats["turns"] = f"off: {why}"
        say(f"turn steps: not applied ({why})")
        return None
    tg = replace(tg, boundary=R)
    sys_stages, env_stages = tg.stages()
    tg = replace(tg, sys_stages=sys_stages, env_stages=env_stages)
    stats.update(turns="on", turn_starts=g.count(R), turn_start_nodes=len(R),
                 turn_steps=steps)
    say(f"turn steps: {stats['turn_starts']} turn starts ({len(R)} nodes) in {steps} "
        f"turns; {len(shape.env_chain)} + {len(shape.sys_chain)} chain groups")
    A = tuple(a & R for a in assumptions) or (R,)
    G = tuple(x & R for x in goals)
    fp = gr1_winning(g.bdd, tg.cpre, A, G, care=R, must_contain=g.init, progress=say)
    return TurnSolution(tg, fp, A, G)
