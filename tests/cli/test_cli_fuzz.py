"""Mutation fuzzing of the front-end: real spec texts with tokens/characters deleted, duplicated,
swapped or replaced must only ever produce diagnostics -- never an exception -- from
``pipeline.load_model`` and from building the machines, and every diagnostic must point inside the
text it is about.

Seeds: the bundled examples, the back-end golden spec and (when ``../shared`` is present) a
fixed sample of small MTSA conformance specs.  Synthesis composites are posed
(``synthesis_problem``) but not solved, and compositions are capped at a few thousand states,
so the test stays well under 20 s.
"""

from __future__ import annotations

import pytest
from cli_helpers import CORPUS, EXAMPLES, GOLDEN_SPEC
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from iterplan_compiler import pipeline
from iterplan_compiler.diagnostics import render
from tests.robustness.fuzz import mutate as shared_mutate

SYNTHESIS_KEYWORDS = {"controller", "heuristic", "monolithicDirector"}
# Fragments worth inserting: delimiters, keywords, odd characters, large/negative numbers.
EXTRA = ["(", ")", "{", "}", "[", "]", ".", ",", "|", "||", "->", "~", "\\", "@", "/", "'",
         '"', "\x00", "\ufffd", "é", "0..2", "-1", "99999", "if", "then", "else", "when",
         "range", "const", "set", "fluent", "assert", "controller", "include", "ERROR", "STOP",
         "END", "tau", "property", "minimal", "deterministic", "forall", "+", "*", ":", ";",
         "<>", "[]", "X", "U", "W", "!", "=", "\n"]


def _seeds() -> list[tuple[str, str]]:
    # ordered_patrol is left out: posing its game builds large safety automata (~3 s each
    # time), which would dominate the budget without exercising anything new in the parser.
    paths = [p for p in sorted(EXAMPLES.glob("*.lts")) if p.stem != "ordered_patrol"]
    paths.append(GOLDEN_SPEC)
    if CORPUS.is_dir():
        small = [p for p in sorted(CORPUS.rglob("*.lts")) if p.stat().st_size < 2500]
        paths += small[::7]  # a fixed, spread-out sample (~25 files)
    return [(str(p), p.read_text(encoding="utf-8", errors="replace")) for p in paths]


SEEDS = _seeds()


def mutate(text: str, ops: list[tuple[int, int, int, int]]) -> str:
    """Apply ``(op, i, j, k)`` edits (:func:`tests.robustness.fuzz.mutate`; ops 0-6: token
    and character edits, with this test's fragments)."""
    return shared_mutate(text, ops, EXTRA)


def exercise(path: str, text: str) -> None:
    """Everything a user can trigger short of synthesis; raises only on a front-end bug."""
    model, diags = pipeline.load_model(path, text=text)
    diags = list(diags)
    if model is not None:
        for name in model.names():
            if SYNTHESIS_KEYWORDS & set(model.composite_keywords.get(name, ())):
                _, ds = model.synthesis_problem(name)
            else:
                _, ds = model.build_lts(name)
            diags.extend(ds)
    n_lines = text.count("\n") + 1
    for d in diags:
        assert d.code and d.message, d
        if d.span.file == path and d.span.line > 0:
            assert d.span.line <= n_lines + 1 and d.span.column >= 1, (d, n_lines)
    render(diags, {path: text})  # the renderer copes with every span


@pytest.fixture
def small_limits(monkeypatch):
    from iterplan_compiler.frontend import declarations

    # The front-end's composition cap; a mutated range can otherwise ask for millions of states.
    # (This patched the `elaborate` *function* before: `frontend.elaborate` is not the module.)
    monkeypatch.setattr(declarations, "MAX_STATES", 3000)


@settings(max_examples=150, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(seed=st.sampled_from(SEEDS),
       ops=st.lists(st.tuples(st.integers(0, 6), st.integers(0, 10**6), st.integers(0, 10**6),
                              st.integers(0, 10**3)), min_size=1, max_size=4))
def test_mutated_specs_give_diagnostics_not_exceptions(small_limits, seed, ops):
    path, text = seed
    exercise(path, mutate(text, ops))


# Minimised inputs that crashed the front-end once.  Random mutation found none (5,500 offline
# mutations of the corpus and examples, synthesis included, gave diagnostics only); the crashes
# QA found by construction (deep nesting -> RecursionError) are pinned, through the CLI, in
# test_cli_bad_inputs.py::test_deeply_nested_input.  Add new ones here.
REGRESSIONS: list[str] = [
    "A = (" + " -> ".join(f"a{i}" for i in range(1000)) + " -> A).\n",
    "fluent F = <a, b>\nA = (a -> b -> A).\nassert P = " + "!" * 1000 + "F\n",
]


@pytest.mark.parametrize("text", REGRESSIONS, ids=["long-sequence", "nested-not"])
def test_regressions(small_limits, text):
    exercise("regression.lts", text)
