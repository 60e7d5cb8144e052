"""The compiler pipeline, one pass after another (amaranth's ``build_netlist`` is the model)::

    parse(path, text)              -> Parsed        frontend: syntax tree, includes expanded
    elaborate(parsed)              -> Elaborated    frontend: tables, fluents, formulas, specs
    build(elaborated, name, mode)  -> Built         composition and operators (an LTS)
    pose(elaborated, composite)    -> Posed         the SynthesisProblem of a controller composite
    synthesise(posed, options)     -> Synthesised   GR(1) synthesis (SynthesisResult)
    emit(synthesised, kind)        -> Emitted       back-ends: Python module, DOT, FSP, JSON

Every pass is a function from one frozen record to the next and carries the diagnostics so far;
a pass whose input has errors does nothing.  Every command that compiles specs goes through
here: ``iterc check`` (``load``; ``--build``: :func:`build`), ``iterc lts`` (:func:`build` in
:attr:`BuildMode.PLANT`: nothing is solved), ``iterc verify`` / ``animate``, ``iterc synth``
(:func:`pose` + :func:`synthesise`), ``iterc compile`` (:func:`compile_spec`, all passes) and
``iterc dot`` (:func:`draw`).

Diagnostic codes of the driver (registry: :data:`iterplan_compiler.diagnostics.CODES`):
E0901 unrealizable, E0904 no (such) controller composite, W0905 a warning synthesis reported,
E0104 no such process/composite, E1001 not an emittable controller, E1002 no LTS, no reason.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path, PurePath

from iterplan_compiler import frontend
from iterplan_compiler.backends import output
from iterplan_compiler.backends.output import EmitKind
from iterplan_compiler.backends.python import BackendError
from iterplan_compiler.diagnostics import NO_SPAN, Diagnostic, Related, Span, error, warning
from iterplan_compiler.fltl.open_safety import safety_of_formulas
from iterplan_compiler.frontend.syntax import SpecFile
from iterplan_compiler.ir.lts import LTS
from iterplan_compiler.ir.model import Model, SynthesisProblem
from iterplan_compiler.ir.solving import Synthesis
from iterplan_compiler.synthesis import driver as synthesis_driver
from iterplan_compiler.synthesis import encode as synthesis_encode
from iterplan_compiler.synthesis.driver import (
    MacroSteps,
    Solver,
    SynthesisResult,
    SynthesisStats,
    VariableOrder,
)

__all__ = ["BuildMode", "Built", "CompileOutput", "Elaborated", "EmitKind", "Emitted",
           "Parsed", "Posed", "Solver", "SynthesisOptions", "Synthesised", "build",
           "SYNTHESIS", "compile_spec", "draw", "elaborate", "emit", "load", "load_model", "parse",
           "pose", "synthesise"]

E_UNREALIZABLE = "E0901"   # the controller composite has no controller
E_NO_COMPOSITE = "E0904"   # no controller composite in the file / the named one is not one
E_UNKNOWN_NAME = "E0104"   # a command names no process or composite of the spec
E_NOT_EMITTABLE = "E1001"  # synthesis returned something that is not a deterministic controller
E_NO_LTS = "E1002"         # the model built no LTS for NAME and said nothing (should not happen)
W_SYNTHESIS = "W0905"      # a warning synthesis reported while posing the game

Diagnostics = tuple[Diagnostic, ...]


def _has_errors(diags: Diagnostics) -> bool:
    return any(d.is_error for d in diags)


# ------------------------------------------------------------------ the injected synthesis

class DriverSynthesis:
    """:class:`~iterplan_compiler.ir.solving.Synthesis` over ``synthesis.driver``: what the
    front-end calls when a build needs solving (it may not import synthesis, a higher layer).
    Defaults of the driver (symbolic solver), as ``iterc check --build`` / ``verify`` use."""

    @property
    def input_errors(self) -> tuple[type[Exception], ...]:
        return (synthesis_encode.SynthesisError, synthesis_encode.PreconditionFailure)

    def synthesize(self, problem: SynthesisProblem) -> SynthesisResult:
        # looked up at call time, so tests may monkeypatch synthesis_driver.synthesize
        return synthesis_driver.synthesize(problem)

    def check_compatibility(self, problem: SynthesisProblem) -> tuple[bool, str]:
        return synthesis_driver.check_compatibility(problem)

    def plant_components(self, problem: SynthesisProblem) -> tuple[LTS, ...]:
        return tuple(synthesis_encode.prepare(problem).components)


#: the synthesis every model loaded through the pipeline uses
SYNTHESIS: Synthesis = DriverSynthesis()


# ------------------------------------------------------------------ parse, elaborate

@dataclass(frozen=True)
class Parsed:
    """The syntax tree of a file with its includes expanded (None after a syntax error)."""

    path: str
    spec: SpecFile | None
    diagnostics: Diagnostics
    sources: Mapping[str, str]

    @property
    def ok(self) -> bool:
        return self.spec is not None and not _has_errors(self.diagnostics)


@dataclass(frozen=True)
class Elaborated:
    """The elaborated :class:`Model` (None when parsing failed; a model with elaboration
    errors is kept so that callers can inspect what is well-formed)."""

    path: str
    model: Model | None
    diagnostics: Diagnostics
    sources: Mapping[str, str]

    @property
    def ok(self) -> bool:
        return self.model is not None and not _has_errors(self.diagnostics)


def parse(path: str | Path, text: str | None = None) -> Parsed:
    """Pass 1: read (``text`` overrides the file), lex, parse and expand includes."""
    spec, diags, sources = frontend.parse_file(str(path), text)
    return Parsed(str(path), spec, tuple(diags), dict(sources))


def elaborate(parsed: Parsed) -> Elaborated:
    """Pass 2: evaluate the declarations into a :class:`Model` (LTSs are built by :func:`build`)."""
    if not parsed.ok or parsed.spec is None:
        return Elaborated(parsed.path, None, parsed.diagnostics, parsed.sources)
    model, diags = frontend.elaborate_spec(parsed.spec, dict(parsed.sources), parsed.path,
                                           synthesis=SYNTHESIS)
    sources = model.sources if model is not None else parsed.sources
    if model is not None and not any(d.is_error for d in diags):
        diags = [*diags, *safety_of_formulas(model)]   # e.g. `ltl_property L = []<> land`
    return Elaborated(parsed.path, model, parsed.diagnostics + tuple(diags), dict(sources))


def load(path: str | Path, text: str | None = None) -> Elaborated:
    """Passes 1-2."""
    return elaborate(parse(path, text))


def load_model(path: str | Path, text: str | None = None
               ) -> tuple[Model | None, list[Diagnostic]]:
    """:func:`frontend.load <iterplan_compiler.frontend.load>` with :data:`SYNTHESIS`
    injected: ``(model, diagnostics)`` of passes 1-2 without the pipeline's extra checks, for
    callers that build (and so may solve) machines of the model themselves."""
    return frontend.load(str(path), text, synthesis=SYNTHESIS)


def load_model_with_sources(path: str | Path, text: str | None = None
                            ) -> tuple[Model | None, list[Diagnostic], dict[str, str]]:
    """:func:`load_model`, also returning the sources (as ``frontend.load_with_sources``)."""
    return frontend.load_with_sources(str(path), text, synthesis=SYNTHESIS)


# ------------------------------------------------------------------ build

class BuildMode(enum.Enum):
    """How :func:`build` treats synthesis composites (``controller ||C = ...``)."""

    #: MTSA's composition: the controlled system (synthesis runs; ``check --build``, ``verify``)
    SOLVE = "solve"
    #: nothing is solved: a synthesis composite gives the plant its game is played on
    #: (``iterc lts``)
    PLANT = "plant"


@dataclass(frozen=True)
class Built:
    """One machine built from the model."""

    name: str
    lts: LTS | None
    diagnostics: Diagnostics


def build(elab: Elaborated, name: str, mode: BuildMode = BuildMode.SOLVE) -> Built:
    """Pass 3: compose ``name`` and apply its operators."""
    if elab.model is None:
        return Built(name, None, elab.diagnostics)
    lts, diags = elab.model.build_lts(name, solve=mode is BuildMode.SOLVE)
    return Built(name, lts, tuple(diags))


def unknown_name(elab: Elaborated, name: str | None) -> Diagnostic | None:
    """E0104 when ``name`` (None: the default) names nothing :func:`build` can build."""
    assert elab.model is not None
    model = elab.model
    whole_file = Span(elab.path, 0, 0)
    if name is None:
        return error(E_UNKNOWN_NAME, "the spec defines no process or composite to build",
                     whole_file)
    if name in model.names() or name == "DEFAULT":  # DEFAULT: MTSA's all-processes
        return None
    import difflib

    close = difflib.get_close_matches(name, model.names(), n=1)
    hint = (f"did you mean '{close[0]}'?" if close
            else "defined: " + (", ".join(model.names()) or "none"))
    return error(E_UNKNOWN_NAME, f"no process or composite named '{name}'; {hint}", whole_file)


# ------------------------------------------------------------------ pose, synthesise

@dataclass(frozen=True)
class Posed:
    """The synthesis problem of one controller composite."""

    composite: str
    problem: SynthesisProblem | None
    diagnostics: Diagnostics


def pick_composite(elab: Elaborated, composite: str | None) -> str | Diagnostic:
    """The controller composite to synthesise: ``composite``, else the last one of the file;
    E0904 when there is none or ``composite`` is not a composite."""
    assert elab.model is not None
    model = elab.model
    file_name = PurePath(elab.path).name
    whole_file = Span(elab.path, 0, 0)
    if composite is None:
        candidates = model.controller_composites()
        if not candidates:
            return error(E_NO_COMPOSITE, f"{file_name} defines no 'controller' composite to "
                         "compile (write `controller ||C = (Env)~{Spec}.` or name one with -c)",
                         whole_file)
        return candidates[-1]
    if composite not in model.composites:
        import difflib

        close = difflib.get_close_matches(composite, model.composites, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        return error(E_NO_COMPOSITE, f"no composite named '{composite}' in {file_name}{hint}",
                     whole_file)
    return composite


def pose(elab: Elaborated, composite: str) -> Posed:
    """Pass 4: the resolved :class:`SynthesisProblem` of ``composite``."""
    if elab.model is None:
        return Posed(composite, None, ())
    problem, diags = elab.model.synthesis_problem(composite)
    return Posed(composite, problem, tuple(diags))


@dataclass(frozen=True)
class SynthesisOptions:
    """How :func:`synthesise` solves (``iterc synth``/``compile`` flags)."""

    solver: Solver = Solver.SYMBOLIC
    explain: bool = True
    order: VariableOrder = VariableOrder.CLUSTERED
    macro: MacroSteps = MacroSteps.AUTO
    progress: Callable[[str], None] | None = field(default=None, compare=False)
    #: stop at the verdict: no controller (``iterc synth --realizability-only``)
    realizability_only: bool = False


@dataclass(frozen=True)
class Synthesised:
    """The outcome of synthesis for one composite; ``result`` is None when it did not run."""

    composite: str
    problem: SynthesisProblem | None
    result: SynthesisResult | None
    diagnostics: Diagnostics

    @property
    def ok(self) -> bool:
        return self.result is not None and self.result.realizable \
            and not _has_errors(self.diagnostics)


def synthesise(posed: Posed, options: SynthesisOptions = SynthesisOptions()) -> Synthesised:
    """Pass 5: solve the game; unrealizable is error E0901 carrying the explanation (as a
    note), warnings synthesis noticed while posing the game are W0905."""
    problem = posed.problem
    if problem is None or _has_errors(posed.diagnostics):
        return Synthesised(posed.composite, problem, None, posed.diagnostics)
    result = synthesis_driver.synthesize(problem, solver=options.solver,
                                         progress=options.progress, explain=options.explain,
                                         order=options.order,
                                         macro=options.macro,
                                         realizability_only=options.realizability_only)
    diags = [*posed.diagnostics, *result.diagnostics]
    for text in result.stats.warnings:
        diags.append(warning(W_SYNTHESIS, text, problem.span))
    if not result.realizable and not _has_errors(result.diagnostics):
        why = (result.explanation or "").strip()
        msg = (f"no controller exists for '{posed.composite}': the specification is "
               "unrealizable")
        # the explanation goes in a note so it prints after the composite's source line
        notes = [Related(NO_SPAN, why)] if why else []
        diags.append(error(E_UNREALIZABLE, msg, problem.span, *notes))
    return Synthesised(posed.composite, problem, result, tuple(diags))


# ------------------------------------------------------------------ emit

@dataclass(frozen=True)
class Emitted:
    """Emitted text (None exactly when there are errors) and the controller it renders."""

    text: str | None
    controller: LTS | None
    controllable: frozenset[str]
    diagnostics: Diagnostics


def emit(elab: Elaborated, synth: Synthesised, kind: EmitKind) -> Emitted:
    """Pass 6: render the (canonically renumbered) controller as ``kind``."""
    result, problem = synth.result, synth.problem
    if not synth.ok or result is None or result.controller is None or problem is None:
        return Emitted(None, None, frozenset(), synth.diagnostics)
    controller = output.canonical_controller(result.controller)
    controllable = frozenset(problem.controllable)
    source = elab.sources.get(elab.path) or ""
    try:
        text = output.emit(kind, controller, controllable, name=synth.composite,
                           source_name=PurePath(elab.path).name,
                           spec_hash=output.spec_sha256(source),
                           origins=_origins(elab, problem, synth.composite))
    except BackendError as exc:
        diag = error(E_NOT_EMITTABLE, f"cannot emit the controller of '{synth.composite}': "
                     f"{exc}", problem.span)
        return Emitted(None, controller, controllable, (*synth.diagnostics, diag))
    return Emitted(text, controller, controllable, synth.diagnostics)


def _origins(elab: Elaborated, problem: SynthesisProblem, composite: str) -> dict[str, Span]:
    origins: dict[str, Span] = {}
    if problem.span != NO_SPAN:
        origins[f"controller composite {composite}"] = problem.span
    spec = elab.model.controller_specs.get(problem.spec_name) if elab.model else None
    if spec is not None and spec.span != NO_SPAN:
        origins[f"controllerSpec {spec.name}"] = spec.span
    return origins


# ------------------------------------------------------------------ whole pipelines

@dataclass(frozen=True)
class CompileOutput:
    """The result of :func:`compile_spec`: ``text`` is None exactly when errors were reported.

    ``sources`` maps file names to their text (to render diagnostics with source lines); once
    synthesis succeeded, ``synthesised`` is synthesis's controller, ``controller`` its
    canonical renumbering (what was emitted) and ``controllable`` the spec's controllable set.
    """

    text: str | None
    diagnostics: Diagnostics
    composite: str | None = None
    controller: LTS | None = None
    controllable: frozenset[str] = frozenset()
    sources: Mapping[str, str] = field(default_factory=dict)
    #: synthesis's sizes and times (an empty record when synthesis did not run)
    stats: SynthesisStats = field(default_factory=lambda: SynthesisStats(Solver.SYMBOLIC))
    synthesised: LTS | None = None


def compile_spec(path: str | Path, *, composite: str | None = None,
                 emit_kind: EmitKind | str = EmitKind.PY,
                 solver: Solver | str = Solver.SYMBOLIC, text: str | None = None,
                 progress: Callable[[str], None] | None = None) -> CompileOutput:
    """All passes: compile ``composite`` (default: the last controller composite) of the spec
    at ``path`` into ``emit_kind`` text."""
    elab = load(path, text)
    if not elab.ok:
        return CompileOutput(None, elab.diagnostics, sources=elab.sources)
    picked = pick_composite(elab, composite)
    if isinstance(picked, Diagnostic):
        return CompileOutput(None, (*elab.diagnostics, picked), sources=elab.sources)
    synth = synthesise(pose(elab, picked),
                       SynthesisOptions(Solver(solver), explain=True, progress=progress))
    diags = elab.diagnostics + synth.diagnostics
    stats = synth.result.stats if synth.result is not None else SynthesisStats(Solver.SYMBOLIC)
    if not synth.ok:
        return CompileOutput(None, diags, picked, sources=elab.sources, stats=stats)
    out = emit(elab, synth, EmitKind(emit_kind))
    synthesised = synth.result.controller if synth.result is not None else None
    return CompileOutput(out.text, elab.diagnostics + out.diagnostics, picked, out.controller,
                         out.controllable, elab.sources, stats, synthesised)


@dataclass(frozen=True)
class Drawing:
    """What ``iterc dot`` draws: a machine and the controllable set to mark (None: none)."""

    lts: LTS | None
    controllable: frozenset[str] | None
    diagnostics: Diagnostics
    sources: Mapping[str, str]


def draw(path: str | Path, name: str | None = None, *, controller: bool = False,
         solver: Solver | str = Solver.SYMBOLIC, text: str | None = None) -> Drawing:
    """The machine ``iterc dot`` draws.

    ``name`` defaults to the last controller composite, else the last definition.  With
    ``controller=True`` the synthesised controller of composite ``name`` instead of its
    controlled system.  ``controllable`` is that of ``name`` when it is a controller
    composite, else that of the last controller composite (so plain processes are drawn with
    the same dashed/solid split), else None.
    """
    elab = load(path, text)
    if not elab.ok or elab.model is None:
        return Drawing(None, None, elab.diagnostics, elab.sources)
    model = elab.model
    names = list(model.names())
    composites = list(model.controller_composites())
    if name is None:
        name = composites[-1] if composites else (names[-1] if names else None)
    if name is None or name not in names:
        whole = Span(elab.path, 0, 0)
        diag = (error(E_UNKNOWN_NAME, "the spec defines nothing to draw", whole) if name is None
                else error(E_UNKNOWN_NAME, f"no process or composite named '{name}'; defined: "
                           f"{', '.join(names) or '(none)'}", whole))
        return Drawing(None, None, (*elab.diagnostics, diag), elab.sources)
    owner = name if name in composites else (composites[-1] if composites else None)
    controllable = frozenset(model.controllable(owner)) if owner else None
    if controller:
        if name not in composites:
            diag = error(E_NO_COMPOSITE, f"'{name}' is not a controller composite, so it has "
                         "no synthesised controller", Span(elab.path, 0, 0))
            return Drawing(None, None, (*elab.diagnostics, diag), elab.sources)
        synth = synthesise(pose(elab, name), SynthesisOptions(Solver(solver)))
        diags = elab.diagnostics + synth.diagnostics
        if not synth.ok or synth.result is None or synth.result.controller is None \
                or synth.problem is None:
            return Drawing(None, controllable, diags, elab.sources)
        return Drawing(output.canonical_controller(synth.result.controller),
                       frozenset(synth.problem.controllable), diags, elab.sources)
    built = build(elab, name)
    diags = elab.diagnostics + built.diagnostics
    if built.lts is None and not _has_errors(diags):
        diags += (error(E_NO_LTS, f"could not build '{name}'", Span(elab.path, 0, 0)),)
    return Drawing(built.lts, controllable, diags, elab.sources)
