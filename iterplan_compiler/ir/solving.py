"""The synthesis the front-end needs, as an interface (dependency injection, not an import).

Building a composite that uses a controller composite (MTSA's ``||Sys = (C || Plant)``), a
``checkCompatibility`` composite or a ``plant`` composite needs the synthesis stage, which sits
*above* the front-end (layers: ir < fltl < frontend < synthesis).  So the front-end never
imports synthesis: it receives an object with this :class:`Synthesis` interface
(``frontend.load(..., synthesis=...)``) and the pipeline passes the real one
(:data:`iterplan_compiler.pipeline.SYNTHESIS`, an adapter around ``synthesis.driver``).
Without one, such a build reports E0909 instead of solving.
"""

from __future__ import annotations

from typing import Protocol

from iterplan_compiler.ir.lts import LTS
from iterplan_compiler.ir.model import SynthesisProblem

__all__ = ["Solved", "Synthesis"]


class Solved(Protocol):
    """What the front-end reads of a synthesis result (``synthesis.driver.SynthesisResult``)."""

    @property
    def realizable(self) -> bool: ...

    @property
    def controller(self) -> LTS | None:
        """The controller over the plant alphabet (None when unrealizable)."""

    @property
    def composition(self) -> LTS | None:
        """``controller ∥ other body machines ∥ safety machines`` (None when unrealizable)."""

    @property
    def explanation(self) -> str:
        """Why the problem is unrealizable ("" otherwise)."""


class Synthesis(Protocol):
    """The synthesis stage as the front-end uses it (MTSA semantics doc §3)."""

    @property
    def input_errors(self) -> tuple[type[Exception], ...]:
        """The exceptions that are about the *input* (reported as diagnostic E0901); every
        other exception is a compiler bug and must reach the CLI's exit 3 handler."""

    def synthesize(self, problem: SynthesisProblem) -> Solved:
        """Solve ``problem`` and build its controller (``controller ||C = ...``)."""

    def check_compatibility(self, problem: SynthesisProblem) -> tuple[bool, str]:
        """MTSA's ``checkCompatibility`` (§3.11): ``(compatible, message)``."""

    def plant_components(self, problem: SynthesisProblem) -> tuple[LTS, ...]:
        """The game's components with the goal's fluent monitors (``plant ||P``, §3.2 step 6),
        not composed."""
