"""Elaborated declarations shared between the front-end, the FLTL layer and synthesis.

The front-end (``frontend/elaborate.py``) owns the full ``Model`` type (processes, composites,
constants, ...) and may extend this module; the two records below are the contract with
synthesis and must keep their field names.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from iterplan_compiler.diagnostics import NO_SPAN, Span
from iterplan_compiler.ir.formulas import Fluent, Formula
from iterplan_compiler.ir.lts import LTS


@dataclass(frozen=True, slots=True)
class ControllerSpec:
    """An elaborated ``controllerSpec G = {...}`` (MTSA semantics doc §1.10).

    Name lists keep the names as written; ``controllable`` and ``marking`` are expanded label
    sets.  ``marking`` is ``None`` when the field is absent.  ``flags`` holds the bare
    keywords (``nonblocking``, ``permissive``, ``reachability``, ...).
    """

    name: str
    safety: tuple[str, ...] = ()
    assumptions: tuple[str, ...] = ()
    liveness: tuple[str, ...] = ()
    failures: tuple[str, ...] = ()
    controllable: frozenset[str] = frozenset()
    marking: frozenset[str] | None = None
    flags: frozenset[str] = frozenset()
    span: Span = field(default=NO_SPAN, compare=False)

    @property
    def nonblocking(self) -> bool:
        return "nonblocking" in self.flags


@dataclass(frozen=True, slots=True)
class SynthesisProblem:
    """Everything synthesis needs for ``controller ||C = (Env)~{G}.``, already resolved.

    * ``plant`` — the environment's components, *not yet composed* (the symbolic engine composes
      them); each is an explicit LTS (ERROR transitions allowed).
    * ``safety`` — LTSs of the spec's ``safety`` entries (processes, ``ltl_property`` automata
      with their ERROR moves, ``constraint`` automata), ``@`` acceptance actions removed.
    * ``assumptions`` / ``guarantees`` / ``failures`` — propositional formulas over ``fluents``
      and action propositions (§2.10); a guarantee that names a bare fluent becomes
      ``FluentProp``.
    * ``keywords`` — the operator keywords on the composite (``controller``, ``heuristic``,
      ``monolithicDirector``, ``checkCompatibility``, ``property``, ``minimal``, ...).
    """

    name: str
    keywords: frozenset[str]
    plant: tuple[LTS, ...]
    safety: tuple[LTS, ...]
    assumptions: tuple[Formula, ...]
    guarantees: tuple[Formula, ...]
    failures: tuple[Formula, ...]
    fluents: tuple[Fluent, ...]
    controllable: frozenset[str]
    marking: frozenset[str] | None = None
    nonblocking: bool = False
    spec_name: str = ""
    span: Span = field(default=NO_SPAN, compare=False)
