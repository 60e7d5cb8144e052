"""The checks of one conformance row: what the corpus names, run one by one, each with a status.

A row of ``verdicts.tsv`` names a *verdict family* (the ``expected`` column) and, in its
``checks`` column, what MTSA's test asserts.  :func:`plan` turns both into a list of
:class:`Check` values (the verdict first, then every clause of the ``checks`` column); an
unknown family or an unrecognised clause is itself a check whose status is ``error``, so nothing
the corpus names can pass by being skipped.  :func:`run_checks` runs them against a loaded
model and returns one :class:`CheckResult` per check; the row's status is the worst of them
(:func:`worst`).

Statuses, best to worst: ``pass``, ``unsupported`` (an error diagnostic with the front-end's
"unsupported construct" code E0150 and nothing else wrong), ``fail`` (the tool disagrees with
MTSA's expectation), ``error`` (error diagnostics where MTSA compiles, or a check that cannot
be run), ``crash`` (an exception escaped), ``timeout``.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from iterplan_compiler.diagnostics import Diagnostic, Severity
from iterplan_compiler.ir.formulas import FormulaKind
from iterplan_compiler.ir.model import Unrealizable

if TYPE_CHECKING:
    from iterplan_compiler.ir.lts import LTS
    from iterplan_compiler.ir.model import Model
    from iterplan_compiler.synthesis.driver import SynthesisResult


class Status(str, enum.Enum):
    """A check's or a row's outcome, in order from best to worst."""

    PASS = "pass"
    UNSUPPORTED = "unsupported"
    FAIL = "fail"
    ERROR = "error"
    CRASH = "crash"
    TIMEOUT = "timeout"


STATUSES: tuple[str, ...] = tuple(s.value for s in Status)
_RANK = {s: i for i, s in enumerate(Status)}

#: the front-end's code for a construct it rejects on purpose (frontend/parse.py)
UNSUPPORTED_CODE = "E0150"
#: the front-end's code for a recursive composition (frontend/elaborate.py)
RECURSION_CODE = "E0401"
#: the front-end's code for a synthesis that failed or found no controller (frontend/elaborate.py)
SYNTHESIS_CODE = "E0901"


class Family(str, enum.Enum):
    """The verdict families of the ``expected`` column."""

    REALIZABLE = "realizable"
    UNREALIZABLE = "unrealizable"
    COMPILES = "compiles"
    NEVER_FAILS = "compiles (never fails)"
    ALPHABET = "alphabet"
    RECURSION = "recursion"
    BISIMILAR = "bisimilar"
    LEGAL = "legal"
    NOT_LEGAL = "not legal"
    UNKNOWN = "unknown"


_FAMILIES = {
    "realizable": Family.REALIZABLE,
    "realizable (implied)": Family.REALIZABLE,
    "unrealizable": Family.UNREALIZABLE,
    "compiles": Family.COMPILES,
    "compiles (errors only printed, never fail)": Family.NEVER_FAILS,
    "alphabet check": Family.ALPHABET,
    "error: recursive composition": Family.RECURSION,
    "n.a. (no synthesis: plain/property composite)": Family.BISIMILAR,
    "legal": Family.LEGAL,
    "not legal": Family.NOT_LEGAL,
}


def family(expected: str) -> Family:
    """The verdict family of an ``expected`` cell; anything not listed is ``UNKNOWN``."""
    return _FAMILIES.get(expected.strip(), Family.UNKNOWN)


def worst(statuses: Sequence[Status]) -> Status:
    """A row's status: the worst of its checks' (``error`` when there are none)."""
    return max(statuses, key=_RANK.__getitem__) if statuses else Status.ERROR


@dataclass(frozen=True, slots=True)
class CheckResult:
    """One named check of a row and its outcome."""

    name: str
    status: Status
    detail: str = ""

    def line(self) -> str:
        return f"{self.name}: {self.status.value}" + (f" ({self.detail})" if self.detail else "")


# --------------------------------------------------------------------------------------------
# Diagnostics as statuses


def errors_of(diags: Sequence[Diagnostic]) -> list[Diagnostic]:
    return [d for d in diags if d.severity == Severity.ERROR]


def diag_status(diags: Sequence[Diagnostic]) -> Status | None:
    """``None`` when there is no error; ``unsupported`` when every error is E0150 (the explicit
    reason), else ``error``."""
    errs = errors_of(diags)
    if not errs:
        return None
    return Status.UNSUPPORTED if all(d.code == UNSUPPORTED_CODE for d in errs) else Status.ERROR


def first_error(diags: Sequence[Diagnostic]) -> str:
    errs = errors_of(diags)
    if not errs:
        return ""
    d = errs[0]
    return f"{d.span.line}:{d.span.column}: [{d.code}] {d.message}"


# --------------------------------------------------------------------------------------------
# The checks


class Context:
    """A loaded model plus caches, shared by a row's checks (synthesis runs once per name)."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self._synth: dict[str, tuple[SynthesisResult | None, list[Diagnostic]]] = {}
        self._built: dict[str, tuple[LTS | None, list[Diagnostic]]] = {}

    def synthesis(self, name: str) -> tuple[SynthesisResult | None, list[Diagnostic]]:
        if name not in self._synth:
            from iterplan_compiler.synthesis.driver import synthesize

            problem, diags = self.model.synthesis_problem(name)
            if problem is None or errors_of(diags):
                self._synth[name] = (None, list(diags))
            else:
                res = synthesize(problem, explain=False)
                self._synth[name] = (res, list(diags) + list(res.diagnostics))
        return self._synth[name]

    def build(self, name: str, unrealizable: Unrealizable = Unrealizable.ERROR) -> tuple[LTS | None, list[Diagnostic]]:
        key = f"{name}\0{unrealizable}"
        if key not in self._built:
            self._built[key] = self.model.build_lts(name, unrealizable=unrealizable)
        return self._built[key]


Runner = Callable[[Context], CheckResult]


@dataclass(frozen=True, slots=True)
class Check:
    """A planned check: its name (shown in the report) and how to run it."""

    name: str
    run: Runner


def _problem(name: str, diags: Sequence[Diagnostic], what: str) -> CheckResult:
    status = diag_status(diags) or Status.ERROR
    return CheckResult(name, status, f"{what}: {first_error(diags) or 'no result'}")


def verdict(composite: str, want: bool) -> Check:
    """``composition != null`` (realizable) or ``== null`` (unrealizable) for ``composite``."""
    name = f"{'realizable' if want else 'unrealizable'} {composite}"

    def run(ctx: Context) -> CheckResult:
        res, diags = ctx.synthesis(composite)
        if res is None or (errors_of(diags) and not res.realizable):
            return _problem(name, diags, f"no synthesis of {composite}")
        got = "realizable" if res.realizable else "unrealizable"
        size = f"{got}; game {res.stats.get('game_states', '?')} states"
        return CheckResult(name, Status.PASS if res.realizable == want else Status.FAIL, size)

    return Check(name, run)


def ntransitions(composite: str) -> Check:
    """The controller of ``composite`` has at least one transition."""
    name = f"ntransitions>0 {composite}"

    def run(ctx: Context) -> CheckResult:
        res, diags = ctx.synthesis(composite)
        if res is None or res.controller is None:
            return CheckResult(name, Status.FAIL if res is not None else Status.ERROR,
                               "no controller")
        n = res.controller.num_transitions
        return CheckResult(name, Status.PASS if n > 0 else Status.FAIL, f"{n} transitions")

    return Check(name, run)


def holds(formula: str, system: str) -> Check:
    """``assert formula`` holds on the composition of ``system``."""
    name = f"assert {formula} on {system}"

    def run(ctx: Context) -> CheckResult:
        from iterplan_compiler.fltl.check import model_check

        named = ctx.model.formulas.get(formula)
        if named is None or named.kind is not FormulaKind.ASSERT:
            return CheckResult(name, Status.ERROR, f"no assert {formula} in the file")
        lts, diags = ctx.build(system)
        if lts is None or errors_of(diags):
            return _problem(name, diags, f"building {system}")
        res = model_check(lts, named.formula, ctx.model.fluents)
        return CheckResult(name, Status.PASS if res.holds else Status.FAIL,
                           "holds" if res.holds else "violated")

    return Check(name, run)


def legality(composite: str, want: bool) -> Check:
    """MTSA's LegalityAnalyser over ``composite``'s controller/plant pair."""
    name = f"{'legal' if want else 'not legal'} {composite}"

    def run(ctx: Context) -> CheckResult:
        legal, detail = ctx.model.legality(composite)
        if detail.startswith("error:"):  # Model.legality's contract for "could not be run"
            return CheckResult(name, Status.ERROR, detail)
        return CheckResult(name, Status.PASS if legal == want else Status.FAIL, detail)

    return Check(name, run)


def builds(composite: str) -> Check:
    """``composite`` compiles and composes (an unrealizable controller gives MTSA's plant)."""
    name = f"builds {composite}"

    def run(ctx: Context) -> CheckResult:
        names = set(ctx.model.names()) | {"DEFAULT"}
        if composite not in names:
            return CheckResult(name, Status.ERROR, "no such composite in the file")
        lts, diags = ctx.build(composite, unrealizable=Unrealizable.PLANT)
        errs = errors_of(diags)
        if errs and all(d.code == SYNTHESIS_CODE for d in errs):
            # a synthesis failure (e.g. an unrealizable controller used inside this
            # composite) is not an LTSException: MTSA's test swallows it
            return CheckResult(name, Status.PASS, f"no LTSException; synthesis: {first_error(errs)}")
        if lts is None or errs:
            return _problem(name, diags, "building")
        return CheckResult(name, Status.PASS,
                           f"{lts.num_states} states, {lts.num_transitions} transitions")

    return Check(name, run)


def never_fails(composite: str) -> Check:
    """MTSA's ParserTests print errors and never fail: building runs, any outcome passes."""
    name = f"compileCompositeState {composite}"

    def run(ctx: Context) -> CheckResult:
        if composite not in ctx.model.names():
            return CheckResult(name, Status.ERROR, "no such composite in the file")
        lts, diags = ctx.build(composite, unrealizable=Unrealizable.PLANT)
        got = first_error(diags) or (f"{lts.num_states} states" if lts is not None else "")
        return CheckResult(name, Status.PASS, got)

    return Check(name, run)


def alphabet(composite: str, expected: frozenset[str]) -> Check:
    """The composition's alphabet equals the listed labels, as a set."""
    name = f"alphabet {composite}"

    def run(ctx: Context) -> CheckResult:
        # an unrealizable controller composite composes to the plant C_#NC# (§3.7)
        lts, diags = ctx.build(composite, unrealizable=Unrealizable.PLANT)
        if lts is None or errors_of(diags):
            return _problem(name, diags, "building")
        got = frozenset(lts.alphabet)
        ok = got == expected
        detail = f"{sorted(got)}" + ("" if ok else f", expected {sorted(expected)}")
        return CheckResult(name, Status.PASS if ok else Status.FAIL, detail)

    return Check(name, run)


def recursion(composite: str) -> Check:
    """Loading or building ``composite`` reports a recursive composition (E0401)."""
    name = f"recursive composition {composite}"

    def run(ctx: Context) -> CheckResult:
        _, diags = ctx.build(composite)
        ok = any(d.code == RECURSION_CODE for d in errors_of(diags))
        return CheckResult(name, Status.PASS if ok else Status.FAIL,
                           "E0401 reported" if ok else "no recursive-composition error")

    return Check(name, run)


def bisimilar_to(composite: str, expected: str) -> Check:
    """``composite`` is strongly bisimilar to ``expected`` (a synthesised controller composite
    is compared after §2.6's ``property`` completion when the composite says ``property``)."""
    name = f"{composite} bisimilar to {expected}"

    def run(ctx: Context) -> CheckResult:
        from iterplan_compiler.ir.minimise import bisimilar

        ours, diags = ctx.build(composite)
        if ours is None or errors_of(diags):
            return _problem(name, diags, f"building {composite}")
        theirs, more = ctx.build(expected)
        if theirs is None or errors_of(more):
            return _problem(name, more, f"building {expected}")
        same_alphabet = True
        keywords = ctx.model.composite_keywords.get(composite, frozenset())
        if {"controller", "heuristic"} & keywords:
            same_alphabet = False
        ok = bisimilar(ours, theirs, same_alphabet=same_alphabet)
        return CheckResult(name, Status.PASS if ok else Status.FAIL,
                           f"{ours.num_states} vs {theirs.num_states} states: "
                           + ("bisimilar" if ok else "not bisimilar"))

    return Check(name, run)


def unknown(name: str, text: str) -> Check:
    """A verdict or clause this runner does not know: an error, never a pass."""
    return Check(name, lambda _ctx: CheckResult(name, Status.ERROR, f"not understood: {text!r}"))


# --------------------------------------------------------------------------------------------
# Planning: a row's cells -> its checks

_ALPHABET = re.compile(r"\[([^\]]*)\]")
_NOTE = re.compile(r"^NOTE:")


def _clause_checks(clause: str, fam: Family, composites: Sequence[str]) -> list[Check] | None:
    """The checks one clause of the ``checks`` column names (``None``: not recognised)."""
    c = clause.strip()
    first = composites[0]
    if not c or _NOTE.match(c):
        return []
    if c in ("composition!=null", "composition==null", "see WithAsterisk row"):
        return []  # the verdict check already covers it
    if c == "ntransitions>0":
        return [ntransitions(first)]
    m = re.fullmatch(r"assert (\w+) holds on \|\|(\w+)", c)
    if m:
        return [holds(m[1], m[2])]
    m = re.fullmatch(r"LegalityAnalyser\((\w+),'\w+','\w+',controllable of \w+\) legal", c)
    if m:
        return [legality(m[1], True)]
    if c == "LegalityAnalyser over composite" and fam in (Family.LEGAL, Family.NOT_LEGAL):
        return [legality(first, fam == Family.LEGAL)]
    if c == "both composites null":
        return [verdict("WithAsterisk", False), verdict("WithAlphabetSet", False)]
    if c == "WithAsterisk and WithAlphabetSet must agree (both non-null)":
        return [verdict("WithAsterisk", True), verdict("WithAlphabetSet", True)]
    if c == "CheckWith/CheckWithout hold on SysWith and SysWithout":
        return [holds("CheckWith", "SysWith"), holds("CheckWithout", "SysWithout")]
    m = re.fullmatch(r"composition\((\w+)\) strongly refines .*composition\((\w+)\)", c)
    if m:
        return [bisimilar_to(m[1], m[2])]
    if c.startswith("composition alphabet array equals") and (m := _ALPHABET.search(c)):
        return [alphabet(first, frozenset(m[1].split()))]
    if c.startswith("LTSException containing 'recursive expression"):
        return [recursion(first)]
    if c.startswith("every composite compiles+composes without LTSException"):
        return [builds(name) for name in composites]
    if re.fullmatch(r'"?MTSCompiler\.compileCompositeState\(""?(\w+)""?\)"?', c):
        return [never_fails(first)]
    if c.startswith("other exceptions/timeouts are swallowed"):
        return []
    return None


def _clauses(checks: str) -> list[str]:
    """``a & b; c; NOTE: ...`` -> its clauses (a ``NOTE`` keeps its ``;``/``&``)."""
    head, sep, note = checks.partition("NOTE:")
    parts = [p for chunk in head.split(";") for p in chunk.split("&")]
    return parts + ([sep + note] if sep else [])


def plan(expected: str, composites: Sequence[str], checks: str) -> list[Check]:
    """Every check a row names: the verdict family's own check, then each clause's."""
    fam = family(expected)
    first = composites[0]
    out: list[Check] = []
    if fam == Family.UNKNOWN:
        out.append(unknown("verdict", expected))
    elif fam in (Family.REALIZABLE, Family.UNREALIZABLE):
        out.append(verdict(first, fam == Family.REALIZABLE))
    for clause in _clauses(checks):
        found = _clause_checks(clause, fam, composites)
        if found is None:
            out.append(unknown("check", clause.strip()))
        else:
            out.extend(found)
    if not out:
        out.append(unknown("checks", checks or "(empty)"))
    unique = {c.name: c for c in reversed(out)}  # a clause may repeat the verdict
    return [c for c in out if unique[c.name] is c]


def run_checks(model: Model, checks: Sequence[Check]) -> list[CheckResult]:
    """Run every planned check (each on its own: one that raises is a ``crash`` of that
    check, the others still run)."""
    ctx = Context(model)
    results = []
    for check in checks:
        try:
            results.append(check.run(ctx))
        except Exception as exc:  # noqa: BLE001 - a compiler bug, reported as a crash
            results.append(CheckResult(check.name, Status.CRASH,
                                       f"{type(exc).__name__}: {exc}"))
    return results
