"""Python back-end: a synthesised controller LTS -> the source text of a controller module.

The generated module is meant to be read, diffed and shipped to the aircraft:

* it imports only :mod:`iterplan_compiler.runtime` (no lark, no dd);
* it is deterministic — no timestamps, no absolute paths; the header names the compiler
  version, the spec file's *base name* and its sha256;
* it carries ``# spec.lts:LINE:COL`` comments pointing back to the composite / controllerSpec;
* the automaton is a dict-of-dicts table (``DELTA[state][label] = next``) wrapped in a
  :class:`~iterplan_compiler.runtime.controller.ControllerTable`; stepping is one or two dict
  look-ups in the runtime's :class:`~iterplan_compiler.runtime.controller.Controller`.

Module contract (what ``iterc run`` and user code may rely on) — see ``docs/backends.md``:
``COMPILER_VERSION``, ``SPEC_FILE``, ``SPEC_SHA256``, ``NAME``, ``CONTROLLABLE``,
``UNCONTROLLABLE``, ``STATE_NAMES``, ``DELTA``, ``TRANSITIONS``, ``TABLE``, the controller class
(alias ``CONTROLLER_CLASS``) and ``make_controller()``.
"""

from __future__ import annotations

import keyword
import re
from collections.abc import Mapping
from pathlib import PurePath

from iterplan_compiler import __version__
from iterplan_compiler.backends.emit import Emitter
from iterplan_compiler.diagnostics import Span
from iterplan_compiler.ir.lts import ERROR, LTS, TAU


class BackendError(ValueError):
    """The LTS cannot be emitted as a controller (ERROR/tau moves or nondeterminism).

    Synthesis never produces such a controller, so for the driver this signals a bug upstream
    or a request to compile something that is not a controller; it is turned into a diagnostic.
    """


def class_name(name: str) -> str:
    """Return the controller class name for composite ``name`` (``FirePatrol`` ->
    ``FirePatrolController``); always a valid, non-keyword identifier."""
    parts = [p for p in re.split(r"[^0-9A-Za-z]+", name) if p]
    base = "".join(p[:1].upper() + p[1:] for p in parts) or "Spec"
    if base[0].isdigit():
        base = "C" + base
    ident = base + "Controller"
    return ident + "_" if keyword.iskeyword(ident) else ident


def _one_line(text: str) -> str:
    """Make ``text`` safe inside a comment or docstring line."""
    return text.replace("\\", "/").replace('"""', "'''").replace("\r", " ").replace("\n", " ")


def _where(span: Span) -> str:
    """``file:line:col`` with only the file's base name (generated code holds no paths)."""
    return f"{PurePath(span.file).name}:{span.line}:{span.column}"


def check_controller(controller: LTS) -> dict[int, dict[str, int]]:
    """Return ``delta[state][label] = target`` or raise :class:`BackendError`.

    A controller must be deterministic, tau-free and never enter ERROR.
    """
    delta: dict[int, dict[str, int]] = {s: {} for s in range(controller.num_states)}
    for s, a, t in controller.transitions:
        if t == ERROR:
            raise BackendError(f"{controller.name}: state {s} enters ERROR on {a!r}")
        if a == TAU:
            raise BackendError(f"{controller.name}: state {s} has a tau transition")
        if a in delta[s] and delta[s][a] != t:
            raise BackendError(
                f"{controller.name}: nondeterministic on {a!r} in state {s} "
                f"(targets {delta[s][a]} and {t})"
            )
        delta[s][a] = t
    return delta


def _frozenset_literal(em: Emitter, name: str, labels: list[str]) -> None:
    if not labels:
        em.line(f"{name}: frozenset[str] = frozenset()")
        return
    em.line(f"{name}: frozenset[str] = frozenset({{")
    with em.indent():
        for a in labels:
            em.line(f"{a!r},")
    em.line("})")


def emit_module(
    controller: LTS,
    *,
    controllable: frozenset[str],
    name: str,
    source_name: str,
    spec_hash: str,
    origins: Mapping[str, Span] | None = None,
) -> str:
    """Return the source of a Python module that runs ``controller``.

    ``controllable`` is the spec's controllable set (labels outside the controller's alphabet
    are ignored); every other alphabet label is uncontrollable.  ``name`` is the composite's
    name, ``source_name`` the spec file (only its base name is written), ``spec_hash`` the
    sha256 of the spec text.  ``origins`` maps a description (``"controller composite C"``,
    ``"controllerSpec G"``) to its span; each becomes a ``# file:line:col`` comment.

    The controller's initial state must be 0 (synthesis renumbers reachable states from 0);
    otherwise the table still records ``initial`` faithfully.  Raises :class:`BackendError` if the
    LTS is not a deterministic, tau-free, ERROR-free machine.
    """
    delta = check_controller(controller)
    alphabet = sorted(controller.alphabet)
    ctrl = [a for a in alphabet if a in controllable]
    unctrl = [a for a in alphabet if a not in controllable]
    spec_file = PurePath(source_name).name
    cls = class_name(name)

    em = Emitter()
    _emit_header(em, controller, name, spec_file, spec_hash, origins, len(ctrl), len(unctrl))
    em.line(f"COMPILER_VERSION = {__version__!r}")
    em.line(f"SPEC_FILE = {spec_file!r}")
    em.line(f"SPEC_SHA256 = {spec_hash!r}")
    em.line(f"NAME = {name!r}")
    em.line("")
    em.line("# Actions the controller issues (dashed in `iterc dot`).")
    _frozenset_literal(em, "CONTROLLABLE", ctrl)
    em.line("# Answers and events of the environment; never blocked by a correct controller.")
    _frozenset_literal(em, "UNCONTROLLABLE", unctrl)
    em.line("")
    _emit_tables(em, controller, delta)
    _emit_class(em, cls, name)
    em.line("")
    em.line("")
    em.line(f"CONTROLLER_CLASS = {cls}")
    em.line("")
    em.line("")
    em.line(f"def make_controller() -> {cls}:")
    with em.indent():
        em.line('"""Return a fresh controller in its initial state."""')
        em.line(f"return {cls}()")
    return em.text()


def _emit_header(em: Emitter, controller: LTS, name: str, spec_file: str, spec_hash: str,
                 origins: Mapping[str, Span] | None, n_ctrl: int, n_unctrl: int) -> None:
    """The provenance comments, the module docstring, the imports and ``__all__``."""
    em.line(f"# Generated by iterc {__version__} from {_one_line(spec_file)}"
            " -- do not edit; regenerate with `iterc compile`.")
    em.line(f"# spec sha256: {spec_hash}")
    for what, span in sorted((origins or {}).items()):
        em.line(f"# {_one_line(what)}: {_one_line(_where(span))}")
    em.line(f'"""Controller ``{_one_line(name)}`` synthesised from ``{_one_line(spec_file)}``.')
    em.line("")
    em.line(f"{controller.num_states} states, {controller.num_transitions} transitions; "
            f"{n_ctrl} controllable and {n_unctrl} uncontrollable labels.")
    em.line("")
    em.line("Use::")
    em.line("")
    with em.indent():
        em.lines(
            "ctrl = make_controller()",
            "ctrl.enabled()            # labels allowed now",
            "ctrl.step(label)          # RefusedEvent if not allowed",
            "ctrl.run(bindings)        # execute through action bindings",
        )
    em.line('"""')
    em.line("")
    em.line("from __future__ import annotations")
    em.line("")
    em.line("from collections.abc import Callable, Iterable, Mapping")
    em.line("")
    em.line("from iterplan_compiler.runtime.controller import (")
    with em.indent():
        em.lines("Controller,", "ControllerTable,", "RefusedEvent,", "run_bindings,")
    em.line(")")
    em.line("")
    em.line('__all__ = ["CONTROLLER_CLASS", "RefusedEvent", "TABLE", "make_controller"]')
    em.line("")


def _emit_tables(em: Emitter, controller: LTS, delta: Mapping[int, Mapping[str, int]]) -> None:
    """``STATE_NAMES``, ``DELTA``, ``TRANSITIONS`` and ``TABLE``."""
    names = controller.state_names
    if names is None:
        em.line("STATE_NAMES: tuple[str, ...] | None = None")
    else:
        em.line("STATE_NAMES: tuple[str, ...] | None = (")
        with em.indent():
            for i, n in enumerate(names):
                em.line(f"{n!r},  # {i}")
        em.line(")")
    em.line("")
    em.line("# DELTA[state][label] = next state.")
    em.line("DELTA: dict[int, dict[str, int]] = {")
    with em.indent():
        for s in range(controller.num_states):
            row = ", ".join(f"{a!r}: {t}" for a, t in sorted(delta[s].items()))
            tag = ""
            if names is not None:
                tag = f"  # {_one_line(names[s])}"
            elif not delta[s]:
                tag = "  # no moves: the controller stops here"
            em.line(f"{s}: {{{row}}},{tag}")
    em.line("}")
    em.line("")
    em.line("TRANSITIONS: tuple[tuple[int, str, int], ...] = tuple(")
    with em.indent():
        em.line("(s, a, t) for s, row in DELTA.items() for a, t in sorted(row.items())")
    em.line(")")
    em.line("")
    em.line(f"TABLE = ControllerTable(NAME, {controller.num_states}, {controller.initial}, "
            "DELTA, CONTROLLABLE, UNCONTROLLABLE)")
    em.line("")
    em.line("")


# The run loop itself lives in the runtime (``runtime.controller.run_bindings``); the generated
# method only adds the up-front binding check, so a plan with an unbound action fails before
# take-off rather than in flight.
_RUN_BODY = '''\
"""Drive the controller through action bindings; return ``run_bindings``'s report.

``bindings`` maps every controllable label to a callable run *after* the controller
takes the action; it performs it and returns the environment's answer: an uncontrollable
label (``has.next`` -> ``"y.next"``), several labels, or ``None`` (instantaneous action).
Answers are fed back through :meth:`step` in order.  When no answer is pending and no
controllable action is enabled, ``events()`` supplies the next uncontrollable label
(``None`` stops the run).  ``choose`` picks among enabled controllable labels (default:
the first in sorted order).  Returns ``{"steps": n, "trace": [labels], "stopped": why}``.
"""
missing = sorted(CONTROLLABLE - set(bindings))
if missing:
    raise ValueError(f"{NAME}: no binding for controllable action(s): {', '.join(missing)}")
return run_bindings(self, bindings, max_steps=max_steps, choose=choose, events=events)'''


def _emit_class(em: Emitter, cls: str, name: str) -> None:
    em.line(f"class {cls}(Controller):")
    with em.indent():
        em.line(f'"""The synthesised controller for ``{_one_line(name)}`` (a runtime Controller).')
        em.line("")
        em.line("``step(label)`` raises :class:`RefusedEvent` for a label not allowed now.")
        em.line('"""')
        em.line("")
        em.line("__slots__ = ()")
        em.line("")
        em.line("controllable = CONTROLLABLE")
        em.line("uncontrollable = UNCONTROLLABLE")
        em.line("transitions = TRANSITIONS")
        em.line("states = range(TABLE.num_states)")
        em.line("")
        em.line("def __init__(self) -> None:")
        with em.indent():
            em.line("super().__init__(TABLE)")
        em.line("")
        em.line("def run(")
        with em.indent():
            em.lines(
                "self,",
                "bindings: Mapping[str, Callable[[], str | Iterable[str] | None]],",
                "*,",
                "max_steps: int | None = None,",
                "choose: Callable[[list[str]], str] | None = None,",
                "events: Callable[[], str | None] | None = None,",
            )
        em.line(") -> dict:")
        with em.indent():
            for ln in _RUN_BODY.splitlines():
                em.line(ln)

