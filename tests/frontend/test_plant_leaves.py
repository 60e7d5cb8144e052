"""Synthesis problems take plain sub-composites as their leaf machines (issue 12): no
explicit product of `Env` is built; composites with operators or tails stay one machine."""

from __future__ import annotations

from iterplan_compiler.pipeline import load_model as load
from iterplan_compiler.synthesis.driver import synthesize

SPEC = """
A = (a -> b -> A).
B = (b -> c -> B).
C = (c -> a -> C).
||Inner = (A || B).
||Env = (Inner || C).
||Hidden = (A || B) \\ {x}.
||Relab = (Inner / {d/a}).
minimal ||Min = (A || B).
fluent FA = <a, b>
assert GA = FA
controllerSpec G = { liveness = {GA} controllable = {a, c} }
controller ||K = (Env)~{G}.
controller ||K2 = (Env || A)~{G}.
controller ||KH = (Hidden || C)~{G}.
controller ||KR = (p:Env)~{G}.
controller ||KL = (Relab || Min)~{G}.
"""


def _model(tmp_path):
    f = tmp_path / "leaves.lts"
    f.write_text(SPEC)
    model, diags = load(str(f))
    assert model is not None, diags
    return model


def test_plain_composites_become_leaves(tmp_path):
    model = _model(tmp_path)
    p, _ = model.synthesis_problem("K")
    assert [m.name for m in p.plant] == ["A", "B", "C"] and p.env_machines == 3
    p2, _ = model.synthesis_problem("K2")
    assert [m.name for m in p2.plant] == ["A", "B", "C", "A"] and p2.env_machines == 3


def test_operators_and_relabelling_keep_one_machine(tmp_path):
    model = _model(tmp_path)
    ph, _ = model.synthesis_problem("KH")
    assert len(ph.plant) == 2 and ph.env_machines == 1
    pl, _ = model.synthesis_problem("KL")
    assert len(pl.plant) == 2


def test_prefix_distributes_over_leaves(tmp_path):
    model = _model(tmp_path)
    p, _ = model.synthesis_problem("KR")
    assert len(p.plant) == 3
    assert all(all(a.startswith("p.") for a in m.alphabet) for m in p.plant)


def test_leaves_give_the_flattened_verdict_and_controller(tmp_path):
    from dataclasses import replace

    from iterplan_compiler.ir.compose import compose
    from iterplan_compiler.ir.minimise import bisimilar

    model = _model(tmp_path)
    p, _ = model.synthesis_problem("K")
    flat = replace(p, plant=(compose(list(p.plant), "Env"),), env_machines=1)
    r1, r2 = synthesize(p), synthesize(flat)
    assert r1.realizable == r2.realizable
    if r1.realizable:
        assert bisimilar(r1.controller, r2.controller)
        assert bisimilar(r1.composition, r2.composition)
