"""Alphabet operators of FSP on explicit LTSs (``mtsa-semantics.md`` §2.3, §2.4, §1.5).

Every function is pure: it takes an :class:`~iterplan_compiler.ir.lts.LTS` and returns a new
one.  Label sets follow MTSA's membership rule: a listed label ``x`` matches ``x`` itself and
every label with ``x`` as a dotted prefix (``x.1``, ``x.a.b``).  ``tau`` is never renamed,
hidden or exposed.
"""

from __future__ import annotations

from collections.abc import Iterable

from .compose import label_matcher
from .lts import ERROR, LTS, TAU, make_lts, reachable

__all__ = [
    "NotDeterministic",
    "NotSequential",
    "apply_priority",
    "expose",
    "extend_alphabet",
    "hide",
    "is_deterministic",
    "prefix_labels",
    "property_complete",
    "sequential",
    "share_labels",
]


class NotDeterministic(ValueError):
    """``property`` completion of a machine with tau or a nondeterministic choice."""

    def __init__(self, name: str, state: int, label: str) -> None:
        what = "a tau move" if label == TAU else f"two '{label}' moves"
        super().__init__(f"property {name} is not deterministic: state {state} has {what}")
        self.name = name
        self.state = state
        self.label = label


class NotSequential(ValueError):
    """``P;Q`` where ``P`` cannot reach END."""

    def __init__(self, name: str) -> None:
        super().__init__(f"{name} is not a sequential process (it has no reachable END)")
        self.name = name


def _rebuild(lts: LTS, transitions: Iterable[tuple[int, str, int]], alphabet: Iterable[str]) -> LTS:
    return make_lts(lts.name, lts.num_states, transitions, alphabet, lts.initial,
                    lts.end_states, lts.state_names)


def hide(lts: LTS, labels: Iterable[str]) -> LTS:
    """``P \\ {labels}``: matching labels become ``tau`` and leave the alphabet."""
    m = label_matcher(labels)
    trans = [(s, TAU if a != TAU and m(a) else a, t) for s, a, t in lts.transitions]
    alpha = [a for a in lts.alphabet if not m(a)]
    return _rebuild(lts, trans, alpha)


def expose(lts: LTS, labels: Iterable[str]) -> LTS:
    """``P @ {labels}``: hide every label that does *not* match ``labels``."""
    m = label_matcher(labels)
    trans = [(s, a if a == TAU or m(a) else TAU, t) for s, a, t in lts.transitions]
    alpha = [a for a in lts.alphabet if m(a)]
    return _rebuild(lts, trans, alpha)


def extend_alphabet(lts: LTS, labels: Iterable[str]) -> LTS:
    """``P + {labels}``: add labels to the alphabet without transitions (``tau`` ignored)."""
    return _rebuild(lts, lts.transitions, set(lts.alphabet) | (set(labels) - {TAU}))


def prefix_labels(lts: LTS, prefix: str) -> LTS:
    """``prefix:P``: every non-tau label ``x`` becomes ``prefix.x``."""
    def p(a: str) -> str:
        return a if a == TAU else f"{prefix}.{a}"

    trans = [(s, p(a), t) for s, a, t in lts.transitions]
    return _rebuild(lts, trans, [p(a) for a in lts.alphabet])


def share_labels(lts: LTS, prefixes: Iterable[str]) -> LTS:
    """``{p1,..,pn}::P``: every non-tau move ``x`` is offered as each ``pi.x`` (same endpoints)."""
    pre = sorted(set(prefixes))
    trans = [
        (s, a, t) if a == TAU else (s, f"{p}.{a}", t)
        for s, a, t in lts.transitions
        for p in ([""] if a == TAU else pre)
    ]
    return _rebuild(lts, trans, [f"{p}.{a}" for a in lts.alphabet for p in pre])


def is_deterministic(lts: LTS) -> bool:
    """True iff the LTS has no tau move and at most one move per (state, label)."""
    return _first_nondeterminism(lts) is None


def _first_nondeterminism(lts: LTS) -> tuple[int, str] | None:
    seen: set[tuple[int, str]] = set()
    for s, a, _ in lts.transitions:  # sorted, so the first witness is deterministic
        if a == TAU or (s, a) in seen:
            return s, a
        seen.add((s, a))
    return None


def property_complete(lts: LTS, error_set: Iterable[str] | None = None) -> LTS:
    """``property P``: every alphabet label not enabled in a state goes to ERROR (§2.4).

    With ``error_set`` (``!{S}``) only labels of the alphabet matching ``S`` are completed.
    END is forgotten.  Raises :class:`NotDeterministic` if ``lts`` has a tau move or two moves
    with one label from one state; a composite must be determinised first
    (:func:`iterplan_compiler.ir.minimise.determinise`).
    """
    bad = _first_nondeterminism(lts)
    if bad is not None:
        raise NotDeterministic(lts.name, *bad)
    if error_set is None:
        completed = sorted(lts.alphabet)
    else:
        m = label_matcher(error_set)
        completed = sorted(a for a in lts.alphabet if m(a))
    enabled: list[set[str]] = [set() for _ in range(lts.num_states)]
    for s, a, _ in lts.transitions:
        enabled[s].add(a)
    extra = [
        (s, a, ERROR)
        for s in range(lts.num_states)
        for a in completed
        if a not in enabled[s]
    ]
    return make_lts(lts.name, lts.num_states, [*lts.transitions, *extra], lts.alphabet,
                    lts.initial, (), lts.state_names)


def sequential(p: LTS, q: LTS, name: str | None = None) -> LTS:
    """``P;Q``: run ``P``; on reaching one of its END states continue as ``Q``.

    The result has ``P``'s states followed by ``Q``'s, P's END states merged into Q's initial
    state, Q's END states as END, and the union of the alphabets; unreachable states are
    dropped (canonical BFS numbering).  Raises :class:`NotSequential` if ``P`` has no END.
    """
    if not p.end_states:
        raise NotSequential(p.name)
    off = p.num_states
    q0 = off + q.initial

    def mp(s: int) -> int:
        if s == ERROR:
            return ERROR
        return q0 if s in p.end_states else s

    trans = [(mp(s), a, mp(t)) for s, a, t in p.transitions if s not in p.end_states]
    trans += [(off + s, a, ERROR if t == ERROR else off + t) for s, a, t in q.transitions]
    names = None
    if p.state_names is not None and q.state_names is not None:
        names = [*p.state_names, *q.state_names]
    joined = make_lts(name or p.name, off + q.num_states, trans, p.alphabet | q.alphabet,
                      mp(p.initial), (off + e for e in q.end_states), names)
    return reachable(joined)


def apply_priority(lts: LTS, labels: Iterable[str], high: bool) -> LTS:
    """Apply ``<< labels`` (``high``) or ``>> labels`` to one LTS, then drop unreachable states.

    ``high``: in a state where some listed label is enabled, only listed labels remain.
    Not ``high``: listed labels remain only in states where nothing else (tau included) is
    enabled.  The alphabet is unchanged.
    """
    m = label_matcher(labels)
    by_state: dict[int, list[tuple[int, str, int]]] = {}
    for tr in lts.transitions:
        by_state.setdefault(tr[0], []).append(tr)
    kept: list[tuple[int, str, int]] = []
    for moves in by_state.values():
        flags = [a != TAU and m(a) for _, a, _ in moves]
        if high and any(flags):
            kept += [tr for tr, f in zip(moves, flags, strict=True) if f]
        elif not high and not all(flags):
            kept += [tr for tr, f in zip(moves, flags, strict=True) if not f]
        else:
            kept += moves
    return reachable(_rebuild(lts, kept, lts.alphabet))
