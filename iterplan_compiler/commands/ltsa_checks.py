"""LTSA's safety and progress checks for ``iterc check SPEC --safety NAME --progress NAME``.

Not a command of its own: :mod:`iterplan_compiler.commands.check` calls :func:`run_checks`.
The analyses are :mod:`iterplan_compiler.ir.analysis`; this module builds the composite through
``Model.build_lts`` (the same machine ``iterc lts`` prints), elaborates the ``progress``
declarations and reports:

* on stdout, LTSA's text (``Trace to DEADLOCK:``, ``Trace to property violation in P:``,
  ``Progress violation: P`` / ``Trace to terminal set of states:`` / ``Cycle in terminal set:``
  / ``Actions in terminal set:``, actions one per tab-indented line);
* on stderr, one diagnostic per finding at the composite's declaration (E1301 deadlock, E1302
  ERROR reachable, E1303 progress violation, with a note at the ``progress`` declaration).

Semantics and examples: ``docs/ltsa.md``.
"""

from __future__ import annotations

import difflib
import re
import sys
from collections.abc import Iterable

from iterplan_compiler.diagnostics import Diagnostic, Related, Span, error, render
from iterplan_compiler.ir.analysis import (
    ProgressProperty,
    check_progress,
    check_safety,
    default_progress,
    tau_closure,
    terminal_sets,
)
from iterplan_compiler.ir.formulas import FormulaKind
from iterplan_compiler.ir.lts import ERROR, LTS

E_DEADLOCK = "E1301"
E_ERROR = "E1302"
E_PROGRESS = "E1303"
E_NO_TARGET = "E0104"  # as `iterc lts`/`iterc dot`: the same mistake gets the same code


def decl_span(model, name: str) -> Span:
    """Where ``name`` (a composite, process or formula) is declared; the file otherwise."""
    backend = getattr(model, "backend", None)
    for table in ("composites", "processes", "formula_decls", "progress_decls"):
        d = getattr(backend, table, {}).get(name)
        span = getattr(d, "span", None)
        if isinstance(span, Span) and span.line > 0:
            return span
    return Span(model.source_path, 0, 0)


def one_line(trace: Iterable[str]) -> str:
    trace = list(trace)
    return ", ".join(trace) if trace else "(empty: the initial state)"


def block(title: str, trace: Iterable[str]) -> str:
    """LTSA's rendering: a title line, then one tab-indented action per line."""
    lines = [title] + [f"\t{a}" for a in trace]
    return "\n".join(lines)


def progress_properties(model) -> tuple[list[tuple[ProgressProperty, Span]], list[Diagnostic]]:
    """Elaborate the ``progress`` declarations (indexed ones expanded as ``P[v]``)."""
    from iterplan_compiler.frontend.expressions import EvalError, expand_set, part_values

    backend = model.backend
    decls = getattr(backend, "progress_decls", {})
    out: list[tuple[ProgressProperty, Span]] = []
    diags: list[Diagnostic] = []
    for name, d in decls.items():
        try:
            keys = [(name, backend.env())]
            for part in d.indices:
                keys = [(f"{k}[{t}]", e2) for k, e in keys for t, e2 in part_values(part, e)]
            for key, env in keys:
                actions = frozenset(expand_set(d.actions, env))
                cond = (frozenset(expand_set(d.condition, env))
                        if d.condition is not None else None)
                out.append((ProgressProperty(key, actions, cond), d.span))
        except EvalError as e:
            diags.append(e.diag)
    return out, diags


def replays_to_error(machine: LTS, trace: tuple[str, ...]) -> bool:
    """Does ``machine`` (run alone on the actions of ``trace`` in its alphabet) reach ERROR on
    the trace's last action and not before?  Nondeterminism is followed as a set of states."""
    if not trace or trace[-1] not in machine.alphabet:
        return False
    out = machine.out_edges()
    current = tau_closure(out, {machine.initial})
    for k, a in enumerate(trace):
        if a not in machine.alphabet:
            continue
        current = tau_closure(out, {t for s in current if s != ERROR
                                     for b, t in out.get(s, ()) if b == a})
        if ERROR in current:
            return k == len(trace) - 1
        if not current:
            return False
    return False


def violated_property(model, target: str, lts: LTS, trace: tuple[str, ...]) -> str | None:
    """Name the declared machine that moves to ERROR at the end of ``trace``: an
    ``ltl_property``, a ``property`` process or a process with an explicit ``ERROR``.

    The composite does not keep its components, so the candidates are replayed on the trace;
    those named in ``target``'s declaration are tried first.  ``None`` if no declared machine
    explains it (e.g. a relabelled instance)."""
    backend = getattr(model, "backend", None)
    span = decl_span(model, target)
    text = model.sources.get(span.file, model.source_text) if span.line > 0 else ""
    lines = text.splitlines()[max(span.line - 1, 0):(span.end_line or span.line)]
    mentioned = " ".join(lines)
    names = [n for n, f in model.formulas.items() if f.kind is FormulaKind.LTL_PROPERTY]
    names += list(model.processes)
    procs = getattr(backend, "processes", {})

    def rank(n: str) -> tuple[int, int]:
        named = re.search(rf"(?<![\w.]){re.escape(n)}(?![\w])", mentioned) is not None
        is_prop = n in model.formulas or "property" in getattr(procs.get(n), "keywords", ())
        return (0 if named else 1, 0 if is_prop else 1)

    for n in sorted(dict.fromkeys(names), key=rank):
        if n == target:
            continue
        try:
            machine, ds = model.build_lts(n)
        except Exception:  # a candidate that cannot be built alone is simply not the culprit
            continue
        if machine is None or not machine.has_error or not machine.alphabet <= lts.alphabet:
            continue
        if replays_to_error(machine, trace):
            return n
    return None


def _resolve(model, name: str, spec: str) -> Diagnostic | None:
    if name in model.names() or name == "DEFAULT":
        return None
    close = difflib.get_close_matches(name, model.names(), n=1)
    hint = (f"did you mean '{close[0]}'?" if close
            else "defined: " + (", ".join(model.names()) or "none"))
    return error(E_NO_TARGET, f"no process or composite named '{name}'; {hint}",
                 Span(spec, 0, 0))


def _build(model, name: str, spec: str) -> tuple[LTS | None, list[Diagnostic]]:
    missing = _resolve(model, name, spec)
    if missing is not None:
        return None, [missing]
    lts, ds = model.build_lts(name)
    return lts, list(ds)


def safety(model, name: str, spec: str) -> tuple[int, list[Diagnostic]]:
    """Deadlock and ERROR check of ``name``; prints LTSA's text, returns (exit, diagnostics)."""
    lts, ds = _build(model, name, spec)
    errs = [d for d in ds if d.is_error]
    if lts is None or errs:
        return 1, errs
    result = check_safety(lts)
    span = decl_span(model, name)
    diags: list[Diagnostic] = []
    print(f"Safety check of {name}: {result.states} states")
    if result.deadlock is not None:
        print(block("Trace to DEADLOCK:", result.deadlock))
        diags.append(error(E_DEADLOCK, f"potential DEADLOCK in {name}; Trace to DEADLOCK: "
                           f"{one_line(result.deadlock)}", span))
    if result.error is not None:
        culprit = violated_property(model, name, lts, result.error)
        where = culprit or name
        print(block(f"Trace to property violation in {where}:", result.error))
        related: tuple[Related, ...] = ()
        if culprit is not None and decl_span(model, culprit).line > 0:
            related = (Related(decl_span(model, culprit), f"{culprit} is declared here"),)
        diags.append(error(E_ERROR, f"{name} can reach ERROR; Trace to property violation in "
                           f"{where}: {one_line(result.error)}", span, *related))
    if result.ok:
        print("No deadlocks/errors")
    return (1 if diags else 0), diags


def progress(model, name: str, spec: str) -> tuple[int, list[Diagnostic]]:
    """Progress check of ``name`` against every ``progress`` declaration (LTSA's default check,
    every action in every terminal set, when there is none)."""
    lts, ds = _build(model, name, spec)
    errs = [d for d in ds if d.is_error]
    if lts is None or errs:
        return 1, errs
    props, pdiags = progress_properties(model)
    if any(d.is_error for d in pdiags):
        return 1, pdiags
    sets = terminal_sets(lts)
    span = decl_span(model, name)
    diags: list[Diagnostic] = []
    print(f"Progress check of {name}: {len(sets)} terminal set(s)")

    def report(title: str, ts, note: Related | None, what: str) -> None:
        print(title)
        print(block("Trace to terminal set of states:", ts.trace))
        print(block("Cycle in terminal set:", cycle_in(lts, ts.states, ts.entry)))
        acts = "{" + ", ".join(sorted(ts.actions)) + "}"
        print(f"Actions in terminal set:\n\t{acts}")
        related = (note,) if note is not None else ()
        diags.append(error(E_PROGRESS, f"{what} in {name}; Trace to terminal set of states: "
                           f"{one_line(ts.trace)}; Actions in terminal set: {acts}",
                           span, *related))

    if props:
        spans = {p.name: sp for p, sp in props}
        for v in check_progress(lts, [p for p, _ in props], sets):
            report(f"Progress violation: {v.prop.name}", v.terminal,
                   Related(spans[v.prop.name], f"progress {v.prop.name} is declared here"),
                   f"progress violation: {v.prop.name}")
    else:
        for ts, missing in default_progress(lts, sets):
            acts = "{" + ", ".join(sorted(missing)) + "}"
            report(f"Progress violation for actions:\n\t{acts}", ts, None,
                   f"progress violation for actions {acts}")
    if not diags:
        print("No progress violations detected.")
    return (1 if diags else 0), [*pdiags, *diags]


def cycle_in(lts: LTS, states: frozenset[int], entry: int) -> tuple[str, ...]:
    """A shortest cycle from ``entry`` back to itself inside ``states`` (BFS)."""
    from collections import deque

    out = lts.out_edges()
    parent: dict[int, tuple[int, str]] = {}
    queue: deque[int] = deque()
    for a, t in out[entry]:
        if t in states and t not in parent:
            parent[t] = (entry, a)
            if t == entry:
                return (a,)
            queue.append(t)
    while queue:
        s = queue.popleft()
        for a, t in out[s]:
            if t == entry:
                labels = [a]
                while s != entry:
                    s, b = parent[s]
                    labels.append(b)
                return tuple(reversed(labels))
            if t in states and t not in parent:
                parent[t] = (s, a)
                queue.append(t)
    return ()


def run_checks(args, model) -> int:
    """``--safety`` and ``--progress`` of ``iterc check``; the exit code (0 all pass)."""
    code = 0
    diags: list[Diagnostic] = []
    for name in getattr(args, "safety", None) or ():
        c, ds = safety(model, name, args.spec)
        code, diags = max(code, c), [*diags, *ds]
    for name in getattr(args, "progress", None) or ():
        c, ds = progress(model, name, args.spec)
        code, diags = max(code, c), [*diags, *ds]
    sys.stdout.flush()
    if diags:
        print(render(diags, model.sources), file=sys.stderr)
    return code
