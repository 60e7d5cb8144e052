"""The explicit labelled transition system (LTS) every stage reads and writes.

Conventions (MTSA's):

* states are ``0 .. num_states-1``; ``initial`` is usually 0;
* the ERROR state is not counted in ``num_states``: a transition whose target is
  :data:`ERROR` (``-1``) enters it; ERROR has no outgoing transitions;
* the silent action is :data:`TAU` and is never part of ``alphabet``;
* ``alphabet`` may contain labels that label no transition (they still synchronise and so
  block partners in parallel composition);
* ``end_states`` are the states reached by ``END`` (successful termination), used by
  sequential composition ``P;Q``.

An :class:`LTS` is immutable and hashable; ``transitions`` is a sorted tuple without duplicates
so equal machines compare equal and every printed output is byte-stable.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

ERROR = -1
TAU = "tau"

Transition = tuple[int, str, int]


@dataclass(frozen=True, slots=True)
class LTS:
    """An explicit LTS.  Build with :func:`make_lts` to get the canonical form."""

    name: str
    num_states: int
    transitions: tuple[Transition, ...]
    alphabet: frozenset[str]
    initial: int = 0
    end_states: frozenset[int] = field(default=frozenset())
    state_names: tuple[str, ...] | None = None

    @property
    def has_error(self) -> bool:
        """True if some transition enters ERROR."""
        return any(t == ERROR for _, _, t in self.transitions)

    @property
    def num_transitions(self) -> int:
        return len(self.transitions)

    def out_edges(self) -> dict[int, list[tuple[str, int]]]:
        """Return ``{state: [(label, target), ...]}`` (built on each call; cache it yourself)."""
        out: dict[int, list[tuple[str, int]]] = {s: [] for s in range(self.num_states)}
        for s, a, t in self.transitions:
            out[s].append((a, t))
        return out

    def labels_used(self) -> frozenset[str]:
        """Labels that occur on some transition (including tau)."""
        return frozenset(a for _, a, _ in self.transitions)


def make_lts(
    name: str,
    num_states: int,
    transitions: Iterable[Transition],
    alphabet: Iterable[str] = (),
    initial: int = 0,
    end_states: Iterable[int] = (),
    state_names: Iterable[str] | None = None,
) -> LTS:
    """Build an LTS in canonical form: transitions sorted and unique, alphabet closed.

    The alphabet is extended with every non-tau label used by a transition.
    """
    trans = tuple(sorted(set(transitions)))
    alpha = set(alphabet) | {a for _, a, _ in trans if a != TAU}
    alpha.discard(TAU)
    for s, _, t in trans:
        if not (0 <= s < num_states) or not (t == ERROR or 0 <= t < num_states):
            raise ValueError(f"transition ({s}, _, {t}) outside 0..{num_states - 1}")
    names = tuple(state_names) if state_names is not None else None
    return LTS(name, num_states, trans, frozenset(alpha), initial, frozenset(end_states), names)


def renamed(lts: LTS, name: str) -> LTS:
    """Return the same machine under another name."""
    return LTS(name, lts.num_states, lts.transitions, lts.alphabet, lts.initial,
               lts.end_states, lts.state_names)


def reachable(lts: LTS) -> LTS:
    """Drop states unreachable from the initial state and renumber in BFS order.

    BFS numbering from the initial state (which becomes 0), visiting successors in sorted
    (label, target) order, makes the numbering canonical for a given machine.
    """
    out = lts.out_edges()
    order = [lts.initial]
    index = {lts.initial: 0}
    i = 0
    while i < len(order):
        s = order[i]
        i += 1
        for _, t in sorted(out[s]):
            if t != ERROR and t not in index:
                index[t] = len(order)
                order.append(t)
    trans = [
        (index[s], a, ERROR if t == ERROR else index[t])
        for s, a, t in lts.transitions
        if s in index
    ]
    names = None
    if lts.state_names is not None:
        names = [lts.state_names[s] for s in order]
    return make_lts(
        lts.name, len(order), trans, lts.alphabet, 0,
        (index[s] for s in lts.end_states if s in index), names,
    )


def relabel_map(lts: LTS, mapping: Mapping[str, Iterable[str]]) -> LTS:
    """Apply a relabelling that maps a label to one or more new labels (MTSA ``/{}``).

    Labels not in ``mapping`` are unchanged.  This is the primitive; the front-end expands
    prefix relabelling (``new/old`` matching ``old.x``) into an explicit mapping.
    """
    def image(a: str) -> Iterable[str]:
        return mapping.get(a, (a,))

    trans = [(s, b, t) for s, a, t in lts.transitions for b in image(a)]
    alpha = {b for a in lts.alphabet for b in image(a)}
    return make_lts(lts.name, lts.num_states, trans, alpha, lts.initial, lts.end_states,
                    lts.state_names)
