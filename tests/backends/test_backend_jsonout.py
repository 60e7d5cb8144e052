"""The JSON back-end: stable text and a lossless round trip."""

from __future__ import annotations

import json

from backends_helpers import FIRE_PATROL_CONTROLLABLE, fire_patrol, toggle
from hypothesis import given, settings
from hypothesis import strategies as st

from iterplan_compiler.backends.jsonout import FORMAT, from_json, to_json
from iterplan_compiler.ir.lts import make_lts


def test_fields_and_stability():
    text = to_json(fire_patrol(), FIRE_PATROL_CONTROLLABLE | {"not.in.alphabet"})
    assert text == to_json(fire_patrol(), FIRE_PATROL_CONTROLLABLE | {"not.in.alphabet"})
    d = json.loads(text)
    assert d["format"] == FORMAT and d["name"] == "FirePatrol" and d["num_states"] == 12
    assert d["controllable"] == sorted(FIRE_PATROL_CONTROLLABLE)
    assert set(d["uncontrollable"]) == fire_patrol().alphabet - FIRE_PATROL_CONTROLLABLE
    assert [tuple(t) for t in d["transitions"]] == list(fire_patrol().transitions)
    assert text.endswith("}\n")


def test_round_trip_with_names():
    lts = toggle()
    assert from_json(to_json(lts, {"on"})) == (lts, frozenset({"on"}))


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(1, 5),
    trans=st.lists(st.tuples(st.integers(0, 4), st.sampled_from(["a", "b.c", "tau", 'x"']),
                             st.integers(-1, 4)), max_size=8),
    ctrl=st.sets(st.sampled_from(["a", "b.c", "z"])),
)
def test_round_trip_random(n, trans, ctrl):
    trans = [(s % n, a, t if t < 0 else t % n) for s, a, t in trans]
    lts = make_lts("R", n, trans, end_states=[n - 1])
    back, back_ctrl = from_json(to_json(lts, ctrl))
    assert back == lts and back_ctrl == frozenset(ctrl) & lts.alphabet
