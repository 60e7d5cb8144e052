"""FLTL formulas and fluents as an immutable IR.

The front-end produces these after elaboration: ranges, ``exists``/``forall``, indexed fluents
and ``assert`` references are already expanded, so a formula mentions only concrete fluents
(:class:`FluentProp`) and concrete action sets (:class:`ActionProp`).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from iterplan_compiler.diagnostics import NO_SPAN, Span


@dataclass(frozen=True, slots=True)
class Fluent:
    """``fluent Name = <Initiating, Terminating> initially b`` (one concrete member)."""

    name: str
    initiating: frozenset[str]
    terminating: frozenset[str]
    initially: bool = False
    span: Span = field(default=NO_SPAN, compare=False)


class Formula:
    """Base class of FLTL formula nodes (all frozen dataclasses)."""

    __slots__ = ()


@dataclass(frozen=True, slots=True)
class Const(Formula):
    """``true``/``false`` (MTSA's ``rigid`` expressions also elaborate to this)."""

    value: bool


@dataclass(frozen=True, slots=True)
class FluentProp(Formula):
    """Truth value of a fluent (by name; the fluent is looked up in the model)."""

    name: str


@dataclass(frozen=True, slots=True)
class ActionProp(Formula):
    """An action proposition: true at a position whose last action is in ``actions``."""

    actions: frozenset[str]


@dataclass(frozen=True, slots=True)
class Not(Formula):
    arg: Formula


@dataclass(frozen=True, slots=True)
class And(Formula):
    left: Formula
    right: Formula


@dataclass(frozen=True, slots=True)
class Or(Formula):
    left: Formula
    right: Formula


@dataclass(frozen=True, slots=True)
class Implies(Formula):
    left: Formula
    right: Formula


@dataclass(frozen=True, slots=True)
class Iff(Formula):
    left: Formula
    right: Formula


@dataclass(frozen=True, slots=True)
class Next(Formula):
    """``X f``."""

    arg: Formula


@dataclass(frozen=True, slots=True)
class Always(Formula):
    """``[] f``."""

    arg: Formula


@dataclass(frozen=True, slots=True)
class Eventually(Formula):
    """``<> f``."""

    arg: Formula


@dataclass(frozen=True, slots=True)
class Until(Formula):
    """``f U g`` (strong)."""

    left: Formula
    right: Formula


@dataclass(frozen=True, slots=True)
class WeakUntil(Formula):
    """``f W g``."""

    left: Formula
    right: Formula


class FormulaKind(enum.Enum):
    """Which declaration a :class:`NamedFormula` comes from (the value is its keyword)."""

    ASSERT = "assert"                # checked by `iterc verify` (FLTL model checking)
    LTL_PROPERTY = "ltl_property"    # a safety property: composed as a safety automaton
    CONSTRAINT = "constraint"        # the same, as an environment constraint


@dataclass(frozen=True, slots=True)
class NamedFormula:
    """An elaborated ``assert`` / ``ltl_property`` / ``constraint`` declaration.

    ``kind`` is a :class:`FormulaKind` (its value, the keyword, is converted here);
    ``extra_alphabet`` is the ``+ {...}`` extension of the formula's alphabet.
    """

    name: str
    kind: FormulaKind
    formula: Formula
    extra_alphabet: frozenset[str] = frozenset()
    span: Span = field(default=NO_SPAN, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "kind", FormulaKind(self.kind))


_BINARY: dict[type, str] = {And: "&&", Or: "||", Implies: "->", Iff: "<->", Until: "U",
                            WeakUntil: "W"}
_UNARY: dict[type, str] = {Not: "!", Next: "X ", Always: "[]", Eventually: "<>"}


def show(f: Formula) -> str:
    """``f`` in FLTL syntax (names as in the spec; every compound operand parenthesised)."""
    if isinstance(f, FluentProp):
        return f.name
    if isinstance(f, ActionProp):
        acts = sorted(f.actions)
        return acts[0] if len(acts) == 1 else "{" + ", ".join(acts) + "}"
    if isinstance(f, Const):
        return "true" if f.value else "false"
    if type(f) in _UNARY:
        return f"{_UNARY[type(f)]}{_operand(f.arg)}"  # type: ignore[attr-defined]
    if type(f) in _BINARY:
        return (f"{_operand(f.left)} {_BINARY[type(f)]} "  # type: ignore[attr-defined]
                f"{_operand(f.right)}")  # type: ignore[attr-defined]
    return type(f).__name__


def _operand(f: Formula) -> str:
    text = show(f)
    return text if isinstance(f, (FluentProp, ActionProp, Const)) else f"({text})"
