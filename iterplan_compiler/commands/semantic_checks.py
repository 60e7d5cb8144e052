"""Cheap semantic checks that ``iterc check`` runs after elaboration (no composition, no game).

Each check is a pure function of the elaborated :class:`~iterplan_compiler.ir.model.Model`
(plus, for token positions, the syntax tree of the file and its includes) returning
diagnostics at the offending token:

* :func:`~iterplan_compiler.fltl.open_safety.safety_of_formulas` — an ``ltl_property``/``constraint`` whose safety LTS forbids
  nothing over its alphabet Σφ must still be a safety formula once an action outside Σφ is
  allowed (E0605, the FLTL stage's code, with a witness).  Over ``{land}`` alone every word
  satisfies ``[]<> land``, so the translation of §2.8 accepts it and a controller spec listing
  it as ``safety`` would be "realizable"; MTSA's tableau test (not confined to Σφ-words)
  rejects it, and so do we.  Formulas that do forbid something are left to the translation's
  own test (run by building), so nothing MTSA accepts is rejected here.
* :func:`labels_against_plants` — a ``controllable`` action of a spec some synthesis composite
  uses that no process (nor plant) can do (W0704: usually a misspelling; a library set with
  actions this plant leaves out is fine), and an action of a fluent declared in the file that no
  plant can do (W0905, the code synthesis uses for the same problem, docs/backends.md); without
  a synthesis composite, fluents are checked against the processes' alphabets.
* :func:`include_set_dependencies` — a set an included file mentions but nobody declares
  (E0209, e.g. ``set HereActions`` needed by ``stdlib/sensors.lts``), at the use in the
  included file, with a note at the ``include``.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Iterable, Iterator

from iterplan_compiler.diagnostics import Diagnostic, Related, Span, error, warning
from iterplan_compiler.fltl.open_safety import safety_of_formulas
from iterplan_compiler.frontend import syntax as S
from iterplan_compiler.ir.model import Model

W_CONTROLLABLE = "W0704"   # a controllable action no plant of the spec's composites can do
W_FLUENT = "W0905"          # a fluent action no plant can do (as synthesis reports it)
E_INCLUDE_SET = "E0209"    # a set an included file needs is declared nowhere

_KEYWORD_STATES = frozenset({"STOP", "END", "ERROR"})


def run_all(model: Model) -> list[Diagnostic]:
    """Every check of this module, in a stable order."""
    return [*safety_of_formulas(model), *labels_against_plants(model),
            *include_set_dependencies(model)]


# --------------------------------------------------------------------------------------------
# controllable and fluent labels against the plant alphabets


def _synthesis_plants(model: Model) -> dict[str, tuple[str, frozenset[str]]]:
    """``composite -> (spec name, plant alphabet)`` for every synthesis composite whose
    problem can be posed (one that cannot is reported by building it)."""
    from iterplan_compiler.diagnostics import has_errors
    from iterplan_compiler.ir.model import SYNTHESIS_KEYWORDS

    out = {}
    for name in model.composites:
        if not model.composite_keywords.get(name, frozenset()) & SYNTHESIS_KEYWORDS:
            continue
        problem, diags = model.synthesis_problem(name)
        if problem is None or has_errors(diags):
            continue
        alphabet = frozenset().union(*(m.alphabet for m in (*problem.plant, *problem.safety)))
        out[name] = (problem.spec_name, alphabet)
    return out


def _label_span(model: Model, label: str, near: Span) -> Span:
    """Where ``label`` is written: in ``near``'s file, the first whole-word occurrence from
    ``near``'s line on (else anywhere in that file), else ``near`` itself."""
    text = model.sources.get(near.file)
    if not text:
        return near
    pattern = re.compile(rf"(?<![\w.]){re.escape(label)}(?![\w])")
    lines = text.splitlines()
    order = list(range(max(0, near.line - 1), len(lines))) + list(range(0, near.line - 1))
    for i in order:
        m = pattern.search(lines[i])
        if m:
            return Span(near.file, i + 1, m.start() + 1, i + 1, m.end() + 1)
    return near


def labels_against_plants(model: Model) -> list[Diagnostic]:
    """W0704 for a controllable action no process can do; W0905 for an action of a fluent
    declared in the main file that no plant (no process, without synthesis) can do."""
    plants = _synthesis_plants(model)
    processes = _process_alphabets(model)
    out: list[Diagnostic] = []
    specs = {spec for spec, _ in plants.values()}
    known = frozenset().union(processes, *(a for _, a in plants.values()))
    for spec_name in sorted(specs):
        spec = model.controller_specs.get(spec_name)
        if spec is None:
            continue
        for label in sorted(spec.controllable - known):
            out.append(warning(
                W_CONTROLLABLE,
                f"controllerSpec {spec_name}: controllable action '{label}' is not an action "
                f"of any process{_suggest(label, known)}", _label_span(model, label, spec.span)))
    universe, where = known, "of any process"
    if plants:
        universe, where = frozenset().union(*(a for _, a in plants.values())), "of any plant"
    for fluent in model.fluents.values():
        if fluent.span.file != model.source_path or not universe:
            continue
        for label in sorted((fluent.initiating | fluent.terminating) - universe):
            out.append(warning(
                W_FLUENT, f"fluent {fluent.name}: action '{label}' is not an action {where}"
                f"{_suggest(label, universe)}; the fluent never changes through it",
                _label_span(model, label, fluent.span)))
    return out


def _process_alphabets(model: Model) -> frozenset[str]:
    """The union of the alphabets of the processes that build (at their default
    parameters; one that does not is reported by building it)."""
    labels: set[str] = set()
    for name in model.processes:
        lts, _ = model.build_lts(name)
        if lts is not None:
            labels |= lts.alphabet
    return frozenset(labels)


def _suggest(label: str, known: Iterable[str]) -> str:
    import difflib

    close = difflib.get_close_matches(label, sorted(known), n=1, cutoff=0.75)
    return f" (did you mean '{close[0]}'?)" if close else ""


# --------------------------------------------------------------------------------------------
# Sets an included file needs


def _nodes(node: object) -> Iterator[object]:
    """Every syntax node under ``node`` (dataclass fields and tuples, depth first)."""
    stack = [node]
    while stack:
        n = stack.pop()
        yield n
        if isinstance(n, tuple):
            stack.extend(reversed(n))
        elif dataclasses.is_dataclass(n) and not isinstance(n, (type, Span)):
            stack.extend(reversed([getattr(n, f.name) for f in dataclasses.fields(n)]))


def include_set_dependencies(model: Model) -> list[Diagnostic]:
    """E0209 for each set name an included declaration uses that is declared nowhere."""
    from iterplan_compiler.frontend import parse_file
    from iterplan_compiler.frontend.parse import parse_text

    if len(model.sources) < 2:
        return []
    spec, _, _ = parse_file(model.source_path, model.sources.get(model.source_path))
    if spec is None:
        return []
    declared = set(model.sets) | set(model.ranges) | set(model.constants) | _KEYWORD_STATES
    declared |= set(model.processes) | set(model.composites) | set(model.formulas)
    declared |= set(model.fluents) | set(model.controller_specs)
    for n in _nodes(spec.decls):
        if isinstance(n, (S.Param, S.LocalDef, S.SetDecl, S.RangeDecl, S.ConstDecl)):
            declared.add(n.name)
    top, _ = parse_text(model.sources[model.source_path], model.source_path)
    includes = [d for d in top.decls if isinstance(d, S.IncludeDecl)]
    out, seen = [], set()
    for decl in _used_included(spec.decls, model.source_path):
        span = decl.span
        for n in _nodes(decl):
            if isinstance(n, S.SetName) and n.name not in declared and n.name not in seen:
                seen.add(n.name)
                out.append(_missing_set(n, includes, span.file))
    return out


def _used_included(decls: tuple, main: str) -> list:
    """The included declarations the main file's own declarations use, transitively (a
    library fragment nobody uses may mention sets the including file has no reason to
    declare)."""
    by_name = {d.name: d for d in decls if isinstance(getattr(d, "name", None), str)}
    todo = [d for d in decls if getattr(d, "span", None) is not None and d.span.file == main]
    used: dict[str, object] = {}
    while todo:
        for n in _nodes(todo.pop()):
            names: tuple[str, ...] = ()
            if isinstance(n, (S.CRef, S.StateRef, S.FRef)):
                names = (n.name,)
            elif isinstance(n, S.SpecItem):
                names = n.names
            for name in names:
                d = by_name.get(name)
                if d is not None and name not in used and d.span.file != main:
                    used[name] = d
                    todo.append(d)
    return list(used.values())


def _missing_set(use: S.SetName, includes: list[S.IncludeDecl], file: str) -> Diagnostic:
    base = file.rsplit("/", 1)[-1]
    via = [d for d in includes if d.path.rsplit("/", 1)[-1] == base] or includes
    related = tuple(Related(d.span, f"'{d.path}' is included here; declare "
                                    f"`set {use.name} = {{...}}` in the including file")
                    for d in via[:1])
    return error(E_INCLUDE_SET, f"set '{use.name}' is used by the included file {base} but is "
                                "declared nowhere", use.span, *related)
