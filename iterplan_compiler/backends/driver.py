"""The compile pipeline: spec file -> model -> synthesis problem -> controller -> emitted text.

``compile_spec`` is what ``iterc compile`` runs::

    frontend.load(path)                       -> Model, diagnostics
    model.synthesis_problem(C)                -> SynthesisProblem, diagnostics
    synthesis.driver.synthesize(problem)      -> SynthesisResult (realizable?, controller LTS)
    python.emit_module / graphviz.to_dot / fsp_print.lts_to_fsp / jsonout.to_json

Each step stops the pipeline when it reports errors; every failure a user can cause comes back as
a :class:`~iterplan_compiler.diagnostics.Diagnostic` (codes ``E09xx``/``E10xx``, listed in
``docs/backends.md``), never as an exception.  The heavy stages are imported lazily so that
importing this module stays cheap.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path, PurePath
from typing import Any

from iterplan_compiler.diagnostics import (
    NO_SPAN,
    Diagnostic,
    Related,
    Span,
    error,
    has_errors,
    warning,
)
from iterplan_compiler.ir.lts import LTS, reachable

#: ``--emit`` choices of ``iterc compile``.
EMIT_KINDS = ("py", "dot", "fsp", "json")

# Stable diagnostic codes of this stage.
E_UNREALIZABLE = "E0901"   # the controller composite has no controller
E_NO_COMPOSITE = "E0904"   # no controller composite in the file / the named one is not one
E_NOT_EMITTABLE = "E1001"  # synthesis returned something that is not a deterministic controller
E_UNKNOWN_NAME = "E0104"   # `iterc dot SPEC NAME`: NAME is not defined
E_NO_LTS = "E1002"         # the model built no LTS for NAME and said nothing (should not happen)
W_SYNTHESIS = "W0905"      # a warning synthesis reported while posing the game


@dataclass(frozen=True)
class CompileOutput:
    """The result of :func:`compile_spec`: ``text`` is None exactly when errors were reported.

    ``sources`` maps file names to their text so the caller can render diagnostics with
    source lines; once synthesis succeeded, ``synthesised`` is synthesis's controller,
    ``controller`` its canonical renumbering (what was emitted) and ``controllable`` the spec's
    controllable set.
    """

    text: str | None
    diagnostics: tuple[Diagnostic, ...]
    composite: str | None = None
    controller: LTS | None = None
    controllable: frozenset[str] = frozenset()
    sources: dict[str, str] = field(default_factory=dict)
    stats: dict[str, Any] = field(default_factory=dict)
    synthesised: LTS | None = None


def spec_sha256(text: str) -> str:
    """Return the sha256 hex digest of the spec text (UTF-8), as written into generated headers."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def load_model(path: str | Path, text: str | None = None) -> tuple[Any | None, list[Diagnostic]]:
    """Run the front-end on ``path`` (``text`` overrides reading the file)."""
    from iterplan_compiler import frontend

    return frontend.load(str(path), text=text)


def _sources(model: Any, path: str | Path, text: str | None) -> dict[str, str]:
    src = getattr(model, "source_text", None) if model is not None else None
    if src is None:
        src = text
    if src is None:
        try:
            # Decoded like the front-end (bad bytes become U+FFFD, which the lexer then reports
            # with a position) so non-UTF-8 input never raises; a UTF-8 byte-order mark (written
            # by some Windows editors) is dropped so it does not shift line 1's caret.
            src = Path(path).read_text(encoding="utf-8-sig", errors="replace")
        except OSError:
            return {}
    key = str(getattr(model, "source_path", None) or path)
    out = {key: src, str(path): src}
    extra = getattr(model, "sources", None)
    if isinstance(extra, dict):
        out.update({str(k): v for k, v in extra.items() if isinstance(v, str)})
    return out


#: Composite keywords that make a composite a synthesis problem (MTSA §1.11, §3.9, §3.10).
SYNTHESIS_KEYWORDS = frozenset({"controller", "heuristic", "monolithicDirector"})


def controller_composites(model: Any) -> list[str]:
    """Names of the synthesis composites of ``model`` (``controller``/``heuristic``/
    ``monolithicDirector ||C = ...``), in file order.

    Uses ``model.controller_composites()`` when the front-end provides it, else the model's
    ``composites`` and ``composite_keywords``; as a last resort keeps the names whose synthesis
    problem builds without errors.
    """
    provided = getattr(model, "controller_composites", None)
    if provided is not None:
        names = provided() if callable(provided) else provided
        return list(names)
    keywords = getattr(model, "composite_keywords", None)
    composites = getattr(model, "composites", None)
    if isinstance(keywords, dict) and composites is not None:
        return [c for c in composites if SYNTHESIS_KEYWORDS & set(keywords.get(c, ()))]
    found = []
    for name in model.names():
        problem, diags = model.synthesis_problem(name)
        if problem is not None and not has_errors(diags):
            found.append(name)
    return found


def _file_span(path: str | Path) -> Span:
    return Span(str(path), 0, 0)


def _synthesize(problem: Any, solver: str, progress: Callable[..., Any] | None) -> Any:
    """Call ``synthesis.driver.synthesize`` (a seam tests replace with a stub)."""
    from iterplan_compiler.synthesis import driver as synthesis_driver

    return synthesis_driver.synthesize(problem, solver=solver, progress=progress)


def synthesize_composite(
    model: Any,
    composite: str,
    *,
    solver: str = "symbolic",
    progress: Callable[..., Any] | None = None,
) -> tuple[Any | None, Any | None, list[Diagnostic]]:
    """Build the synthesis problem of ``composite`` and solve it.

    Returns ``(problem, result, diagnostics)``; an unrealizable problem yields an ``E0901``
    error carrying synthesis's explanation (and ``result`` with ``realizable == False``); a
    problem synthesis could not pose as a game yields synthesis's own diagnostics instead.
    """
    problem, diags = model.synthesis_problem(composite)
    diags = list(diags)
    if problem is None or has_errors(diags):
        return problem, None, diags
    result = _synthesize(problem, solver, progress)
    posed = list(getattr(result, "diagnostics", ()) or ())
    diags.extend(posed)
    # Modelling pitfalls synthesis noticed (e.g. fluent actions outside the plant) are strings.
    for text in (getattr(result, "stats", None) or {}).get("warnings", ()):
        diags.append(warning(W_SYNTHESIS, str(text), problem.span))
    if not result.realizable and not has_errors(posed):
        why = (result.explanation or "").strip()
        msg = f"no controller exists for '{composite}': the specification is unrealizable"
        # The explanation goes in a note so it prints after the composite's source line.
        notes = [Related(NO_SPAN, why)] if why else []
        diags.append(error(E_UNREALIZABLE, msg, problem.span, *notes))
    return problem, result, diags


def canonical_controller(controller: LTS) -> LTS:
    """Renumber ``controller`` canonically: breadth-first from the initial state (which becomes
    0), successors in label order, unreachable states dropped.

    For a deterministic controller the numbering then depends only on the machine, not on how
    synthesis numbered its states, so generated modules and golden files stay stable when
    synthesis internals change.  The result is isomorphic to the input when every state is
    reachable (synthesis drops unreachable pairs).
    """
    return reachable(controller)


def _origins(model: Any, problem: Any, composite: str) -> dict[str, Span]:
    origins: dict[str, Span] = {}
    if problem.span != NO_SPAN:
        origins[f"controller composite {composite}"] = problem.span
    spec = getattr(model, "controller_specs", {}).get(getattr(problem, "spec_name", ""))
    if spec is not None and spec.span != NO_SPAN:
        origins[f"controllerSpec {spec.name}"] = spec.span
    return origins


def emit(
    kind: str,
    controller: LTS,
    controllable: frozenset[str],
    *,
    name: str,
    source_name: str,
    spec_hash: str,
    origins: dict[str, Span] | None = None,
) -> str:
    """Render a synthesised controller as ``kind`` (one of :data:`EMIT_KINDS`)."""
    if kind == "py":
        from iterplan_compiler.backends.python import emit_module

        return emit_module(controller, controllable=controllable, name=name,
                           source_name=source_name, spec_hash=spec_hash, origins=origins)
    if kind == "dot":
        from iterplan_compiler.backends.graphviz import to_dot

        return to_dot(controller, controllable=controllable)
    if kind == "json":
        from iterplan_compiler.backends.jsonout import to_json

        return to_json(controller, controllable)
    if kind == "fsp":
        from iterplan_compiler.ir.fsp_print import lts_to_fsp

        text = lts_to_fsp(controller)
        return text if text.endswith("\n") else text + "\n"
    raise ValueError(f"unknown emit kind {kind!r}; expected one of {', '.join(EMIT_KINDS)}")


def compile_spec(
    path: str | Path,
    *,
    composite: str | None = None,
    emit_kind: str = "py",
    solver: str = "symbolic",
    text: str | None = None,
    progress: Callable[..., Any] | None = None,
) -> CompileOutput:
    """Compile the spec at ``path`` into ``emit_kind`` text for ``composite``.

    The default composite is the last ``controller`` composite in the file.  The module header
    records the spec's base name and the sha256 of its text.
    """
    model, diags = load_model(path, text)
    diags = list(diags)
    sources = _sources(model, path, text)
    if model is None or has_errors(diags):
        return CompileOutput(None, tuple(diags), sources=sources)
    if composite is None:
        candidates = controller_composites(model)
        if not candidates:
            diags.append(error(
                E_NO_COMPOSITE,
                f"{PurePath(str(path)).name} defines no 'controller' composite to compile "
                "(write `controller ||C = (Env)~{Spec}.` or name one with -c)",
                _file_span(path),
            ))
            return CompileOutput(None, tuple(diags), sources=sources)
        composite = candidates[-1]
    elif composite not in set(model.names()):
        diags.append(error(E_NO_COMPOSITE, f"no composite named '{composite}' in "
                           f"{PurePath(str(path)).name}", _file_span(path)))
        return CompileOutput(None, tuple(diags), sources=sources)

    problem, result, more = synthesize_composite(model, composite, solver=solver,
                                                 progress=progress)
    diags.extend(more)
    stats = dict(getattr(result, "stats", {}) or {})
    if result is None or has_errors(diags):
        return CompileOutput(None, tuple(diags), composite, sources=sources, stats=stats)

    controller = canonical_controller(result.controller)
    controllable = frozenset(problem.controllable)
    src_text = sources.get(str(path)) or ""
    from iterplan_compiler.backends.python import BackendError

    try:
        out = emit(emit_kind, controller, controllable, name=composite,
                   source_name=PurePath(str(path)).name, spec_hash=spec_sha256(src_text),
                   origins=_origins(model, problem, composite))
    except BackendError as exc:
        diags.append(error(E_NOT_EMITTABLE, f"cannot emit the controller of '{composite}': "
                           f"{exc}", problem.span))
        return CompileOutput(None, tuple(diags), composite, controller, controllable, sources,
                             stats, result.controller)
    return CompileOutput(out, tuple(diags), composite, controller, controllable, sources, stats,
                         result.controller)


def build_named(
    path: str | Path,
    name: str | None = None,
    *,
    controller: bool = False,
    solver: str = "symbolic",
    text: str | None = None,
) -> tuple[LTS | None, frozenset[str] | None, list[Diagnostic], dict[str, str]]:
    """Build the LTS ``iterc dot`` draws: ``(lts, controllable, diagnostics, sources)``.

    ``name`` defaults to the last controller composite, else the last definition.  With
    ``controller=True`` the synthesised controller of composite ``name`` is returned instead of
    the composite's (controlled) composition.  ``controllable`` is the composite's controllable
    set when ``name`` is a controller composite, else that of the default controller composite
    (so plain processes such as the iterator are drawn with the same dashed/solid split), else
    None.
    """
    model, diags = load_model(path, text)
    diags = list(diags)
    sources = _sources(model, path, text)
    if model is None or has_errors(diags):
        return None, None, diags, sources
    names: Sequence[str] = list(model.names())
    composites = controller_composites(model)
    if name is None:
        if composites:
            name = composites[-1]
        elif names:
            name = names[-1]
        else:
            diags.append(error(E_UNKNOWN_NAME, "the spec defines nothing to draw",
                               _file_span(path)))
            return None, None, diags, sources
    if name not in set(names):
        known = ", ".join(names) or "(none)"
        diags.append(error(E_UNKNOWN_NAME, f"no process or composite named '{name}'; "
                           f"defined: {known}", _file_span(path)))
        return None, None, diags, sources
    ctrl_owner = name if name in composites else (composites[-1] if composites else None)
    controllable = frozenset(model.controllable(ctrl_owner)) if ctrl_owner else None

    if controller:
        if name not in composites:
            diags.append(error(E_NO_COMPOSITE, f"'{name}' is not a controller composite, so it "
                               "has no synthesised controller", _file_span(path)))
            return None, None, diags, sources
        problem, result, more = synthesize_composite(model, name, solver=solver)
        diags.extend(more)
        if result is None or has_errors(diags):
            return None, controllable, diags, sources
        return (canonical_controller(result.controller), frozenset(problem.controllable), diags,
                sources)

    lts, more = model.build_lts(name)
    diags.extend(more)
    if lts is None and not has_errors(diags):
        diags.append(error(E_NO_LTS, f"could not build '{name}'", _file_span(path)))
    return lts, controllable, diags, sources
