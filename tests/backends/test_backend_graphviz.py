"""The Graphviz back-end: DOT text (golden + structure) and rendering with `dot`."""

from __future__ import annotations

import pydot
import pytest
from backends_helpers import (
    FIRE_PATROL_CONTROLLABLE,
    TOGGLE_CONTROLLABLE,
    check_golden,
    fire_patrol,
    toggle,
)

from iterplan_compiler.backends.graphviz import GraphvizError, dot_binary, render, to_dot
from iterplan_compiler.ir.lts import make_lts

# pydot's DOT parser triggers pyparsing deprecation warnings on recent pyparsing versions.
pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

needs_dot = pytest.mark.skipif(dot_binary() is None,
                               reason="Graphviz `dot` binary not installed")


def _edges(text: str) -> dict[tuple[str, str], list[tuple[str, str | None]]]:
    """Parse DOT back with pydot: (src, dst) -> [(label, style), ...]."""
    (graph,) = pydot.graph_from_dot_data(text)
    out: dict[tuple[str, str], list[tuple[str, str | None]]] = {}
    for e in graph.get_edges():
        out.setdefault((e.get_source(), e.get_destination()), []).append(
            ((e.get("label") or "").strip('"'), e.get("style")))
    return out


def test_golden_dot():
    check_golden(to_dot(fire_patrol(), controllable=FIRE_PATROL_CONTROLLABLE),
                 "fire_patrol_controller.dot")
    check_golden(to_dot(toggle(), controllable=TOGGLE_CONTROLLABLE, title="Toggle"),
                 "toggle_controller.dot")
    # A safety property: ERROR box, an END state, a tau move and a non-zero initial state.
    prop = make_lts("OnlyAfterArrived", 3, [
        (0, "arrived", 1), (0, "take.photo", -1), (1, "take.photo", 1), (1, "has.next", 2),
        (2, "tau", 0), (1, "land", 2)], initial=0, end_states=[2])
    check_golden(to_dot(prop, controllable={"take.photo", "has.next", "land"}),
                 "only_after_arrived.dot")


def test_controllable_dashed_uncontrollable_solid():
    edges = _edges(to_dot(fire_patrol(), controllable=FIRE_PATROL_CONTROLLABLE))
    for s, a, t in fire_patrol().transitions:
        ((label, style),) = edges[(str(s), str(t))]
        assert a in label.split("\\n")
        assert (style == "dashed") == (a in FIRE_PATROL_CONTROLLABLE), (s, a, t)
    assert ("__start", "0") in edges


def test_without_controllable_everything_is_solid():
    edges = _edges(to_dot(fire_patrol()))
    assert all(style is None for pair in edges.values() for _, style in pair)


def test_error_node_initial_and_end_states():
    lts = make_lts("P", 3, [(0, "a", 1), (1, "b", -1), (1, "c", 2), (1, "d", 2)],
                   initial=1, end_states=[2])
    text = to_dot(lts, controllable={"c"})
    (graph,) = pydot.graph_from_dot_data(text)
    nodes = {n.get_name(): n for n in graph.get_nodes()}
    assert nodes["ERROR"].get("shape") == "box" and nodes["ERROR"].get("color") == "red"
    assert nodes["1"].get("style") == "bold" and nodes["0"].get("style") is None
    assert nodes["2"].get("shape") == "doublecircle"
    edges = _edges(text)
    assert edges[("__start", "1")] == [("", None)]
    assert edges[("1", "ERROR")] == [("b", None)]
    # c (dashed) and d (solid) lead to the same state but are drawn as separate edges.
    assert sorted(edges[("1", "2")], key=str) == [("c", "dashed"), ("d", None)]
    assert "ERROR" not in to_dot(make_lts("Q", 1, [(0, "a", 0)]))


def test_quoting_of_odd_names():
    lts = make_lts('we"ird', 2, [(0, 'q"x', 1), (1, "back\\slash", 0)],
                   state_names=("a b", "c\"d"))
    (graph,) = pydot.graph_from_dot_data(to_dot(lts))
    assert len(graph.get_edges()) == 3


@needs_dot
@pytest.mark.parametrize("suffix, magic", [(".svg", b"<?xml"), (".png", b"\x89PNG")])
def test_render(tmp_path, suffix, magic):
    out = tmp_path / f"fire{suffix}"
    render(to_dot(fire_patrol(), controllable=FIRE_PATROL_CONTROLLABLE), out)
    assert out.read_bytes().startswith(magic)


def test_render_dot_text_and_bad_suffix(tmp_path, monkeypatch):
    text = to_dot(toggle())
    render(text, tmp_path / "t.dot")
    assert (tmp_path / "t.dot").read_text() == text
    with pytest.raises(ValueError, match="cannot render"):
        render(text, tmp_path / "t.jpeg2000")
    monkeypatch.setattr("iterplan_compiler.backends.graphviz.dot_binary", lambda: None)
    with pytest.raises(GraphvizError, match="needs Graphviz"):
        render(text, tmp_path / "t.svg")


def _ring(n_states: int, labels_per_state: int):
    # Distinct targets so no two transitions share an edge: n_states * labels_per_state edges.
    trans = [(s, f"a{k}", (s + k + 1) % n_states) for s in range(n_states)
             for k in range(labels_per_state)]
    return make_lts("Ring", n_states, trans)


def test_big_drawings_get_layout_hints():
    from iterplan_compiler.backends import graphviz

    small = to_dot(_ring(10, 3))                                   # 30 edges
    assert "nslimit" not in small and "splines" not in small
    medium = to_dot(_ring(40, 5))                                  # 200 edges
    assert "nslimit=0.2;" in medium and "splines" not in medium
    big = to_dot(_ring(80, 5))                                     # 400 edges
    assert "nslimit=0.2;" in big and "splines=line;" in big
    assert graphviz.FAST_LAYOUT_EDGES < 200 < graphviz.STRAIGHT_EDGES < 400
    pydot.graph_from_dot_data(big)  # still valid DOT
