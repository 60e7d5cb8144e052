"""Hand-made synthesis problems for the tests (no front-end needed)."""

from __future__ import annotations

from iterplan_compiler.ir.formulas import Fluent, FluentProp, Formula
from iterplan_compiler.ir.lts import LTS
from iterplan_compiler.ir.model import SynthesisProblem


def problem(plant: tuple[LTS, ...] | LTS, *, controllable: set[str], fluents=(),
            guarantees: tuple[Formula, ...] = (), assumptions: tuple[Formula, ...] = (),
            failures: tuple[Formula, ...] = (), safety: tuple[LTS, ...] = (),
            keywords=("controller",), marking=None, nonblocking=False) -> SynthesisProblem:
    if isinstance(plant, LTS):
        plant = (plant,)
    return SynthesisProblem("C", frozenset(keywords), tuple(plant), tuple(safety),
                            tuple(assumptions), tuple(guarantees), tuple(failures),
                            tuple(fluents), frozenset(controllable),
                            frozenset(marking) if marking is not None else None, nonblocking)


def fl(name: str, init: set[str], term: set[str], initially: bool = False) -> Fluent:
    return Fluent(name, frozenset(init), frozenset(term), initially)


def F(name: str) -> FluentProp:
    return FluentProp(name)


def assert_same_as_full_game(prob: SynthesisProblem, macro) -> None:
    """``prob`` solved with the compression ``macro`` (a ``MacroSteps``) and as the full
    game: the same verdict and bisimilar controllers."""
    from iterplan_compiler.ir.minimise import bisimilar
    from iterplan_compiler.synthesis.driver import synthesize
    from iterplan_compiler.synthesis.options import MacroSteps

    on = synthesize(prob, macro=macro, explain=False)
    off = synthesize(prob, macro=MacroSteps.OFF, explain=False)
    assert on.realizable == off.realizable
    if on.realizable:
        assert bisimilar(on.controller, off.controller)
