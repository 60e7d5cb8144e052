"""``ltl_property`` / ``constraint`` -> minimal deterministic safety LTS (mtsa-semantics §2.8).

Construction (no per-pattern special cases):

1. build the generalised Büchi automaton *A* of φ over the letters Σφ (fluent actions, action
   propositions and the ``+{...}`` extension; no wildcard: actions outside Σφ are invisible to
   these automata) -- :class:`~iterplan_compiler.fltl.progression.FormulaAutomaton`;
2. keep only the *live* states of *A* (those with a non-empty language);
3. subset construction: a finite trace leads to the set of live states reachable by it; the
   empty set is ERROR.  So a trace is accepted iff it is a *good prefix* (some infinite
   continuation over Σφ satisfies φ), and the first action that makes it a bad prefix moves to
   ERROR;
4. Hopcroft minimisation (:func:`iterplan_compiler.ir.minimise.minimise`), canonical numbering;
5. safety check: φ is a safety formula iff every infinite word all of whose prefixes are good
   satisfies φ, i.e. iff the product of the DFA (every state accepting) with the automaton of
   ¬φ has no accepting lasso.  A lasso found is shown in the diagnostic as a witness.

``constraint`` is the same machine with every transition into ERROR removed.
"""

from __future__ import annotations

import time
from collections import OrderedDict
from collections.abc import Mapping
from typing import TYPE_CHECKING

from iterplan_compiler import limits
from iterplan_compiler.diagnostics import Diagnostic, error, warning
from iterplan_compiler.fltl import safety_cache
from iterplan_compiler.ir.formulas import Fluent, NamedFormula
from iterplan_compiler.ir.lts import ERROR, LTS, make_lts, reachable
from iterplan_compiler.ir.minimise import minimise

if TYPE_CHECKING:
    from iterplan_compiler.fltl.progression import FormulaAutomaton, State

# The translation's own modules (progression, emptiness, semantics: ~900 lines) are imported
# where a translation runs: a run whose formulas all come from the cache (a warm
# ``iterc compile``) does not load them (issue #12).

# Stable diagnostic codes of the FLTL stage.
E_UNKNOWN_FLUENT = "E0604"
E_NOT_SAFETY = "E0605"
E_TOO_LARGE = "E0606"
W_UNSATISFIABLE = "W0604"

DEFAULT_MAX_STATES = 200_000


def safety_dfa(
    named: NamedFormula,
    fluents: Mapping[str, Fluent],
    *,
    max_states: int = DEFAULT_MAX_STATES,
) -> tuple[LTS, FormulaAutomaton, list[frozenset]]:
    """The (non-minimised) subset DFA of step 3 as an LTS with ERROR moves, the automaton it was
    built from and the subset of each DFA state.  Raises :class:`UnknownFluentError` and
    :class:`StateLimitExceeded`."""
    from iterplan_compiler.fltl.emptiness import StateLimitExceeded, analyse
    from iterplan_compiler.fltl.progression import FormulaAutomaton

    aut = FormulaAutomaton(named.formula, fluents)
    letters = sorted(aut.alphabet | named.extra_alphabet)

    def succ(s: State):
        for a in letters:
            for t, m in aut.step(s, a):
                yield a, t, m

    an = analyse([aut.initial], succ, aut.full_mask, max_nodes=max_states)
    live = an.live
    start = frozenset({aut.initial}) & live
    index: dict[frozenset, int] = {start: 0}
    order: list[frozenset] = [start]
    trans: list[tuple[int, str, int]] = []
    head = 0
    while head < len(order):
        cur = order[head]
        src = head
        head += 1
        for a in letters:
            nxt = frozenset(t for s in cur for t, _ in aut.step(s, a) if t in live)
            if not nxt:
                trans.append((src, a, ERROR))
                continue
            k = index.get(nxt)
            if k is None:
                if len(order) >= max_states:
                    raise StateLimitExceeded(max_states)
                k = index[nxt] = len(order)
                order.append(nxt)
            trans.append((src, a, k))
    return make_lts(named.name, len(order), trans, letters), aut, order


#: The subset DFAs of the last few translations, by the key of their inputs
#: (:func:`dfa_key`).  ``iterc`` builds a formula's DFA twice per run: elaboration's
#: open-alphabet test (:mod:`.open_safety`) and the build's translation; on an empty cache the
#: second was Ordered Patrol's costliest repeat (``Phi1``: ~0.16 s CPU, issue #12).  Bounded,
#: so a long-lived process (tests, experiments) does not keep every automaton it ever built.
_RECENT_DFAS: OrderedDict[str, tuple[LTS, FormulaAutomaton, list[frozenset]]] = OrderedDict()
_RECENT_MAX = 8


def dfa_key(named: NamedFormula, fluents: Mapping[str, Fluent], max_states: int) -> str | None:
    """The key of :func:`safety_dfa`'s inputs (the DFA does not depend on property vs
    constraint: that key bit is fixed)."""
    return safety_cache.cache_key(named, fluents, constraint=False, max_states=max_states)


def recent_safety_dfa(
    key: str | None,
    named: NamedFormula,
    fluents: Mapping[str, Fluent],
    *,
    max_states: int,
) -> tuple[LTS, FormulaAutomaton, list[frozenset]]:
    """:func:`safety_dfa`, or the one built for the same ``key`` recently in this process
    (its result is a pure function of what the key hashes; exceptions are not kept)."""
    if key is not None and key in _RECENT_DFAS:
        _RECENT_DFAS.move_to_end(key)
        return _RECENT_DFAS[key]
    out = safety_dfa(named, fluents, max_states=max_states)
    if key is not None:
        _RECENT_DFAS[key] = out
        while len(_RECENT_DFAS) > _RECENT_MAX:
            _RECENT_DFAS.popitem(last=False)
    return out


def not_safety_witness(
    dfa: LTS,
    named: NamedFormula,
    fluents: Mapping[str, Fluent],
    max_states: int = DEFAULT_MAX_STATES,
) -> tuple[list[str], list[str]] | None:
    """An infinite word never rejected by ``dfa`` that violates φ, or ``None`` (φ is safety)."""
    from iterplan_compiler.fltl.emptiness import analyse, lasso
    from iterplan_compiler.fltl.progression import FormulaAutomaton

    neg = FormulaAutomaton(named.formula, fluents, negate=True)
    out = dfa.out_edges()

    def succ(node):
        d, q = node
        for a, t in out[d]:
            if t == ERROR:
                continue
            for q2, m in neg.step(q, a):
                yield a, (t, q2), m

    an = analyse([(dfa.initial, neg.initial)], succ, neg.full_mask, max_nodes=max_states)
    return lasso(an, neg.full_mask)


def safety_lts(
    named: NamedFormula,
    fluents: Mapping[str, Fluent],
    *,
    constraint: bool,
    max_states: int = DEFAULT_MAX_STATES,
) -> tuple[LTS | None, list[Diagnostic]]:
    """Compile an ``ltl_property`` (``constraint=False``) or ``constraint`` into its minimal
    deterministic safety LTS over Σφ (+ ``named.extra_alphabet``).

    Returns ``(None, [error])`` for an unknown fluent (E0604), a formula that is not a safety
    formula (E0605, with a witness trace) or an automaton beyond ``max_states`` (E0606).  An
    unsatisfiable formula gives a warning (W0604): every action leads to ERROR.
    """
    kind = "constraint" if constraint else "ltl_property"
    diags: list[Diagnostic] = []
    too_large = limits.formula_too_large(named.formula)
    if too_large is not None:
        return None, [error("E0603", f"{kind} {named.name}: {too_large}", named.span)]
    max_states = min(max_states, limits.current().max_states)
    key = safety_cache.cache_key(named, fluents, constraint=constraint, max_states=max_states)
    cached = safety_cache.load(key, named.name)
    if cached is not None:
        lts, unsatisfiable = cached
        return lts, [_unsatisfiable(kind, named)] if unsatisfiable else []
    from iterplan_compiler.fltl.emptiness import StateLimitExceeded
    from iterplan_compiler.fltl.semantics import UnknownFluentError

    started = time.process_time()
    try:
        dfa, _, subsets = recent_safety_dfa(
            key if not constraint else dfa_key(named, fluents, max_states), named, fluents,
            max_states=max_states)
        witness = not_safety_witness(dfa, named, fluents, max_states)
    except UnknownFluentError as exc:
        return None, [error(E_UNKNOWN_FLUENT, f"{kind} {named.name}: {exc}", named.span)]
    except StateLimitExceeded:
        return None, [error(E_TOO_LARGE, f"{kind} {named.name}: the formula's automaton exceeds "
                                         f"{max_states:,} states (raise the limit with "
                                         "--max-states)", named.span)]
    except RecursionError:
        # The NNF/tableau code recurses over the formula tree; a formula nested ~1000 deep
        # (generated specs) is a too-large input, not a compiler crash.
        return None, [error(E_TOO_LARGE, f"{kind} {named.name}: the formula is nested too "
                                         "deeply to translate", named.span)]
    if witness is not None:
        prefix, cycle = witness
        trace = " ".join([*prefix, "(" + " ".join(cycle) + ")^w"])
        return None, [error(
            E_NOT_SAFETY,
            f"{kind} {named.name} must be a safety formula, but it is not: the trace {trace} "
            "has no bad prefix, yet it violates the formula",
            named.span,
        )]
    if not subsets[0]:
        diags.append(_unsatisfiable(kind, named))
    lts = minimise(dfa, named.name)
    if constraint:
        lts = reachable(make_lts(lts.name, lts.num_states,
                                 [t for t in lts.transitions if t[2] != ERROR],
                                 lts.alphabet, lts.initial))
    if time.process_time() - started >= safety_cache.WORTH_CACHING_S:
        safety_cache.store(key, lts, not subsets[0])
    return lts, diags


def _unsatisfiable(kind: str, named: NamedFormula) -> Diagnostic:
    return warning(W_UNSATISFIABLE, f"{kind} {named.name} is unsatisfiable: every action "
                                    "violates it", named.span)
