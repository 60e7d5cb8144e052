"""Direct (automaton-free) semantics of FLTL on traces: the oracle for the automata.

Positions follow MTSA (``docs/semantics.md``, "FLTL choices"; mtsa-semantics §2.7): for a trace
``a1 a2 ...`` position *i* is the instant just after ``ai``; a formula holds on a trace iff it
holds at position 1, so the state before the first action is never observed.  A fluent
``<I, T> initially v`` holds at *i* iff the last action of ``I | T`` among ``a1..ai`` is in ``I``,
or no such action occurred and ``v``.  An action proposition holds at *i* iff ``ai`` is one of its
actions.

Two kinds of trace are supported:

* :class:`Lasso` ``prefix (cycle)^omega`` -- the exact infinite-trace semantics of full LTL,
  computed by fixpoints over the finitely many distinct positions of the lasso;
* a finite sequence of actions -- the *good prefix* semantics used for safety automata: the
  trace is accepted iff some infinite continuation over ``alphabet`` satisfies the formula
  (a "bad prefix" is one every continuation violates).  This is decided here by trying every
  lasso continuation ``u (v)^omega`` with ``|u| + |v| <= bound``, which is exact whenever a
  witness that short exists (always so for the small formulas used in tests); it is an oracle,
  not an algorithm -- :mod:`iterplan_compiler.fltl.safety` decides the same thing exactly.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

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


class UnknownFluentError(ValueError):
    """A formula names a fluent that is not in the fluent table (a front-end contract breach)."""

    def __init__(self, name: str):
        super().__init__(f"unknown fluent '{name}'")
        self.name = name


@dataclass(frozen=True, slots=True)
class Lasso:
    """The infinite trace ``prefix cycle cycle cycle ...``; ``cycle`` must be non-empty."""

    prefix: tuple[str, ...]
    cycle: tuple[str, ...]

    def __post_init__(self) -> None:
        if not self.cycle:
            raise ValueError("a lasso needs a non-empty cycle")

    def __str__(self) -> str:
        return " ".join(self.prefix) + " (" + " ".join(self.cycle) + ")^w"


def subformulas(formula: Formula) -> Iterable[Formula]:
    """Yield ``formula`` and all its subformulas (pre-order, with repetitions)."""
    stack = [formula]
    while stack:
        f = stack.pop()
        yield f
        for child in ("arg", "left", "right"):
            sub = getattr(f, child, None)
            if sub is not None:
                stack.append(sub)


def fluents_of(formula: Formula) -> frozenset[str]:
    """Names of the fluents a formula mentions."""
    return frozenset(f.name for f in subformulas(formula) if isinstance(f, FluentProp))


def formula_alphabet(
    formula: Formula, fluents: Mapping[str, Fluent], extra: Iterable[str] = ()
) -> frozenset[str]:
    """The alphabet of a formula, Σφ (§2.8): actions of its fluents, its action propositions and
    ``extra`` (the ``+ {...}`` extension).  Raises :class:`UnknownFluentError`."""
    alpha: set[str] = set(extra)
    for f in subformulas(formula):
        if isinstance(f, ActionProp):
            alpha |= f.actions
        elif isinstance(f, FluentProp):
            if f.name not in fluents:
                raise UnknownFluentError(f.name)
            fl = fluents[f.name]
            alpha |= fl.initiating | fl.terminating
    return frozenset(alpha)


def fluent_trajectory(
    trace: Sequence[str], fluents: Mapping[str, Fluent], names: Iterable[str]
) -> list[dict[str, bool]]:
    """Fluent values at positions 1..len(trace) (index 0 = after the first action)."""
    names = sorted(names)
    for n in names:
        if n not in fluents:
            raise UnknownFluentError(n)
    value = {n: fluents[n].initially for n in names}
    out = []
    for a in trace:
        for n in names:
            # Initiating wins if a malformed fluent lists ``a`` in both sets (the front-end
            # rejects that; we only need a deterministic answer).
            if a in fluents[n].initiating:
                value[n] = True
            elif a in fluents[n].terminating:
                value[n] = False
        out.append(dict(value))
    return out


def _eval_positions(
    formula: Formula, actions: Sequence[str], values: Sequence[Mapping[str, bool]], succ: list[int]
) -> list[bool]:
    """Truth value of ``formula`` at every position of a finite position graph.

    ``succ[i]`` is the successor of position ``i`` (every position has exactly one: the graph is
    a lasso).  Temporal operators are least (U, <>) or greatest (W, []) fixpoints of their
    one-step unfoldings, which is exact on a lasso.
    """
    n = len(actions)
    memo: dict[Formula, list[bool]] = {}

    def fix(step, start: bool) -> list[bool]:
        val = [start] * n
        while True:
            new = [step(i, val) for i in range(n)]
            if new == val:
                return val
            val = new

    def ev(f: Formula) -> list[bool]:
        if f in memo:
            return memo[f]
        if isinstance(f, Const):
            r = [f.value] * n
        elif isinstance(f, FluentProp):
            r = [values[i][f.name] for i in range(n)]
        elif isinstance(f, ActionProp):
            r = [actions[i] in f.actions for i in range(n)]
        elif isinstance(f, Not):
            r = [not x for x in ev(f.arg)]
        elif isinstance(f, And):
            r = [x and y for x, y in zip(ev(f.left), ev(f.right), strict=True)]
        elif isinstance(f, Or):
            r = [x or y for x, y in zip(ev(f.left), ev(f.right), strict=True)]
        elif isinstance(f, Implies):
            r = [(not x) or y for x, y in zip(ev(f.left), ev(f.right), strict=True)]
        elif isinstance(f, Iff):
            r = [x == y for x, y in zip(ev(f.left), ev(f.right), strict=True)]
        elif isinstance(f, Next):
            a = ev(f.arg)
            r = [a[succ[i]] for i in range(n)]
        elif isinstance(f, Always):
            a = ev(f.arg)
            r = fix(lambda i, v: a[i] and v[succ[i]], True)
        elif isinstance(f, Eventually):
            a = ev(f.arg)
            r = fix(lambda i, v: a[i] or v[succ[i]], False)
        elif isinstance(f, Until):
            a, b = ev(f.left), ev(f.right)
            r = fix(lambda i, v: b[i] or (a[i] and v[succ[i]]), False)
        elif isinstance(f, WeakUntil):
            a, b = ev(f.left), ev(f.right)
            r = fix(lambda i, v: b[i] or (a[i] and v[succ[i]]), True)
        else:  # pragma: no cover - the IR has no other node
            raise TypeError(f"not a formula node: {f!r}")
        memo[f] = r
        return r

    return ev(formula)


def evaluate_lasso(
    formula: Formula, lasso: Lasso, fluents: Mapping[str, Fluent], *, at: int = 0
) -> bool:
    """Exact LTL semantics on an infinite lasso trace; ``at`` is a 0-based position index
    (0 = position 1, after the first action) into ``prefix + cycle``."""
    # Fluent values are periodic only from the second pass through the cycle on (the first pass
    # may still see values set in the prefix), so unroll the cycle once.
    prefix = lasso.prefix + lasso.cycle
    actions = prefix + lasso.cycle
    values = fluent_trajectory(actions, fluents, fluents_of(formula))
    n = len(actions)
    succ = [i + 1 for i in range(n - 1)] + [len(prefix)]
    if at >= len(lasso.prefix) + len(lasso.cycle):
        raise ValueError("position outside the lasso")
    return _eval_positions(formula, actions, values, succ)[at]


def is_good_prefix(
    formula: Formula,
    trace: Sequence[str],
    fluents: Mapping[str, Fluent],
    alphabet: Iterable[str],
    *,
    bound: int = 4,
) -> bool:
    """True iff some lasso continuation ``u (v)^omega`` of ``trace`` over ``alphabet`` with
    ``|u| + |v| <= bound`` satisfies ``formula`` (see the module docstring)."""
    letters = sorted(set(alphabet))
    if not letters:
        raise ValueError("good-prefix semantics needs a non-empty alphabet")
    trace = tuple(trace)
    for total in range(1, bound + 1):
        for word in itertools.product(letters, repeat=total):
            for split in range(total):  # cycle = word[split:], never empty
                lasso = Lasso(trace + word[:split], word[split:])
                if evaluate_lasso(formula, lasso, fluents):
                    return True
    return False


def evaluate(
    formula: Formula,
    trace: Sequence[str] | Lasso,
    fluents: Mapping[str, Fluent],
    alphabet: Iterable[str] | None = None,
    *,
    bound: int = 4,
) -> bool:
    """Evaluate ``formula`` on ``trace`` at position 1.

    A :class:`Lasso` gets the exact infinite-trace semantics.  A finite sequence gets the
    good-prefix semantics with continuations over ``alphabet`` (default: the formula's own
    alphabet Σφ, as for ``ltl_property``/``constraint``); see :func:`is_good_prefix`.
    """
    if isinstance(trace, Lasso):
        return evaluate_lasso(formula, trace, fluents)
    if alphabet is None:
        alphabet = formula_alphabet(formula, fluents)
    return is_good_prefix(formula, trace, fluents, alphabet, bound=bound)
