"""Parallel composition of explicit LTSs (MTSA semantics, ``mtsa-semantics.md`` §2.5).

Contract of :func:`compose`:

* a non-tau label ``x`` fires in a product state iff every component whose alphabet contains
  ``x`` has an ``x``-move from its current state; all those components move together (every
  combination of their nondeterministic choices), the others stay put;
* labels owned by one component, and every ``tau``, interleave (tau never synchronises);
* if any moving component enters ERROR the product enters its single ERROR (target ``-1``);
* a product state is an END state iff every component is in one of its END states;
* only reachable product states are built; states are numbered breadth-first from the
  initial tuple, visiting the moves of a state in sorted ``(label, target tuple)`` order, so the
  result is canonical for the given list of components;
* ``priority=(labels, high)`` implements ``<< labels`` (``high=True``: when a listed label is
  enabled only listed labels fire) and ``>> labels`` (``high=False``: listed labels fire only
  when nothing else, tau included, is enabled).  Listed labels match exactly or as a dotted
  prefix (``a`` matches ``a.1``), like every MTSA label set;
* ``max_states`` bounds the number of product states; exceeding it raises
  :class:`StateExplosion` (a plain exception value the caller turns into a diagnostic).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from itertools import product as _cartesian

from .lts import ERROR, LTS, TAU

__all__ = ["StateExplosion", "compose", "explore_product", "label_matcher", "Priority"]

Priority = tuple[Iterable[str], bool]

# A product state is a tuple of component states.
StateTuple = tuple[int, ...]


class StateExplosion(Exception):
    """Raised when a product grows past ``max_states`` states."""

    def __init__(self, name: str, limit: int) -> None:
        super().__init__(f"composition of {name} exceeds {limit} states")
        self.name = name
        self.limit = limit


def label_matcher(labels: Iterable[str]) -> Callable[[str], bool]:
    """Return a predicate: does a label equal, or have as dotted prefix, a listed label?

    This is MTSA's label-set membership used by hiding, exposing and priorities (§2.3).
    """
    exact = frozenset(labels)

    def matches(label: str) -> bool:
        if label in exact:
            return True
        # Walk the dotted prefixes of ``label`` ("a.b.c" -> "a", "a.b"); cheaper than testing
        # every listed label against the label when the set is large.
        i = label.find(".")
        while i != -1:
            if label[:i] in exact:
                return True
            i = label.find(".", i + 1)
        return False

    return matches


def explore_product(
    components: Sequence[LTS],
    priority: Priority | None = None,
    *,
    max_states: int | None = None,
    name: str = "product",
) -> tuple[list[StateTuple], list[tuple[int, str, int]], list[int]]:
    """Explore the reachable product and return ``(tuples, transitions, end_states)``.

    ``tuples[i]`` is the component-state tuple of product state ``i`` (canonical BFS order);
    transitions are ``(source, label, target)`` with target ``ERROR`` for the error state.
    Exposed for analyses (legality, projections) that need to know which component states a
    product state stands for.
    """
    n = len(components)
    if n == 0:
        return [()], [], [0]

    # Who owns each non-tau label: the components that must agree for it to fire.
    owners: dict[str, list[int]] = {}
    for i, c in enumerate(components):
        for a in c.alphabet:
            owners.setdefault(a, []).append(i)

    # Per component and state, precompute:
    #   local[i][s]  : [(label, [targets])] for tau and labels owned only by component i
    #   lead[i][s]   : [(label, [targets], other_owner_indices)] for shared labels whose lowest
    #                  owner is i (the lowest owner "drives" the synchronisation)
    #   lookup[i][s] : {label: [targets]} for shared labels (consulted by the driver)
    local: list[list[list[tuple[str, list[int]]]]] = []
    lead: list[list[list[tuple[str, list[int], list[int]]]]] = []
    lookup: list[list[dict[str, list[int]]]] = []
    for i, c in enumerate(components):
        by_state: list[dict[str, list[int]]] = [{} for _ in range(c.num_states)]
        for s, a, t in c.transitions:
            by_state[s].setdefault(a, []).append(t)
        loc_i: list[list[tuple[str, list[int]]]] = []
        lead_i: list[list[tuple[str, list[int], list[int]]]] = []
        look_i: list[dict[str, list[int]]] = []
        for moves in by_state:
            loc: list[tuple[str, list[int]]] = []
            led: list[tuple[str, list[int], list[int]]] = []
            look: dict[str, list[int]] = {}
            for a, ts in moves.items():
                own = owners.get(a)
                if a == TAU or own is None or len(own) == 1:
                    # A label used on a transition but missing from the alphabet cannot happen
                    # for make_lts-built machines; treat it as private to stay total.
                    loc.append((a, ts))
                else:
                    look[a] = ts
                    if own[0] == i:
                        led.append((a, ts, own[1:]))
            loc_i.append(loc)
            lead_i.append(led)
            look_i.append(look)
        local.append(loc_i)
        lead.append(lead_i)
        lookup.append(look_i)

    # Shared labels the lowest owner cannot drive because it has no move: nothing to do, the
    # label is simply not enabled.  Shared labels with no transition in some owner never fire.

    prio_match: Callable[[str], bool] | None = None
    prio_high = False
    if priority is not None:
        labels, prio_high = priority
        prio_match = label_matcher(labels)

    start: StateTuple = tuple(c.initial for c in components)
    index: dict[StateTuple, int] = {start: 0}
    order: list[StateTuple] = [start]
    transitions: list[tuple[int, str, int]] = []
    end_states: list[int] = []
    ends = [c.end_states for c in components]

    head = 0
    while head < len(order):
        cur = order[head]
        src = head
        head += 1
        # Collect moves as (label, target tuple); ERROR is the empty tuple, which sorts before
        # every real tuple, so a plain tuple sort gives the canonical visiting order.
        moves: list[tuple[str, StateTuple]] = []
        for i in range(n):
            si = cur[i]
            for a, ts in local[i][si]:
                for t in ts:
                    if t == ERROR:
                        moves.append((a, ()))
                    else:
                        moves.append((a, cur[:i] + (t,) + cur[i + 1:]))
            for a, ts, others in lead[i][si]:
                choices: list[list[int]] = [ts]
                ok = True
                for j in others:
                    tj = lookup[j][cur[j]].get(a)
                    if tj is None:
                        ok = False
                        break
                    choices.append(tj)
                if not ok:
                    continue
                movers = (i, *others)
                for combo in _cartesian(*choices):
                    if ERROR in combo:
                        moves.append((a, ()))
                        continue
                    nxt = list(cur)
                    for k, t in zip(movers, combo, strict=True):
                        nxt[k] = t
                    moves.append((a, tuple(nxt)))
        if prio_match is not None and moves:
            flagged = [prio_match(a) if a != TAU else False for a, _ in moves]
            if prio_high:
                if any(flagged):
                    moves = [m for m, f in zip(moves, flagged, strict=True) if f]
            elif not all(flagged):
                moves = [m for m, f in zip(moves, flagged, strict=True) if not f]
        if not moves:
            if all(cur[i] in ends[i] for i in range(n)):
                end_states.append(src)
            continue
        moves.sort()
        out: list[tuple[str, int]] = []
        prev: tuple[str, StateTuple] | None = None
        for mv in moves:
            if mv == prev:  # duplicates are adjacent after sorting
                continue
            prev = mv
            a, tgt = mv
            if not tgt:
                out.append((a, ERROR))
                continue
            k = index.get(tgt)
            if k is None:
                k = len(order)
                if max_states is not None and k >= max_states:
                    raise StateExplosion(name, max_states)
                index[tgt] = k
                order.append(tgt)
            out.append((a, k))
        # Indices of already-known targets may be out of order within a label: sort so the
        # transition list comes out globally sorted (the canonical LTS form) with no extra pass.
        out.sort()
        transitions.extend([(src, a, k) for a, k in out])
    return order, transitions, end_states


def compose(
    components: Sequence[LTS],
    name: str,
    priority: Priority | None = None,
    *,
    max_states: int | None = None,
) -> LTS:
    """Return the MTSA parallel composition of ``components`` named ``name`` (module doc).

    The alphabet is the union of the component alphabets (labels that never fire included).
    An empty component list gives the one-state STOP-like machine with an empty alphabet.
    """
    order, transitions, end_states = explore_product(
        components, priority, max_states=max_states, name=name
    )
    alphabet: set[str] = set()
    for c in components:
        alphabet |= c.alphabet
        alphabet |= c.labels_used()  # only differs for machines not built by make_lts
    alphabet.discard(TAU)
    # explore_product emits transitions sorted and unique and every label belongs to some
    # component alphabet, so the canonical form holds without make_lts's re-sort.
    return LTS(name, len(order), tuple(transitions), frozenset(alphabet), 0,
               frozenset(end_states))
