"""Graphviz back-end: an LTS -> DOT text (via pydot), and DOT -> SVG/PNG with the ``dot`` binary.

Drawing conventions follow the paper's Fig. 2: controllable transitions are **dashed**,
uncontrollable ones **solid**.  The initial state is drawn bold and entered by an arrow from an
invisible point; end states (``END``) are double circles; ERROR is one red box named ``ERROR``
(MTSA draws it as state ``-1``).  Several labels between the same two states with the same
style share one edge, labels stacked one per line in sorted order, so the output is stable.
"""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import Iterable
from pathlib import Path

from iterplan_compiler.ir.lts import ERROR, LTS, TAU

#: Output formats :func:`render` understands, by file suffix.
RENDER_FORMATS = {".svg": "svg", ".png": "png", ".pdf": "pdf"}

#: Layout hints for big drawings, measured with Graphviz 2.43 on a loaded 2-core machine (QA):
#: above ``FAST_LAYOUT_EDGES`` edges, ``nslimit`` bounds the network-simplex pass that places
#: nodes horizontally (69 states/203 edges: 9 s -> 1.5 s); above ``STRAIGHT_EDGES`` edges are
#: drawn as straight lines, because spline routing dominates (144 states/432 edges: 69 of 76 s;
#: 13 s in all with both hints).  Small drawings (the paper's figures) keep curved splines.
FAST_LAYOUT_EDGES = 150
STRAIGHT_EDGES = 300

_ERROR_NODE = "ERROR"
_START_NODE = "__start"


class GraphvizError(RuntimeError):
    """Rendering failed: ``dot`` is missing or rejected the input."""


def _esc(text: str) -> str:
    return text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")


def _q(text: str) -> str:
    """Quote ``text`` as a DOT string (pydot would leave some identifiers bare)."""
    return '"' + _esc(text) + '"'


def to_dot(
    lts: LTS,
    *,
    controllable: Iterable[str] | None = None,
    title: str | None = None,
) -> str:
    """Return DOT text for ``lts``.

    With ``controllable`` given, its labels are dashed and all others solid; without it every
    transition is solid (no control interpretation).  ``tau`` is always solid.  ``title`` (default:
    the LTS's name) labels the graph.  Nodes are named by state number; ``state_names``, when the
    LTS has them, become node labels.
    """
    # pydot (and pyparsing under it) is imported here, not at module level: 20-40 ms that
    # `iterc compile --emit py`, the common case, does not need
    import pydot

    ctrl = frozenset(controllable) if controllable is not None else frozenset()
    graph = pydot.Dot(
        _q(lts.name or "LTS"),
        graph_type="digraph",
        rankdir="LR",
        label=_q(title if title is not None else lts.name),
        labelloc="t",
        fontname="Helvetica",
    )
    graph.set_node_defaults(shape="circle", fontname="Helvetica", fontsize="11")
    graph.set_edge_defaults(fontname="Helvetica", fontsize="10")

    graph.add_node(pydot.Node(_START_NODE, shape="point", style="invis", label=_q("")))
    for s in range(lts.num_states):
        attrs: dict[str, str] = {}
        if lts.state_names is not None:
            attrs["label"] = _q(lts.state_names[s])
        if s in lts.end_states:
            attrs["shape"] = "doublecircle"
        if s == lts.initial:
            attrs["style"] = "bold"
        graph.add_node(pydot.Node(str(s), **attrs))  # type: ignore[arg-type]  # pydot stubs
    if lts.has_error:
        graph.add_node(pydot.Node(
            _ERROR_NODE, shape="box", style="filled", fillcolor="#f4cccc", color="red",
            label=_q("ERROR"),
        ))
    graph.add_edge(pydot.Edge(_START_NODE, str(lts.initial)))

    # (source, target, dashed) -> labels; sorted keys give a byte-stable edge order.
    groups: dict[tuple[int, int, bool], list[str]] = {}
    for s, a, t in lts.transitions:
        dashed = a != TAU and a in ctrl
        groups.setdefault((s, t, dashed), []).append(a)
    if len(groups) > FAST_LAYOUT_EDGES:
        graph.set("nslimit", "0.2")
    if len(groups) > STRAIGHT_EDGES:
        graph.set("splines", "line")
    for (s, t, dashed), labels in sorted(groups.items(), key=lambda kv: (kv[0][0], kv[0][1] == ERROR,
                                                                          kv[0][1], kv[0][2])):
        # DOT's "\n" escape stacks the labels one per line.
        attrs = {"label": '"' + "\\n".join(_esc(a) for a in sorted(labels)) + '"'}
        if dashed:
            attrs["style"] = "dashed"
        target = _ERROR_NODE if t == ERROR else str(t)
        graph.add_edge(pydot.Edge(str(s), target, **attrs))  # type: ignore[arg-type]  # pydot stubs
    return graph.to_string()


def dot_binary() -> str | None:
    """Return the path of Graphviz's ``dot`` program, or None if it is not installed."""
    return shutil.which("dot")


def render(dot_text: str, path: str | Path) -> None:
    """Write ``dot_text`` to ``path``: DOT as-is for ``.dot``/``.gv``, else render by suffix.

    SVG, PNG and PDF need Graphviz's ``dot`` binary; raises :class:`GraphvizError` if it is
    absent or fails, and :class:`ValueError` for an unknown suffix.
    """
    from iterplan_compiler.outputs import atomic_write_bytes, atomic_write_text

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".dot", ".gv"):
        atomic_write_text(path, dot_text)
        return
    fmt = RENDER_FORMATS.get(suffix)
    if fmt is None:
        raise ValueError(f"cannot render to {path.name!r}: use .dot, .gv, .svg, .png or .pdf")
    exe = dot_binary()
    if exe is None:
        raise GraphvizError(
            f"rendering {path.name} needs Graphviz's `dot` program, which is not installed "
            "(install graphviz, or write .dot instead)"
        )
    proc = subprocess.run(  # to stdout, then written atomically (a kill never leaves half)
        [exe, f"-T{fmt}"],
        input=dot_text.encode("utf-8"),
        capture_output=True,
        check=False,
    )
    if proc.returncode != 0:
        msg = proc.stderr.decode("utf-8", "replace").strip()
        raise GraphvizError(f"dot failed on {path.name}: {msg}")
    atomic_write_bytes(path, proc.stdout)
