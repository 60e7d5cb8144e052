"""The emit stage: a synthesised controller rendered as one of :class:`EmitKind`.

``iterc compile --emit`` chooses the kind; :func:`canonical_controller` renumbers the
controller first so generated files depend only on the machine, not on synthesis internals.
"""

from __future__ import annotations

import hashlib

from iterplan_compiler.backends.python import emit_module
from iterplan_compiler.diagnostics import Span
from iterplan_compiler.enums import StrEnum
from iterplan_compiler.ir.lts import LTS, reachable


class EmitKind(StrEnum):
    """What ``iterc compile`` writes."""

    PY = "py"      # a Python controller module (backends/python.py)
    DOT = "dot"    # Graphviz (backends/graphviz.py)
    FSP = "fsp"    # FSP text (ir/fsp_print.py)
    JSON = "json"  # the controller table as JSON (backends/jsonout.py)


#: ``--emit`` choices of ``iterc compile``.
EMIT_KINDS = tuple(k.value for k in EmitKind)


def spec_sha256(text: str) -> str:
    """The sha256 hex digest of the spec text (UTF-8), as written into generated headers."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def canonical_controller(controller: LTS) -> LTS:
    """Renumber ``controller`` canonically: breadth-first from the initial state (which becomes
    0), successors in label order, unreachable states dropped.

    For a deterministic controller the numbering then depends only on the machine, not on how
    synthesis numbered its states, so generated modules and golden files stay stable when
    synthesis internals change.  The result is isomorphic to the input when every state is
    reachable (synthesis drops unreachable pairs).
    """
    return reachable(controller)


def emit(kind: EmitKind, controller: LTS, controllable: frozenset[str], *, name: str,
         source_name: str, spec_hash: str, origins: dict[str, Span] | None = None) -> str:
    """Render a synthesised controller as ``kind`` (the back-end of another kind than the
    default is imported only when asked for: ``iterc compile`` start-up, issue #12)."""
    if kind is EmitKind.PY:
        return emit_module(controller, controllable=controllable, name=name,
                           source_name=source_name, spec_hash=spec_hash, origins=origins)
    if kind is EmitKind.DOT:
        from iterplan_compiler.backends.graphviz import to_dot
        return to_dot(controller, controllable=controllable)
    if kind is EmitKind.JSON:
        from iterplan_compiler.backends.jsonout import to_json
        return to_json(controller, controllable)
    from iterplan_compiler.ir.fsp_print import lts_to_fsp
    text = lts_to_fsp(controller)
    return text if text.endswith("\n") else text + "\n"
