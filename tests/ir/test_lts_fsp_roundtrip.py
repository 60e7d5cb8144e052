"""lts_to_fsp output parses back (through the front-end) to a bisimilar LTS, same alphabet."""

from __future__ import annotations

import pytest
from helpers_lts import E, lts
from hypothesis import given, settings
from hypothesis import strategies as st

from iterplan_compiler.ir.fsp_print import lts_to_fsp, process_name
from iterplan_compiler.ir.lts import LTS, TAU, make_lts
from iterplan_compiler.ir.minimise import bisimilar
from iterplan_compiler.pipeline import load_model as load


def reparse(m: LTS) -> LTS:
    text = lts_to_fsp(m)
    model, diags = load("roundtrip.lts", text=text)
    assert model is not None, (text, [d.message for d in diags])
    back, diags = model.build_lts(process_name(m.name))
    assert back is not None, (text, [d.message for d in diags])
    return back


@pytest.mark.parametrize("m", [
    lts("Exp", 4, [(0, "b", E), (0, "c", E), (0, "a", 1), (0, "d.1", 2), (1, TAU, 3)],
        alphabet={"z", "w.2"}, end={3}),
    lts("Route", 2, [(0, "route.3.observe", 1), (1, "win", 0), (1, "s.10", 1)]),
    lts("Stop", 1, []),
    lts("Loop", 2, [(0, TAU, 1), (1, TAU, 0), (1, "a", E)]),
    lts("C_#NC#", 2, [(0, "a", 1)]),
    lts("Q1", 2, [(0, "a", 1), (1, "b", 0)]),
], ids=["mixed", "indices", "stop", "tau-loop", "odd-name", "state-like-name"])
def test_roundtrip_examples(m):
    back = reparse(m)
    assert back.alphabet == m.alphabet
    assert bisimilar(back, m)


LABELS = ["a", "b.1", "c.x", TAU]


@st.composite
def printable_lts(draw) -> LTS:
    n = draw(st.integers(1, 4))
    trans = draw(st.lists(st.tuples(st.integers(0, n - 1), st.sampled_from(LABELS),
                                    st.integers(-1, n - 1)), max_size=7))
    extra = draw(st.sets(st.sampled_from(["z", "y.2"]), max_size=2))
    ends = draw(st.sets(st.integers(0, n - 1), max_size=1)) - {s for s, _, _ in trans}
    return make_lts("R", n, trans, extra, 0, ends)


@settings(max_examples=40, deadline=None)
@given(printable_lts())
def test_roundtrip_random(m):
    back = reparse(m)
    assert back.alphabet == m.alphabet
    assert bisimilar(back, m)
