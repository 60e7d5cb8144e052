"""Parallel composition of explicit LTSs (MTSA semantics, ``mtsa-semantics.md`` §2.5).

Contract of :func:`compose`:

* a non-tau label ``x`` fires in a product state iff every component whose alphabet contains
  ``x`` has an ``x``-move from its current state; all those components move together (every
  combination of their nondeterministic choices), the others stay put;
* labels owned by one component, and every ``tau``, interleave (tau never synchronises);
* if any moving component enters ERROR the product enters its single ERROR (target ``-1``);
* a product state is END iff it has no move, every component that has END states is in one,
  and every label of the other components belongs to such a terminating component (§2.5);
  all END tuples are merged into one END state (MTSA has a single END);
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

from iterplan_compiler import limits

from .lts import ERROR, LTS, TAU

__all__ = ["StateExplosion", "compose", "explore_product", "label_matcher", "Priority"]

Priority = tuple[Iterable[str], bool]

# A product state is a tuple of component states.
StateTuple = tuple[int, ...]


class StateExplosion(Exception):
    """Raised when a product grows past ``max_states`` states."""

    def __init__(self, name: str, limit: int) -> None:
        super().__init__(f"composition of {name} exceeds {limit:,} states (the state limit; "
                         "raise it with --max-states)")
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
    product state stands for.  Unlike :func:`compose`, END tuples are not merged here.
    """
    codes, transitions, end_states, decode = _explore(components, priority, max_states, name)
    return [decode(c) for c in codes], transitions, end_states


def _explore(
    components: Sequence[LTS],
    priority: Priority | None,
    max_states: int | None,
    name: str,
) -> tuple[list[int], list[tuple[int, str, int]], list[int], Callable[[int], StateTuple]]:
    """The exploration behind :func:`compose` and :func:`explore_product`.

    A product state is encoded as one integer in mixed radix, component 0 most significant, so
    (a) a component move is "add a precomputed delta" instead of building a tuple and (b) the
    integer order equals the lexicographic order of state tuples, which keeps the canonical
    numbering "sorted by (label, target tuple)".  ERROR is the code -1, sorting first.
    """
    n = len(components)
    sizes = [max(c.num_states, 1) for c in components]
    weights = [1] * n
    for i in range(n - 2, -1, -1):
        weights[i] = weights[i + 1] * sizes[i + 1]

    def decode(code: int) -> StateTuple:
        out = [0] * n
        for i in range(n - 1, -1, -1):
            code, out[i] = divmod(code, sizes[i])
        return tuple(out)

    if n == 0:
        return [0], [], [], decode

    local, lead, lookup = _move_tables(components, sizes, weights)
    prio_match, prio_high = (None, False) if priority is None else (
        label_matcher(priority[0]), priority[1])

    ends, terminating, can_end = _end_condition(components)
    start = sum(c.initial * weights[i] for i, c in enumerate(components))
    index: dict[int, int] = {start: 0}
    order: list[int] = [start]
    transitions: list[tuple[int, str, int]] = []
    end_states: list[int] = []
    comp_range = range(n)

    head = 0
    while head < len(order):
        code = order[head]
        src = head
        head += 1
        cur = decode(code)
        moves = _moves(code, cur, comp_range, local, lead, lookup)
        if prio_match is not None and moves:
            moves = _prioritised(moves, prio_match, prio_high)
        if not moves:
            if can_end and all(cur[i] in ends[i] for i in terminating):
                end_states.append(src)
            continue
        moves.sort()
        out: list[tuple[str, int]] = []
        prev: tuple[str, int] | None = None
        for mv in moves:
            if mv == prev:  # duplicates are adjacent after sorting
                continue
            prev = mv
            a, tgt = mv
            if tgt == -1:
                out.append((a, ERROR))
                continue
            k = index.get(tgt)
            if k is None:
                k = len(order)
                if max_states is not None and k >= max_states:
                    raise StateExplosion(name, max_states)
                if not k & 0x3FFF:  # every 16,384 new states: progress, the time limit
                    limits.progress(f"composing {name}", k)
                    limits.check_deadline()
                index[tgt] = k
                order.append(tgt)
            out.append((a, k))
        # Indices of already-known targets may be out of order within a label: sort so the
        # transition list comes out globally sorted (the canonical LTS form) with no extra pass.
        out.sort()
        transitions.extend([(src, a, k) for a, k in out])
    return order, transitions, end_states, decode


Local = list[list[list[tuple[str, int | None]]]]
Lead = list[list[list[tuple[str, list[int | None], list[int]]]]]
Lookup = list[list[dict[str, list[int | None]]]]


def _move_tables(components: Sequence[LTS], sizes: list[int], weights: list[int]
                 ) -> tuple[Local, Lead, Lookup]:
    """The per-component move tables :func:`_explore` adds to a product code (see below)."""
    # Who owns each non-tau label: the components that must agree for it to fire.
    owners: dict[str, list[int]] = {}
    for i, c in enumerate(components):
        for a in c.alphabet:
            owners.setdefault(a, []).append(i)

    # Per component and state, precompute (a delta is (target - source) * weight, None = ERROR):
    #   local[i][s]  : [(label, delta)] for tau and labels owned only by component i
    #   lead[i][s]   : [(label, [deltas], other_owner_indices)] for shared labels whose lowest
    #                  owner is i (the lowest owner "drives" the synchronisation)
    #   lookup[i][s] : {label: [deltas]} for shared labels (consulted by the driver)
    local: Local = []
    lead: Lead = []
    lookup: Lookup = []
    for i, c in enumerate(components):
        w = weights[i]
        by_state: list[dict[str, list[int | None]]] = [{} for _ in range(sizes[i])]
        for s, a, t in c.transitions:
            by_state[s].setdefault(a, []).append(None if t == ERROR else (t - s) * w)
        loc_i: list[list[tuple[str, int | None]]] = []
        lead_i: list[list[tuple[str, list[int | None], list[int]]]] = []
        look_i: list[dict[str, list[int | None]]] = []
        for by_label in by_state:
            loc: list[tuple[str, int | None]] = []
            led: list[tuple[str, list[int | None], list[int]]] = []
            look: dict[str, list[int | None]] = {}
            for a, ds in by_label.items():
                own = owners.get(a)
                if a == TAU or own is None or len(own) == 1:
                    # A label used on a transition but missing from the alphabet cannot happen
                    # for make_lts-built machines; treat it as private to stay total.
                    loc.extend((a, d) for d in ds)
                else:
                    look[a] = ds
                    if own[0] == i:
                        led.append((a, ds, own[1:]))
            loc_i.append(loc)
            lead_i.append(led)
            look_i.append(look)
        local.append(loc_i)
        lead.append(lead_i)
        lookup.append(look_i)
    return local, lead, lookup


def _moves(code: int, cur: StateTuple, comp_range: range, local: Local, lead: Lead,
           lookup: Lookup) -> list[tuple[str, int]]:
    """The moves ``(label, target code)`` of product state ``code`` (tuple ``cur``), target
    -1 for ERROR, before priorities and with duplicates."""
    moves: list[tuple[str, int]] = []
    for i in comp_range:
        si = cur[i]
        for a, d in local[i][si]:
            moves.append((a, -1 if d is None else code + d))
        for a, ds, others in lead[i][si]:
            choices: list[list[int | None]] = [ds]
            for j in others:
                dj = lookup[j][cur[j]].get(a)
                if dj is None:
                    break
                choices.append(dj)
            else:
                if len(choices) == 2 and len(ds) == 1 and len(choices[1]) == 1:
                    d0, d1 = ds[0], choices[1][0]  # the common case, without itertools
                    moves.append((a, -1 if d0 is None or d1 is None else code + d0 + d1))
                    continue
                for combo in _cartesian(*choices):
                    if None in combo:
                        moves.append((a, -1))
                    else:
                        moves.append((a, code + sum(combo)))  # type: ignore[arg-type]
    return moves


def _prioritised(moves: list[tuple[str, int]], prio_match: Callable[[str], bool],
                 high: bool) -> list[tuple[str, int]]:
    """``>> {..}``: only the high-priority moves when there are any; ``<< {..}``: the others
    unless every move is low priority (tau is never prioritised)."""
    flagged = [prio_match(a) if a != TAU else False for a, _ in moves]
    if high:
        if any(flagged):
            return [m for m, f in zip(moves, flagged, strict=True) if f]
    elif not all(flagged):
        return [m for m, f in zip(moves, flagged, strict=True) if not f]
    return moves


def _end_condition(components: Sequence[LTS]) -> tuple[list[frozenset[int]], list[int], bool]:
    """``(end states per component, terminating components, END possible at all)``."""
    # END (§2.5): the terminating components (those with an END state) must all be in END, and
    # every label of a non-terminating component must belong to a terminating one (so that
    # nothing can move any more); with no terminating component there is no END at all.
    ends = [c.end_states for c in components]
    terminating = [i for i, c in enumerate(components) if c.end_states]
    term_alpha: set[str] = set()
    for i in terminating:
        term_alpha |= components[i].alphabet
    can_end = bool(terminating) and all(
        c.alphabet <= term_alpha for c in components if not c.end_states)
    return ends, terminating, can_end


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
    order, transitions, end_states, _ = _explore(components, priority, max_states, name)
    alphabet: set[str] = set()
    for c in components:
        alphabet |= c.alphabet
        alphabet |= c.labels_used()  # only differs for machines not built by make_lts
    alphabet.discard(TAU)
    num_states = len(order)
    if len(end_states) > 1:
        transitions, num_states, end_states = _merge_ends(transitions, num_states, end_states)
    # _explore emits transitions sorted and unique and every label belongs to some
    # component alphabet, so the canonical form holds without make_lts's re-sort.
    return LTS(name, num_states, tuple(transitions), frozenset(alphabet), 0,
               frozenset(end_states))


def _merge_ends(
    transitions: list[tuple[int, str, int]], num_states: int, end_states: list[int]
) -> tuple[list[tuple[int, str, int]], int, list[int]]:
    """Merge all END states into the first one (MTSA has a single END state, §2.5).

    END states have no outgoing moves, so only targets change; the other states keep their
    relative order, so the numbering stays deterministic.
    """
    keep = end_states[0]
    drop = set(end_states[1:])
    remap: list[int] = []
    k = 0
    for old in range(num_states):
        if old in drop:
            remap.append(-2)  # patched below, once the kept state's new index is known
        else:
            remap.append(k)
            k += 1
    for d in drop:
        remap[d] = remap[keep]
    merged = sorted({(remap[s], a, t if t == ERROR else remap[t]) for s, a, t in transitions})
    return merged, k, [remap[keep]]
