"""Composite operators that are not plain LTS algebra: ``controlled_det`` (§1.7, §3.8, §3.11)
and ``starenv`` (§1.7).

Kept here (rather than in ``ir/``) because they need a controllerSpec's controllable set; the
synthesis layer may use :func:`controlled_determinisation` too (MTSA's "legal controllers"
path for nondeterministic plants uses the same construction).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import NamedTuple

from iterplan_compiler.ir.lts import ERROR, LTS, make_lts

__all__ = ["CONTROL_ACTION", "STAR_ACTION", "controlled_determinisation", "eliminate_tau",
           "star_environment"]

#: The label MTSA's controlled determinisation adds: the environment "hands the turn" to the
#: controller in a knowledge state where some possible plant state offers no uncontrollable move.
CONTROL_ACTION = "-1"


class _Node(NamedTuple):
    states: frozenset[int]
    handed: bool  # True: the copy reached by `-1` (only controllable moves leave it)


def controlled_determinisation(lts: LTS, controllable: Iterable[str],
                               name: str | None = None) -> LTS:
    """MTSA's *controllable determinisation* of a nondeterministic plant (adds action ``-1``).

    A knowledge-set construction over the possible current plant states ``S`` (initially
    ``{s0}``), made deterministic by separating the two players' moves:

    * *mixed* states of ``S`` are those with some uncontrollable transition; an uncontrollable
      action ``u`` enabled by some mixed state leads to the set of all its ``u``-successors
      (from the mixed states);
    * if some state of ``S`` is not mixed (it offers only controllable moves, or none), an
      uncontrollable ``-1`` leads to a copy of ``S`` in which the controller moves;
      otherwise the controller moves from ``S`` itself;
    * a controllable action ``c`` is offered only if **every** state of ``S`` enables it
      (the controller does not know which one it is in), and leads to the union of the
      ``c``-successors.

    ``-1`` is added to the alphabet even when no state needs it.  A knowledge set that is
    exactly ``{ERROR}`` is ERROR.  The input should be nondeterministic; MTSA applies the
    operator only then (a deterministic plant is returned unchanged by the caller).  The
    result is deterministic by construction.
    """
    ctrl = frozenset(controllable)
    alphabet = set(lts.alphabet)
    uncontrollable = sorted(a for a in alphabet if a not in ctrl)
    controllable_here = sorted(a for a in alphabet if a in ctrl)
    succ: list[dict[str, set[int]]] = [dict() for _ in range(lts.num_states)]
    for s, a, t in lts.transitions:
        succ[s].setdefault(a, set()).add(t)

    def post(s: int, a: str) -> set[int]:
        return succ[s].get(a, set()) if s != ERROR else set()

    index: dict[_Node, int] = {}
    order: list[_Node] = []
    trans: list[tuple[int, str, int]] = []

    def node_id(n: _Node) -> int:
        if n.states == frozenset({ERROR}) and not n.handed:
            return ERROR
        if n not in index:
            index[n] = len(order)
            order.append(n)
        return index[n]

    node_id(_Node(frozenset({lts.initial}), False))
    i = 0
    while i < len(order):
        node = order[i]
        src = i
        i += 1
        if node.handed:
            continue  # its controllable moves were added with its parent
        mixed = [s for s in sorted(node.states)
                 if s != ERROR and any(post(s, u) for u in uncontrollable)]
        for u in uncontrollable:
            targets: set[int] = set()
            for s in mixed:
                targets |= post(s, u)
            if targets:
                trans.append((src, u, node_id(_Node(frozenset(targets), False))))
        origin = src
        if len(mixed) != len(node.states):
            origin = node_id(_Node(node.states, True))
            trans.append((src, CONTROL_ACTION, origin))
        for c in controllable_here:
            targets = set()
            for s in node.states:
                image = post(s, c)
                if not image:
                    break
                targets |= image
            else:
                if targets:
                    trans.append((origin, c, node_id(_Node(frozenset(targets), False))))
    names = tuple("{" + ",".join(str(s) for s in sorted(n.states)) + "}" + ("'" if n.handed else "")
                  for n in order)
    return make_lts(name or lts.name, len(order), trans, alphabet | {CONTROL_ACTION},
                    initial=0, state_names=names)


def eliminate_tau(lts: LTS, name: str | None = None) -> LTS:
    """A tau-free, possibly nondeterministic LTS with the same weak moves as ``lts``.

    ``s -a-> t`` for every ``s' -a-> t'`` with ``s'`` tau-reachable from ``s`` and ``t``
    tau-reachable from ``t'`` (ERROR stays ERROR); a state is END if it tau-reaches an END
    state.  This is what MTSA's "partial observability" path feeds to the controlled
    determinisation (§3.8: hidden actions are unobservable to the controller).  A tau path
    that ends in ERROR is dropped (the controller cannot see or prevent it; MTSA's treatment
    of that corner is not documented).  The alphabet loses ``tau``.
    """
    from iterplan_compiler.ir.lts import TAU
    from iterplan_compiler.ir.minimise import tau_closure

    closure = tau_closure(lts)
    succ: list[list[tuple[str, int]]] = [[] for _ in range(lts.num_states)]
    for s, a, t in lts.transitions:
        if a != TAU:
            succ[s].append((a, t))
    trans: set[tuple[int, str, int]] = set()
    ends: set[int] = set()
    for s in range(lts.num_states):
        for m in closure[s]:
            if m == ERROR:
                continue
            if m in lts.end_states:
                ends.add(s)
            for a, t in succ[m]:
                if t == ERROR:
                    trans.add((s, a, ERROR))
                else:
                    trans.update((s, a, u) for u in closure[t] if u != ERROR)
    return make_lts(name or lts.name, lts.num_states, sorted(trans),
                    set(lts.alphabet) - {TAU}, lts.initial, sorted(ends), lts.state_names)


#: The label MTSA's starred environment model puts before each state's moves: the Java text of
#: the (empty, for an LTS) set of maybe-actions chosen in that state.
STAR_ACTION = "[]"


def star_environment(lts: LTS, name: str | None = None) -> LTS:
    """MTSA's ``starenv`` of an LTS (§1.7): the *starred environment model*.

    For an MTS, every state with moves first chooses which maybe-actions to make required (one
    ``[set]`` action per subset), then moves.  An LTS has no maybe-actions, so each state with
    outgoing transitions gets a single ``[]`` move to a copy of itself that carries the
    original moves (into the original states); states without moves (STOP, END, ERROR) are
    unchanged.  ``[]`` joins the alphabet.
    """
    has_moves = sorted({s for s, _, _ in lts.transitions})
    copy = {s: lts.num_states + i for i, s in enumerate(has_moves)}
    trans = [(s, STAR_ACTION, copy[s]) for s in has_moves]
    trans += [(copy[s], a, t) for s, a, t in lts.transitions]
    names = None
    if lts.state_names is not None:
        names = [*lts.state_names, *(lts.state_names[s] + "*" for s in has_moves)]
    return make_lts(name or lts.name, lts.num_states + len(has_moves), trans,
                    set(lts.alphabet) | {STAR_ACTION}, lts.initial, lts.end_states, names)
