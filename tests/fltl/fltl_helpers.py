"""Shared builders and hypothesis strategies for the FLTL tests."""

from __future__ import annotations

from hypothesis import strategies as st

from iterplan_compiler.fltl.semantics import Lasso
from iterplan_compiler.ir.formulas import (
    ActionProp,
    Always,
    And,
    Const,
    Eventually,
    Fluent,
    FluentProp,
    Iff,
    Implies,
    Next,
    Not,
    Or,
    Until,
    WeakUntil,
)
from iterplan_compiler.ir.lts import ERROR, LTS, make_lts


def act(*names: str) -> ActionProp:
    return ActionProp(frozenset(names))


def fl(name: str, initiating, terminating, initially: bool = False) -> Fluent:
    return Fluent(name, frozenset(initiating), frozenset(terminating), initially)


ACTIONS = ("a", "b", "c")
FLUENTS = {
    "F": fl("F", {"a"}, {"b"}),
    "G": fl("G", {"c"}, {"a"}, initially=True),
}

_atoms = st.one_of(
    st.sampled_from([act("a"), act("b"), act("c"), act("a", "c")]),
    st.sampled_from([FluentProp("F"), FluentProp("G")]),
    st.sampled_from([Const(True), Const(False)]),
)


def _ltl(children):
    return st.one_of(
        st.builds(Not, children),
        st.builds(And, children, children),
        st.builds(Or, children, children),
        st.builds(Implies, children, children),
        st.builds(Iff, children, children),
        st.builds(Next, children),
        st.builds(Always, children),
        st.builds(Eventually, children),
        st.builds(Until, children, children),
        st.builds(WeakUntil, children, children),
    )


formulas = st.recursive(_atoms, _ltl, max_leaves=5)
"""Arbitrary small FLTL formulas over ACTIONS and FLUENTS."""

_literals = st.one_of(_atoms, st.builds(Not, _atoms))


def _safe(children):
    return st.one_of(
        st.builds(And, children, children),
        st.builds(Or, children, children),
        st.builds(Next, children),
        st.builds(Always, children),
        st.builds(WeakUntil, children, children),
    )


safety_formulas = st.recursive(_literals, _safe, max_leaves=5)
"""Formulas of the syntactic safety fragment (NNF with X, [], W): always safety."""

words = st.lists(st.sampled_from(ACTIONS), max_size=6).map(tuple)
lassos = st.builds(Lasso, words, st.lists(st.sampled_from(ACTIONS), min_size=1,
                                           max_size=4).map(tuple))


@st.composite
def total_lts(draw, max_states: int = 4) -> LTS:
    """A random LTS over ACTIONS in which every state has a move (no deadlock)."""
    n = draw(st.integers(1, max_states))
    trans = set()
    for s in range(n):
        k = draw(st.integers(1, 2))
        for _ in range(k):
            trans.add((s, draw(st.sampled_from(ACTIONS)), draw(st.integers(0, n - 1))))
    return make_lts("R", n, trans, ACTIONS)


def run_dfa(lts: LTS, word) -> int | None:
    """State reached by a deterministic LTS on ``word``; ERROR (-1) or ``None`` if blocked."""
    out = {}
    for s, a, t in lts.transitions:
        assert (s, a) not in out, "not deterministic"
        out[(s, a)] = t
    cur = lts.initial
    for a in word:
        if a not in lts.alphabet:
            continue  # invisible to the automaton
        nxt = out.get((cur, a))
        if nxt is None or nxt == ERROR:
            return nxt
        cur = nxt
    return cur


def dfa_accepts_lasso(lts: LTS, lasso: Lasso) -> bool:
    """True iff the deterministic safety LTS never reaches ERROR/blocks on the lasso."""
    cur = run_dfa(lts, lasso.prefix)
    seen = set()
    while cur is not None and cur != ERROR and cur not in seen:
        seen.add(cur)
        sub = make_lts(lts.name, lts.num_states, lts.transitions, lts.alphabet, cur)
        cur = run_dfa(sub, lasso.cycle)
    return cur is not None and cur != ERROR


def lasso_runs(lts: LTS, max_len: int, *, fair: bool = False):
    """Every lasso run ``(prefix, cycle)`` of ``lts`` with ``len(prefix)+len(cycle) <= max_len``.

    With ``fair``, only strongly fair ones: the cycle takes every transition (ERROR moves
    included, which no cycle can take) of every state it visits.
    """
    out = lts.out_edges()
    stack = [((lts.initial,), ())]
    while stack:
        states, labels = stack.pop()
        if len(labels) >= max_len:
            continue
        for a, t in out[states[-1]]:
            if t == ERROR:
                continue
            for j, s in enumerate(states):
                if s != t:
                    continue
                cyc_states = states[j:] + (t,)
                cyc_labels = labels[j:] + (a,)
                if fair:
                    taken = set(zip(cyc_states, cyc_labels, cyc_states[1:], strict=False))
                    if any((u, b, v) not in taken for u in cyc_states for b, v in out[u]):
                        continue
                yield labels[:j], cyc_labels
            stack.append((states + (t,), labels + (a,)))


def is_fair_cycle(lts: LTS, prefix, cycle) -> bool:
    """``prefix (cycle)^w`` has a strongly fair run in ``lts`` (checked on the state sets the
    cycle can follow; exact for deterministic machines)."""
    out = lts.out_edges()
    for s in states_after(lts, prefix):
        cur, taken, seq = s, set(), [s]
        ok = True
        for a in cycle:
            nxt = [t for b, t in out[cur] if b == a and t != ERROR]
            if not nxt:
                ok = False
                break
            taken.add((cur, a, nxt[0]))
            cur = nxt[0]
            seq.append(cur)
        if ok and cur == s and all((u, b, v) in taken for u in seq for b, v in out[u]):
            return True
    return False


def states_after(lts: LTS, word, start=None) -> set[int]:
    cur = {lts.initial if start is None else start}
    out = lts.out_edges()
    for a in word:
        cur = {t for s in cur for b, t in out[s] if b == a and t != ERROR}
    return cur


def is_run(lts: LTS, prefix, cycle) -> bool:
    """``prefix (cycle)^w`` is a run of ``lts`` (cycle returns to the state it starts in)."""
    after = states_after(lts, prefix)
    if not after:
        return False
    if not cycle:
        return True
    return any(s in states_after(lts, cycle, s) for s in after)



def project(lasso: Lasso, alphabet) -> Lasso | None:
    """The lasso restricted to ``alphabet`` (``None`` if its cycle becomes empty)."""
    cyc = tuple(a for a in lasso.cycle if a in alphabet)
    if not cyc:
        return None
    return Lasso(tuple(a for a in lasso.prefix if a in alphabet), cyc)
