"""Immutable abstract syntax of the MTSA FSP dialect, part 1: every node but the declarations
(re-exported by :mod:`.syntax`, which adds the ``*Decl`` nodes and :class:`SpecFile`).

The syntax of ``mtsa-semantics.md`` §1.

Produced by :mod:`iterplan_compiler.frontend.parse` and consumed by elaboration and by the FSP
printer.  Every node is a frozen dataclass; ``span`` (excluded from equality, so two parses of
the same text at different positions compare equal) points at the node's first token.

Groups of nodes:

* expressions (:class:`Expr` subclasses) — §1.3;
* label expressions (:class:`Label`, :class:`SetDiff`) built from parts (:class:`Ident`,
  :class:`SetName`, :class:`Index`, :class:`RangeIndex`, :class:`Bind`, :class:`SetLit`) — §1.4;
* state expressions of sequential processes (:class:`StateRef`, :class:`SeqComp`,
  :class:`Choices`, :class:`IfState`) — §1.5;
* composite bodies (:class:`CRef`, :class:`CPar`, :class:`CItem`, :class:`CForall`,
  :class:`CIf`) — §1.6;
* FLTL formulas (``F*`` nodes) — §1.9;
* declarations (``*Decl``) collected in a :class:`SpecFile`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING

from iterplan_compiler.diagnostics import NO_SPAN, Span


def _span() -> Span:
    return field(default=NO_SPAN, compare=False, repr=False)


# ------------------------------------------------------------------ expressions


class Expr:
    """Base of expression nodes (every node has a ``span``)."""

    __slots__ = ()
    if TYPE_CHECKING:
        span: Span


@dataclass(frozen=True)
class Num(Expr):
    """Integer or real literal (already converted: octal/hex resolved)."""

    value: int | Fraction
    span: Span = _span()


@dataclass(frozen=True)
class Var(Expr):
    """A lower-case identifier: a variable bound by ``[i:R]``, ``forall`` or a ``def`` parameter."""

    name: str
    span: Span = _span()


@dataclass(frozen=True)
class Name(Expr):
    """An upper-case identifier: parameter, constant, or (as an index) a range name."""

    name: str
    span: Span = _span()


@dataclass(frozen=True)
class Call(Expr):
    """``Name(args)`` — a ``def`` macro call."""

    name: str
    args: tuple[Expr, ...]
    span: Span = _span()


@dataclass(frozen=True)
class LabelConst(Expr):
    """``'label`` — a label constant."""

    label: Label
    span: Span = _span()


@dataclass(frozen=True)
class Card(Expr):
    """``#Set`` — number of labels of a set."""

    set: LabelSetRef
    span: Span = _span()


@dataclass(frozen=True)
class At(Expr):
    """``@(Set, i)`` — the i-th label of a set (0-based)."""

    set: LabelSetRef
    index: Expr
    span: Span = _span()


@dataclass(frozen=True)
class Unary(Expr):
    """``op arg`` with op in ``+ - ! ~``."""

    op: str
    arg: Expr
    span: Span = _span()


@dataclass(frozen=True)
class Binary(Expr):
    """``left op right`` (op as written: ``+``, ``\\``, ``&&``, ``<<``, ...)."""

    op: str
    left: Expr
    right: Expr
    span: Span = _span()


@dataclass(frozen=True)
class Cond(Expr):
    """``c ? a : b``."""

    cond: Expr
    then: Expr
    other: Expr
    span: Span = _span()


# ------------------------------------------------------------------ labels and sets


@dataclass(frozen=True)
class Ident:
    """A lower-case label part ``a`` (or a literal number after a dot, ``a.1``)."""

    name: str
    span: Span = _span()


@dataclass(frozen=True)
class SetName:
    """An upper-case label part: a set name (or, as a state, a local process name)."""

    name: str
    span: Span = _span()


@dataclass(frozen=True)
class Index:
    """``[expr]`` (an upper name alone may denote a range: resolved at elaboration)."""

    expr: Expr
    span: Span = _span()


@dataclass(frozen=True)
class RangeIndex:
    """``[lo..hi]``."""

    low: Expr
    high: Expr
    span: Span = _span()


@dataclass(frozen=True)
class RangeName:
    """The range of a binding given by name ``[i:R]`` (a range or a set)."""

    name: str
    span: Span = _span()


@dataclass(frozen=True)
class RangeLit:
    """The range of a binding given inline ``[i:lo..hi]``."""

    low: Expr
    high: Expr
    span: Span = _span()


@dataclass(frozen=True)
class Bind:
    """``[var : range]`` — binds ``var`` for the rest of the enclosing construct."""

    var: str
    range: RangeName | RangeLit | SetLit
    span: Span = _span()


@dataclass(frozen=True)
class SetLit:
    """``{l1, l2, ...}``."""

    items: tuple[LabelExpr, ...]
    span: Span = _span()


Part = Ident | SetName | Index | RangeIndex | Bind | SetLit


@dataclass(frozen=True)
class Label:
    """A label element: parts concatenated with dots (``a[i].b``, ``{x,y}.c``)."""

    parts: tuple[Part, ...]
    span: Span = _span()


@dataclass(frozen=True)
class SetDiff:
    """``A \\ B \\ C`` — set difference of label elements."""

    base: Label
    minus: tuple[Label, ...]
    span: Span = _span()


LabelExpr = Label | SetDiff
LabelSetRef = SetLit | SetName


# ------------------------------------------------------------------ relabelling


@dataclass(frozen=True)
class RelabelPair:
    """``new/old``."""

    new: LabelExpr
    old: LabelExpr
    span: Span = _span()


@dataclass(frozen=True)
class RelabelForall:
    """``forall [i:R] {new/old, ...}``."""

    binds: tuple[Bind, ...]
    items: tuple[RelabelItem, ...]
    span: Span = _span()


RelabelItem = RelabelPair | RelabelForall


# ------------------------------------------------------------------ process state expressions


@dataclass(frozen=True)
class StateRef:
    """A reference to a local state or process: ``Q``, ``Q[i+1]``, ``P(2)``, ``STOP``.

    ``args`` is ``None`` without parentheses (a local reference) and a tuple for ``P(args)``
    (an instance of another process, spliced in).
    """

    name: str
    args: tuple[Expr, ...] | None = None
    indices: tuple[Expr, ...] = ()
    span: Span = _span()


@dataclass(frozen=True)
class SeqComp:
    """``A; B; C`` — run each process to its END, continue as the last (a local state)."""

    items: tuple[StateRef, ...]
    span: Span = _span()


@dataclass(frozen=True)
class Choice:
    """``[when guard] l1 -> l2 -> ... -> target``."""

    guard: Expr | None
    labels: tuple[LabelExpr, ...]
    target: StateExpr
    span: Span = _span()


@dataclass(frozen=True)
class Choices:
    """``( [foreach [i:R][j:S]...] c1 | c2 | ... )`` (no bindings: ``foreach == ()``)."""

    choices: tuple[Choice, ...]
    foreach: tuple[Bind, ...] = ()
    span: Span = _span()


@dataclass(frozen=True)
class IfState:
    """``if c then S [else S]`` (missing else = STOP)."""

    cond: Expr
    then: StateExpr
    other: StateExpr | None
    span: Span = _span()


StateExpr = StateRef | SeqComp | Choices | IfState


# ------------------------------------------------------------------ tails (operators after a body)


@dataclass(frozen=True)
class Tail:
    """An operator after a body.

    ``kind`` is one of ``extend`` (``+S``), ``relabel`` (``/{..}``; ``relabels`` set),
    ``hide`` (``\\S``), ``expose`` (``@S``), ``error_set`` (``!S``), ``spec`` (``~{G}``; ``name``
    set), ``high`` (``<<S``), ``low`` (``>>S``).
    """

    kind: str
    labels: LabelSetRef | None = None
    relabels: tuple[RelabelItem, ...] = ()
    name: str = ""
    span: Span = _span()


# ------------------------------------------------------------------ composites


@dataclass(frozen=True)
class CRef:
    """``P`` or ``P(args)`` inside a composite body."""

    name: str
    args: tuple[Expr, ...] = ()
    span: Span = _span()


@dataclass(frozen=True)
class CPar:
    """``(B1 || B2 || ...)``."""

    items: tuple[CBody, ...]
    span: Span = _span()


@dataclass(frozen=True)
class Prefix:
    """``label:`` (``share=False``) or ``label::`` (``share=True``) before a composite item."""

    label: Label
    share: bool
    span: Span = _span()


@dataclass(frozen=True)
class CItem:
    """``prefixes* (CRef | CPar) [/ {relabels}]``."""

    prefixes: tuple[Prefix, ...]
    prim: CRef | CPar
    relabels: tuple[RelabelItem, ...] | None = None
    span: Span = _span()


@dataclass(frozen=True)
class CForall:
    """``forall [i:R]... body``."""

    binds: tuple[Bind, ...]
    body: CBody
    span: Span = _span()


@dataclass(frozen=True)
class CIf:
    """``if c then B [else B]``."""

    cond: Expr
    then: CBody
    other: CBody | None
    span: Span = _span()


CBody = CItem | CForall | CIf | CPar | CRef


__all__ = [
    "At",
    "Binary",
    "Bind",
    "CBody",
    "CForall",
    "CIf",
    "CItem",
    "CPar",
    "CRef",
    "Call",
    "Card",
    "Choice",
    "Choices",
    "Cond",
    "Expr",
    "Ident",
    "IfState",
    "Index",
    "Label",
    "LabelConst",
    "LabelExpr",
    "LabelSetRef",
    "Name",
    "Num",
    "Part",
    "Prefix",
    "RangeIndex",
    "RangeLit",
    "RangeName",
    "RelabelForall",
    "RelabelItem",
    "RelabelPair",
    "SeqComp",
    "SetDiff",
    "SetLit",
    "SetName",
    "StateExpr",
    "StateRef",
    "Tail",
    "Unary",
    "Var",
]
