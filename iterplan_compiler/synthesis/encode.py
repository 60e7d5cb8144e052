"""From a :class:`SynthesisProblem` to the component list of the game (§3.2 of the semantics).

Both solvers (explicit and symbolic) start from the same :class:`GameSpec`:

* ``components`` — plant components, then safety machines, then one two-state *fluent monitor*
  per goal fluent (state 0 = false, 1 = true; initiating actions go to 1, terminating to 0,
  from both states).  Composing them is exactly MTSA's ``P ∥ S1 ∥ … ∥ Sk`` followed by
  ``embedFluents`` (§3.2 step 6).  As in MTSA, an action only a fluent mentions is a free move
  of the product (a frequent modelling pitfall, which we report as a warning).
* goal formulas are propositional formulas over fluent names; action propositions become the
  synthetic fluent ``<a, Σ_P \\ a>`` initially false, as in the DCS path (§2.10).  The
  monolithic ``controller`` path of MTSA rejects them; we accept them with the DCS meaning
  (documented in docs/synthesis.md).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from iterplan_compiler.ir.formulas import (
    ActionProp,
    And,
    Const,
    Fluent,
    FluentProp,
    Formula,
    Iff,
    Implies,
    Not,
    Or,
)
from iterplan_compiler.ir.lts import LTS, TAU, make_lts
from iterplan_compiler.ir.model import SynthesisProblem
from iterplan_compiler.synthesis.options import GameMode


class PreconditionFailure(Exception):
    """MTSA's DCS (``heuristic``) refuses the problem: it prints a message and the composite is
    null, which the test-suites read as *unrealizable* (§3.7, §3.9)."""


class SynthesisError(Exception):
    """A problem that cannot be solved as stated (a user error, reported as a diagnostic)."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


@dataclass(frozen=True)
class GameSpec:
    """Components of the game and its goal, ready for either solver.

    ``num_plant`` components come first (they are the ones the controller replaces when
    re-composing), then ``num_safety`` safety machines, then the fluent monitors in the order
    of ``fluent_names``.  ``assumptions``/``guarantees``/``failures`` are propositional
    formulas over ``fluent_names``; empty lists keep MTSA's default (one TRUE set) to the
    solvers.  ``mode`` is :attr:`GameMode.GR1` or :attr:`GameMode.NONBLOCKING` (then
    ``guarantees`` holds the single marking formula).
    """

    name: str
    components: tuple[LTS, ...]
    num_plant: int
    num_safety: int
    fluent_names: tuple[str, ...]
    controllable: frozenset[str]
    assumptions: tuple[Formula, ...]
    guarantees: tuple[Formula, ...]
    failures: tuple[Formula, ...]
    mode: GameMode = GameMode.GR1
    warnings: tuple[str, ...] = field(default=())
    #: per component, per code bit (LSB first): the feature key of that bit or None
    #: (:mod:`recode`; empty: no keys, the plain order)
    bit_keys: tuple[tuple[str | None, ...], ...] = field(default=())

    @property
    def alphabet(self) -> frozenset[str]:
        out: set[str] = set()
        for c in self.components:
            out |= c.alphabet
        return frozenset(out)

    @property
    def plant_alphabet(self) -> frozenset[str]:
        out: set[str] = set()
        for c in self.components[: self.num_plant + self.num_safety]:
            out |= c.alphabet
        return frozenset(out)

    def fluent_component(self, name: str) -> int:
        """Index in ``components`` of the monitor of fluent ``name``."""
        return self.num_plant + self.num_safety + self.fluent_names.index(name)


def fluent_monitor(fl: Fluent) -> LTS:
    """Two-state monitor of ``fl`` (0 = false, 1 = true), initial state = initial value."""
    trans = [(s, a, 1) for s in (0, 1) for a in fl.initiating]
    trans += [(s, a, 0) for s in (0, 1) for a in fl.terminating]
    return make_lts(f"fluent:{fl.name}", 2, trans, fl.initiating | fl.terminating,
                    initial=1 if fl.initially else 0, state_names=("false", "true"))


def _action_fluent_name(actions: frozenset[str]) -> str:
    return "a_" + ("{" + ",".join(sorted(actions)) + "}" if len(actions) != 1
                   else next(iter(actions)))


def prepare(problem: SynthesisProblem, *, mode: GameMode | None = None) -> GameSpec:
    """Collect components and goal sets; raise :class:`SynthesisError` on unsupported goals."""
    kw = problem.keywords
    if mode is None:
        nb = problem.nonblocking and problem.marking is not None
        mode = GameMode.NONBLOCKING if nb and ("heuristic" in kw or "monolithicDirector" in kw) \
            else GameMode.GR1
    plant = tuple(problem.plant)
    safety = tuple(problem.safety)
    if mode is GameMode.NONBLOCKING and "monolithicDirector" in kw:
        safety = ()  # §3.10: the director algorithm only sees machine 0
    plant_alpha: set[str] = set()
    for c in plant + safety:
        plant_alpha |= c.alphabet
    plant_alpha.discard(TAU)
    by_name = {f.name: f for f in problem.fluents}
    used: dict[str, Fluent] = {}
    warnings: list[str] = []

    def convert(f: Formula) -> Formula:
        if isinstance(f, Const):
            return f
        if isinstance(f, FluentProp):
            if f.name not in by_name:
                raise SynthesisError("E0906", f"unknown fluent {f.name!r} in a goal")
            used[f.name] = by_name[f.name]
            return f
        if isinstance(f, ActionProp):
            name = _action_fluent_name(f.actions)
            used[name] = Fluent(name, f.actions, frozenset(plant_alpha - f.actions), False)
            return FluentProp(name)
        if isinstance(f, Not):
            return Not(convert(f.arg))
        if isinstance(f, And | Or | Implies | Iff):
            return type(f)(convert(f.left), convert(f.right))
        raise SynthesisError(
            "E0907", f"goal formula must be propositional (no X, U, W, [], <>): {f!r}")

    if mode is GameMode.NONBLOCKING:
        marking = frozenset(problem.marking or ()) & plant_alpha
        goal_fl = Fluent("_Goal", marking, frozenset(plant_alpha - marking), False)
        used[goal_fl.name] = goal_fl
        assumptions = tuple(convert(a) for a in problem.assumptions)
        guarantees: tuple[Formula, ...] = (FluentProp(goal_fl.name),)
        failures: tuple[Formula, ...] = ()
    else:
        assumptions = tuple(convert(a) for a in problem.assumptions)
        guarantees = tuple(convert(g) for g in problem.guarantees)
        failures = tuple(convert(f) for f in problem.failures)
    if "heuristic" in kw:
        _dcs_preconditions(problem, used, plant_alpha)
    names = tuple(sorted(used))
    monitors = tuple(fluent_monitor(used[n]) for n in names)
    for n in names:
        free = (used[n].initiating | used[n].terminating) - plant_alpha
        if free:
            warnings.append(f"fluent {n}: actions {sorted(free)} are not plant actions; they "
                            "become free moves of the game (as in MTSA)")
    return GameSpec(problem.name, plant + safety + monitors, len(plant), len(safety), names,
                    frozenset(problem.controllable), assumptions, guarantees, failures, mode,
                    tuple(warnings))


def _dcs_preconditions(problem: SynthesisProblem, used: Mapping[str, Fluent],
                       plant_alpha: set[str]) -> None:
    """The checks of MTSA's ``hcs`` entry (§3.9); raise :class:`PreconditionFailure`."""
    if problem.failures:
        raise PreconditionFailure("Failure tag is not supported for heuristic analysis")
    has_marking = bool(problem.marking)
    if bool(problem.guarantees) == has_marking:
        raise PreconditionFailure("heuristic synthesis needs exactly one of liveness / marking")
    if has_marking and len(problem.assumptions) > 1:
        raise PreconditionFailure("heuristic synthesis with marking allows one assumption")
    for fl in used.values():
        if fl.name == "_Goal":
            continue
        extra = (fl.initiating | fl.terminating) - plant_alpha
        if extra:
            raise PreconditionFailure(
                "Assumptions and Guarantees cant include actions that are not permited by the "
                f"plant ({', '.join(sorted(extra))})")


def evaluate(f: Formula, val: Mapping[str, Any], *, true: Any = True, false: Any = False,
             neg: Callable[[Any], Any] = lambda x: not x) -> Any:
    """Evaluate a converted goal formula; ``val`` maps fluent names to values.

    With ``true``/``false``/``neg`` and operator overloading this works for Python booleans
    and for BDD nodes alike (``&``, ``|`` on both).
    """
    if isinstance(f, Const):
        return true if f.value else false
    if isinstance(f, FluentProp):
        return val[f.name]
    if isinstance(f, Not):
        return neg(evaluate(f.arg, val, true=true, false=false, neg=neg))
    a = evaluate(f.left, val, true=true, false=false, neg=neg)  # type: ignore[attr-defined]
    b = evaluate(f.right, val, true=true, false=false, neg=neg)  # type: ignore[attr-defined]
    if isinstance(f, And):
        return a & b
    if isinstance(f, Or):
        return a | b
    if isinstance(f, Implies):
        return neg(a) | b
    if isinstance(f, Iff):
        return (a & b) | (neg(a) & neg(b))
    raise TypeError(f"unexpected formula {f!r}")
