"""Liveness formulas written as ``ltl_property``/``constraint`` (a cheap check over a model).

The translation of §2.8 (:mod:`iterplan_compiler.fltl.safety`) decides safety over words of
the formula's own alphabet Σφ.  Over ``{land}`` alone every word satisfies ``[]<> land``, so
it is accepted, forbids nothing, and a controller spec listing it under ``safety`` is
"realizable"; MTSA's tableau test (not confined to Σφ-words) rejects it.  Here a formula
whose safety LTS forbids nothing over Σφ must still be a safety formula once an action
outside Σφ (:data:`~iterplan_compiler.fltl.progression.WILDCARD`) is allowed, else E0605 with
a witness.  Formulas that do forbid something are left to the translation's own test, so
nothing MTSA accepts is rejected here.  Used by ``iterc check``/``synth`` and the back-ends.
"""

from __future__ import annotations

import time
from dataclasses import replace

from iterplan_compiler import limits
from iterplan_compiler.diagnostics import Diagnostic, error
from iterplan_compiler.fltl import safety_cache
from iterplan_compiler.fltl.safety import (
    DEFAULT_MAX_STATES,
    not_safety_witness,
    recent_safety_dfa,
    safety_dfa,
)
from iterplan_compiler.ir.formulas import FormulaKind, NamedFormula
from iterplan_compiler.ir.lts import ERROR
from iterplan_compiler.ir.model import Model

E_NOT_SAFETY = "E0605"      # the FLTL stage's code (fltl/safety.py) for the same problem


def open_safety_witness(named: NamedFormula, model: Model) -> str | None:
    """For a formula whose safety LTS over Σφ forbids nothing: a trace (``prefix (cycle)^w``,
    ``*`` an action outside Σφ) that violates it without a bad prefix, or ``None``.

    ``None`` also when the LTS forbids something (the translation's own test over Σφ, run
    when building, is then MTSA's) or cannot be built (building reports that)."""
    if limits.formula_too_large(named.formula) is not None:
        return None  # building reports E0603
    cap = min(DEFAULT_MAX_STATES, limits.current().max_states)
    key = safety_cache.cache_key(named, model.fluents, constraint=False, max_states=cap)
    found, cached = safety_cache.load_witness(key)
    if found:
        return cached
    started = time.process_time()
    witness = _open_witness(named, model, cap, key)
    if time.process_time() - started >= safety_cache.WORTH_CACHING_S:
        safety_cache.store_witness(key, witness)
    return witness


def _open_witness(named: NamedFormula, model: Model, cap: int, key: str | None
                  ) -> str | None:
    # the translation's modules: only when the cache did not answer (see safety.py)
    from iterplan_compiler.fltl.emptiness import StateLimitExceeded
    from iterplan_compiler.fltl.progression import WILDCARD
    from iterplan_compiler.fltl.semantics import UnknownFluentError

    wide = replace(named, extra_alphabet=named.extra_alphabet | {WILDCARD})
    try:
        # the build's translation of the same formula reuses this DFA (safety.py)
        closed, _, _ = recent_safety_dfa(key, named, model.fluents, max_states=cap)
        if any(t == ERROR for _, _, t in closed.transitions):
            return None  # it forbids something: the builder's own safety test (§2.8) decides
        dfa, _, _ = safety_dfa(wide, model.fluents, max_states=cap)
        witness = not_safety_witness(dfa, wide, model.fluents, cap)
    except (UnknownFluentError, StateLimitExceeded, RecursionError):
        return None
    if witness is None:
        return None
    prefix, cycle = witness
    return " ".join([*prefix, "(" + " ".join(cycle) + ")^w"])


def safety_of_formulas(model: Model) -> list[Diagnostic]:
    """E0605 for every ``ltl_property``/``constraint`` that is not a safety formula."""
    out = []
    for name, named in model.formulas.items():
        if named.kind is FormulaKind.ASSERT:
            continue
        trace = open_safety_witness(named, model)
        if trace is None:
            continue
        out.append(error(
            E_NOT_SAFETY,
            f"{named.kind.value} {name} must be a safety formula, but it is not: the trace {trace} "
            "(* = any action outside the formula's alphabet) has no bad prefix, yet it "
            "violates the formula; state a liveness goal in the controllerSpec's liveness "
            "list instead", named.span))
    return out
