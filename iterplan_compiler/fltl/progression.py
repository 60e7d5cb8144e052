"""FLTL formula -> transition-based generalised Büchi automaton over *actions*.

The construction is a tableau by formula progression, done directly on actions instead of on
abstract valuation letters: an automaton state is ``(fluent valuation, obligations)`` where the
valuation (a bit mask over the formula's fluents) is what the trace so far determines, and
``obligations`` is a set of negation-normal-form subformulas that must hold from the *next*
position on.  Reading action ``a``:

1. the valuation is updated by ``a`` (initiating/terminating sets), giving the observation at
   the new position: (``a``, new valuation);
2. the obligations are expanded against that observation (the usual one-step unfolding
   ``f U g = g | (f & X(f U g))`` and friends), which yields the possible sets of next
   obligations; each choice records which eventualities (``U``/``<>``) it *postponed*.

Acceptance is transition based and generalised: there is one acceptance set per eventuality
subformula, and a transition belongs to it iff that choice did not postpone the eventuality.
An infinite run is accepting iff it is in every set infinitely often, i.e. no eventuality is
postponed forever.  Because the first observation is made after the first action, the state
before any action is never observed (MTSA's FLTL convention, §2.7).

Letters are action names plus :data:`WILDCARD`, "an action outside the formula's alphabet"
(it changes no fluent and satisfies no action proposition; used by model checking, §2.9).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass

from iterplan_compiler.fltl.semantics import UnknownFluentError, fluents_of, formula_alphabet
from iterplan_compiler.ir.formulas import (
    ActionProp,
    Always,
    And,
    Const,
    Eventually,
    Fluent,
    FluentProp,
    Formula,
    Iff,
    Implies,
    Next,
    Not,
    Or,
    Until,
    WeakUntil,
)

WILDCARD = "*"
"""The letter standing for any action outside the formula's alphabet."""

# Negation-normal-form nodes are plain tuples (hashable, cheap):
#   ("true",) ("false",) ("lit", atom, positive) ("and", l, r) ("or", l, r)
#   ("X", f) ("G", f) ("E", f) ("U", l, r) ("W", l, r)
# where atom is ("fl", index) or ("act", frozenset_of_actions).
Node = tuple
TRUE: Node = ("true",)
FALSE: Node = ("false",)

State = tuple[int, frozenset]
"""An automaton state: (fluent valuation bit mask, obligations for the next position)."""


def _and(a: Node, b: Node) -> Node:
    if a == FALSE or b == FALSE:
        return FALSE
    if a == TRUE:
        return b
    if b == TRUE or a == b:
        return a
    return ("and", a, b)


def _or(a: Node, b: Node) -> Node:
    if a == TRUE or b == TRUE:
        return TRUE
    if a == FALSE:
        return b
    if b == FALSE or a == b:
        return a
    return ("or", a, b)


def to_nnf(f: Formula, fluent_index: Mapping[str, int], neg: bool = False) -> Node:
    """Negation normal form of ``f`` (negated if ``neg``) over infinite traces.

    Dualities used: ``!X f = X !f``, ``![] f = <> !f``, ``!(f U g) = !g W (!f & !g)`` and
    ``!(f W g) = !g U (!f & !g)``.
    """

    def rec(f: Formula, neg: bool) -> Node:
        if isinstance(f, Const):
            return TRUE if f.value != neg else FALSE
        if isinstance(f, FluentProp):
            return ("lit", ("fl", fluent_index[f.name]), not neg)
        if isinstance(f, ActionProp):
            return ("lit", ("act", f.actions), not neg)
        if isinstance(f, Not):
            return rec(f.arg, not neg)
        if isinstance(f, And):
            lf, rf = rec(f.left, neg), rec(f.right, neg)
            return _or(lf, rf) if neg else _and(lf, rf)
        if isinstance(f, Or):
            lf, rf = rec(f.left, neg), rec(f.right, neg)
            return _and(lf, rf) if neg else _or(lf, rf)
        if isinstance(f, Implies):
            return rec(Or(Not(f.left), f.right), neg)
        if isinstance(f, Iff):
            pos_l, pos_r = rec(f.left, False), rec(f.right, False)
            neg_l, neg_r = rec(f.left, True), rec(f.right, True)
            if neg:
                return _or(_and(pos_l, neg_r), _and(neg_l, pos_r))
            return _or(_and(pos_l, pos_r), _and(neg_l, neg_r))
        if isinstance(f, Next):
            a = rec(f.arg, neg)
            return a if a in (TRUE, FALSE) else ("X", a)
        if isinstance(f, (Always, Eventually)):
            a = rec(f.arg, neg)
            if a in (TRUE, FALSE):
                return a
            always = isinstance(f, Always) != neg
            return ("G", a) if always else ("E", a)
        if isinstance(f, (Until, WeakUntil)):
            weak = isinstance(f, WeakUntil)
            if neg:
                g = rec(f.right, True)
                return _unt(g, _and(rec(f.left, True), g), strong=weak)
            return _unt(rec(f.left, False), rec(f.right, False), strong=not weak)
        raise TypeError(f"not a formula node: {f!r}")  # pragma: no cover

    return rec(f, neg)


def _unt(left: Node, right: Node, *, strong: bool) -> Node:
    """``left U right`` (strong) or ``left W right`` with constant folding."""
    if right == TRUE:
        return TRUE
    if left == FALSE:
        return right
    if right == FALSE:
        return FALSE if strong else ("G", left) if left != TRUE else TRUE
    if left == TRUE:
        return ("E", right) if strong else TRUE
    return ("U" if strong else "W", left, right)


@functools.lru_cache(maxsize=1 << 16)
def node_key(node: Node) -> tuple:
    """A hash-seed independent sort key for an NNF node (frozensets become sorted tuples), so
    that choices, acceptance bits and hence counterexamples are the same on every run.

    Memoised: the tableau sorts obligation sets on every expansion, and recomputing the key of
    a large formula recursively each time dominated safety_lts (QA profile: 3 M calls, 60 % of
    `iterc check --build examples/ordered_patrol.lts`).  NNF nodes are immutable tuples, so
    caching by value is sound; the bound keeps a long-lived process from growing without limit.
    """
    out = []
    for part in node:
        if isinstance(part, tuple):
            out.append(node_key(part))
        elif isinstance(part, frozenset):
            out.append(tuple(sorted(part)))
        else:
            out.append(part)
    return tuple(out)


def _obligations_key(obligations: frozenset) -> tuple:
    return tuple(sorted(node_key(n) for n in obligations))


def _eventualities(node: Node) -> list[Node]:
    """All ``U``/``<>`` subformulas of an NNF node, in a deterministic order."""
    seen: dict[Node, None] = {}
    stack = [node]
    while stack:
        n = stack.pop()
        if n[0] in ("U", "E") and n not in seen:
            seen[n] = None
        for child in n[1:]:
            if isinstance(child, tuple) and child and isinstance(child[0], str) and \
                    child[0] in ("true", "false", "lit", "and", "or", "X", "G", "E", "U", "W"):
                stack.append(child)
    return sorted(seen, key=node_key)


@dataclass(frozen=True, slots=True)
class _Obs:
    action: str
    valuation: int


class FormulaAutomaton:
    """The generalised Büchi automaton of an FLTL formula (or of its negation), built lazily.

    ``step(state, letter)`` returns ``[(next_state, acceptance_mask), ...]``; the automaton is
    nondeterministic.  ``full_mask`` has one bit per eventuality; a run is accepting iff every
    bit occurs infinitely often.  Raises :class:`UnknownFluentError` for a missing fluent.
    """

    def __init__(
        self, formula: Formula, fluents: Mapping[str, Fluent], *, negate: bool = False
    ) -> None:
        self.formula = formula
        self.alphabet: frozenset[str] = formula_alphabet(formula, fluents)
        self.fluent_names: tuple[str, ...] = tuple(sorted(fluents_of(formula)))
        index = {n: i for i, n in enumerate(self.fluent_names)}
        for n in self.fluent_names:
            if n not in fluents:  # pragma: no cover - formula_alphabet raised already
                raise UnknownFluentError(n)
        self.root: Node = to_nnf(formula, index, negate)
        evs = _eventualities(self.root)
        self._ev_bit = {e: 1 << i for i, e in enumerate(evs)}
        self.full_mask = (1 << len(evs)) - 1
        init = 0
        # Per-action valuation update: (bits set, bits cleared).
        self._update: dict[str, tuple[int, int]] = {}
        for n, i in index.items():
            fl = fluents[n]
            if fl.initially:
                init |= 1 << i
            for a in fl.terminating:
                s, c = self._update.get(a, (0, 0))
                self._update[a] = (s, c | (1 << i))
            for a in fl.initiating:  # initiating wins over terminating (see semantics.py)
                s, c = self._update.get(a, (0, 0))
                self._update[a] = (s | (1 << i), c & ~(1 << i))
        self.initial: State = (init, frozenset({self.root}))
        self._cache: dict[tuple[State, str], list[tuple[State, int]]] = {}
        self._prop: dict[Node, bool] = {}

    def letters(self, *, wildcard: bool) -> list[str]:
        """The formula's alphabet, sorted, plus :data:`WILDCARD` if asked."""
        out = sorted(self.alphabet)
        return out + [WILDCARD] if wildcard else out

    def step(self, state: State, letter: str) -> list[tuple[State, int]]:
        """Successors of ``state`` reading action ``letter`` (any action outside the formula's
        alphabet behaves like :data:`WILDCARD`)."""
        key = (state, letter)
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        val, obligations = state
        s, c = self._update.get(letter, (0, 0))
        val = (val & ~c) | s
        obs = _Obs(letter, val)
        out = [((val, nxt), self.full_mask & ~post) for nxt, post in self._expand(obligations, obs)]
        self._cache[key] = out
        return out

    def _propositional(self, node: Node) -> bool:
        """True iff ``node`` has no temporal operator (memoised)."""
        hit = self._prop.get(node)
        if hit is None:
            tag = node[0]
            if tag in ("true", "false", "lit"):
                hit = True
            elif tag in ("and", "or"):
                hit = self._propositional(node[1]) and self._propositional(node[2])
            else:
                hit = False
            self._prop[node] = hit
        return hit

    def _eval_prop(self, node: Node, obs: _Obs) -> bool:
        tag = node[0]
        if tag == "lit":
            return self._holds(node[1], obs) == node[2]
        if tag == "and":
            return self._eval_prop(node[1], obs) and self._eval_prop(node[2], obs)
        if tag == "or":
            return self._eval_prop(node[1], obs) or self._eval_prop(node[2], obs)
        return tag == "true"

    def _holds(self, atom: tuple, obs: _Obs) -> bool:
        if atom[0] == "fl":
            return bool(obs.valuation >> atom[1] & 1)
        return obs.action in atom[1]

    def _expand(self, obligations: frozenset, obs: _Obs) -> list[tuple[frozenset, int]]:
        """All ways to satisfy ``obligations`` at the observed position: a list of
        (obligations for the next position, mask of postponed eventualities), with choices
        that are dominated (more obligations and more postponements) removed."""
        results: set[tuple[frozenset, int]] = set()
        stack: list[tuple[list[Node], frozenset, int]] = [(list(obligations), frozenset(), 0)]
        while stack:
            todo, nxt, post = stack.pop()
            alive = True
            while todo:
                f = todo.pop()
                tag = f[0]
                if tag == "true":
                    continue
                if tag == "false":
                    alive = False
                    break
                if tag in ("lit", "and", "or") and self._propositional(f):
                    # Evaluated on the observation at once: branching on the disjuncts of a
                    # large propositional formula (e.g. an expanded ``exists``) would create
                    # exponentially many choices that all carry the same obligations.
                    if not self._eval_prop(f, obs):
                        alive = False
                        break
                elif tag == "and":
                    todo.append(f[1])
                    todo.append(f[2])
                elif tag == "or":
                    # A propositional disjunct is decided now; when it holds, that choice adds
                    # nothing and so dominates the other one.
                    left, right = f[1], f[2]
                    if self._propositional(left):
                        if not self._eval_prop(left, obs):
                            todo.append(right)
                        continue
                    if self._propositional(right):
                        if not self._eval_prop(right, obs):
                            todo.append(left)
                        continue
                    stack.append((todo + [right], nxt, post))
                    todo.append(left)
                elif tag == "X":
                    nxt = nxt | {f[1]}
                elif tag == "G":
                    nxt = nxt | {f}
                    todo.append(f[1])
                elif tag == "E":
                    stack.append((list(todo), nxt | {f}, post | self._ev_bit[f]))
                    todo.append(f[1])
                elif tag == "U":
                    stack.append((todo + [f[1]], nxt | {f}, post | self._ev_bit[f]))
                    todo.append(f[2])
                elif tag == "W":
                    stack.append((todo + [f[1]], nxt | {f}, post))
                    todo.append(f[2])
                else:  # pragma: no cover
                    raise AssertionError(tag)
            if alive:
                results.add((nxt, post))
        # Drop dominated choices: a subset of the obligations with a subset of the
        # postponements accepts at least the same continuations.
        res = sorted(results, key=lambda r: (len(r[0]), bin(r[1]).count("1"),
                                             _obligations_key(r[0]), r[1]))
        kept: list[tuple[frozenset, int]] = []
        for nxt, post in res:
            if not any(k[0] <= nxt and (k[1] & ~post) == 0 for k in kept):
                kept.append((nxt, post))
        return kept
