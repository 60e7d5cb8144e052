"""Elaborated declarations shared between the front-end, the FLTL layer and synthesis.

The front-end (``frontend/elaborate.py``) owns the full ``Model`` type (processes, composites,
constants, ...) and may extend this module; the two records below are the contract with
synthesis and must keep their field names.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass, field

from iterplan_compiler.diagnostics import NO_SPAN, Diagnostic, Span
from iterplan_compiler.ir.formulas import Fluent, Formula, FormulaKind, NamedFormula
from iterplan_compiler.ir.lts import LTS

#: Composite keywords that make a composite a synthesis problem (MTSA §1.11, §3.9, §3.10):
#: building it solves a game.  (``checkCompatibility`` also poses the game, without solving.)

class Unrealizable(enum.Enum):
    """What building an unrealizable ``controller`` composite gives."""

    #: error E0901, no LTS (``iterc`` commands)
    ERROR = "error"
    #: MTSA's composition: the plant the game was played on, ``C_#NC#``, and warning W0902
    PLANT = "plant"

SYNTHESIS_KEYWORDS = frozenset({"controller", "gr", "heuristic", "monolithicDirector"})


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
    #: the spec's ``permissive`` flag (§3.6: also keep winning, not rank-improving moves)
    permissive: bool = False
    #: how many leading ``plant`` machines make up the body's first item (MTSA's
    #: "environment", which the controller replaces when re-composing, §3.6): a plain
    #: sub-composite is passed as its leaves, not flattened
    env_machines: int = 1


class ModelBackend:
    """What :class:`Model` delegates its lazy operations to (implemented by the front-end's
    elaborator, ``frontend/elaborate.py``).  Kept abstract here so ``ir`` does not import the
    front-end."""

    def build_lts(self, name: str, unrealizable: Unrealizable = Unrealizable.ERROR,
                  solve: bool = True) -> tuple[LTS | None, list[Diagnostic]]:  # pragma: no cover
        raise NotImplementedError

    def synthesis_problem(self, name: str) -> tuple[SynthesisProblem | None, list]:  # pragma: no cover
        raise NotImplementedError

    def controllable(self, name: str) -> frozenset[str]:  # pragma: no cover - interface
        raise NotImplementedError

    def legality(self, name: str) -> tuple[bool, str]:  # pragma: no cover - interface
        raise NotImplementedError

    def synthesis_components(self, name: str) -> tuple[str, ...]:  # pragma: no cover
        raise NotImplementedError


@dataclass(frozen=True, eq=False)
class Model:
    """An elaborated FSP file (the front-end's output).

    * ``processes`` / ``composites`` — names of sequential processes and composites in source
      order; ``composite_keywords[name]`` — operator keywords written before a composite;
    * ``fluents`` — every concrete fluent (indexed families expanded as ``F.v``);
    * ``formulas`` — ``assert``/``ltl_property``/``constraint`` declarations (non-parameterised
      ones, and parameterised ones at their default values);
    * ``controller_specs`` — elaborated ``controllerSpec`` declarations;
    * ``constants``, ``ranges``, ``sets`` — evaluated global tables.

    LTSs are built lazily (and cached) by :meth:`build_lts`; every method returns diagnostics
    instead of raising for bad input.
    """

    source_path: str
    source_text: str
    processes: tuple[str, ...]
    composites: tuple[str, ...]
    composite_keywords: Mapping[str, frozenset[str]]
    fluents: Mapping[str, Fluent]
    formulas: Mapping[str, NamedFormula]
    controller_specs: Mapping[str, ControllerSpec]
    constants: Mapping[str, int | float | str]
    ranges: Mapping[str, tuple[int, int]]
    sets: Mapping[str, tuple[str, ...]]
    backend: ModelBackend = field(repr=False)
    sources: Mapping[str, str] = field(default_factory=dict, repr=False)
    #: file that declares each process/composite/formula (``source_path`` or an included file)
    origins: Mapping[str, str] = field(default_factory=dict, repr=False)

    def names(self) -> tuple[str, ...]:
        """Names accepted by :meth:`build_lts`: processes, composites, ltl_property/constraint."""
        extra = tuple(n for n, f in self.formulas.items() if f.kind is not FormulaKind.ASSERT)
        return self.processes + self.composites + extra

    def own_names(self) -> tuple[str, ...]:
        """The :meth:`names` declared in ``source_path`` itself, not in an included file.

        ``iterc check --build`` builds these (and, transitively, whatever they use): an
        included library may hold fragments that only make sense once the including file
        declares the sets they mention."""
        return tuple(n for n in self.names()
                     if self.origins.get(n, self.source_path) == self.source_path)

    def default_name(self) -> str | None:
        """What ``iterc lts SPEC`` builds without a name: the last composite, else the last
        process (MTSA's "DEFAULT" composes all processes; we keep it simple)."""
        if self.composites:
            return self.composites[-1]
        if self.processes:
            return self.processes[-1]
        return None

    def build_lts(self, name: str, unrealizable: Unrealizable = Unrealizable.ERROR,
                  solve: bool = True) -> tuple[LTS | None, list[Diagnostic]]:
        """Build (compose, apply operators, synthesise when asked) the named machine.

        An unrealizable ``controller`` composite is an error (E0901, no LTS) by default; with
        ``unrealizable=Unrealizable.PLANT`` it gives MTSA's composition instead: the plant the
        game was played on, named ``C_#NC#`` (MTSA semantics §3.7/§3.8), and the verdict as warning
        W0902.  With ``solve=False`` nothing is synthesised: a synthesis composite (also one
        used as a component) gives the plant its game is played on, under its own name
        (``iterc lts``)."""
        return self.backend.build_lts(name, unrealizable, solve)

    def is_synthesis_composite(self, name: str) -> bool:
        """True for a composite whose keywords ask for synthesis (``controller``, ...)."""
        return bool(self.composite_keywords.get(name, frozenset()) & SYNTHESIS_KEYWORDS)

    def synthesis_components(self, name: str) -> tuple[str, ...]:
        """The synthesis composites composite ``name`` uses (directly or through others)."""
        return self.backend.synthesis_components(name)

    def controller_composites(self) -> tuple[str, ...]:
        """The synthesis composites, in file order (nothing is built)."""
        return tuple(c for c in self.composites if self.is_synthesis_composite(c))

    def synthesis_problem(self, composite_name: str) -> tuple[SynthesisProblem | None, list]:
        """The resolved synthesis problem of ``controller ||C = (E)~{G}`` (and the other
        synthesis keywords)."""
        return self.backend.synthesis_problem(composite_name)

    def controllable(self, composite_name: str) -> frozenset[str]:
        """Controllable actions of the spec attached to a composite (empty if none)."""
        return self.backend.controllable(composite_name)

    def legality(self, composite_name: str) -> tuple[bool, str]:
        """MTSA's ``LegalityAnalyser`` on the composite's machine 0 (controller) and machine 1
        (plant): ``(legal, detail)``; see ``Elaborator.legality`` for how the controllable set
        is chosen."""
        return self.backend.legality(composite_name)
