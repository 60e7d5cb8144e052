"""Immutable abstract syntax of the MTSA FSP dialect (``mtsa-semantics.md`` §1).

Expressions, labels, process states, tails and composite bodies are in :mod:`.syntax_nodes`
(re-exported here: one namespace, ``S.X``); FLTL formulas and declarations are here.

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

from dataclasses import dataclass

from iterplan_compiler.diagnostics import Span
from iterplan_compiler.frontend.syntax_nodes import *  # noqa: F403 - one namespace, `S.X`
from iterplan_compiler.frontend.syntax_nodes import (
    Bind,
    CBody,
    Expr,
    Label,
    LabelExpr,
    LabelSetRef,
    Part,
    SetLit,
    StateExpr,
    Tail,
    _span,
)

# ------------------------------------------------------------------ formulas


class FNode:
    """Base of syntactic FLTL formula nodes."""

    __slots__ = ()


@dataclass(frozen=True)
class FUnary(FNode):
    """``op arg`` with op in ``!``, ``X``, ``[]``, ``<>``."""

    op: str
    arg: FNode
    span: Span = _span()


@dataclass(frozen=True)
class FBinary(FNode):
    """``left op right`` with op in ``&&``, ``||``, ``U``, ``W``, ``->``, ``<->``."""

    op: str
    left: FNode
    right: FNode
    span: Span = _span()


@dataclass(frozen=True)
class FQuant(FNode):
    """``exists``/``forall`` over bindings (disjunction / conjunction)."""

    kind: str
    binds: tuple[Bind, ...]
    body: FNode
    span: Span = _span()


@dataclass(frozen=True)
class FRigid(FNode):
    """``rigid expr`` — a constant truth value."""

    expr: Expr
    span: Span = _span()


@dataclass(frozen=True)
class FRef(FNode):
    """``Name`` / ``Name[i]`` / ``Name[i:R]`` — a fluent (family member) or an assert."""

    name: str
    indices: tuple[Part, ...] = ()
    span: Span = _span()


@dataclass(frozen=True)
class FCall(FNode):
    """``Name(args)`` — a parameterised assert."""

    name: str
    args: tuple[Expr, ...]
    span: Span = _span()


@dataclass(frozen=True)
class FAction(FNode):
    """An action proposition (``a``, ``go[1]``, ``{a,b}``)."""

    label: Label
    span: Span = _span()


# ------------------------------------------------------------------ declarations


@dataclass(frozen=True)
class Param:
    """``Name = default`` in a parameter list."""

    name: str
    default: Expr
    span: Span = _span()


@dataclass(frozen=True)
class ConstDecl:
    name: str
    value: Expr
    span: Span = _span()


@dataclass(frozen=True)
class RangeDecl:
    name: str
    low: Expr
    high: Expr
    span: Span = _span()


@dataclass(frozen=True)
class SetDecl:
    name: str
    value: SetLit
    span: Span = _span()


@dataclass(frozen=True)
class DefDecl:
    """``def F(x, y) = expr`` (macro)."""

    name: str
    params: tuple[str, ...]
    body: Expr
    span: Span = _span()


@dataclass(frozen=True)
class IncludeDecl:
    """``include "file.lts"`` (iterplan extension; resolved by :mod:`.includes`)."""

    path: str
    span: Span = _span()


@dataclass(frozen=True)
class FluentDecl:
    """``fluent F[i:R] = <I, T> initially e``."""

    name: str
    indices: tuple[Part, ...]
    initiating: LabelExpr
    terminating: LabelExpr
    initially: Expr | None
    span: Span = _span()


@dataclass(frozen=True)
class FormulaDecl:
    """``assert`` / ``ltl_property`` / ``constraint`` ``Name[(params)] = formula [+ S]``."""

    kind: str
    name: str
    params: tuple[Param, ...]
    formula: FNode
    extension: LabelSetRef | None
    span: Span = _span()


@dataclass(frozen=True)
class SpecItem:
    """One field of a ``controllerSpec``.

    ``key`` is the keyword; exactly one of ``names`` (name lists), ``labels`` (label sets),
    ``ints`` (``lazyness``/``test_latency``) is meaningful; flags have none.
    """

    key: str
    names: tuple[str, ...] = ()
    labels: LabelSetRef | None = None
    ints: tuple[int, ...] = ()
    span: Span = _span()


@dataclass(frozen=True)
class SpecDecl:
    name: str
    items: tuple[SpecItem, ...]
    span: Span = _span()


@dataclass(frozen=True)
class LocalDef:
    """``, Q[i:R] = body`` — a local state (family) of a process."""

    name: str
    indices: tuple[Part, ...]
    body: StateExpr
    accept: bool = False
    span: Span = _span()


@dataclass(frozen=True)
class ProcessDecl:
    """``[keywords] P[(params)] = body, locals... tails .``"""

    name: str
    params: tuple[Param, ...]
    keywords: tuple[str, ...]
    body: StateExpr
    locals: tuple[LocalDef, ...]
    tails: tuple[Tail, ...]
    accept: bool = False
    span: Span = _span()


@dataclass(frozen=True)
class CompositeDecl:
    """``[keywords] ||C[(params)] = body tails .``"""

    name: str
    params: tuple[Param, ...]
    keywords: tuple[str, ...]
    body: CBody
    tails: tuple[Tail, ...]
    span: Span = _span()


@dataclass(frozen=True)
class IgnoredDecl:
    """A declaration that is parsed but has no meaning here (``menu``, ``animation``);
    elaboration warns once."""

    kind: str
    name: str
    span: Span = _span()


@dataclass(frozen=True)
class ProgressDecl:
    """``progress P[i:R] = {a, b}`` or ``progress P = if {a} then {b}`` (LTSA progress
    property, checked by ``iterc check --progress``; ``condition`` is the ``if`` set)."""

    name: str
    indices: tuple[Part, ...]
    condition: SetLit | None
    actions: SetLit
    span: Span = _span()


Decl = (ConstDecl | RangeDecl | SetDecl | DefDecl | IncludeDecl | FluentDecl | FormulaDecl
        | SpecDecl | ProcessDecl | CompositeDecl | IgnoredDecl | ProgressDecl)


@dataclass(frozen=True)
class SpecFile:
    """A parsed file: its declarations in source order."""

    path: str
    decls: tuple[Decl, ...]
