"""Macro steps: the MTSA game with its controller-only chains compressed (issue 12).

Equation.  For the game of :mod:`symbolic_game` on ``care`` (the reachable states, or all
live ones), with GR(1) propositions ``P`` (the assumptions and the goals)::

    C    ⊆ care ∧ ¬Env ∖ init   the chain states: only the controller moves there, and for
                                every P either C ∧ P = ∅, or C ⊆ P and every state outside
                                C with a successor in C satisfies P (P is *absorbed*)
    V    = care ∖ C,   Ent = C ∧ post(V)            (where a play enters a chain)
    M(e, v)   : e ∈ Ent, v ∈ V, and a controllable path e → c_1 → … → v with every c_i ∈ C
    Esc(X)    = {e ∈ Ent | ∃v. M(e, v) ∧ X(v)}
    CPre_V(X) = V ∧ CPre(X_V ∪ Esc(X_V)),   X_V = X ∧ V
    W         = W_V ∪ Attr_C(W_V),   Attr_C(S) = μA. S ∨ (C ∧ CPre(A))

where ``W_V`` is the GR(1) fixpoint (:func:`fixpoint.gr1_winning`) over ``V`` with
``CPre_V`` and the propositions ``∧ V``.  Condition: ``C`` has no infinite controllable path
(``νA. C ∧ CPre(A) = ∅``, checked).

Why ``W`` is the winning region.  A chain state belongs to the controller alone, so a play
that enters ``C`` at ``e`` (by either player's move) is continued by the controller alone
until it leaves ``C`` — after finitely many steps, as ``C`` has no infinite controllable
path — at some ``v`` with ``M(e, v)``, or it ends in a dead end of ``C`` (lost, and then
``M`` has no pair from that path).  So the full game and the game on ``V`` whose moves are
the moves inside ``V`` and "into ``e``, then to any ``v`` with ``M(e, v)``" (the
controller's choice) have the same plays up to the chain segments, and strategies
translate both ways (follow the chain the strategy picks; pick the exit its chain reaches).
``CPre_V`` is that game's controllable predecessor: an environment state needs each
uncontrollable successor in ``X``, or to be an entry with an exit in ``X``; a controller
state one controllable successor that is.  The winning condition is the same on both
plays: a proposition false on ``C`` is seen on the same ``V``-states; an absorbed one holds
on the state before every chain, so the full play sees it infinitely often iff the
compressed one does.  Hence ``W ∧ V = W_V``; a chain state wins iff the controller can walk
``C`` to a winning ``V``-state: ``Attr_C(W_V)``.  The controller extraction then runs on
``W`` as before (the rank layers of the full game).

Construction (:func:`chain_states`).  Start from ``care ∧ ctrl_owned ∖ init`` (the initial
state stays in ``V``, so the engine's early stop ``init ∉ Z`` still applies); each
proposition is absorbed if most candidates satisfy it (``C ∧= P``), else excluded
(``C ∧= ¬P``); then the states entered from outside through a state where an absorbed ``P``
is false are removed (``C ∖= post(entries ∖ P)``; one pass: the removed states satisfy
every absorbed ``P``, so the entries they create are good).  SYNTECH15 specs: the
``Clock``/``Turns`` turn structure makes every state inside a system turn (after a
controlled action other than ``tick``) a chain state; the goals (``tick && …``) and the
``tock && …`` assumptions are false there, ``A_clock = Tock`` holds throughout the turn and
is absorbed.

``M`` (:func:`exit_relation`) is computed forward with the entry kept in a third copy of the
state variables (``x''``, inserted right below each next variable so the three copies stay
interleaved): ``F_0(e'', x) = Ent(e) ∧ x = e``, ``F_{k+1} = post_ctrl(F_k ∧ C(x)) ∧ C(x)``
(new pairs only), ``M = ∨_k post_ctrl(F_k ∧ C(x)) ∧ V(x)``; then
``Esc(X) = Ent ∧ (∃x. M(e'', x) ∧ X(x))[e'' := e]`` — one relational product per CPre.
Only the variables a controllable move modifies (:func:`modified_vars`) get a copy: any
other keeps ``x = e`` along every chain and stands for its own entry value, so ``∃x`` and
``[e'' := e]`` range over the copied ones.

Measured on GyroLTL_637 (2,308,414 reachable states): ``C`` has 2,261,055, ``V`` 47,359
(5.5 k nodes, against 12.6 k for ``care``), ``Ent`` 67,861; ``M`` takes 17 steps, 10 s CPU,
145 k nodes.  The fixpoint over ``V``: 85 CPre in 4.3 s (163 νX steps), against 620 νX
steps and 57.6 s for the full game (same process, load 2).  Computing ``Esc`` per CPre by
an attractor into ``C`` instead of through ``M`` (no third copy) was measured too: the same
85 CPre took 253 s — each attractor layer costs as much as a full CPre of today's game, and
``Attr_C`` of an iterate is as large as the full game's iterate (98 k nodes).  Hence the
precomputed relation.

When it is not applied (``solve_macro`` returns None, the caller runs the full game):
``MacroSteps.OFF``; fewer chain states than :data:`MIN_CHAIN_SHARE` of ``care``; a
controllable cycle inside ``C``; ``M`` past :data:`MAX_EXIT_NODES`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

from iterplan_compiler import limits
from iterplan_compiler.symbolic.bdd import and_exists
from iterplan_compiler.synthesis.fixpoint import Gr1Fixpoint, gr1_winning
from iterplan_compiler.synthesis.symbolic_game import SymbolicGame

__all__ = ["MAX_EXIT_NODES", "MIN_CHAIN_SHARE", "MacroGame", "chain_states", "exit_relation",
           "modified_vars", "solve_macro"]

Node = Any

#: apply only if at least this share of ``care`` (in states) are chain states: a game with
#: few chains gains little and would pay for ``M``.  The SYNTECH15 games measured have
#: 90–98 % (GyroLTL_637 98 %, GyroLTLVar3_702 98 %, GyroLTL_588 90 %), the paper's tasks
#: 19–36 % (Cover 12 of 33 states): those keep the full game and their compile time
MIN_CHAIN_SHARE = 0.5
#: give up on ``M`` (and on the transform) once it, or the set of (entry, position) pairs,
#: passes this many nodes.  GyroLTL_637: at most 159 k; GyroLTL_595 (reachability run to
#: the end): 895 k pairs after the first step, 9.5 M after the sixth (630 s CPU)
MAX_EXIT_NODES = 500_000


@dataclass(frozen=True)
class MacroGame:
    """The compressed game: ``V``, the entries and ``M`` over a third copy of the
    ``copied`` variables (:func:`modified_vars`)."""

    g: SymbolicGame
    chain: Node
    v: Node
    entries: Node
    exits: Node
    from_copy: dict[str, Node]
    copied: frozenset[str]

    def esc(self, X: Node) -> Node:
        """The entries from which the controller can walk ``C`` to a state of ``X ⊆ V``."""
        b = self.g.bdd
        return self.entries & b.let(self.from_copy,
                                    and_exists(b, self.exits, X, self.copied))

    def cpre(self, X: Node) -> Node:
        """``CPre_V`` (module doc)."""
        xv = X & self.v
        return self.v & self.g.cpre(xv | self.esc(xv))

    def attractor(self, S: Node) -> Node:
        """``Attr_C(S)``: ``S`` and the chain states that can walk ``C`` into it."""
        g, b = self.g, self.g.bdd
        out, layer = S, S
        while layer != b.false:
            limits.check_deadline()
            layer = self.chain & g.pre_of(True, layer) & ~out
            out |= layer
        return out


def chain_states(g: SymbolicGame, care: Node, props: Sequence[Node]) -> Node:
    """``C`` of the module doc: controller-only states, every proposition absorbed or
    excluded, bad entries removed."""
    b = g.bdd
    cand = care & g.ctrl_owned & ~g.init
    C = cand
    absorbed = []
    for P in props:
        if g.count(cand & P) > g.count(cand & ~P):
            C &= P
            absorbed.append(P)
        else:
            C &= ~P
    if C == b.false or not absorbed:
        return C
    entries = care & ~C & g.pre_any(C)
    bad = b.false
    for P in absorbed:
        bad |= entries & ~P
    return C & ~g.post(bad) if bad != b.false else C


def acyclic(g: SymbolicGame, C: Node) -> bool:
    """``C`` has no infinite controllable path: ``νA. C ∧ ∃ctrl succ ∈ A`` is empty."""
    b = g.bdd
    A = C
    while A != b.false:
        limits.check_deadline()
        nxt = A & g.pre_of(True, A)
        if nxt == A:
            return False
        A = nxt
    return True


def modified_vars(g: SymbolicGame) -> frozenset[str]:
    """The current variables some controllable move may change — the only ones ``M`` keeps
    a copy of.  Every controllable group counts (the chain moves and the exit moves such
    as ``tick``), with all its owners' variables (a fluent variable shared with a machine
    outside the group counts once an owner writes it), less those its relation keeps on
    every move (``x' = x``; a framed group owns every variable).

    A variable no controllable move changes keeps its entry value along every chain, so
    ``x = e`` on it throughout: it stands for its own entry copy (no copy, no identity
    constraint), and :meth:`MacroGame.esc` quantifies and renames the copied ones only.
    Measured (docs/synthesis.md, "Macro steps"): GyroLTL_637 copies 60 of 87 variables,
    ``M`` 145.6 k -> 113.6 k nodes, 9.6 -> 7.3 s CPU, verdict 26.0 -> 23.6 s (medians of 3,
    alternated; GyroLTL_700 26.3 -> 23.0 s); restricting the test to moves from ``C``
    copies 59.  GyroLTL_595's pairs shrink by a quarter only (still past the cap)."""
    b = g.bdd
    out: set[str] = set()
    for grp in g.groups:
        if not grp.controllable:
            continue
        for c in sorted(grp.cur_vars - out):
            if grp.rel & ~b.var(c).equiv(b.var(g.prime[c])) != b.false:
                out.add(c)
    return frozenset(out)


def _copy_vars(g: SymbolicGame, copied: frozenset[str]
               ) -> tuple[dict[str, Node], dict[str, Node], set[str]]:
    """The third copy ``x''`` of the ``copied`` current variables, each right below its next
    variable (``dd.cudd``; ``dd.autoref`` appends them); ``(to_copy, from_copy, names)``."""
    b = g.bdd
    names = {c: g.prime[c] + "'" for c in copied}
    for c in sorted(copied, key=lambda v: -b.level_of_var(g.prime[v])):
        if names[c] in b.vars:
            continue
        if hasattr(b, "insert_var"):
            b.insert_var(names[c], b.level_of_var(g.prime[c]) + 1)
        else:
            b.declare(names[c])
    to_copy = {c: b.var(n) for c, n in names.items()}
    from_copy = {n: b.var(c) for c, n in names.items()}
    return to_copy, from_copy, set(names.values())


def exit_relation(g: SymbolicGame, C: Node, V: Node, entries: Node,
                  to_copy: dict[str, Node], max_nodes: int = MAX_EXIT_NODES
                  ) -> tuple[Node | None, int]:
    """``M(e'', v)`` (module doc), or None past ``max_nodes``; also the number of steps."""
    b = g.bdd
    same = b.true
    for c, cc in to_copy.items():
        x = b.var(c)
        same &= (x & cc) | (~x & ~cc)
    F = b.let(to_copy, entries) & same
    seen, M, steps = F, b.false, 0
    while F != b.false:
        limits.check_deadline()
        img = g.post_of(True, F & C)
        M |= img & V
        F = img & C & ~seen
        seen |= F
        steps += 1
        if len(M) > max_nodes or len(seen) > max_nodes:
            return None, steps
    return M, steps


def solve_macro(g: SymbolicGame, care: Node, assumptions: Sequence[Node],
                goals: Sequence[Node], *, say: Callable[[str], None], stats: dict[str, Any],
                min_share: float = MIN_CHAIN_SHARE,
                max_nodes: int = MAX_EXIT_NODES) -> Gr1Fixpoint | None:
    """The fixpoint of the compressed game with ``winning`` = the full winning region ``W``
    (the iteration counts are those over ``V``), or None where the transform does not apply
    (module doc); ``stats["macro"]`` says which, with the sizes."""
    A = list(assumptions) or [g.live]
    C = chain_states(g, care, [*A, *goals])
    n_chain = g.count(C)
    stats["macro_chain_states"] = n_chain
    if n_chain == 0 or n_chain < min_share * g.count(care):
        stats["macro"] = "off: few chain states"
        return None
    if not acyclic(g, C):
        stats["macro"] = "off: controllable cycle among the chain states"
        say("macro steps: not applied (a controllable cycle among the chain states)")
        return None
    V = care & ~C
    entries = C & g.post(V)
    copied = modified_vars(g)
    stats["macro_copied_vars"] = f"{len(copied)}/{len(g.cur_vars)}"
    to_copy, from_copy, _ = _copy_vars(g, copied)
    M, steps = exit_relation(g, C, V, entries, to_copy, max_nodes)
    if M is None:
        stats["macro"] = f"off: exit relation past {max_nodes} nodes"
        say(f"macro steps: not applied (exit relation past {max_nodes} nodes)")
        return None
    stats.update(macro="on", macro_exit_nodes=len(M), macro_exit_steps=steps,
                 macro_v_states=g.count(V))
    say(f"macro steps: {n_chain} chain states, {stats['macro_v_states']} others, exit "
        f"relation {len(M)} nodes in {steps} steps")
    mg = MacroGame(g, C, V, entries, M, from_copy, copied)
    fp = gr1_winning(g.bdd, mg.cpre, [a & V for a in A], [x & V for x in goals],
                     care=V, must_contain=g.init, progress=say)
    if not fp.complete:
        return fp
    return replace(fp, winning=mg.attractor(fp.winning & V))
