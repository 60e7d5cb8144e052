"""Legality (MTSA LegalityAnalyser): hand-built versions of conformance/mtsa/Legality/*."""

from __future__ import annotations

from helpers_lts import cycle, lts

from iterplan_compiler.ir.alphabet_ops import extend_alphabet
from iterplan_compiler.ir.legality import is_legal

AC = {"makeA", "ready"}


def make_a():
    return cycle("MAKE_A", "makeA", "ready", "used")


def make_b():
    return cycle("MAKE_B", "makeB", "ready", "used")


def test_factory_is_legal():
    res = is_legal(make_a(), make_b(), AC)
    assert res.legal and res.witness is None and bool(res)
    assert res.product_states > 0


def test_not_legal_alphabet_extension_blocks_uncontrollable():
    # MAKE_A = (...) + {makeB}: makeB is uncontrollable, in MAKE_A's alphabet, never enabled.
    res = is_legal(extend_alphabet(make_a(), {"makeB"}), make_b(), AC)
    assert not res.legal
    assert res.witness is not None
    assert res.witness.action == "makeB" and res.witness.trace == ()
    assert "makeB" in res.witness.describe()


def test_not_legal_2():
    a = cycle("A", "a", "b")
    b = lts("B", 1, [(0, "a", 0), (0, "b", 0)])
    res = is_legal(a, b, {"a"})
    assert not res.legal and res.witness.action == "b"
    # if b were controllable the controller may refuse it
    assert is_legal(a, b, {"a", "b"}).legal


def test_witness_trace_is_shortest_path():
    ctrl = lts("C", 3, [(0, "go", 1), (1, "go", 2)], alphabet={"u"})
    plant = lts("P", 2, [(0, "go", 0), (0, "u", 1)])
    # controller never offers u; plant offers it from the start
    res = is_legal(ctrl, plant, {"go"})
    assert res.witness.trace == ()
    plant2 = lts("P", 3, [(0, "go", 1), (1, "go", 1), (1, "u", 2)])
    ctrl2 = lts("C", 3, [(0, "go", 1), (1, "u", 1), (1, "go", 2)], alphabet={"u"})
    res2 = is_legal(ctrl2, plant2, {"go"})
    assert not res2.legal and res2.witness.trace == ("go", "go")
    assert (res2.witness.controller_state, res2.witness.plant_state) == (2, 1)
